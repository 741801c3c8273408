"""A run in progress read back from its checkpoint, every field checked (package-internal: its
face is ``kinema.checkpoint``'s ``load_run``, ``resume_run`` and ``run_plan``):
``read_progress`` (how far the run has come: frames recorded and in all, steps per frame,
how often a checkpoint is written, checked against the clock) and ``read_run`` (that, and the
frames it has recorded, as the recorder of ``kinema.trajectory`` holds them). The checked
reads are ``kinema._checkpoint_reader``'s."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ._checkpoint_reader import INT64_MAX, TIME_STEPS, CheckpointError, Reader, field_at, first_line
from ._checks import describe
from .contact_record import FIELDS, ContactRecord, offsets_problem
from .frames import plan as frames_plan

_ABOUT = ("masses", "radii", "ids", "species", "colors", "groups", "springs", "dim", "dt", "method", "periodic", "box_edges", "colliders")
_ABOUT_LATER = ("groups",)  # (absent from checkpoints written before the groups were recorded: the first set's)


def read_progress(r: Reader, dt: float, steps: int) -> dict:
    """How far the run in progress has come (the attributes of the group `run`), checked:
    frames recorded and in all, steps per frame (what `fps` makes of `dt`), how often a
    checkpoint is written; and that it ends within the steps a clock counts."""
    if "run" not in r.f:
        raise CheckpointError(f"{r.path}: a checkpoint of a world, not of a run in progress (no group 'run'; World.run(checkpoint=...) writes those)")
    total = r.int_attr("frames_total", 0, INT64_MAX, "the frames the run records after its first: an integer >= 0", "run")
    done = r.int_attr("frames_done", 0, total, f"the frames recorded after the first: an integer from 0 to run/frames_total = {total}", "run")
    per_frame = r.int_attr("per_frame", 1, INT64_MAX, "the steps between frames: an integer >= 1", "run")
    every = r.int_attr("every", 1, INT64_MAX, "the frames between checkpoints: an integer >= 1", "run")
    fps = r.real_attr("fps", lambda v: math.isfinite(v) and v > 0, "frames per second: a finite number > 0", "run")
    steps_per_frame = 1.0 / fps / dt
    if not steps_per_frame < 2.0**63:
        raise r.invalid("attribute 'run/fps'", fps, f"one frame would take {steps_per_frame:.3g} steps of dt = {dt:g} s (at most 2**63)")
    if r.version < 2:
        raise CheckpointError(
            f"{r.path}: a run in progress written by checkpoint version 1, before frames came at exact times: "
            "load_checkpoint reads its world; run it again from there with World.run"
        )
    t0 = r.real_attr("t0", lambda v: math.isfinite(v) and v >= 0, "the time the run started: a finite number of seconds >= 0", "run")
    duration = r.real_attr("duration", lambda v: math.isfinite(v) and v >= 0, "the run's duration: a finite number of seconds >= 0", "run")
    plan = frames_plan(duration, dt, fps)
    if per_frame != plan.per_frame:
        raise r.invalid(
            "attribute 'run/per_frame'",
            per_frame,
            f"the run records a frame every ⌈1/(fps·dt)⌉ = {plan.per_frame} steps (run/fps = {fps:g}, dt = {dt:g} s)",
        )
    if total != plan.frames:
        raise r.invalid(
            "attribute 'run/frames_total'",
            total,
            f"a run of run/duration = {describe(duration)} s at run/fps = {fps:g} records {plan.frames} frames after its first",
        )
    end = steps + (total - done) * per_frame + plan.tail
    if end > TIME_STEPS:
        raise r.invalid(
            "attribute 'run/frames_total'",
            total,
            f"the run would end after {end:.3g} steps ({total - done} frames to go × {per_frame} steps from step {steps}), more than 2**53, "
            "where t = steps·dt no longer grows with every step",
        )
    source = {}  # the scene file kinema run started the run from, and its scene's hash (absent from a run started in Python)
    for key in ("scene_file", "scene_sha256"):
        value = r.f["run"].attrs.get(key)
        source[key] = value.decode(errors="replace") if isinstance(value, bytes) else (None if value is None else str(value))
    return {"frames_done": done, "frames_total": total, "per_frame": per_frame, "every": every, "fps": fps, "t0": t0, "duration": duration, **source}


def read_run(r: Reader, world: Any, time: float, steps: int) -> dict:
    """The run in progress: its progress and the frames it has recorded, every one checked
    (`World.run` records them: `kinema.trajectory._Recorder`)."""
    from .collider_descriptions import _describe_colliders
    from .trajectory import Trajectory

    run = read_progress(r, world.dt, steps)
    frames = run["frames_done"] + 1
    field_t, t = r.reals("run/t", (frames,), np.isfinite, f"the time of each frame recorded (run/frames_done + 1 = {frames}), finite, s")
    if frames > 1:
        k = int(np.argmin(np.diff(t) > 0)) + 1
        if t[k] <= t[k - 1]:
            raise r.invalid(field_at(field_t, (k,)), t[k], f"the times of the frames must increase (t[{k - 1}] = {describe(t[k - 1])})")
    if t[-1] > time:
        raise r.invalid(field_at(field_t, (frames - 1,)), t[-1], f"the last frame cannot be after attribute 'time' = {describe(time)} s")
    finite = np.isfinite
    _, kinetic = r.reals("run/kinetic", (frames,), lambda a: finite(a) & (a >= 0), "each frame's kinetic energy: finite, >= 0 J")
    _, momentum = r.reals("run/momentum", (frames, 3), finite, "each frame's momentum: 3 finite numbers")
    _, angular = r.reals("run/angular_momentum", (frames, 3), finite, "each frame's angular momentum: 3 finite numbers")
    _, contacts = r.ints("run/contacts", (frames,), 0, INT64_MAX, "each frame's number of contacts: an integer >= 0")
    _, balance = r.reals("run/impulse_total", (frames, 3), finite, "each frame's impulse total: 3 finite numbers")
    _, lost = r.reals("run/energy_lost", (frames,), finite, "each frame's energy taken by the collisions: finite, J")
    # (checkpoints written before these were recorded lack all three: zeros)
    if any(f"run/{name}" in r.f for name in ("impacts_total", "virial_total", "kinetic_tensor")):
        _, impacts = r.ints("run/impacts_total", (frames,), 0, INT64_MAX, "the impacts up to each frame: integers >= 0")
        _, virial = r.reals("run/virial_total", (frames, 9), finite, "the virial summed up to each frame: 9 finite numbers, N m s")
        _, kinetic_tensor = r.reals("run/kinetic_tensor", (frames, 9), finite, "each frame's sum of m v v: 9 finite numbers, J")
    else:
        impacts, virial, kinetic_tensor = np.zeros(frames, dtype=np.int64), np.zeros((frames, 9)), np.zeros((frames, 9))
    _, counts = r.ints("run/counts", (frames,), 0, INT64_MAX, "the particles at each frame: integers >= 0")
    rows = sum(counts.tolist())
    field_x, x = r.reals("run/x", (rows, 3), finite, f"the positions of the particles at each frame ({rows} in all, run/counts), finite")
    field_v, v = r.reals("run/v", (rows, 3), finite, f"the velocities of the particles at each frame ({rows} in all, run/counts), finite")
    if world.dim == 2:
        r.each(field_x, x, x[:, 2] == 0, "z = 0 in a 2D world")
        r.each(field_v, v, v[:, 2] == 0, "z = 0 in a 2D world")
    field_ids, ids = r.ints("run/ids", (rows,), 0, INT64_MAX, f"the ids of the particles at each frame ({rows} in all, run/counts): integers >= 0")
    cut = np.cumsum(counts)[:-1]
    ids_by_frame = np.split(ids, cut)
    for k, a in enumerate(ids_by_frame):
        if a.size > 1 and not (np.diff(a) > 0).all():
            raise r.fail(field_ids, f"at frame {k}: the ids must increase strictly ({describe(a)})")
    field_pot, pot = r.json("potential", "run")
    if not isinstance(pot, list) or len(pot) != frames:
        raise r.invalid(field_pot, pot, f"it must be a list of {frames} dicts, each frame's potential energy by force")
    for k, energies in enumerate(pot):
        if not isinstance(energies, dict):
            raise r.invalid(f"{field_pot} [{k}]", energies, "it must be a dict {force name: energy in J}")
        for name, value in energies.items():
            r.real(f"{field_pot} [{k}].{name}", value, lambda u: not math.isnan(u), "an energy in J, not NaN")
    sets = _recorded_sets(r, frames, ids_by_frame)
    about = _recorded_about(r, world, sets[0], _describe_colliders)
    turning: list[dict[str, np.ndarray]] = [{} for _ in range(frames)]
    for name, key, width in (("w", "angular_velocities", 3), ("q", "orientations", 4), ("inertia", "inertia", 1)):
        if f"run/{name}" in r.f:
            _, a = r.reals(
                f"run/{name}", (rows, width), finite, f"the {key.replace('_', ' ')} of the particles at each frame ({rows} in all, run/counts), finite"
            )
            for k, part in enumerate(np.split(a, cut)):
                turning[k][key] = part
    record_contacts = "contact_record" in r.group("run")  # (the run records contacts: World.run(record_contacts=True))
    rec = Trajectory._recorder(contacts=record_contacts)
    rec.turning = turning
    rec.walls = _recorded_walls(r, frames, len(world.colliders))
    if record_contacts:
        rec.touching = _recorded_contacts(r, frames)
    rec.frames = list(
        zip(
            t.tolist(),
            np.split(x, cut),
            np.split(v, cut),
            kinetic.tolist(),
            pot,
            list(momentum),
            list(angular),
            contacts.tolist(),
            list(balance),
            lost.tolist(),
            ids_by_frame,
            impacts.tolist(),
            list(virial),
            list(kinetic_tensor),
            strict=True,
        )
    )
    rec.about, rec.sets = about, sets
    run.update(recorder=rec)
    return run


def _recorded_walls(r: Reader, frames: int, colliders: int) -> list[dict[str, np.ndarray]] | None:
    """What the particles had given each collider at each recorded frame (datasets
    `run/collider_momentum`, `run/collider_normal`, `run/collider_tangential`, (frames, K, 3)
    N·s, K at most the world's colliders): the recorder's `walls`; `None` where the run
    records none (its steps book nothing, or a checkpoint from before)."""
    from .trajectory import COLLIDER_RECORD

    if not any(f"run/{name}" in r.f for name in COLLIDER_RECORD):
        return None
    arrays, k = {}, None
    for name, key in COLLIDER_RECORD.items():
        shape = (frames, k, 3)
        what = f"what the particles had given each collider by each frame (run/frames_done + 1 = {frames}), 3 finite numbers per collider, N·s"
        field, a = r.reals(f"run/{name}", shape, np.isfinite, what)
        if a.shape[1] > colliders:
            raise r.fail(field, f"has rows for {a.shape[1]} colliders; the world has {colliders}")
        arrays[key], k = a, a.shape[1]
    return [{key: a[i] for key, a in arrays.items()} for i in range(frames)]


def _recorded_contacts(r: Reader, frames: int) -> list[dict[str, np.ndarray]]:
    """Each recorded frame's contacts (group `run/contact_record`: `offsets` (frames + 1,) and a
    column of each `kinema.contact_record.FIELDS` name), checked as a `ContactRecord`."""
    _, offsets = r.ints("run/contact_record/offsets", (frames + 1,), 0, INT64_MAX, "each frame's first row of the contact table, from 0, never decreasing")
    problem = offsets_problem(offsets)
    if problem is not None:
        raise r.fail("dataset 'run/contact_record/offsets'", problem)
    total = int(offsets[-1])
    values = {}
    for name in r.group("run/contact_record"):
        if name == "offsets":
            continue
        known = FIELDS.get(name)
        if known is None:
            raise r.fail(f"dataset 'run/contact_record/{name}'", f"is not a column of a contact record ({', '.join(FIELDS)})")
        # a vector per contact, or one number (a column the engine gives as a number)
        shape = (total,) if getattr(r.f[f"run/contact_record/{name}"], "ndim", 1) == 1 else (total, None)
        if known.kind == "int":
            _, a = r.ints(f"run/contact_record/{name}", shape, -1, INT64_MAX, f"the contacts' {name}: integers >= -1")
        elif known.kind == "bool":
            _, a = r.dataset(f"run/contact_record/{name}", "bool", shape, f"the contacts' {name}: a flag per contact")
        else:
            _, a = r.reals(f"run/contact_record/{name}", shape, lambda a: ~np.isinf(a), f"the contacts' {name}: numbers (NaN where not given)")
        values[name] = a
    try:
        record = ContactRecord(offsets, values)
    except ValueError as e:
        raise r.fail("group 'run/contact_record'", str(e)) from None
    return [record.frame(k) for k in range(frames)]


def _recorded_sets(r: Reader, frames: int, ids_by_frame: list[np.ndarray]) -> list[tuple]:
    """The particle sets recorded (attribute `run/sets`): (ids, masses, radii, species,
    colors, groups) each time the particles changed, in the order the frames show them. A set
    of five (a checkpoint written before the collision groups were recorded) has every
    particle in group 0."""
    field, raw = r.json("sets", "run")
    if not isinstance(raw, list) or not raw:
        raise r.invalid(field, raw, "it must be a list of the particle sets recorded (at least one)")
    sets = []
    for k, entry in enumerate(raw):
        at = f"{field} [{k}]"
        if not isinstance(entry, list) or len(entry) not in (5, 6):
            raise r.invalid(at, entry, "it must be [ids, masses, radii, species, colors, groups] (or, written before the groups were, the first five)")
        ids = r.array(f"{at}[0] (ids)", entry[0], (None,), "int")
        n = ids.shape[0]
        r.each(f"{at}[0] (ids)", ids, ids >= 0, "ids are integers >= 0")
        if n > 1 and not (np.diff(ids) > 0).all():
            raise r.fail(f"{at}[0] (ids)", f"= {describe(ids)} is invalid: ids must increase strictly")
        masses = r.array(f"{at}[1] (masses)", entry[1], (n,), "real")
        r.each(f"{at}[1] (masses)", masses, np.isfinite(masses) & (masses > 0), "masses are finite and > 0 kg")
        radii = r.array(f"{at}[2] (radii)", entry[2], (n,), "real")
        r.each(f"{at}[2] (radii)", radii, np.isfinite(radii) & (radii >= 0), "radii are finite and >= 0 m")
        species = None if entry[3] is None else r.array(f"{at}[3] (species)", entry[3], (n,), "text")
        colors = None
        if entry[4] is not None:
            colors = r.array(f"{at}[4] (colors)", entry[4], (n, 3), "real")
            r.each(f"{at}[4] (colors)", colors, np.isnan(colors) | ((colors >= 0) & (colors <= 1)), "r g b in [0, 1] (NaN: none)")
        groups = np.zeros(n, dtype=np.int64)
        if len(entry) == 6:
            groups = r.array(f"{at}[5] (groups)", entry[5], (n,), "int").astype(np.int64)
            r.each(f"{at}[5] (groups)", groups, (groups >= 0) & (groups <= 31), "collision groups are integers in 0..31")
        sets.append((ids, masses, radii, species, colors, groups))
    # the recorder adds a set whenever a frame's ids differ from the last set's
    j = 0
    for k, ids in enumerate(ids_by_frame):
        if not np.array_equal(ids, sets[j][0]):
            j += 1
            if j == len(sets) or not np.array_equal(ids, sets[j][0]):
                raise r.fail(
                    "dataset 'run/ids'",
                    f"at frame {k}: the particles {describe(ids)} are not those of the set recorded next ({field} [{min(j, len(sets) - 1)}])",
                )
    if j != len(sets) - 1:
        raise r.fail(field, f"has {len(sets)} sets but the frames (dataset 'run/ids') show {j + 1}")
    return sets


def _recorded_about(r: Reader, world: Any, first: tuple, describe_colliders: Any) -> dict:
    """What the recording knows of the world (attribute `run/about`, `World._trajectory_info`)."""
    field, about = r.json("about", "run")
    if not isinstance(about, dict):
        raise r.invalid(field, about, "it must be a dict of what the trajectory knows of the world")
    for key in about:
        if key not in _ABOUT:
            raise r.fail(f"{field}.{key}", f"is not one of {', '.join(_ABOUT)}")
    for key in _ABOUT:
        if key not in about and key not in _ABOUT_LATER:
            raise r.fail(f"{field}.{key}", "is missing")
    out: dict[str, Any] = {}
    # the particles as the first set has them
    particles = (("ids", "int", 0), ("masses", "real", 0), ("radii", "real", 0), ("species", "text", 0), ("colors", "real", 3), ("groups", "int", 0))
    for k, (key, kind, width) in enumerate(particles):
        if key not in about:  # (an older checkpoint's: the first set's zeros)
            out[key] = first[k]
            continue
        value = about[key]
        n = first[0].shape[0]
        a = None if value is None else r.array(f"{field}.{key}", value, (n, 3) if width else (n,), kind)
        same = (a is None) == (first[k] is None) and (a is None or np.array_equal(a, first[k], equal_nan=kind == "real"))
        if not same:
            raise r.fail(f"{field}.{key}", f"= {describe(a)} is invalid: it must be the first set's (attribute 'run/sets' [0]: {describe(first[k])})")
        out[key] = a
    springs = about["springs"]
    out["springs"] = None if springs is None else r.array(f"{field}.springs", springs, (None, 2), "int")
    if out["springs"] is not None:
        r.each(f"{field}.springs", out["springs"], out["springs"] >= 0, "ids are integers >= 0")
    for key, value in (("dim", world.dim), ("dt", world.dt), ("method", world.method)):
        if type(about[key]) is not type(value) or about[key] != value:
            raise r.invalid(f"{field}.{key}", about[key], f"it must be the world's ({describe(value)}, attribute 'scene')")
        out[key] = about[key]
    periodic = about["periodic"]
    if periodic is not None and not (isinstance(periodic, list) and len(periodic) == 3 and all(isinstance(p, bool) for p in periodic)):
        raise r.invalid(f"{field}.periodic", periodic, "it must be null or 3 bools")
    out["periodic"] = None if periodic is None else tuple(periodic)
    edges = about["box_edges"]
    out["box_edges"] = None if edges is None else r.array(f"{field}.box_edges", edges, (3,), "real")
    if out["box_edges"] is not None:
        r.each(f"{field}.box_edges", out["box_edges"], np.isfinite(out["box_edges"]) & (out["box_edges"] >= 0), "3 finite numbers >= 0, m")
    colliders = about["colliders"]
    if not isinstance(colliders, list):
        raise r.invalid(f"{field}.colliders", colliders, "it must be a list of collider descriptions")
    from .io.h5md_reader import collider_problem

    try:
        problem = collider_problem([f"[{k}]" for k in range(len(colliders))], describe_colliders(colliders), world.dim)
    except (ValueError, TypeError, KeyError) as e:
        problem = first_line(e)
    if problem is not None:
        raise r.fail(f"{field}.colliders", f"is invalid: {problem}")
    out["colliders"] = colliders
    return out
