"""A checkpoint's world read back, every field checked (package-internal: its face is
``kinema.checkpoint.load_checkpoint``). ``load_world`` builds the world by its scene
(``scene.build()``: this module never imports ``kinema.world``) and gives it the rest through
its state (``World._state()``, ``World._restore(state)``: ``kinema._state.WorldState``): the
clock and the ids, each particle's time of death and colour, the springs' end ids, the
advisor's books, the collision books, the emitters' progress and random streams, and, last,
what is carried from step to step. The checked reads are ``kinema._checkpoint_reader``'s."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ._checkpoint_reader import INT64_MAX, Reader, first_line, scene_and_clock, scene_error

_STREAMS = ("position", "velocity", "size", "life")  # an emitter's random streams (kinema.emitter)
_WAITING = {"x": 3, "v": 3, "spawn": 3, "m": 0, "r": 0, "death": 0, "born": 0, "life": 0}  # births held back: vectors, numbers
_STATS_NEEDED = ("contacts", "impacts", "impulses", "solver_sweeps", "islands", "unconverged")
_STATS_LATER = ("resting", "speculative", "bounced", "asleep", "asleep_contacts", "slept", "woke")  # (0 where absent: older checkpoints)


def load_world(r: Reader) -> Any:
    """The world of the checkpoint `r` reads, every field checked (see `reading`)."""
    from .scene import SceneError

    c = scene_and_clock(r)
    n, ids, next_id, time = c["n"], c["ids"], c["next_id"], c["time"]
    try:
        world = c["scene"].build(f"{r.path}: attribute 'scene'")
    except SceneError as e:
        raise scene_error(e) from None
    except ValueError as e:
        raise r.fail("attribute 'scene'", f"cannot be built: {first_line(e)}") from None
    state = world._state()  # the built world's, its fields set from the file below and given back to it
    core = state.engine
    r.engine("dataset 'ids'", core.restore_clock_and_ids, time, c["steps"], ids.tolist(), next_id)
    r.engine("attribute 'clock_steps'", core.restore_clock, *c["clock"])
    # what the Python world keeps per particle
    _, state.death = r.reals("death", (n,), lambda a: ~np.isnan(a), "one time of death per particle, s (inf: none), not NaN")
    _, state.colors = r.reals("colors", (n, 3), lambda a: np.isnan(a) | ((a >= 0) & (a <= 1)), "one colour per particle, r g b in [0, 1] (NaN: none)")
    _, state.spring_ids = r.ints("spring_ids", (None, 2), 0, next_id - 1, f"the ids at the ends of each spring: integers from 0 to next_id - 1 = {next_id - 1}")
    state.warned = r.bool_attr("warned")
    state.advised_at = r.int_attr("advised_at", 0, INT64_MAX, "the particles when the advisor last looked: an integer >= 0")
    wall_carry = _read_books(r, world, core)
    # what is carried from step to step
    carry, spin_carry, orientations = _read_integrator_carry(r, world, n)
    memory = _read_contact_history(r, world, n)
    warm, sleep, built = _read_collision_carry(r, world, n)
    _restore_emitters(r, state.emitters, world.dim, time)
    if orientations is not None:
        r.engine("dataset 'orientations'", core.set_orientations, np.ascontiguousarray(orientations))
    state.advice_due = False  # the advisor had looked at this state already (its warning is in `warned`)
    world._restore(state)  # (and the views read anew)
    # last: nothing after these may start the caches again
    r.engine("group 'collision_carry'", core.restore_collision_carry, warm)
    r.engine("dataset 'collision_carry/sleep_island'", core.restore_sleep_carry, *sleep)
    if built is not None:
        r.engine("dataset 'collision_carry/list_built_at'", core.restore_list_carry, *built)
    if carry is not None:
        r.engine("dataset 'integrator_carry'", core.restore_integrator_carry, carry.tolist())
    if spin_carry is not None:
        r.engine("dataset 'spin_carry'", core.restore_spin_carry, spin_carry.tolist())
    if wall_carry is not None:
        r.engine("group 'collider_books/carry'", core.restore_wall_force_carry, wall_carry)
    if memory[0] or memory[1]:
        r.engine("group 'contact_history'", core.restore_contact_history, *memory)
    return world


def _read_books(r: Reader, world: Any, core: Any) -> Any:
    """The collision books, there exactly when collisions are on, given to the engine; a force
    model's collider forces of the last step (rates), or None."""
    wall_carry = None
    if world.collision_stats() is not None:
        books = _collision_books(r)
        r.engine("attribute 'collision_stats'", core.restore_collision_stats, books["total"], books["last"])
        if "collider_books" in r.f:  # (a checkpoint from before: the world books from zero)
            carried = _carried_books(r, len(world.colliders))
            r.engine("group 'collider_books'", core.restore_collider_books, carried["total"], carried["last"])
            wall_carry = carried.get("carry")
    elif "collision_stats" in r.f.attrs:
        raise r.fail("attribute 'collision_stats'", "is there but attribute 'scene' has collisions off; only a world with collisions has collision books")
    elif "collider_books" in r.f:
        raise r.fail("group 'collider_books'", "is there but attribute 'scene' has collisions off; only a world with collisions has collider books")
    return wall_carry


