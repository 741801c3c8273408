"""Pictures of the example scenes for the README: docs/img/scene_<name>.png.

Every scene of examples/scenes/*.toml is loaded with ``kinema.load_scene``, run for its own
[world] duration at its own frame rate (none is shortened; the slowest is sand_box), and drawn
by kinema's own renderer alone (``kinema.render_frames``) with the scene's [render] colouring,
colormap and background, and with what the renderer draws besides the particles: the
colliders (``colliders=traj.colliders``: the floor of bouncing_balls, seen level with it, as a
line; the boxes of demo and maxwell_gas; the cushions of billiards_2d; the sphere under the
cloth; the box of sand_box, which has no lid, drawn 0.4 m high), the springs (``springs=``:
the strings of newtons_cradle, whose pinned anchors have no radius and are drawn as 12 mm pins,
and the cloth's springs) and the colour bar of the scenes coloured by speed (``legend=``, in
every panel, as in a video). Cameras are the renderer's default (one ``render_frames`` call per
camera, so the panels it draws share it: the particles of those frames and the colliders fill
the frame, clear of the colour bar), except for bouncing_balls (``kinema.Camera3D.framing`` of
the balls and their mirror images under the floor, which puts the eye level with the floor)
and billiards_2d (the scene's own camera, 1 cm wider so that the cushions show whole). Nothing
is drawn over the rendered frames: they are cut to the rows or columns they use, put side by
side with Pillow under titles that carry the time, and one caption line with numbers measured
in the run is printed per scene, for the README.

kepler_euler, kepler_rk4 and kepler_verlet make one picture together, scene_kepler.png:
each run's last frame by kinema's renderer, with the planet's whole path as its trail and the
attractor marked, on one camera that holds the widest orbit.
maxwell_gas calls examples/maxwell_gas.py (``main``, which runs the scene and plots the speed
histogram and the Kolmogorov–Smirnov distance) and puts one rendered frame of the gas, coloured
by speed, to the left of that figure.

    .venv/bin/python docs/pictures.py [OUTDIR]        # default docs/img
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import sys
import tempfile
import time
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from PIL import Image, ImageDraw, ImageFont

import kinema
from kinema.render import own_colours

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "examples" / "scenes"
FONT_FILE = Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"
MAX_BYTES = 150 * 1024  # larger pictures are saved with a 256-colour palette
WHITE = (255, 255, 255)


# -- running scenes ---------------------------------------------------------------------------


def run_scene(name: str, duration: float | None = None, fps: float | None = None):
    """Load examples/scenes/<name>.toml and run it (default: its own duration and fps).
    Returns the world and the trajectory; warnings are printed, one line each."""
    world = kinema.load_scene(SCENES / f"{name}.toml")
    seconds = world.scene.world.duration if duration is None else duration
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        traj = world.run(seconds, fps=world.scene.world.fps if fps is None else fps)
    for w in caught:
        print(f"  warning ({name}): {w.message}")
    return world, traj


def frame_at(traj, t: float) -> int:
    """Index of the recorded frame nearest to the time t (s)."""
    return int(np.argmin(np.abs(traj.t - t)))


def scene_camera(world):
    """The scene's [render] camera as a kinema camera, or None."""
    table = world.scene.render.camera
    if table is None:
        return None
    if table.type == "2d":
        return kinema.Camera2D(table.xmin, table.ymin, table.xmax, table.ymax)
    return kinema.Camera3D(tuple(table.eye), tuple(table.target), tuple(table.up), table.fov_deg)


def render(sc, traj, frames, *, width, height, camera, colliders=None, radius=None, vmax=None, springs=None, legend=False):
    """The recorded frames (indices) of ``traj`` as images, coloured as the scene's [render]
    table ``sc`` says (speed from 0 to ``vmax``), with the trajectory's colliders (or
    ``colliders``) and ``springs`` drawn by the renderer, and its colour bar when ``legend``;
    ``radius`` replaces the recorded radii."""
    out = kinema.render_frames(
        traj.positions[frames],
        traj.radii if radius is None else radius,
        traj.t[frames],
        dim=traj.dim,
        velocities=traj.velocities[frames],
        color_by=own_colours(traj) if sc.color_by == "color" else sc.color_by,
        colormap=sc.colormap,
        vmin=0.0 if sc.color_by == "speed" else None,
        vmax=vmax,
        width=width,
        height=height,
        camera=camera,
        background=tuple(sc.background),
        time_format=None,  # the time goes into the panel's title
        colliders=traj.colliders if colliders is None else colliders,
        springs=springs,
        legend=legend,
        trail=0,  # the panels are a few frames far apart: a line between them is no path
    )
    return [np.array(f) for f in out]


