"""Recorded frames of a world run: times, positions, velocities and diagnostics as arrays,
and what a trajectory read from a file knows of that file (`FileInfo`).

This module imports `kinema.io` only inside the methods that write or read files; the
readers and writers of `kinema.io` take any object with a `Trajectory`'s attributes and
never import this module. The recorder `World.run` drives is `_Recorder`: its recording
(`Recorder`, and `COLLIDER_RECORD`, `_stacked_walls`, `_prefaulted`) is in
`kinema._recorder`, and `_Recorder` adds `finish`, the frames made a `Trajectory`."""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from ._recorder import COLLIDER_RECORD as COLLIDER_RECORD
from ._recorder import Recorder
from ._recorder import _prefaulted as _prefaulted
from ._recorder import _stacked_walls as _stacked_walls
from .contact_record import ContactRecord


@dataclass
class FileInfo:
    """What only the file a trajectory was read from knows (`Trajectory.source`): its
    `path`, the particle `group` read (/particles/<group>), `step` (F,) the integration
    step of each frame as the file numbers them, the file's `author` and `creator`
    (program and version; `None` where it names none) and `box_edges_by_frame` (F, 3) m,
    the periodic cell at each frame (a box that may change; `Trajectory.box_edges` is the
    first frame's), `None` with open boundaries."""

    path: Path
    group: str
    step: np.ndarray
    author: str | None = None
    creator: str | None = None
    box_edges_by_frame: np.ndarray | None = None


@dataclass(frozen=True)
class ColliderForces:
    """The mean forces the particles exerted on each of K colliders over the F − 1 intervals
    between frames (`Trajectory.collider_forces`), N: the interval k runs from `start[k]` to
    `end[k]` (F − 1,), s; `normal` (F − 1, K, 3) is the force along the contacts' normals,
    which presses on the collider (on a floor under a resting pile of mass M: (0, 0, −M g)),
    `tangential` the shear across them (friction), `total` their sum, the change of the
    momentum the collider took over the interval's time."""

    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    total: np.ndarray