def _read_integrator_carry(r: Reader, world: Any, n: int) -> tuple[Any, Any, Any]:
    """What the method carries from step to step (Verlet's a or implicit Euler's last Δv; Verlet's
    α with spin) and the particles' orientations, each None where there is none."""
    carry = None
    if "integrator_carry" in r.f:
        if world.method not in ("verlet", "implicit_euler"):
            raise r.fail("dataset 'integrator_carry'", f"is there but the method is {world.method}; only verlet and implicit_euler carry anything")
        _, carry = r.reals("integrator_carry", (3 * n,), np.isfinite, "3 finite numbers per particle (Verlet's a, m/s², or implicit Euler's last Δv, m/s)")
    spin_carry = None
    if "spin_carry" in r.f:
        if carry is None or world.method != "verlet" or not world.spin:
            raise r.fail("dataset 'spin_carry'", "is there without Verlet's carry in a world with spin; only such a world carries angular accelerations")
        _, spin_carry = r.reals("spin_carry", (3 * n,), np.isfinite, "3 finite numbers per particle (Verlet's α, rad/s²)")
    orientations = None
    if "orientations" in r.f:  # (a checkpoint from before: unturned)
        if not world.spin:
            raise r.fail("dataset 'orientations'", "is there in a world without spin; only particles that turn have orientations")
        _, orientations = r.reals(
            "orientations", (n, 4), lambda a: np.isfinite(a) & (np.linalg.norm(a, axis=-1, keepdims=True) > 0), "a finite quaternion (w, x, y, z) per particle"
        )
    return carry, spin_carry, orientations


def _read_contact_history(r: Reader, world: Any, n: int) -> tuple[list, list]:
    """The force models' contact memory: touching pairs (i, j, springs) and collider touches (i, k,
    normal, springs)."""
    memory: tuple[list, list] = ([], [])
    if "contact_history" in r.f:
        r.group("contact_history")
        springs = "7 finite numbers per contact (the tangential spring's stretch, m, 3; the rolling spring's, m, 3; the twist, rad)"
        _, pi = r.ints("contact_history/pair_i", (None,), 0, n - 1, f"a particle index from 0 to {n - 1}")
        kp = pi.shape[0]
        _, pj = r.ints("contact_history/pair_j", (kp,), 0, n - 1, f"a particle index from 0 to {n - 1}")
        _, ps = r.reals("contact_history/pair_springs", (kp, 7), np.isfinite, springs)
        _, wi = r.ints("contact_history/wall_particle", (None,), 0, n - 1, f"a particle index from 0 to {n - 1}")
        kw = wi.shape[0]
        colliders = len(world.colliders)
        _, wk = r.ints("contact_history/wall_collider", (kw,), 0, max(colliders - 1, 0), f"a collider index below {colliders}")
        _, wn = r.reals("contact_history/wall_normal", (kw, 3), np.isfinite, "3 finite numbers per touch (its normal)")
        _, ws = r.reals("contact_history/wall_springs", (kw, 7), np.isfinite, springs)
        memory = (
            list(zip(pi.tolist(), pj.tolist(), ps.tolist(), strict=True)),
            list(zip(wi.tolist(), wk.tolist(), wn.tolist(), ws.tolist(), strict=True)),
        )
    return memory