def speed_max(traj, frames=slice(None)) -> float:
    return float(np.nanmax(np.linalg.norm(traj.velocities[frames], axis=2)))  # NaN: not alive


def springs_of(world, traj) -> np.ndarray | None:
    """The springs as pairs of particle indices: the trajectory's (ids, which are the indices
    of a world without births) or else the world's Spring forces."""
    if traj.springs is not None and len(traj.springs):
        return traj.springs
    pairs = [np.stack([np.ravel(f.i), np.ravel(f.j)], axis=1) for f in world.forces if isinstance(f, kinema.Spring)]
    return np.concatenate(pairs).astype(np.int64) if pairs else None


def framing(points, radius, direction, width: int, height: int, margin: float = 0.03):
    """``kinema.Camera3D.framing`` of the box around the points (m) as spheres of ``radius``."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return kinema.Camera3D.framing(pts.min(0) - radius, pts.max(0) + radius, direction=direction, width=width, height=height, margin=margin)


# -- composing ----------------------------------------------------------------------------------


def font(size: int):
    return ImageFont.truetype(str(FONT_FILE), size)


def titled(frame, title: str, size: int = 15) -> np.ndarray:
    """The frame under a strip with the title (in a smaller font where it would not fit)."""
    h = size + 12
    while size > 9 and font(size).getlength(title) > frame.shape[1] - 6:
        size -= 1
    img = Image.new("RGB", (frame.shape[1], frame.shape[0] + h), WHITE)
    img.paste(Image.fromarray(frame), (0, h))
    ImageDraw.Draw(img).text((frame.shape[1] // 2, h // 2 + 1), title, fill=(30, 30, 30), font=font(size), anchor="mm")
    return np.asarray(img)


def crop_columns(images, margin: int = 12, background=WHITE):
    """The images cut to the columns where any of them differs from the background (plus a
    margin): one camera's frames with much empty space at the sides."""
    used = np.zeros(images[0].shape[1], bool)
    for f in images:
        used |= np.any(f != np.asarray(background, np.uint8), axis=(0, 2))
    cols = np.nonzero(used)[0]
    a, b = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, images[0].shape[1])
    return [np.ascontiguousarray(f[:, a:b]) for f in images]


def hstack(panels, gap: int = 10) -> np.ndarray:
    """Panels side by side, top-aligned, on white."""
    h = max(p.shape[0] for p in panels)
    row = []
    for k, p in enumerate(panels):
        row.append(np.concatenate([p, np.full((h - p.shape[0], p.shape[1], 3), 255, np.uint8)]))
        if k < len(panels) - 1:
            row.append(np.full((h, gap, 3), 255, np.uint8))
    return np.concatenate(row, axis=1)


def save(image: np.ndarray, path: Path) -> Path:
    """A PNG; one over MAX_BYTES is saved again with a 256-colour palette."""
    img = Image.fromarray(np.ascontiguousarray(image))
    img.save(path, optimize=True)
    if path.stat().st_size > MAX_BYTES:
        print(f"  {path.name}: {path.stat().st_size // 1024} KiB as RGB, saved with a palette")
        img.quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    return path


# -- the scenes ---------------------------------------------------------------------------------