@dataclass(repr=False)
class Trajectory:
    """Frames of a run. `t` (F,), `positions` and `velocities` (F, N, 3); energies in J:
    `kinetic` (F,), `potential` {force name: (F,)}, `total` (F,); `momentum` and
    `angular_momentum` (F, 3).

    Collisions (all zeros while they are off): `contacts` (F,), the number of contacts at
    the frame; `impulse_balance` (F, 3), N·s, the sum of the impulses between movable
    particles since the previous frame (0 at frame 0), zero by action and reaction up to
    rounding; `collision_energy_lost` (F,), J, the mechanical energy the collisions took
    since they were turned on (total energy + it is conserved); `impacts` (F,), the impacts
    since the previous frame (0 at frame 0): found inside the steps by the impulse model, the
    events of an event-driven gas, the contacts begun with the spring–dashpot and Hertz models
    (velocity Verlet), so that `impacts / diff(t)` is the collision frequency.

    `pressure` (F, 3, 3): the pressure tensor of a periodic world (every axis of its
    dimension periodic; `None` otherwise, and for a file), Pa in 3D (N/m in 2D): the kinetic
    part Σ m v ⊗ v / V at the frame plus the virial of the pair impulses and contact forces,
    Σ (x_i − x_j) ⊗ J / (V Δt), over the Δt since the previous frame (NaN at frame 0); V the
    cell's volume (area in 2D). Its trace over the dimension is the pressure (LAMMPS's
    `compute pressure`; for hard spheres the virial route of the equation of state).

    About the world (`None` when unknown): `masses` (N,) kg, `radii` (N,) m, `ids`
    (N,), `species` (N,) names (`World.add_particles(species=)`), `groups` (N,) ints, each
    particle's collision group 0..31 (`World.groups` as recorded at the start and whenever
    particles were born or died, the last of these; a regrouping in between is not a new
    record; `None` for a file that does not hold them), `dim` (2 or 3), `dt` s, `method`, `periodic` (3 bools) and `box_edges`
    (3,) m, the periodic cell. `fps`: the frames per second asked of `World.run` (frame k
    is at t₀ + k/fps exactly; `step`: the steps' length where dt does not divide a frame,
    `kinema.frames`); saved in H5MD files, it is the default rate of a video of them. `colliders`: the world's colliders as plain descriptions, in
    the order added — {"type": "plane", "point": [3], "normal": [3]}, {"type": "box", "lo",
    "hi"} (2 or 3 values each, ±inf for an open face), {"type": "sphere", "center": [3],
    "radius"}, with "restitution" and "friction" where the collider sets them; m. Empty when
    there are none or they are unknown (a file written before they were recorded).

    Births and deaths (emitters, `World.remove_particles`): N counts every particle alive
    in some frame, one column per particle in the order of their `ids` (stable, never
    reused); `alive` (F, N) bool says which exist at each frame, and their positions and
    velocities are NaN where they do not. Without births or deaths `alive` is all True.
    `springs` (S, 2): the ids at the ends of each spring, drawn while both are alive.
    `colors` (N, 3): each particle's own colour, r g b in [0, 1] (NaN: none; an
    `Emitter`'s `color`), or None.

    Spin (a world made with `spin=True`; `None` otherwise): `angular_velocities` (F, N, 3),
    rad/s, each particle's ω at each frame; `orientations` (F, N, 4), each particle's
    orientation as a unit quaternion (w, x, y, z) that turns its body frame into the world's
    (identity at the world's start, integrated from ω by the engine; `None` where the engine
    has none). NaN where a particle is not alive. `inertia` (N,), kg·m², each particle's
    moment of inertia about its centre (`World.inertia`).

    Wall forces (a world with colliders; `None` otherwise): `collider_momentum` (F, K, 3),
    N·s, the momentum the particles had given each of its K colliders (in the order of
    `colliders`) since the world began, at each frame (`World.collider_books()["momentum"]`:
    −Σ J over the impulses and the contact forces' impulses J the collider gave them), and its
    parts along and across each contact's normal, `collider_normal` and `collider_tangential`
    (F, K, 3), N·s: the pressure's and the shear's impulses. `collider_forces()` makes the
    mean forces between frames of them. `None` where the steps book nothing: a force model
    (`"spring_dashpot"`, `"hertz"`) stepped by a method other than `verlet`.

    `contact_record`: the contacts at each frame (`World.run(record_contacts=True)`), a
    `kinema.contact_record.ContactRecord` whose `frame(k)` is what `World.contacts()`
    gave at frame k, particles named by their ids; `None` when not recorded.

    `source`: a trajectory read from a file (`Trajectory.load`) keeps what only the file
    knows, a `FileInfo` (path, group, step of each frame, author, creator, the cell
    at each frame); `None` for one recorded by `World.run`.

    `save` writes an H5MD file, `Trajectory.load` (or `kinema.load_trajectory`) reads
    one back, `export` writes VTK, PLY, extended XYZ or CSV (see `kinema.io`), `render`
    a video (see `kinema.render`)."""

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    kinetic: np.ndarray
    potential: dict[str, np.ndarray]
    momentum: np.ndarray
    angular_momentum: np.ndarray
    contacts: np.ndarray
    impulse_balance: np.ndarray
    collision_energy_lost: np.ndarray
    impacts: np.ndarray | None = None
    pressure: np.ndarray | None = None
    masses: np.ndarray | None = None
    radii: np.ndarray | None = None
    ids: np.ndarray | None = None
    species: np.ndarray | None = None
    groups: np.ndarray | None = None
    dim: int = 3
    dt: float | None = None
    method: str | None = None
    fps: float | None = None
    # the length of the run's steps, s, where a frame of 1/fps is not whole steps of dt
    # (``kinema.frames``: ⌈1/(fps·dt)⌉ steps of (1/fps)/⌈1/(fps·dt)⌉); None: dt
    step: float | None = None
    periodic: tuple[bool, bool, bool] | None = None
    box_edges: np.ndarray | None = None
    colliders: list[dict[str, Any]] = field(default_factory=list)
    alive: np.ndarray | None = None
    springs: np.ndarray | None = None
    colors: np.ndarray | None = None
    angular_velocities: np.ndarray | None = None
    orientations: np.ndarray | None = None
    inertia: np.ndarray | None = None
    contact_record: ContactRecord | None = None
    collider_momentum: np.ndarray | None = None
    collider_normal: np.ndarray | None = None
    collider_tangential: np.ndarray | None = None
    source: FileInfo | None = None
    total: np.ndarray = field(init=False)

    def _summary(self) -> list[tuple[str, str]]:
        """What the short repr and the notebook's table show: (what, value) pairs."""
        frames, n = self.positions.shape[:2]
        span = f"{self.t[0]:g} .. {self.t[-1]:g} s" if frames else "none"
        rows = [("frames", f"{frames}"), ("t", span), ("particles", f"{n}"), ("dim", f"{self.dim}")]
        if self.method is not None:
            rows.append(("method", f"{self.method!r}"))
        if self.dt is not None:
            rows.append(("dt", f"{self.dt:g} s"))
        if self.step is not None:
            rows.append(("step", f"{float(self.step):.6g} s"))
        if frames and np.isfinite(self.total[[0, -1]]).all():
            rows.append(("energy", f"{self.total[0]:.6g} J → {self.total[-1]:.6g} J"))
        elif frames:  # a file without velocities or potential energies
            rows.append(("energy", "unknown"))
        if self.source is not None:
            rows.append(("file", str(self.source.path)))
        return rows

    def __repr__(self) -> str:
        """One line (a dataclass's repr would print every frame: 26,516 characters for 5 s of
        a spring)."""
        return "Trajectory(" + ", ".join(f"{k}={v}" for k, v in self._summary()) + ")"

    def _repr_html_(self) -> str:
        """A small table for Jupyter (`show()` plays the frames)."""
        from html import escape

        cells = "".join(f"<tr><th style='text-align:left'>{escape(k)}</th><td style='text-align:left'>{escape(v)}</td></tr>" for k, v in self._summary())
        return f"<table><caption style='text-align:left'><b>kinema.Trajectory</b> (<code>.show()</code> plays it)</caption>{cells}</table>"

    def __post_init__(self) -> None:
        self.total = self.kinetic + sum(self.potential.values(), np.zeros_like(self.kinetic))
        frames, n = self.positions.shape[:2]
        if self.alive is None:
            self.alive = np.ones((frames, n), dtype=bool)
        else:
            self.alive = np.asarray(self.alive, dtype=bool)
            if self.alive.shape != (frames, n):
                raise ValueError(f"alive has shape {self.alive.shape}; it must be (frames, particles) = {(frames, n)}")
        if self.springs is not None:
            self.springs = np.asarray(self.springs, dtype=np.int64).reshape(-1, 2)
        for name, width in (("angular_velocities", 3), ("orientations", 4)):
            value = getattr(self, name)
            if value is not None:
                value = np.asarray(value, dtype=np.float64)
                if value.shape != (frames, n, width):
                    raise ValueError(f"{name} has shape {value.shape}; it must be (frames, particles, {width}) = {(frames, n, width)}")
                setattr(self, name, value)
        if self.groups is not None:
            groups = np.asarray(self.groups)
            if groups.size and groups.dtype.kind not in "iu":
                raise ValueError(f"groups has dtype {groups.dtype}; collision groups are integers in 0..31")
            self.groups = groups.astype(np.int64)
            if self.groups.shape != (n,):
                raise ValueError(f"groups has shape {self.groups.shape}; it must be (particles,) = ({n},)")
        if self.inertia is not None:
            self.inertia = np.asarray(self.inertia, dtype=np.float64)
            if self.inertia.shape != (n,):
                raise ValueError(f"inertia has shape {self.inertia.shape}; it must be (particles,) = ({n},)")
        if self.contact_record is not None and self.contact_record.n_frames != frames:
            raise ValueError(f"contact_record has {self.contact_record.n_frames} frames; the trajectory has {frames}")
        colliders = None
        for name in COLLIDER_RECORD:
            value = getattr(self, name)
            if value is not None:
                value = np.asarray(value, dtype=np.float64)
                if value.ndim != 3 or value.shape[0] != frames or value.shape[2] != 3 or colliders not in (None, value.shape[1]):
                    k = "K" if colliders is None else colliders
                    raise ValueError(f"{name} has shape {value.shape}; it must be (frames, colliders, 3) = ({frames}, {k}, 3)")
                colliders = value.shape[1]
                setattr(self, name, value)

    @property
    def changes_count(self) -> bool:
        """Whether particles are born or die during the recording (some are not alive at some frame)."""
        return not bool(self.alive.all())

    def collider_forces(self) -> ColliderForces:
        """The mean force the particles exerted on each collider over each interval between
        frames, the change of the recorded impulses over the interval's time,
        Δ`collider_normal` / Δt and Δ`collider_tangential` / Δt (LIGGGHTS's wall force, the
        base pressure of a pile, a silo wall's Janssen pressure): a `ColliderForces`, (F − 1,
        K, 3) N. A `ValueError` where the trajectory has no such record (`None`: a world
        without colliders, a file without them)."""
        missing = [name for name in COLLIDER_RECORD if getattr(self, name) is None]
        if missing:
            raise ValueError(
                f"this trajectory has no {missing[0]}: World.run records the collider books in a world with colliders "
                "(and, with a force model, the verlet method), and H5MD files keep them"
            )
        dt = np.diff(self.t)[:, None, None]
        normal, tangential = np.diff(self.collider_normal, axis=0) / dt, np.diff(self.collider_tangential, axis=0) / dt
        return ColliderForces(self.t[:-1], self.t[1:], normal, tangential, np.diff(self.collider_momentum, axis=0) / dt)

    def frame(self, k: int) -> dict[str, np.ndarray]:
        """The particles alive at frame `k`: `ids`, `positions`, `velocities` and, where
        known, `angular_velocities`, `orientations`, `masses`, `radii`, `species`,
        `colors` and `groups`, each with one row per live particle."""
        live = self.alive[k]
        out = {"ids": (self.ids if self.ids is not None else np.arange(live.size))[live]}
        out["positions"], out["velocities"] = self.positions[k][live], self.velocities[k][live]
        for name in ("angular_velocities", "orientations"):
            value = getattr(self, name)
            if value is not None:
                out[name] = value[k][live]
        for name in ("masses", "radii", "species", "colors", "groups"):
            value = getattr(self, name)
            if value is not None:
                out[name] = value[live]
        return out

    @staticmethod
    def _recorder(expected: int = 0, contacts: bool = False) -> _Recorder:
        return _Recorder(expected, contacts)

    def save(self, path: Any, group: str = "all", **options: Any) -> Any:
        """Write the frames to an H5MD file (`kinema.io.save_h5md`); returns its path.

        What is written is first checked by the rules `load` reads it with (finite
        times that increase, finite positions and velocities, masses > 0, radii >= 0, ...):
        a trajectory that would not load back is refused before anything is written, with a
        one-line `kinema.io.TrajectoryFileError` naming the file, the attribute and the
        value. A failure of the system (a name too long, a full disk) is a
        `kinema.io.FileWriteError` naming the file."""
        from .io import save_h5md

        return save_h5md(self, path, group=group, **options)

    @classmethod
    def load(
        cls,
        path: Any,
        group: str | None = None,
        follow_links: bool = False,
        *,
        format: str | None = None,
        units: Any = None,
        atom_style: str | None = None,
    ) -> Trajectory:
        """Read a trajectory file, kinema's or another program's, in SI units; what only the file
        knows (its path, group, step of each frame, author, creator, the cell at each frame) is
        `source`, a `FileInfo`. Quantities the file does not hold are filled in as
        `_from_file` says (velocities and energies NaN, "unknown").

        Formats (`format`, default: told by the file's first bytes, its suffix, its first
        lines; `kinema.io.readers`): `"h5md"` (`save`'s and other programs' H5MD;
        `kinema.io.load_h5md`), `"xyz"` (extended XYZ: ASE's, OVITO's, kinema's `.xyz`),
        `"gsd"` (HOOMD-blue's, kinema's `.gsd`), `"lammps"` (a LAMMPS text dump),
        `"lammps-data"` (a LAMMPS data file), `"usd"` (kinema's USD exports and another
        program's first `UsdGeom.Points`, through usd-core), and kinema's own exports `"csv"`,
        `"vtk"` (the `.pvd` series) and `"ply"` (the `<stem>_ply/` series). docs/files.md says
        what each gives (ids, births and deaths, units).

        `units`: for a file that does not say its units, what they are: a LAMMPS unit style
        (`"real"`, `"metal"`, `"si"`, `"cgs"`, `"electron"`, `"micro"`,
        `"nano"`), `"ase"`, or {"length": m, "time": s, "mass": kg}; a LAMMPS file that
        says neither is refused, a HOOMD GSD file without them is read as SI with a
        `kinema.io.UnitWarning`. `atom_style`: a LAMMPS data file's atom style, where its
        Atoms section does not name it.

        What the file holds is checked as it is read (H5MD: shapes, types and the memory they
        need before any data; every format: finite positions, velocities and times, times that
        increase, masses > 0, radii >= 0 and at most 1e150 m, printable species names, a box
        along the axes, an id once per frame): a `kinema.io.TrajectoryFileError` (a
        `ValueError`), one line, names the file, where in it and the bad value. A file of
        no format kinema reads is refused with the list of those it reads.

        An H5MD file is read alone: one with an external link, a virtual dataset of another file
        or data stored in external files is refused, unless `follow_links=True` (then those
        other files are read too); `group` picks its particle group."""
        from .io.readers import read_trajectory

        return cls._from_file(read_trajectory(path, format=format, units=units, group=group, follow_links=follow_links, atom_style=atom_style))

    @classmethod
    def _from_file(cls, read: Any) -> Trajectory:
        """The `Trajectory` of what `kinema.io.load_h5md` read (a `LoadedTrajectory`):
        every field the constructor takes, from the attribute of the same name, so it follows
        the class as it grows. What the file does not hold is filled in: velocities, kinetic
        energy, momentum and angular momentum that were not recorded (a file of another
        program) are NaN, "unknown" (`total` is then NaN too), absent collision observables
        zeros, other absent attributes their defaults. The file's own facts become
        `source`; the periodic cell is the first frame's (`box_edges`), a box that
        changes keeps every frame's in `source.box_edges_by_frame`."""
        f, n = read.positions.shape[:2]
        unknown = {
            "velocities": lambda: np.full((f, n, 3), np.nan),
            "kinetic": lambda: np.full(f, np.nan),
            "momentum": lambda: np.full((f, 3), np.nan),
            "angular_momentum": lambda: np.full((f, 3), np.nan),
            "contacts": lambda: np.zeros(f, dtype=np.int64),
            "impulse_balance": lambda: np.zeros((f, 3)),
            "collision_energy_lost": lambda: np.zeros(f),
            "impacts": lambda: np.zeros(f, dtype=np.int64),
        }
        args = {}
        for fl in fields(cls):
            # a file's `step` is each frame's step number (kept in `source.step`), not the
            # length of the steps that `Trajectory.step` is: that one no file records
            if not fl.init or fl.name in ("source", "step"):
                continue
            value = getattr(read, fl.name, None)
            if value is None and fl.name in unknown:
                value = unknown[fl.name]()
            if value is not None:  # else: optional, its default
                args[fl.name] = value
        source = FileInfo(
            path=read.path,
            group=read.group,
            step=read.step,
            author=read.author,
            creator=read.creator,
            box_edges_by_frame=read.box_edges_by_frame,
        )
        return cls(**args, source=source)

    def render(self, path: Any, fps: float | None = None, draw_colliders: bool = True, **options: Any) -> Any:
        """Render the frames to a video, `.mp4` (H.264) or `.gif`, and return its path.

        `fps` defaults to real time (`kinema.render.playback_rate`): the trajectory's own
        `fps` (the rate asked of `World.run`, also read from an H5MD file kinema wrote),
        else the nearest of the common rates 24, 25, 30, 50 and 60 within 2 % of the
        recording's rate, else the recording's rate; the frames are placed by their times
        (`write_video(times=)`: a recording every 33 ms, 30.30 a second, as an older kinema
        made them, makes a 30 fps video with one frame in about a hundred dropped, and a GIF, whose delays are whole
        1/100 s, still plays in real time; the rate written is `kinema.render.video_rate`).
        A number gives one video frame per recorded frame at that rate. The trajectory's
        `colliders` are drawn with the particles unless `draw_colliders` is False (or
        `colliders=` gives others). `options` go to `kinema.render_frames`
        (`color_by`, `width`, `height`, `camera`, ...) and `preset`/`crf` to
        `kinema.write_video`. Particles without a radius are drawn at 1/200 of the scene's
        size. Each frame shows the particles `alive` then, and the `springs` whose ends
        both are, as lines."""
        from .render import _trajectory_options, own_colours, playback_rate, render_frames, write_video

        video = {k: options.pop(k) for k in ("preset", "crf") if k in options}
        options.setdefault("colliders", self.colliders if draw_colliders else None)
        times = None
        if fps is None:
            fps, real_time, _ = playback_rate(self.t, self.fps)
            times = self.t if real_time else None
        # The radii (or a stand-in), the alive mask and the springs (ids → columns); options win.
        for name, value in _trajectory_options(self).items():
            options.setdefault(name, value)
        if isinstance(options.get("color_by"), str) and options["color_by"] == "color":  # each particle's own
            options["color_by"] = own_colours(self)
        frames = render_frames(self.positions, t=self.t, dim=self.dim, velocities=self.velocities, **options)
        return write_video(frames, path, fps=fps, times=times, **video)

    def show(self, mode: str = "viewer", **options: Any) -> Any:
        """Play the frames, inline in Jupyter, else outside it.

        `mode="viewer"` (the default): the browser viewer (three.js, bundled; play/pause,
        scrub, speed, orbit camera, colouring). In a notebook, returns an IPython `HTML`
        object holding the self-contained page in an iframe (`options`: `title`,
        `max_bytes`, `color_by`, `camera`; `open_browser` and `port` are ignored there);
        elsewhere, serves it on 127.0.0.1 (`kinema.viewer.serve`: `open_browser`, `port`,
        `title`, `max_bytes`, `color_by`, `camera`), opens the user's browser when there is one and returns the page's
        URL. The server runs on a daemon thread until the process ends.

        `mode="video"`: an H.264 MP4 rendered by `render` (`options` go to it:
        `fps`, `color_by`, `width`, `height`, `camera`, ...). In a notebook, returns
        an IPython `Video` embedded in the notebook (an HTML5 `<video>` with the MP4 as a
        base64 data URI; nothing is left on disk); elsewhere, writes the MP4 to a new
        temporary file (`kinema-*.mp4` in the system's temporary folder) and returns its
        path."""
        if mode not in ("viewer", "video"):
            raise ValueError(f"mode = {mode!r} is invalid: use 'viewer' (the browser viewer) or 'video' (an MP4)")
        try:
            from IPython import get_ipython  # type: ignore[import-not-found]

            shell = get_ipython()
            # A Jupyter kernel's shell (ZMQInteractiveShell) has a kernel; a terminal IPython's has not.
            in_notebook = shell is not None and (getattr(shell, "kernel", None) is not None or "IPKernelApp" in shell.config)
        except ImportError:
            in_notebook = False
        if mode == "video":
            import os
            import tempfile
            from pathlib import Path

            if not in_notebook:
                fd, name = tempfile.mkstemp(prefix="kinema-", suffix=".mp4")
                os.close(fd)
                try:
                    return self.render(name, **options)
                except BaseException:
                    os.unlink(name)
                    raise
            from IPython.display import Video  # type: ignore[import-not-found]

            with tempfile.TemporaryDirectory(prefix="kinema-") as folder:
                data = Path(self.render(Path(folder) / "show.mp4", **options)).read_bytes()
            return Video(data, embed=True, mimetype="video/mp4", html_attributes="controls loop")
        if in_notebook:
            import html

            from IPython.display import HTML  # type: ignore[import-not-found]

            from .viewer.page import html_page

            options = {k: v for k, v in options.items() if k not in ("open_browser", "port")}
            page = html_page(self, **options)
            # (in a div: IPython warns "Consider using IPython.display.IFrame" of any HTML that
            # is one bare iframe, but IFrame takes a URL, and the page is embedded whole)
            return HTML(f'<div><iframe srcdoc="{html.escape(page)}" style="width:100%;height:480px;border:0"></iframe></div>')
        from .viewer import serve

        url, _server = serve(self, **options)
        return url

    def export(self, path: Any, format: str | None = None, *, plain_dump: bool = False) -> list[Any]:
        """Write the frames for other tools: `vtk` (ParaView), `ply` (Blender, Houdini),
        `xyz` (OVITO), `csv`, `gsd`, `lammps`, `usd` or `blend` (a Blender scene, built by
        Blender, and the USD stage it plays), inferred from the suffix when
        `format` is None; returns the files written (`kinema.io.export`). Values the
        format's readers or kinema's would refuse are refused before anything is written.
        The spins go into every format, the `contact_record` into `lammps` (dump
        local files) and `vtk` (force-chain lines). `plain_dump=True`: a `lammps` dump
        without its `ITEM: UNITS`, `ITEM: TIME` and type-label items, which MDAnalysis needs."""
        from .io import export

        return export(self, path, format, plain_dump=plain_dump)

    def plot_energy(self, ax: Any = None) -> Any:
        """Kinetic, each potential and the total energy against time, and the energy lost in
        collisions when there is any; returns the Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 4))
        ax.plot(self.t, self.kinetic, label="kinetic")
        for name, u in self.potential.items():
            ax.plot(self.t, u, label=f"potential ({name})")
        ax.plot(self.t, self.total, "k", lw=2, label="total")
        if np.any(self.collision_energy_lost != 0):
            ax.plot(self.t, self.collision_energy_lost, "k--", label="lost in collisions")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("energy (J)")
        ax.legend(fontsize="small")
        ax.grid(True, alpha=0.3)
        return ax


class _Recorder(Recorder):
    """Collects frames while a world runs (`kinema._recorder.Recorder`), and makes them a
    `Trajectory` at the end (`finish`)."""

    def finish(self) -> Trajectory:
        return Trajectory(**self.fields())