def _read_collision_carry(r: Reader, world: Any, n: int) -> tuple[list, list, Any]:
    """The impulse model's warm start (each contact's totals and whether it carried load), sleep
    (calm times, islands) and where its candidate list was built."""
    g = r.group("collision_carry")
    _, particle = r.ints("collision_carry/particle", (None,), 0, n - 1, f"the particle of each contact: an index from 0 to {n - 1}")
    k = particle.shape[0]
    _, collider = r.dataset("collision_carry/collider", "bool", (k,), "one bool per contact (its partner is a collider)")
    field, partner = r.ints("collision_carry/partner", (k,), 0, INT64_MAX, "the partner of each contact: an index >= 0")
    colliders = len(world.colliders)
    r.each(
        field,
        partner,
        np.where(collider, partner < colliders, partner < n),
        f"the partner of each contact: one of the {n} particles, or of the {colliders} colliders",
    )
    _, impulse = r.reals("collision_carry/impulse", (k, 3), np.isfinite, "each contact's impulse totals, 3 finite numbers, N·s")
    carried: list = [None] * k  # (a checkpoint from before: taken from the impulse)
    if "carried" in g:
        carried = r.dataset("collision_carry/carried", "bool", (k,), "one bool per contact (whether it carried load)")[1].tolist()
    warm = list(zip(particle.tolist(), collider.tolist(), partner.tolist(), impulse.tolist(), carried, strict=True))
    sleep: list[list] = [[], []]
    present = [name in g for name in ("sleep_calm", "sleep_island")]
    if any(present):  # (a checkpoint from before sleeping has neither: everything awake)
        if not all(present):
            missing = "sleep_island" if present[0] else "sleep_calm"
            raise r.fail(f"dataset 'collision_carry/{missing}'", "is missing (sleep_calm and sleep_island go together)")
        m = r.dataset("collision_carry/sleep_calm", "real", (None,), "", read=False)[1][0]
        if m not in (0, n):
            raise r.fail("dataset 'collision_carry/sleep_calm'", f"has {m} values; it must have one per particle ({n}), or none")
        _, calm = r.reals("collision_carry/sleep_calm", (m,), lambda a: np.isfinite(a) & (a >= 0), "each particle's calm time: finite, >= 0 s")
        _, island = r.ints("collision_carry/sleep_island", (m,), -1, INT64_MAX, "each particle's island: an integer >= 0, or -1 (awake)")
        sleep = [calm.tolist(), island.tolist()]
    built = None
    present = [name in g for name in ("list_built_at", "list_skin")]
    if any(present):  # (a checkpoint from before: the list is built afresh)
        if not all(present):
            missing = "list_skin" if present[0] else "list_built_at"
            raise r.fail(f"dataset 'collision_carry/{missing}'", "is missing (list_built_at and list_skin go together)")
        _, at = r.reals("collision_carry/list_built_at", (n, 3), np.isfinite, "where the candidate list was built: 3 finite numbers per particle, m")
        _, skin = r.reals("collision_carry/list_skin", (), lambda a: np.isfinite(a) & (a > 0), "the candidate list's skin: a finite number > 0, m")
        built = (at.reshape(-1).tolist(), float(skin))
    return warm, sleep, built


# What the particles gave each collider (`World.collider_books`): each key's unit and width.
_COLLIDER_BOOKS = {"momentum": ("N·s", 3), "angular_momentum": ("N·m·s", 3), "work": ("J", 0), "normal": ("N·s", 3), "tangential": ("N·s", 3)}