def bouncing_balls(out: Path) -> str:
    world, traj = run_scene("bouncing_balls")
    e = np.linspace(0.1, 0.9, 9)  # the scene's restitution list, left to right
    r = float(traj.radii[0])
    x0 = traj.positions[0, :, 0]
    h0 = float(traj.positions[0, 0, 2]) - r  # drop height of the balls' bottoms, m
    # Rebound heights, measured on a run recorded at every step (9 particles: cheap): the
    # first rebound starts where v_z first turns positive and ends where it next turns negative.
    _, fine = run_scene("bouncing_balls", duration=1.6, fps=1.0 / world.dt)
    z, vz = fine.positions[:, :, 2], fine.velocities[:, :, 2]
    up = np.argmax(vz > 0, axis=0)
    h1 = np.array([z[up[k] :, k][: np.argmax(vz[up[k] :, k] < 0) + 1].max() - r for k in range(9)])
    ratio = h1 / h0

    # The eye just above the floor, level with it, so that the floor is seen edge-on as a line:
    # the camera frames the balls and their mirror images under the floor, which puts the
    # floor on the image's middle row, and the image is cut to its upper half and a little floor.
    width, height = 440, 430
    pts = np.concatenate([traj.positions.reshape(-1, 3), [(x0[0] - 0.15, 0, 0), (x0[-1] + 0.15, 0, 0)]])
    camera = framing(np.concatenate([pts, pts * [1, 1, -1]]), r, (0.0, -1.0, 0.005), width, height, margin=0.02)
    times = [0.0, 0.59, 0.79]
    titles = ["dropped from 1 m", "rising after the first bounce", "e = 0.8 and 0.9 at the top"]
    frames = [frame_at(traj, t) for t in times]
    images = render(world.scene.render, traj, frames, width=width, height=height, camera=camera)
    panels = [titled(f[: height // 2 + 12], f"t = {traj.t[k]:.2f} s: {title}") for k, f, title in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_bouncing_balls.png")
    pairs = ", ".join(f"{q:.3f}" for q in ratio)
    return (
        f"Nine balls dropped from 1 m onto the floor with e = 0.1, 0.2 … 0.9 (left to right), whose first rebounds reach e²·h as Newton's law "
        f"says. Measured first rebound / drop height: {pairs} (e² to within {np.abs(ratio - e**2).max():.0e})."
    )


def newtons_cradle(out: Path) -> str:
    world, traj = run_scene("newtons_cradle")
    anchors = np.arange(5)
    radius = traj.radii.copy()
    radius[anchors] = 0.012  # the pinned anchors have no radius: drawn as pins
    x = traj.positions
    impact = int(np.argmax(np.linalg.norm(traj.velocities[:, 9], axis=1) > 0.05))  # the right ball starts
    top = int(np.argmax(np.where(traj.t < 1.5, x[:, 9, 1], -np.inf)))  # and swings out to here
    frames = [0, impact + 1, top]
    width, height = 400, 290
    kw = dict(width=width, height=height, camera=None, radius=radius, vmax=speed_max(traj), springs=springs_of(world, traj), legend=True)
    images = render(world.scene.render, traj, frames, **kw)
    titles = ["the left ball raised by 30°", "the impulse has passed through", "the right ball swings out"]
    images = crop_columns(images, margin=16)
    panels = [titled(f, f"t = {traj.t[k]:.2f} s: {title}") for k, f, title in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_newtons_cradle.png")
    h_start = x[0, 5, 1] - x[0, 6, 1]
    h_right = x[top, 9, 1] - x[0, 9, 1]
    still = np.abs(x[:top, 6:9, :2] - x[0, 6:9, :2]).max()
    return (
        f"Newton's cradle: the left ball, raised by {h_start * 100:.1f} cm, hits the row at t = {traj.t[impact]:.2f} s and stops; the right ball "
        f"swings out to {h_right * 100:.1f} cm ({h_right / h_start:.1%} of the height) at t = {traj.t[top]:.2f} s while the middle three move by at "
        f"most {still * 1000:.1f} mm; the swing repeats, {world.collision_stats()['total']['impacts']} impacts in {traj.t[-1]:.0f} s."
    )


def billiards_2d(out: Path) -> str:
    world, traj = run_scene("billiards_2d")
    table = scene_camera(world)  # the table itself: widened a little so that its outline shows whole
    camera = kinema.Camera2D.framing((table.xmin, table.ymin), (table.xmax, table.ymax), margin=0.01)
    width, height = 430, 215
    frames = [0, frame_at(traj, 0.3), len(traj.t) - 1]
    images = render(world.scene.render, traj, frames, width=width, height=height, camera=camera)
    titles = ["the rack and the cue ball at 6 m/s", "the break", "spread out"]
    panels = [titled(f, f"t = {traj.t[k]:.2f} s: {title}") for k, f, title in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_billiards_2d.png")
    ke = traj.kinetic
    stats = world.collision_stats()["total"]
    return (
        f"The break: the cue ball at 6 m/s scatters the 15-ball rack over the 2.54 m × 1.27 m table; "
        f"{stats['impacts']} impacts in {traj.t[-1]:.0f} s, after which {ke[-1] / ke[0]:.1%} of the {ke[0]:.2f} J is left "
        f"(the collisions took {stats['energy_lost']:.2f} J, the drag the rest)."
    )


def sand_box(out: Path) -> str:
    world, traj = run_scene("sand_box")
    box = traj.colliders[0]
    # The box has no lid: the renderer would draw its walls up to the top of the falling
    # column; they are drawn 0.4 m high instead.
    box_lo, box_hi = np.asarray(box["lo"], float), np.array([box["hi"][0], box["hi"][1], 0.4])
    drawn = [{"type": "box", "lo": box_lo, "hi": box_hi}]
    frames = [0, frame_at(traj, 0.4), len(traj.t) - 1]
    vmax = speed_max(traj, frames)
    # One camera for the column and the fall, another closer one for the settled grains.
    tall_w, tall_h, near_w = 300, 380, 460
    kw = dict(height=tall_h, camera=None, colliders=drawn, vmax=vmax, legend=True)
    images = render(world.scene.render, traj, frames[:2], width=tall_w, **kw) + render(world.scene.render, traj, frames[2:], width=near_w, **kw)
    titles = ["a column of 2,000 grains", "falling in", "settled (closer)"]
    panels = [titled(f, f"t = {traj.t[k]:.2f} s: {title}") for k, f, title in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_sand_box.png")
    z = traj.positions[-1, :, 2]
    xy = traj.positions[-1, :, :2] - 0.5 * (box_lo[:2] + box_hi[:2])
    centre = np.linalg.norm(xy, axis=1) < 0.08
    edge = np.abs(xy).max(axis=1) > 0.15
    top_c, top_e = np.percentile(z[centre], 95), np.percentile(z[edge], 95)
    stats = world.collision_stats()["total"]
    return (
        f"2,000 grains (r = 1 cm, e = 0.2, μ = 0.5) fall from a 0.2 m × 0.2 m column, 0.3–1.9 m high, into a 0.4 m box and spread over its floor "
        f"as a low mound: at t = {traj.t[-1]:.1f} s the surface is about {top_c * 100:.0f} cm high in the middle and {top_e * 100:.0f} cm at the walls "
        f"(95th percentile of the grain heights), mean speed {np.linalg.norm(traj.velocities[-1], axis=1).mean() * 100:.1f} cm/s; {stats['impacts']:,} impacts."
    )


def cloth_on_sphere(out: Path) -> str:
    world, traj = run_scene("cloth_on_sphere")
    obstacle = traj.colliders[0]
    centre, radius = np.asarray(obstacle["center"], float), float(obstacle["radius"])
    n = int(round(np.sqrt(traj.positions.shape[1])))  # the n × n lattice, last axis fastest
    width, height = 400, 300
    frames = [0, frame_at(traj, 0.3), len(traj.t) - 1]
    x = traj.positions
    kw = dict(width=width, height=height, camera=None, vmax=speed_max(traj, frames), springs=springs_of(world, traj), legend=True)
    images = render(world.scene.render, traj, frames, **kw)
    titles = ["a 20 × 20 cloth above the sphere", "falling onto it", "draped"]
    panels = [titled(f, f"t = {traj.t[k]:.2f} s: {t}") for k, f, t in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_cloth_on_sphere.png")
    corner = x[-1, [0, n - 1, n * (n - 1), n * n - 1], 2]
    return (
        f"A 20 × 20 cloth on stretch and shear springs (implicit Euler, dt = {world.dt * 1000:.0f} ms) falls onto a sphere and drapes over "
        f"it: at t = {traj.t[-1]:.1f} s the corners hang at z = {corner.mean():.2f} m, {centre[2] + radius - corner.mean():.2f} m below the top of the sphere, "
        f"and the cloth still sways at up to {np.linalg.norm(traj.velocities[-1], axis=1).max():.2f} m/s."
    )


def kepler(out: Path) -> str:
    runs = {method: run_scene(f"kepler_{method}") for method in ("euler", "rk4", "verlet")}
    lim = max(2.0, 1.08 * max(float(np.abs(traj.positions[:, 0, :2]).max()) for _, traj in runs.values()))
    camera = kinema.Camera2D(-lim, -lim, lim, lim)
    drift, panels = {}, []
    for method, (world, traj) in runs.items():
        mu = float(world.scene.forces[0].strength)
        p, v = traj.positions[:, 0, :2], traj.velocities[:, 0, :2]
        energy = 0.5 * np.sum(v**2, axis=1) - mu / np.linalg.norm(p, axis=1)
        rel = (energy - energy[0]) / abs(energy[0])
        drift[method] = (rel[-1], np.abs(rel).max(), np.linalg.norm(p[-1]))
        # kinema's renderer alone: the planet at the end with its whole path as a trail, the
        # attractor marked at its point
        *_, last = kinema.render_frames(
            traj.positions,
            traj.radii,
            traj.t,
            dim=2,
            velocities=traj.velocities,
            color_by="speed",
            width=330,
            height=330,
            camera=camera,
            time_format=None,
            legend=False,
            min_radius_px=4.0,  # the planet (r = 0.02 m) would be 1.6 px
            trail=float(traj.t[-1]),
            attractors=[world.scene.forces[0].point],
        )
        panels.append(titled(np.array(last), f"{method}: ΔE/|E₀| = {rel[-1]:+.2g} at t = {traj.t[-1]:.2f} s"))
    save(hstack(panels), out / "scene_kepler.png")
    e, r, v = drift["euler"], drift["rk4"], drift["verlet"]
    return (
        f"kepler_euler / kepler_rk4 / kepler_verlet: the circular orbit (μ = 1, r = 1, period 2π) for three periods at dt = 0.05. Euler spirals out "
        f"(energy {e[0]:+.0%}, r = {e[2]:.2f} at the end), RK4 stays on the circle while its energy drifts ({r[0]:+.1e}), Verlet keeps the orbit "
        f"(|ΔE|/|E₀| ≤ {v[1]:.1e} throughout, {v[0]:+.0e} at the end)."
    )


def maxwell_gas(out: Path) -> str:
    spec = importlib.util.spec_from_file_location("maxwell_gas_example", ROOT / "examples" / "maxwell_gas.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()):
        result = example.main(Path(tmp))
        figure = np.asarray(Image.open(Path(tmp) / "maxwell_gas.png").convert("RGB"))
    traj = result["trajectory"]
    world = kinema.load_scene(SCENES / "maxwell_gas.toml")  # its [render] table
    height = figure.shape[0] - 27
    width = round(1.25 * height)  # room for the colour bar beside the box
    vmax = float(np.ceil(np.percentile(result["speed"], 99.5) * 10) / 10)
    k = len(traj.t) - 1
    # The renderer's own camera: the box and the gas as large as the frame allows, clear of the bar.
    frame = render(world.scene.render, traj, [k], width=width, height=height, camera=None, vmax=vmax, legend=True)[0]
    panel = titled(frame, f"t = {traj.t[k]:.2f} s: the gas, coloured by speed")
    save(hstack([panel, figure], gap=4), out / "scene_maxwell_gas.png")
    ks = result["ks"]
    level = 1.63 / np.sqrt(traj.positions.shape[1])
    above = np.nonzero(ks >= level)[0]
    below = traj.t[above[-1] + 1] if above.size and above[-1] + 1 < len(ks) else float("nan")  # from here on below the level
    return (
        f"maxwell_gas: 1,000 hard spheres in a periodic box, all at 1 m/s at t = 0, relax to Maxwell–Boltzmann with a = √(kT/m) = {result['a']:.3f} m/s "
        f"(the speed histogram and the Kolmogorov–Smirnov distance on the right are drawn by examples/maxwell_gas.py): D falls from {ks[0]:.2f} to "
        f"{ks[-1]:.3f} at t = {traj.t[-1]:.0f} s and stays below the 1 % level of the test from t = {below:.2f} s."
    )


def fountain(out: Path) -> str:
    world, traj = run_scene("fountain")
    frames = [frame_at(traj, 0.5), frame_at(traj, 2.0), frame_at(traj, 4.0), frame_at(traj, 5.8)]
    width, height = 330, 300
    kw = dict(width=width, height=height, camera=None, vmax=speed_max(traj, frames), legend=True)
    images = render(world.scene.render, traj, frames, **kw)
    titles = ["the first droplets", "the jet and the splash", "steady: born = dying", "the source is off"]
    panels = [titled(f, f"t = {traj.t[k]:.1f} s: {t} ({traj.alive[k].sum()})") for k, f, t in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_fountain.png")
    born = traj.ids / 250.0
    last = traj.alive.shape[0] - 1 - traj.alive[::-1].argmax(axis=0)
    died = last < traj.alive.shape[0] - 1
    return (
        f"A fountain: 250 droplets a second for 5 s leave a 3 cm nozzle at 4 m/s in a 12° cone, bounce on the floor (e = 0.4, μ = 0.4) and die "
        f"3 ± 0.3 s after birth: {traj.ids.size:,} born, at most {traj.alive.sum(axis=1).max()} alive at once, the oldest seen "
        f"{(traj.t[last] - born)[died].max():.2f} s old."
    )


def pour(out: Path) -> str:
    world, traj = run_scene("pour")
    frames = [frame_at(traj, 0.6), frame_at(traj, 1.6), len(traj.t) - 1]
    width, height = 360, 330
    images = render(world.scene.render, traj, frames, width=width, height=height, camera=None)
    titles = ["the stream lands", "a heap grows", "settled"]
    panels = [titled(f, f"t = {traj.t[k]:.1f} s: {t} ({traj.alive[k].sum():,} grains)") for k, f, t in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_pour.png")
    x = traj.positions[-1][traj.alive[-1]]
    r = traj.radii[traj.alive[-1]]
    top = float((x[:, 2] + r).max())
    spread = float(np.percentile(np.linalg.norm(x[:, :2] - 0.25, axis=1), 95))
    slope = np.degrees(np.arctan(top / spread))
    return (
        f"Sand poured from a 4 cm spout 0.5 m up into a 0.5 m box, 600 grains a second for 2.5 s (r = 7 mm, e = 0.1, μ = 0.6): the "
        f"{len(x):,} grains settle into a heap {top * 100:.0f} cm high, 95 % of them within {spread * 100:.0f} cm of the axis "
        f"(a mean slope of about {slope:.0f}°), mean speed {np.linalg.norm(traj.velocities[-1][traj.alive[-1]], axis=1).mean() * 100:.1f} cm/s."
    )


def demo(out: Path) -> str:
    world, traj = run_scene("demo")
    width, height = 360, 338  # the scene's height, 960 × 540, smaller; the box is tall and narrow
    frames = [0, frame_at(traj, 0.4), len(traj.t) - 1]
    kw = dict(width=width, height=height, camera=scene_camera(world), vmax=speed_max(traj, frames), legend=True)
    images = render(world.scene.render, traj, frames, **kw)
    titles = ["400 balls on a jittered lattice", "falling into the box", "settled"]
    panels = [titled(f, f"t = {traj.t[k]:.2f} s: {t}") for k, f, t in zip(frames, images, titles, strict=True)]
    save(hstack(panels), out / "scene_demo.png")
    stats = world.collision_stats()["total"]
    ke = traj.kinetic
    return (
        f"demo (`kinema demo`): 400 balls (e = 0.7) fall into a 0.5 m box and settle; in {traj.t[-1]:.0f} s {stats['impacts']:,} impacts take "
        f"{stats['energy_lost']:.0f} J, the kinetic energy falls from {ke.max():.0f} J (at its peak) to {ke[-1]:.1f} J and the pile is {traj.positions[-1, :, 2].max() + traj.radii.max():.2f} m high."
    )


PICTURES = {
    "bouncing_balls": bouncing_balls,
    "newtons_cradle": newtons_cradle,
    "billiards_2d": billiards_2d,
    "sand_box": sand_box,
    "cloth_on_sphere": cloth_on_sphere,
    "kepler": kepler,
    "maxwell_gas": maxwell_gas,
    "fountain": fountain,
    "pour": pour,
    "demo": demo,
}


def main(out: Path) -> dict[str, str]:
    out.mkdir(parents=True, exist_ok=True)
    missing = {p.stem for p in SCENES.glob("*.toml")} - {f"kepler_{m}" for m in ("euler", "rk4", "verlet")} - set(PICTURES)
    if missing:
        print(f"scenes without a picture here: {', '.join(sorted(missing))}")
    captions = {}
    start = time.perf_counter()
    for name, make in PICTURES.items():
        t0 = time.perf_counter()
        captions[name] = make(out)
        path = out / f"scene_{name}.png"
        w, h = Image.open(path).size
        print(f"{name:16s} {time.perf_counter() - t0:6.1f} s  {path}  {w} × {h}, {path.stat().st_size / 1024:.0f} KiB", flush=True)
    print(f"all in {time.perf_counter() - start:.1f} s\n")
    for name, caption in captions.items():
        print(f"scene_{name}.png: {caption}")
    return captions


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "img")