def _carried_books(r: Reader, colliders: int) -> dict:
    """The collider books the world that wrote the checkpoint had (group `collider_books`:
    `total` and `last`, each a dataset per key of `World.collider_books`, one row per
    collider; and with a force model `carry`, the last step's collider forces as rates), for
    the world read from it to go on with."""
    g = r.group("collider_books")
    out: dict = {}
    for part in ("total", "last", "carry"):
        if part == "carry" and "carry" not in g:
            continue
        out[part] = {}
        for key, (unit, width) in _COLLIDER_BOOKS.items():
            shape = (colliders, width) if width else (colliders,)
            when = {"total": "over all steps", "last": "in the last step", "carry": "per second at the last step's end"}[part]
            rate = {"N·s": "N", "N·m·s": "N·m", "J": "W"}[unit] if part == "carry" else unit
            what = f"{when}: one {'vector' if width else 'number'} per collider ({colliders}), finite, {rate}"
            out[part][key] = r.reals(f"collider_books/{part}/{key}", shape, np.isfinite, f"what the particles gave each collider {what}")[1]
    return out


def _collision_books(r: Reader) -> dict:
    """The collision books (attribute `collision_stats`): "total" and "last", each the
    counts and sums `World.collision_stats` gives."""
    field, books = r.json("collision_stats")
    if not (isinstance(books, dict) and set(books) == {"total", "last"}):
        raise r.invalid(field, books, "it must be {'total': {...}, 'last': {...}}")
    out = {}
    for part, stats in books.items():
        at = f"{field} {part}"
        if not isinstance(stats, dict):
            raise r.invalid(at, stats, "it must be a dict of the collision figures")
        unknown = set(stats) - {*_STATS_NEEDED, *_STATS_LATER, "impulse_balance", "virial", "energy_lost", "max_overlap", "converged"}
        if unknown:
            raise r.fail(f"{at}.{sorted(unknown)[0]}", "is not a collision figure kinema writes")
        clean: dict[str, Any] = {}
        for key in (*_STATS_NEEDED, "impulse_balance", "energy_lost", "max_overlap"):
            if key not in stats:
                raise r.fail(f"{at}.{key}", "is missing")
        for key in (*_STATS_NEEDED, *_STATS_LATER):
            if key in stats:
                clean[key] = r.integer(f"{at}.{key}", stats[key], 0, INT64_MAX, "a count: an integer >= 0")
        balance = r.array(f"{at}.impulse_balance", stats["impulse_balance"], (3,), "real")
        r.each(f"{at}.impulse_balance", balance, np.isfinite(balance), "3 finite numbers, N·s")
        clean["impulse_balance"] = balance
        if "virial" in stats:  # (older checkpoints lack it: zeros)
            virial = r.array(f"{at}.virial", stats["virial"], (3, 3), "real")
            r.each(f"{at}.virial", virial, np.isfinite(virial), "3 × 3 finite numbers, N·m·s")
            clean["virial"] = virial
        for key in ("energy_lost", "max_overlap"):
            clean[key] = r.real(f"{at}.{key}", stats[key], math.isfinite, "a finite number")
        if "converged" in stats and not isinstance(stats["converged"], bool):
            raise r.invalid(f"{at}.converged", stats["converged"], "it must be true or false")
        out[part] = clean
    return out


def _restore_emitters(r: Reader, sources: list[Any], dim: int, time: float) -> None:
    """Each emitter's progress and random streams (attribute `emitters`), checked, given to
    the world's emitters at work `sources` (in a `dim`-D world)."""
    field, saved = r.json("emitters")
    if not isinstance(saved, list) or len(saved) != len(sources):
        raise r.invalid(field, saved, f"it must be a list of the {len(sources)} emitters' states (attribute 'scene' has {len(sources)})")
    for k, (source, state) in enumerate(zip(sources, saved, strict=True)):
        at = f"{field} [{k}]"
        if not isinstance(state, dict) or not {"emitted", "streams"} <= set(state) <= {"emitted", "streams", "waiting", "dropped", "told"}:
            raise r.invalid(at, state, "it must be {'emitted': n, 'streams': {...}, 'waiting': ..., 'dropped': n, 'told': bool}")
        due = min(source.due(time), INT64_MAX)
        emitted = r.integer(
            f"{at}.emitted", state["emitted"], 0, due, f"the particles emitted by t = {time:g} s: an integer from 0 to {due} (those due by then)"
        )
        streams = state["streams"]
        if not (isinstance(streams, dict) and set(streams) == set(_STREAMS)):
            raise r.invalid(f"{at}.streams", streams, f"it must be the states of the streams {', '.join(_STREAMS)}")
        for name in _STREAMS:
            _check_stream(r, f"{at}.streams.{name}", streams[name])
        waiting = state.get("waiting")
        if waiting is not None:
            waiting = _check_waiting(r, f"{at}.waiting", waiting, dim)
        held = 0 if waiting is None else len(waiting["m"])
        dropped = r.integer(
            f"{at}.dropped",
            state.get("dropped", 0),
            0,
            emitted - held,
            f"the births dropped: an integer from 0 to {emitted - held} (emitted, less those waiting)",
        )
        told = state.get("told", False)
        if not isinstance(told, bool):
            raise r.invalid(f"{at}.told", told, "it must be true or false")
        source.emitted, source.waiting, source.dropped, source.told = emitted, waiting, dropped, told
        for name in _STREAMS:
            try:
                source.rng[name].bit_generator.state = streams[name]
            except (ValueError, TypeError, OverflowError) as e:
                raise r.fail(f"{at}.streams.{name}", f"is refused by NumPy: {first_line(e)}") from None


def _check_stream(r: Reader, field: str, state: Any) -> None:
    """A PCG64 state as `Generator.bit_generator.state` gives it."""
    keys = {"bit_generator", "state", "has_uint32", "uinteger"}
    if not (isinstance(state, dict) and set(state) == keys):
        raise r.invalid(field, state, "it must be a PCG64 state {'bit_generator': 'PCG64', 'state': {'state', 'inc'}, 'has_uint32', 'uinteger'}")
    if state["bit_generator"] != "PCG64":
        raise r.invalid(f"{field}.bit_generator", state["bit_generator"], "it must be 'PCG64'")
    inner = state["state"]
    if not (isinstance(inner, dict) and set(inner) == {"state", "inc"}):
        raise r.invalid(f"{field}.state", inner, "it must be {'state': s, 'inc': i}")
    r.integer(f"{field}.state.state", inner["state"], 0, 2**128 - 1, "an integer from 0 to 2**128 - 1")
    inc = r.integer(f"{field}.state.inc", inner["inc"], 0, 2**128 - 1, "an odd integer from 1 to 2**128 - 1")
    if inc % 2 == 0:
        raise r.invalid(f"{field}.state.inc", inc, "it must be an odd integer (PCG64's increment)")
    r.integer(f"{field}.has_uint32", state["has_uint32"], 0, 1, "0 or 1")
    r.integer(f"{field}.uinteger", state["uinteger"], 0, 2**32 - 1, "an integer from 0 to 2**32 - 1")


def _check_waiting(r: Reader, field: str, waiting: Any, dim: int) -> dict[str, np.ndarray]:
    """The births an emitter held back: for each, position, velocity, spawn point (3 each),
    mass, radius, times of death and birth, lifetime."""
    if not (isinstance(waiting, dict) and set(waiting) == set(_WAITING)):
        raise r.invalid(field, waiting, f"it must be null or {{{', '.join(_WAITING)}}}, a list for each")
    m = waiting["m"]
    count = len(m) if isinstance(m, list) else None
    out = {}
    for key, width in _WAITING.items():
        at = f"{field}.{key}"
        a = r.numbers(at, waiting[key], (count, 3) if width else (count,))
        if key in ("life", "death"):
            r.each(at, a, ~np.isnan(a), "numbers of seconds, not NaN (inf: no lifetime)")
        elif key == "m":
            r.each(at, a, np.isfinite(a) & (a > 0), "masses, finite and > 0 kg")
        elif key == "r":
            r.each(at, a, np.isfinite(a) & (a >= 0), "radii, finite and >= 0 m")
        else:
            r.each(at, a, np.isfinite(a), "finite numbers")
        if width and dim == 2:
            r.each(at, a, a[:, 2] == 0, "z = 0 in a 2D world")
        out[key] = a
    return out
