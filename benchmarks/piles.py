"""Piles at rest: kinema beside pymunk and Box2D v3 (2D), pybullet and Jolt (3D), same piles.

Every scene starts from the same state in each engine (built from a seeded RNG in the worker),
falls under gravity, dt = 1 ms, and should end as a pile at rest. Masses 1 kg. The scenes:

  pour2d     2,000 discs, radii uniform in [0.025, 0.04] m, e = 0.7, mu = 0, on a jittered grid
             above the floor (spacing >= 2 r_max + 5 mm, no overlaps) in a box 1 m wide
             (walls x = 0 and x = 1, floor y = 0, a lid far above: nothing reaches it), 5 s;
             g = (0, -9.81).
  pour2d_mu  the same with mu = 0.5.
  pyramid2d  a 20-row pyramid of equal discs (r = 0.05 m, e = 0, mu = 0.5) standing on the
             floor of a box 4 m wide, rows touching (row k has 20 - k discs), 10 s; its own
             figure: the largest displacement of any disc from its start ("drift").
  column2d   a 40-row column of 400 discs (10 a row, same radii, e = 0.7, mu = 0.5) on a
             jittered grid in a box just 10 columns wide (10 (2 r_max + 5 mm) = 0.85 m), 5 s.
  pour3d     10,000 balls, radii uniform in [0.025, 0.04] m, e = 0.7, mu = 0, on a jittered
             lattice above the floor of a 1 m x 1 m box (floor z = 0), 5 s; g = (0, 0, -9.81).
  pour3d_mu  the same with mu = 0.5.
  deep3d     5 x 5 x 60 balls on a jittered lattice (same radii, e = 0.7, mu = 0.5) in a
             0.5 m x 0.5 m box, 5 s: a tall narrow column.
  demo3d     the demo's 400 balls (same radii, e = 0.7, mu = 0.5) on a jittered lattice (5 x 5
             a layer, 16 layers) in a 0.5 m x 0.5 m box, 4 s.

The engines:

  kinema   World(dim, dt=1e-3, method="verlet"), Gravity, Box (the lid 1 m above the
           highest particle), set_collisions(restitution=e, friction=mu): the impulse model,
           ccd on. `--threads` rayon threads (RAYON_NUM_THREADS, default 2).
  pymunk   (2D) Space(), iterations = 10, gravity (0, -9.81), step(1e-3); each disc a dynamic
           Body of moment inf (no rotation: kinema's particles are points with a radius, so
           no engine here rolls), walls static Segments of radius 0 (no lid: nothing rises
           above its start with e < 1). collision_slop = 1e-4 m (Chipmunk's default 0.1 is
           in its pixel-sized units and would let discs overlap by 3 radii). Broadphase:
           use_spatial_hash(2 r_mean, 10 N), Chipmunk's advice for many shapes of one size
           (2.5x faster on pour2d than its default bounding-box tree). One thread (its
           threaded space with 2 threads was no faster here).
  pybullet (3D) DIRECT, setTimeStep(1e-3), numSolverIterations = 10, gravity (0, 0, -9.81);
           one sphere collision shape per ball (the radii are continuous: no binning, the
           exact radii of the other engines; building is not timed), each ball a maximal-
           coordinates body (btRigidBody, useMaximalCoordinates=True) changed to mass 1,
           localInertiaDiagonal (0, 0, 0) (Bullet reads a zero inertia as infinite: no
           rotation, as in the other engines), rollingFriction = spinningFriction = 0 and
           linearDamping = angularDamping = 0 (pybullet's default 0.04 is a drag none of the
           others has). The box: one static multibody of 5 box shapes 0.5 m thick (floor and
           4 walls, no lid). Bullet's restitutionVelocityThreshold (0.2 m/s: slower impacts
           do not bounce) and its sleeping are left at pybullet's defaults.
  box2d    (2D) Box2D v3 (the boxdd 0.6.0 crate: Box2D 3.2.0 at 56edae7, single precision),
           driven by benchmarks/peers/engines (the `pile-peer` binary). World at its defaults
           but gravity (0, -9.81): contact hertz 30, damping ratio 10, contact speed (the
           push-out cap) 3 m/s, restitutionThreshold 1 m/s, sleeping and continuous on; each
           disc a dynamic body with a circle of density 1 / (pi r^2) and its mass data then set
           to exactly 1 kg with rotational inertia 0 (inverse inertia 0: no rotation, as
           pymunk's moment inf; also the motion lock angularZ), no damping; the box:
           3 static box polygons 0.5 m thick (floor, 2 walls). b2World_Step(dt, substeps):
           the plain table's setting is Box2D's own default, 4 substeps, contact hertz 30, at
           dt = 1 ms. Box2D caps the contact hertz at 1/8 of the substep rate
           (physics_world.c: min(hertz, 0.125 substeps / dt)): 2,000 Hz needs 16 substeps at
           1 ms; the tables show the capped value after an arrow.
  jolt     (3D) Jolt Physics 5.0.0 (the rolt 0.3.1 / joltc-sys 0.3.1 crates), same binary.
           PhysicsSystem at its defaults (10 velocity and 2 position steps, Baumgarte 0.2,
           speculative contact distance 0.02 m, penetration slop 0.02 m,
           mMinVelocityForRestitution 1 m/s, sleeping after 0.5 s below 0.03 m/s) but gravity
           (0, 0, -9.81), Update(dt, 1 collision step); each ball a dynamic sphere of density
           1 / (4/3 pi r^3) (1 kg to a rounding: the worker reports the masses), allowed DOFs
           the three translations (no rotation), motion quality discrete, no damping (Jolt's
           default 0.05 is a drag); the box: 5 static boxes 0.5 m thick (floor, 4 walls). The
           plain table's setting: dt = 1 ms, the defaults. JoltC's C API has no
           PhysicsSettings nor SetGravity: the crate compiles a small C++ file
           (src/jolt_settings.cpp) against the Jolt headers joltc-sys vendors, with the
           definitions of its build, and checks on every run that it reads Jolt's defaults.
           Box2D and Jolt run with `--peer-threads` threads (default 1).

Restitution and friction of a pair: kinema, Box2D v3 and Jolt take the pair's values as
e = max(e_i, e_j) and mu = sqrt(mu_i mu_j) (Box2D: b2DefaultRestitutionCallback /
b2DefaultFrictionCallback in physics_world.c; Jolt: ContactConstraintManager's
mCombineRestitution / mCombineFriction), so every disc, ball and wall there gets e and mu.
Bullet and Chipmunk combine restitution by the product rule: give each body √e. So are friction
coefficients combined: every ball, disc and wall of pymunk and pybullet gets √e and √mu.
Restitution thresholds (slower approaches do not bounce): kinema restitution_threshold=None,
2 g dt (0.02 m/s at 1 ms); Box2D restitutionThreshold 1 m/s; Jolt mMinVelocityForRestitution
1 m/s; Bullet restitutionVelocityThreshold 0.2 m/s; Chipmunk none. Each left at its default.

Building the Box2D/Jolt peers: piles.py runs `cargo build --release --quiet --manifest-path
benchmarks/peers/engines/Cargo.toml` the first time it needs them (a few minutes: Jolt is C++
built by CMake; it needs cmake, a C++ compiler and libclang for bindgen, which `make bench`
installs where it can). Where the build fails, piles.py says why and runs the others.

Each engine runs in a fresh process, `--repeat` times, interleaved (kinema, peers, kinema,
peers, ...); an engine's runs of a scene stop early once they took `--budget` seconds (default
600: a run of pour3d took 20-30 min in each engine on a 2-core machine, so it ran once, and a
full default run took hours there, most of it pour3d and pour3d_mu); the table's "runs"
column says how many there were. Timed: the simulation steps alone (kinema's `World.step`
after a first `step(0)`, the peers' step loops), not the building: "sim s" their wall seconds,
"cpu s" the CPU seconds of the process over them (all its threads). With `--threads-scaling`
(on by default; pour3d only) kinema also runs pour3d with 1 and with 2 threads, interleaved
with the others, and the speed-up of 2 threads over 1 is printed.

The figures, measured on the final state (the median over the runs of each):
  disp med / max  median and largest displacement over the last 0.1 s (positions at
                  t_end - 0.1 s against t_end), m
  drift           pyramid2d: the largest displacement from the start, m
  overlap/r       the largest overlap r_i + r_j - |x_i - x_j| of any pair (found by brute force
                  with scipy's cKDTree, pairs within 2 r_max), over the mean radius
  wall pen/r      how far any particle's surface is beyond any wall of the box, over mean r
  max |v|         m/s;  KE  ½ Σ m v², J
  asleep          the bodies asleep at the end (kinema: collision_stats; pymunk: is_sleeping,
                  none as its sleeping is off; Box2D: b2Body_IsAwake; Jolt: IsActive;
                  pybullet: not told, "-")
  speed-up        on kinema's row: pymunk's / pybullet's time over kinema's (> 1: kinema is
                  faster); on a Box2D / Jolt row: that engine's time over kinema's
  sleeping        (the 3D pours of 10,000) the particles asleep at the end, and the time of a
                  step of the settled pile as it is (asleep) against the same pile kept awake
                  (set_collisions(sleep_time=None), 300 steps to rebuild its warm start), each
                  over 200 steps after the run: target <= 5 %
The targets are printed beside them, and PASS/FAIL per target for kinema. Exit status 1 when
kinema misses a target (--quick's 1 s runs are judged by the full scenes' targets too).

`--work-precision`: for each scene, each engine at several settings, the CPU seconds beside the
rest figures, one table a scene (sorted by engine, then CPU seconds), the rows also written as
JSON to out/piles_work_precision.json; no targets judged. The settings:
  kinema   KINEMA_SETTINGS: dt 1, 2, 4 ms and 1/60 s at the default accuracy ("physics"),
           and accuracy="animation" (shock propagation) at 1/120 s and 1/60 s (each a dict of
           World and set_collisions keyword arguments);
  box2d    dt {1 ms, 1/60 s} x substeps {4, 8, 16} x contact hertz {30, 2000} (with --quick
           the four of 1 ms/16/2000 Hz, the issue's figure setting, 1 ms/4/30, 1/60 s/4/30 and
           1/60 s/8/30);
  jolt     dt {1 ms, 1/60 s} x penetration slop {0.02 m (its default), 1 mm};
  pymunk, pybullet  their settings above.
A run at a dt other than 1 ms steps int(seconds / dt) steps, and its last window is still
0.1 s (round(0.1 / dt) steps). `--repeat` defaults to 1 there.

`--quick` shrinks every scene to about 1/10 of its particles and 1 s (and `--repeat` to 1
unless given): a check in under a minute (a few minutes with --work-precision).

    python benchmarks/piles.py [--scenes pour2d pour2d_mu pyramid2d column2d pour3d pour3d_mu
                                deep3d demo3d] [--repeat 3] [--threads 2] [--peer-threads 1]
                               [--quick] [--no-threads-scaling] [--budget 600] [--no-peers]
                               [--work-precision]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DT = 1e-3
G = 9.81
MASS = 1.0
GAP = 0.005  # m, the lattice's spacing beyond 2 r_max
LAST = 0.1  # s: the displacement window at the end
ITERATIONS = 10  # the peers' solver iterations
PYMUNK_SLOP = 1e-4  # m
WALL = 0.5  # m, pybullet's wall thickness
# kinema's targets (the peers are measured against the same figures)
TARGET_OVERLAP = 0.01  # of mean r
TARGET_PEN = 0.01  # of mean r
TARGET_DISP = 1e-5  # m per LAST
TARGET_VMAX = 1e-3  # m/s
TARGET_DRIFT = 1e-3  # m (pyramid2d)
TARGET_THREADS = 1.6  # pour3d: 1-thread time over 2-thread time
TARGET_SLEEP = 0.05  # the settled 3D pours: a step asleep over a step of the same pile awake
SLEEP_STEPS = 200  # steps timed asleep, and awake
WARM_STEPS = 300  # steps before the awake ones are timed (the warm start rebuilt)

# Box2D (2D) and Jolt (3D): benchmarks/peers/engines, a Rust crate built on first use
PEER_CRATE = Path(__file__).resolve().parent / "peers" / "engines"
PEER_BIN = PEER_CRATE / "target" / "release" / "pile-peer"
PEER_LIBRARIES = {"box2d": "boxdd 0.6.0 (Box2D 3.2.0)", "jolt": "rolt/joltc-sys 0.3.1 (Jolt 5.0.0)"}
WORK_PRECISION_JSON = Path(__file__).resolve().parents[1] / "out" / "piles_work_precision.json"

# The settings. kinema's: keyword arguments of World ("world") and of set_collisions
# ("collisions"), the first the plain table's; the work-precision mode runs them all.
KINEMA_SETTINGS: list[dict] = [
    {"world": {"dt": 1e-3}, "collisions": {}},
    {"world": {"dt": 2e-3}, "collisions": {}},
    {"world": {"dt": 4e-3}, "collisions": {}},
    {"world": {"dt": 1 / 60}, "collisions": {}},
    {"world": {"dt": 1 / 120}, "collisions": {"accuracy": "animation"}},
    {"world": {"dt": 1 / 60}, "collisions": {"accuracy": "animation"}},
]
# Box2D's own defaults (4 substeps, contact hertz 30) at 1 ms for the plain table
BOX2D_DEFAULT = {"dt": 1e-3, "substeps": 4, "contact_hertz": 30.0}
BOX2D_SETTINGS = [{"dt": dt, "substeps": n, "contact_hertz": hz} for dt in (1e-3, 1 / 60) for n in (4, 8, 16) for hz in (30.0, 2000.0)]
BOX2D_SETTINGS_QUICK = [  # --quick --work-precision: the figure setting first
    {"dt": 1e-3, "substeps": 16, "contact_hertz": 2000.0},
    {"dt": 1e-3, "substeps": 4, "contact_hertz": 30.0},
    {"dt": 1 / 60, "substeps": 4, "contact_hertz": 30.0},
    {"dt": 1 / 60, "substeps": 8, "contact_hertz": 30.0},
]
# Jolt at 1 ms with its defaults (penetration slop 0.02 m) for the plain table
JOLT_DEFAULT: dict = {"dt": 1e-3}
JOLT_SETTINGS: list[dict] = [{"dt": dt, **({"penetration_slop": slop} if slop else {})} for dt in (1e-3, 1 / 60) for slop in (None, 1e-3)]
ENGINE_ORDER = ("kinema", "pymunk", "box2d", "pybullet", "jolt")


@dataclass(frozen=True)
class Scene:
    name: str
    dim: int
    kind: str  # "lattice" or "pyramid"
    n: int  # particles (lattice) or rows (pyramid)
    width: float  # m, the box's side(s) across gravity
    e: float
    mu: float
    seconds: float
    speed_target: float | None  # kinema's speed-up over the peer
    per_row: int | None = None  # lattice sites per horizontal axis (None: as many as fit)
    r_range: tuple[float, float] = (0.025, 0.04)
    seed: int = 1

    @property
    def peer(self) -> str:
        """The Python peer (whose speed kinema's speed target is against)."""
        return "pymunk" if self.dim == 2 else "pybullet"

    @property
    def engine_peer(self) -> str:
        """The peer of benchmarks/peers/engines: Box2D v3 in 2D, Jolt in 3D."""
        return "box2d" if self.dim == 2 else "jolt"


SCENES = {
    s.name: s
    for s in (
        Scene("pour2d", 2, "lattice", 2000, 1.0, 0.7, 0.0, 5.0, 1.0, seed=11),
        Scene("pour2d_mu", 2, "lattice", 2000, 1.0, 0.7, 0.5, 5.0, None, seed=11),
        Scene("pyramid2d", 2, "pyramid", 20, 4.0, 0.0, 0.5, 10.0, None, r_range=(0.05, 0.05)),
        Scene("column2d", 2, "lattice", 400, 10 * (2 * 0.04 + GAP), 0.7, 0.5, 5.0, None, per_row=10, seed=19),
        Scene("pour3d", 3, "lattice", 10_000, 1.0, 0.7, 0.0, 5.0, 5.0, seed=13),
        Scene("pour3d_mu", 3, "lattice", 10_000, 1.0, 0.7, 0.5, 5.0, 5.0, seed=13),
        Scene("deep3d", 3, "lattice", 1500, 0.5, 0.7, 0.5, 5.0, None, per_row=5, seed=17),
        Scene("demo3d", 3, "lattice", 400, 0.5, 0.7, 0.5, 4.0, None, seed=23),
    )
}


def shrink(s: Scene) -> Scene:
    """--quick: about 1/10 of the particles, 1 s."""
    if s.kind == "pyramid":
        rows = max(2, round((-1 + math.sqrt(1 + 8 * s.n * (s.n + 1) / 2 / 10)) / 2))  # rows(rows+1)/2 ≈ N/10
        return Scene(**{**s.__dict__, "n": rows, "seconds": 1.0})
    return Scene(**{**s.__dict__, "n": max(1, s.n // 10), "seconds": 1.0})


# -- the initial state --------------------------------------------------------------------------
def initial_state(s: Scene) -> dict:
    """Positions (N, 3) (z = 0 in 2D), radii (N,), the box's lo and hi (dim values each)."""
    rng = np.random.default_rng(s.seed)
    if s.kind == "pyramid":
        r = s.r_range[0]
        x0 = s.width / 2 - s.n * r  # the bottom row is centred
        pts = [(x0 + r * (2 * i + k + 1), r + k * math.sqrt(3) * r, 0.0) for k in range(s.n) for i in range(s.n - k)]
        x = np.array(pts)
        radii = np.full(len(x), r)
    else:
        r_max = s.r_range[1]
        across = s.dim - 1  # horizontal axes
        per_row = s.per_row or int(s.width // (2 * r_max + GAP))
        a = s.width / per_row  # horizontal spacing >= 2 r_max + GAP
        layers = -(-s.n // per_row**across)
        up = 2 * r_max + GAP  # vertical spacing
        grids = np.meshgrid(*[np.arange(per_row)] * across, np.arange(layers), indexing="ij")
        idx = np.stack([g.ravel() for g in grids], axis=-1)
        idx = idx[np.argsort(idx[:, -1], kind="stable")][: s.n]  # bottom layers first
        x = np.zeros((s.n, 3))
        x[:, :across] = (idx[:, :across] + 0.5) * a
        x[:, across] = r_max + GAP + idx[:, -1] * up
        # jitter: each coordinate moves by at most 0.4 of the free space between neighbours,
        # so neighbours stay > 2 r_max apart and clear of the walls
        x[:, :across] += rng.uniform(-1, 1, (s.n, across)) * 0.4 * (a - 2 * r_max)
        x[:, across] += rng.uniform(-1, 1, s.n) * 0.4 * GAP
        radii = rng.uniform(*s.r_range, s.n)
    up_axis = s.dim - 1
    height = math.ceil(float(x[:, up_axis].max()) + 1.0)
    lo = [0.0] * s.dim
    hi = [s.width] * (s.dim - 1) + [float(height)]
    return {"x": x, "r": radii, "lo": lo, "hi": hi}


# -- the engines (in the worker) -----------------------------------------------------------------
def run_kinema(s: Scene, st: dict, steps: int, last: int, setting: dict, sleep_check: bool = True) -> dict:
    import kinema

    t0 = time.perf_counter()
    w = kinema.World(dim=s.dim, **{"dt": DT, "method": "verlet", **setting.get("world", {})})
    w.add_particles(st["x"], mass=MASS, radius=st["r"])
    w.add(kinema.Gravity(g=(0.0, -G, 0.0) if s.dim == 2 else (0.0, 0.0, -G)))
    w.add(kinema.Box(st["lo"], st["hi"]))
    w.set_collisions(**{"restitution": s.e, "friction": s.mu, **setting.get("collisions", {})})
    w.step(0)
    build = time.perf_counter() - t0
    t0, c0 = time.perf_counter(), time.process_time()
    w.step(steps - last)
    sim, cpu = time.perf_counter() - t0, time.process_time() - c0
    before = w.positions.copy()
    t0, c0 = time.perf_counter(), time.process_time()
    w.step(last)
    sim, cpu = sim + time.perf_counter() - t0, cpu + time.process_time() - c0
    stats = w.collision_stats() or {}
    total, final = stats.get("total", {}), stats.get("last", {})
    extra = {f"unconverged steps (of {steps})": total.get("unconverged")}
    extra.update({f"last step's {key}": final.get(key) for key in ("contacts", "max_overlap", "solver_sweeps", "islands", "asleep")})
    extra = {k: float(v) for k, v in extra.items() if v is not None}
    out = {"build": build, "sim": sim, "cpu": cpu, "before": before, "x": w.positions.copy(), "v": w.velocities.copy(), "extra": extra}
    out["asleep"] = int(final["asleep"]) if final.get("asleep") is not None else None
    if sleep_check and s.dim == 3 and s.n >= 10_000:
        # The settled pile of 10,000 balls: a step of it as it is (asleep, where it fell asleep)
        # against a step of the same pile kept awake (sleeping off, its warm start rebuilt).
        t0 = time.perf_counter()
        w.step(SLEEP_STEPS)
        asleep_time = time.perf_counter() - t0
        w.set_collisions(restitution=s.e, friction=s.mu, sleep_time=None)
        w.step(WARM_STEPS)
        t0 = time.perf_counter()
        w.step(SLEEP_STEPS)
        awake_time = time.perf_counter() - t0
        out["sleep"] = {"asleep": int(final.get("asleep", 0)), "asleep_ms": 1e3 * asleep_time / SLEEP_STEPS, "awake_ms": 1e3 * awake_time / SLEEP_STEPS}
    return out


def peer_result(build: float, sim: float, cpu: float, before: np.ndarray, x: np.ndarray, v: np.ndarray, spin: float, asleep: int | None) -> dict:
    """A peer's run as the worker reports it, with what the peer itself tells: its largest
    angular speed (0: nothing rolled) and how many bodies are at rest to the last bit."""
    return {
        "build": build,
        "sim": sim,
        "cpu": cpu,
        "before": before,
        "x": x,
        "v": v,
        "asleep": asleep,
        "extra": {"max |omega|": spin, "at |v| = 0 exactly": int(np.sum(~v.any(axis=1)))},
    }


def run_pymunk(s: Scene, st: dict, steps: int, last: int, setting: dict) -> dict:
    import pymunk

    t0 = time.perf_counter()
    space = pymunk.Space()
    space.iterations = ITERATIONS
    space.gravity = (0.0, -G)
    space.collision_slop = PYMUNK_SLOP
    # Chipmunk's advice for many shapes of one size: a spatial hash of cells the size of a
    # shape and ~10 cells per shape (2.5x faster than its default bounding-box tree on pour2d)
    space.use_spatial_hash(2 * float(st["r"].mean()), 10 * len(st["r"]))
    e, mu = math.sqrt(s.e), math.sqrt(s.mu)
    (x0, y0), (x1, y1) = st["lo"], st["hi"]
    for a, b in (((x0, y0), (x1, y0)), ((x0, y0), (x0, y1)), ((x1, y0), (x1, y1))):
        seg = pymunk.Segment(space.static_body, a, b, 0.0)
        seg.elasticity, seg.friction = e, mu
        space.add(seg)
    bodies = []
    for p, r in zip(st["x"], st["r"], strict=True):
        body = pymunk.Body(MASS, float("inf"))
        body.position = (float(p[0]), float(p[1]))
        disc = pymunk.Circle(body, float(r))
        disc.elasticity, disc.friction = e, mu
        space.add(body, disc)
        bodies.append(body)
    build = time.perf_counter() - t0

    def state() -> tuple[np.ndarray, np.ndarray]:
        x = np.zeros((len(bodies), 3))
        v = np.zeros((len(bodies), 3))
        x[:, :2] = [tuple(b.position) for b in bodies]
        v[:, :2] = [tuple(b.velocity) for b in bodies]
        return x, v

    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps - last):
        space.step(DT)
    sim, cpu = time.perf_counter() - t0, time.process_time() - c0
    before = state()[0]
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(last):
        space.step(DT)
    sim, cpu = sim + time.perf_counter() - t0, cpu + time.process_time() - c0
    x, v = state()
    spin = max((abs(b.angular_velocity) for b in bodies), default=0.0)
    return peer_result(build, sim, cpu, before, x, v, spin, sum(b.is_sleeping for b in bodies))


def run_pybullet(s: Scene, st: dict, steps: int, last: int, setting: dict) -> dict:
    import pybullet as pb

    t0 = time.perf_counter()
    pb.connect(pb.DIRECT)
    pb.setGravity(0.0, 0.0, -G)
    pb.setTimeStep(DT)
    pb.setPhysicsEngineParameter(numSolverIterations=ITERATIONS)
    e, mu = math.sqrt(s.e), math.sqrt(s.mu)
    (lx, ly, lz), (hx, hy, hz) = st["lo"], st["hi"]
    cx, cy, h, t = (lx + hx) / 2, (ly + hy) / 2, hz - lz, WALL
    half = [[(hx - lx) / 2 + t, (hy - ly) / 2 + t, t]] + [[t, (hy - ly) / 2 + t, h / 2]] * 2 + [[(hx - lx) / 2 + t, t, h / 2]] * 2
    at = [[cx, cy, lz - t], [lx - t, cy, lz + h / 2], [hx + t, cy, lz + h / 2], [cx, ly - t, lz + h / 2], [cx, hy + t, lz + h / 2]]
    box = pb.createMultiBody(0.0, pb.createCollisionShapeArray([pb.GEOM_BOX] * 5, halfExtents=half, collisionFramePositions=at))
    pb.changeDynamics(box, -1, restitution=e, lateralFriction=mu, rollingFriction=0.0, spinningFriction=0.0)
    balls = []
    for p, r in zip(st["x"], st["r"], strict=True):
        shape = pb.createCollisionShape(pb.GEOM_SPHERE, radius=float(r))
        ball = pb.createMultiBody(MASS, shape, -1, [float(c) for c in p], useMaximalCoordinates=True)
        # mass= again: changeDynamics(localInertiaDiagonal=...) alone sets a maximal-coordinates
        # body's mass to 0 (pybullet 3.2.7)
        pb.changeDynamics(
            ball,
            -1,
            mass=MASS,
            localInertiaDiagonal=[0.0, 0.0, 0.0],
            restitution=e,
            lateralFriction=mu,
            rollingFriction=0.0,
            spinningFriction=0.0,
            linearDamping=0.0,
            angularDamping=0.0,
        )
        balls.append(ball)
    build = time.perf_counter() - t0

    def state() -> tuple[np.ndarray, np.ndarray, float]:
        x = np.array([pb.getBasePositionAndOrientation(b)[0] for b in balls])
        vel = [pb.getBaseVelocity(b) for b in balls]
        v = np.array([lin for lin, _ in vel])
        spin = max((float(np.linalg.norm(ang)) for _, ang in vel), default=0.0)
        return x, v, spin

    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(steps - last):
        pb.stepSimulation()
    sim, cpu = time.perf_counter() - t0, time.process_time() - c0
    before = state()[0]
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(last):
        pb.stepSimulation()
    sim, cpu = sim + time.perf_counter() - t0, cpu + time.process_time() - c0
    x, v, spin = state()
    return peer_result(build, sim, cpu, before, x, v, spin, None)  # pybullet does not tell who sleeps


def run_engine_peer(engine: str, s: Scene, st: dict, steps: int, last: int, setting: dict) -> dict:
    """Box2D or Jolt: the job to benchmarks/peers/engines's pile-peer (in its own process: its
    CPU seconds are its step loop's), the result back. setting: dt, threads, and Box2D's
    substeps, contact_hertz, contact_damping_ratio, contact_speed, or Jolt's penetration_slop."""
    job = {
        "engine": engine,
        "dim": s.dim,
        "positions": st["x"].tolist(),
        "radii": st["r"].tolist(),
        "lo": st["lo"],
        "hi": st["hi"],
        "e": s.e,
        "mu": s.mu,
        "gravity": [0.0, -G] if s.dim == 2 else [0.0, 0.0, -G],
        "steps": steps,
        "last": last,
        "wall": WALL,
        **setting,
    }
    with tempfile.TemporaryDirectory(prefix="piles-") as tmp:
        job_path, out_path = Path(tmp) / "job.json", Path(tmp) / "out.json"
        job_path.write_text(json.dumps(job))
        res = subprocess.run([str(PEER_BIN), str(job_path), str(out_path)], capture_output=True, text=True)
        if res.returncode != 0:
            raise RuntimeError(f"pile-peer exited {res.returncode}: {res.stderr.strip()[-1000:]}")
        out = json.loads(out_path.read_text())
    k = out["settings"]
    if engine == "box2d":  # the values every setting shares (the others are in the setting's words)
        told = f"restitution threshold {k['restitution_threshold']:g} m/s, contact damping ratio {k['contact_damping_ratio']:g}, contact speed {k['contact_speed']:g} m/s"
    else:
        told = (
            f"min velocity for restitution {k['min_velocity_for_restitution']:g} m/s, speculative contact distance "
            f"{k['speculative_contact_distance']:.3g} m, {k['num_velocity_steps']} velocity / {k['num_position_steps']} position steps"
        )
    return {
        "build": out["build"],
        "sim": out["wall"],
        "cpu": out["cpu"],
        "before": np.array(out["before"]),
        "x": np.array(out["x"]),
        "v": np.array(out["v"]),
        "asleep": out["asleep"],
        "extra": {
            "max |omega|": out["max_omega"],
            "mass min kg": out["mass_min"],
            "mass max kg": out["mass_max"],
            "at |v| = 0 exactly": int(np.sum(~np.array(out["v"]).any(axis=1))),
        },
        "told": f"{out['library']}: {told}" + "".join(f"; WARNING {w}" for w in out["warnings"]),
    }


def figures(s: Scene, st: dict, out: dict) -> dict:
    """The rest figures of the final state."""
    from scipy.spatial import cKDTree

    x, v, r = out["x"], out["v"], st["r"]
    d = s.dim
    r_mean = float(r.mean())
    if not (np.isfinite(x).all() and np.isfinite(v).all()):
        nan = float("nan")
        return dict.fromkeys(("disp_med", "disp_max", "drift", "overlap", "pen", "vmax", "ke"), nan)
    disp = np.linalg.norm(x - out["before"], axis=1)
    pairs = cKDTree(x[:, :d]).query_pairs(2 * float(r.max()), output_type="ndarray")
    if len(pairs):
        gap = np.linalg.norm(x[pairs[:, 0], :d] - x[pairs[:, 1], :d], axis=1)
        overlap = max(0.0, float(np.max(r[pairs[:, 0]] + r[pairs[:, 1]] - gap)))
    else:
        overlap = 0.0
    lo, hi = np.array(st["lo"]), np.array(st["hi"])
    beyond = np.maximum(lo - (x[:, :d] - r[:, None]), (x[:, :d] + r[:, None]) - hi)
    speed = np.linalg.norm(v, axis=1)
    return {
        "disp_med": float(np.median(disp)),
        "disp_max": float(disp.max()),
        "drift": float(np.linalg.norm(x - st["x"], axis=1).max()),
        "overlap": overlap / r_mean,
        "pen": max(0.0, float(beyond.max())) / r_mean,
        "vmax": float(speed.max()),
        "ke": float(0.5 * np.sum(MASS * speed**2)),
    }


def setting_dt(engine: str, setting: dict | None) -> float:
    """The step of an engine at a setting (pymunk and pybullet: DT)."""
    if not setting:
        return DT
    if engine == "kinema":
        return setting.get("world", {}).get("dt", DT)
    return setting.get("dt", DT)


def worker(engine: str, scene: str, quick: bool, setting: dict | None) -> dict:
    """One run: setting None is the plain table's (kinema: KINEMA_SETTINGS[0]; Box2D, Jolt:
    BOX2D_DEFAULT, JOLT_DEFAULT), else a work-precision setting."""
    s = shrink(SCENES[scene]) if quick else SCENES[scene]
    st = initial_state(s)
    plain = not setting
    if plain:
        setting = {"kinema": KINEMA_SETTINGS[0], "box2d": BOX2D_DEFAULT, "jolt": JOLT_DEFAULT}.get(engine, {})
    dt = setting_dt(engine, setting)
    steps = int(s.seconds / dt + 1e-9)  # at dt = 1/60: 5 / dt = 300.00000000000006
    last = round(LAST / dt)  # the last window is 0.1 s whatever the step
    try:
        if engine == "kinema":
            out = run_kinema(s, st, steps, last, setting, sleep_check=plain)
        elif engine in ("box2d", "jolt"):
            out = run_engine_peer(engine, s, st, steps, last, setting)
        else:
            out = {"pymunk": run_pymunk, "pybullet": run_pybullet}[engine](s, st, steps, last, setting)
    except Exception as exc:  # a diverged or failed run is reported, not hidden
        return {"n": len(st["r"]), "error": f"{type(exc).__name__}: {exc}"}
    return {
        "n": len(st["r"]),
        "build": out["build"],
        "sim": out["sim"],
        "cpu": out["cpu"],
        "asleep": out.get("asleep"),
        "figures": figures(s, st, out),
        "extra": out["extra"],
        "told": out.get("told"),
        "sleep": out.get("sleep"),
    }


# -- the runs (in the parent) --------------------------------------------------------------------
def spawn(engine: str, scene: str, quick: bool, threads: int, setting: dict | None = None) -> dict:
    env = {**os.environ, "RAYON_NUM_THREADS": str(threads), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    cmd = [sys.executable, __file__, "--worker", engine, scene, json.dumps(setting or {})] + (["--quick"] if quick else [])
    res = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if res.returncode != 0:
        return {"error": f"worker exited {res.returncode}: {res.stderr.strip()[-2000:]}"}
    return json.loads(res.stdout.strip().splitlines()[-1])


def version(module: str) -> str | None:
    """The peer's version, or None when it is not installed."""
    if importlib.util.find_spec(module) is None:
        return None
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version

    try:
        return dist_version(module)
    except PackageNotFoundError:
        return "?"


def build_engine_peers() -> str | None:
    """Builds benchmarks/peers/engines (Box2D, Jolt) where it is not built and up to date:
    None when pile-peer is there, else why not (no cargo, a failed build)."""
    cargo = os.environ.get("CARGO", "cargo")
    cmd = [cargo, "build", "--release", "--quiet", "--manifest-path", str(PEER_CRATE / "Cargo.toml")]
    print("piles: building the Box2D/Jolt peers (benchmarks/peers/engines; the first time takes minutes: Jolt's C++)", file=sys.stderr, flush=True)
    try:
        res = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as exc:
        return f"{cargo} could not be run ({exc})"
    if res.returncode != 0:
        tail = " | ".join(res.stderr.strip().splitlines()[-6:])
        return f"`cargo build` of benchmarks/peers/engines failed ({tail[-600:]})"
    return None if PEER_BIN.exists() else f"{PEER_BIN} is missing after its build"


def dt_words(dt: float) -> str:
    for k in (60, 120):
        if abs(dt - 1 / k) < 1e-12:
            return f"1/{k} s"
    return f"{dt * 1e3:g} ms"


def setting_words(engine: str, setting: dict | None) -> str:
    """A setting as the work-precision table names it."""
    if engine == "kinema":
        setting = setting or KINEMA_SETTINGS[0]
        words = [f"dt {dt_words(setting.get('world', {}).get('dt', DT))}"]
        words += [f"{k}={v}" for k, v in setting.get("world", {}).items() if k != "dt"]
        words += [f"{k}={v}" for k, v in setting.get("collisions", {}).items()]
        return ", ".join(words)
    if engine == "box2d":
        setting = setting or BOX2D_DEFAULT
        dt, n, hz = setting["dt"], setting["substeps"], setting["contact_hertz"]
        capped = min(hz, 0.125 * n / dt)  # physics_world.c: min(contactHertz, 0.125 * inv_h)
        return f"dt {dt_words(dt)}, {n} substeps, {hz:g} Hz" + (f" (->{capped:.3g})" if capped < hz else "")
    if engine == "jolt":
        setting = setting or JOLT_DEFAULT
        slop = setting.get("penetration_slop")
        return f"dt {dt_words(setting['dt'])}, slop " + (f"{slop * 1e3:g} mm" if slop else "20 mm (default)")
    return f"dt {dt_words(DT)}, {ITERATIONS} iterations"


COLUMNS = [  # key, title, width, format of a number
    ("n", "N", 7, ","),
    ("runs", "runs", 4, "d"),
    ("sim", "sim s", 9, ".2f"),
    ("cpu", "cpu s", 9, ".2f"),
    ("speedup", "speed-up", 9, ""),
    ("disp_med", "disp med m", 11, ".2e"),
    ("disp_max", "disp max m", 11, ".2e"),
    ("drift", "drift m", 10, ".2e"),
    ("overlap", "overlap/r", 10, ".2e"),
    ("pen", "wall pen/r", 11, ".2e"),
    ("vmax", "max|v| m/s", 11, ".2e"),
    ("ke", "KE J", 10, ".2e"),
    ("asleep", "asleep", 7, ","),
]


def table_row(first: str, second: str, values: dict) -> str:
    """A row of the table: a value per column key (missing or None: '-')."""
    out = f"{first:<10} {second:<9}"
    for key, _, width, spec in COLUMNS:
        v = values.get(key)
        text = "-" if v is None else v if isinstance(v, str) else format(v, spec)
        out += f" {text:>{width}}"
    return out


def targets(s: Scene) -> dict[str, tuple[str, float]]:
    """kinema's targets of a scene: key -> (the words, the bound); speed-up is a lower bound."""
    t = {
        "disp_med": ("<=", TARGET_DISP),
        "overlap": ("<=", TARGET_OVERLAP),
        "pen": ("<=", TARGET_PEN),
        "vmax": ("<=", TARGET_VMAX),
    }
    if s.kind == "pyramid":
        t["drift"] = ("<=", TARGET_DRIFT)
    if s.speed_target is not None:
        t["speedup"] = (">=", s.speed_target)
    return t


def median_row(runs: list[dict]) -> dict | None:
    ok = [r for r in runs if "error" not in r]
    if not ok:
        return None
    row = {
        "n": ok[0]["n"],
        "runs": len(ok),
        "sim": statistics.median(r["sim"] for r in ok),
        "cpu": statistics.median(r["cpu"] for r in ok),
        "build": statistics.median(r["build"] for r in ok),
    }
    asleep = [r["asleep"] for r in ok if r.get("asleep") is not None]
    row["asleep"] = round(statistics.median(asleep)) if asleep else None
    for key in ok[0]["figures"]:
        row[key] = statistics.median(r["figures"][key] for r in ok)
    return row


def work_precision(args: argparse.Namespace, repeat: int, peers: dict[str, str | None]) -> int:
    """--work-precision: each engine at each of its settings, a table a scene, and the rows as JSON."""
    rows_out: list[dict] = []
    tables: list[str] = []
    for name in args.scenes:
        s = SCENES[name]
        entries: list[tuple[str, dict | None]] = [("kinema", k) for k in KINEMA_SETTINGS] if "kinema" in args.engines else []
        if peers.get(s.peer) and s.peer in args.engines:
            entries.append((s.peer, None))
        if peers.get(s.engine_peer) and s.engine_peer in args.engines:
            listed = BOX2D_SETTINGS_QUICK if (s.engine_peer == "box2d" and args.quick) else BOX2D_SETTINGS if s.engine_peer == "box2d" else JOLT_SETTINGS
            entries += [(s.engine_peer, {**k, "threads": args.peer_threads}) for k in listed]
        runs: list[list[dict]] = [[] for _ in entries]
        for k in range(repeat):  # interleaved: every entry once a round
            started = time.perf_counter()
            for (engine, setting), got in zip(entries, runs, strict=True):
                if sum(r["wall"] for r in got) < args.budget:
                    t0 = time.perf_counter()
                    got.append(spawn(engine, name, args.quick, args.threads, setting))
                    got[-1]["wall"] = time.perf_counter() - t0
            print(f"  {name}: round {k + 1} of {repeat} done in {time.perf_counter() - started:.0f} s", file=sys.stderr, flush=True)
        lines = []
        done = []
        for (engine, setting), got in zip(entries, runs, strict=True):
            row = median_row(got)
            words = setting_words(engine, setting)
            record = {"scene": name, "engine": engine, "setting": words, "parameters": setting or {}, "n": got[0].get("n"), "runs": len(got)}
            if row is None:
                record["error"] = next(r["error"] for r in got if "error" in r)[:300]
            else:
                record.update({k: row[k] for k in ("cpu", "sim", "overlap", "pen", "vmax", "disp_med", "disp_max", "ke", "asleep")})
                record["drift"] = row["drift"] if s.kind == "pyramid" else None
            done.append(record)
        done.sort(key=lambda r: (ENGINE_ORDER.index(r["engine"]), r.get("cpu", math.inf)))
        n = done[0]["n"]
        head = (
            f"{'engine':<9} {'setting':<36} {'cpu s':>8} {'wall s':>8} {'overlap/r':>10} {'wall pen/r':>10} {'max|v| m/s':>10} {'disp med m':>10} {'asleep':>7}"
        )
        if s.kind == "pyramid":
            head += f" {'drift m':>9}"
        lines.append(f"\n{name}: {n:,} {'discs' if s.dim == 2 else 'balls'}, {shrink(s).seconds if args.quick else s.seconds:g} s")
        lines += [head, "-" * len(head)]
        for r in done:
            if "error" in r:
                lines.append(f"{r['engine']:<9} {r['setting']:<36} failed: {r['error']}")
                continue
            line = f"{r['engine']:<9} {r['setting']:<36} {r['cpu']:>8.2f} {r['sim']:>8.2f} {r['overlap']:>10.2e} {r['pen']:>10.2e} {r['vmax']:>10.2e} {r['disp_med']:>10.2e} {'-' if r['asleep'] is None else format(r['asleep'], ','):>7}"
            if s.kind == "pyramid":
                line += f" {r['drift']:>9.2e}"
            lines.append(line)
        for (engine, _), got in zip(entries, runs, strict=True):
            told = next((r["told"] for r in got if r.get("told")), None)
            if told and not any(t.startswith(f"  {engine}: ") for t in lines):
                lines.append(f"  {engine}: {told}")
        rows_out += done
        tables += lines
        print("\n".join(lines), file=sys.stderr, flush=True)  # as it goes; the whole again at the end

    mode = "--quick: ~1/10 of the particles, 1 s; " if args.quick else ""
    peer_words = ", ".join(f"{p} {v}" if v else f"{p} missing" for p, v in peers.items())
    print(f"piles, work-precision: kinema ({args.threads} threads) beside {peer_words}; {mode}median of {repeat} interleaved runs; {os.cpu_count()} CPUs")
    print("cpu s: the CPU seconds of the steps (all threads of the process), wall s their wall seconds; overlap, wall pen: over the mean radius;")
    print("disp med: the median displacement over the last 0.1 s; asleep: bodies asleep at the end (pybullet: not told); sorted by engine, then cpu s")
    print("restitution: max(e_i, e_j) in kinema, Box2D, Jolt (the product rule with sqrt(e) per body in pymunk, pybullet); thresholds: kinema 2 g dt,")
    print("  Box2D 1 m/s, Jolt 1 m/s, Bullet 0.2 m/s, Chipmunk none; Box2D's contact hertz is capped at substeps / (8 dt) (->)")
    print("\n".join(tables))
    WORK_PRECISION_JSON.parent.mkdir(parents=True, exist_ok=True)
    WORK_PRECISION_JSON.write_text(
        json.dumps(
            {"quick": args.quick, "repeat": repeat, "threads": args.threads, "peer_threads": args.peer_threads, "peers": peers, "rows": rows_out}, indent=1
        )
    )
    print(f"\nthe rows: {WORK_PRECISION_JSON}")
    return 0


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] == "--worker":
        print(json.dumps(worker(sys.argv[2], sys.argv[3], "--quick" in sys.argv[5:], json.loads(sys.argv[4]) or None)))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", choices=list(SCENES), default=list(SCENES))
    ap.add_argument("--repeat", type=int, default=None, help="runs per engine and scene (default 3; 1 with --quick)")
    ap.add_argument("--threads", type=int, default=2, help="kinema's threads (RAYON_NUM_THREADS)")
    ap.add_argument("--peer-threads", type=int, default=1, help="Box2D's workers and Jolt's threads")
    ap.add_argument("--quick", action="store_true", help="every scene at ~1/10 of its particles, 1 s")
    ap.add_argument(
        "--budget",
        type=float,
        default=600.0,
        help="s: no further runs of an engine in a scene once its runs there took this long (a pour3d run takes ~20-30 min)",
    )
    ap.add_argument("--threads-scaling", action=argparse.BooleanOptionalAction, default=True, help="pour3d: kinema with 1 and 2 threads")
    ap.add_argument(
        "--peers",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="run the peers (--no-peers: kinema alone, e.g. for pour3d, whose pybullet run takes ~30 min)",
    )
    ap.add_argument(
        "--engines",
        nargs="+",
        choices=ENGINE_ORDER,
        default=list(ENGINE_ORDER),
        help="the engines to run (default all; e.g. --engines kinema jolt leaves out pour3d's 30-min pybullet run)",
    )
    ap.add_argument(
        "--work-precision",
        action="store_true",
        help="each engine at several settings (KINEMA_SETTINGS, BOX2D_SETTINGS, JOLT_SETTINGS): CPU s beside the rest figures; rows also to out/piles_work_precision.json",
    )
    args = ap.parse_args()
    repeat = args.repeat if args.repeat is not None else (1 if args.quick or args.work_precision else 3)
    if repeat < 1 or args.threads < 1 or args.peer_threads < 1:
        raise SystemExit("--repeat >= 1, --threads >= 1 and --peer-threads >= 1")

    peers: dict[str, str | None] = {"pymunk": version("pymunk"), "pybullet": version("pybullet")}
    for name, v in peers.items():
        if v is None and any(SCENES[s].peer == name for s in args.scenes):
            print(f"piles: {name} is missing (pip install -r requirements/bench.txt): kinema alone in its scenes", file=sys.stderr)
    wanted = sorted({SCENES[s].engine_peer for s in args.scenes})
    why_not = build_engine_peers() if args.peers else "--no-peers"
    for name in wanted:
        peers[name] = PEER_LIBRARIES[name] if why_not is None else None
        if why_not is not None and args.peers:
            print(f"piles: {name} skipped: {why_not}", file=sys.stderr)
    if not args.peers:
        peers = dict.fromkeys(peers)
    if args.work_precision:
        return work_precision(args, repeat, peers)

    results: dict[str, dict[str, list[dict]]] = {}
    scaling: dict[int, list[dict]] = {1: [], 2: []}
    for name in args.scenes:
        s = SCENES[name]
        peer = s.peer if peers[s.peer] and args.peers and s.peer in args.engines else None
        other = s.engine_peer if peers.get(s.engine_peer) and s.engine_peer in args.engines else None
        runs: dict[str, list[dict]] = {"kinema": [], **({peer: []} if peer else {}), **({other: []} if other else {})}
        scale = args.threads_scaling and name == "pour3d"
        # the runs of each engine: kinema at --threads, the peer, and for the scaling kinema at
        # 1 and 2 threads (the first list again where --threads is 1 or 2)
        lists: dict[tuple[str, int], list[dict]] = {("kinema", args.threads): runs["kinema"]}
        if peer:
            lists[(peer, args.threads)] = runs[peer]
        if other:
            lists[(other, args.threads)] = runs[other]
        settings = {"box2d": {**BOX2D_DEFAULT, "threads": args.peer_threads}, "jolt": {**JOLT_DEFAULT, "threads": args.peer_threads}}
        if scale:
            for t in (1, 2):
                scaling[t] = lists.setdefault(("kinema", t), scaling[t])
        for k in range(repeat):  # interleaved
            started = time.perf_counter()
            for (engine, t), got in lists.items():
                if sum(r["wall"] for r in got) < args.budget:  # the first run always
                    t0 = time.perf_counter()
                    got.append(spawn(engine, name, args.quick, t, settings.get(engine)))
                    got[-1]["wall"] = time.perf_counter() - t0
            print(f"  {name}: round {k + 1} of {repeat} done in {time.perf_counter() - started:.0f} s", file=sys.stderr, flush=True)
        results[name] = runs

    # -- the table
    mode = "--quick: ~1/10 of the particles, 1 s; " if args.quick else ""
    peer_words = ", ".join(f"{p} {v}" if v else f"{p} missing" for p, v in peers.items())
    print(
        f"piles at rest: kinema ({args.threads} threads) beside {peer_words}; dt = {DT * 1e3:g} ms, {ITERATIONS} solver iterations for the peers; "
        f"{mode}median of {repeat} interleaved runs (fewer, see runs, where an engine's runs of a scene passed --budget {args.budget:g} s); "
        f"{os.cpu_count()} CPUs"
    )
    print(
        f"box2d: {setting_words('box2d', None)} (Box2D's defaults), {args.peer_threads} worker(s); "
        f"jolt: {setting_words('jolt', None)}, {args.peer_threads} thread(s); restitution thresholds: kinema 2 g dt, "
        "Box2D 1 m/s, Jolt 1 m/s, Bullet 0.2 m/s, Chipmunk none"
    )
    print(
        "sim s: the steps alone (wall), cpu s: their CPU seconds (all threads); speed-up: on kinema's row pymunk's / pybullet's time over kinema's, "
        "on a box2d / jolt row its time over kinema's; disp: over the last 0.1 s; overlap, wall pen: over the mean radius"
    )
    head = table_row("scene", "engine", {k: title for k, title, _, _ in COLUMNS})
    print(head)
    print("-" * len(head))
    missed = False
    notes: list[str] = []
    for name, runs in results.items():
        s = SCENES[name]
        rows = {engine: median_row(rs) for engine, rs in runs.items()}
        kin = rows["kinema"]
        peer = s.peer if s.peer in runs else None
        if kin and peer and rows[peer]:
            kin["speedup"] = f"{rows[peer]['sim'] / kin['sim']:.2f}x"
        other = s.engine_peer if s.engine_peer in runs else None
        if kin and other and rows[other]:
            rows[other]["speedup"] = f"{rows[other]['sim'] / kin['sim']:.2f}x"
        for engine, row in rows.items():
            if row is None:
                print(f"{name:<10} {engine:<9} failed: {next(r['error'] for r in runs[engine] if 'error' in r)[:300]}")
                continue
            print(table_row(name, engine, {k: v for k, v in row.items() if k != "drift" or s.kind == "pyramid"}))
            bad = [r["error"] for r in runs[engine] if "error" in r]
            if bad:
                notes.append(f"{name} {engine}: {len(bad)} of {len(runs[engine])} runs failed: {bad[0][:300]}")
        goal = targets(s)
        print(table_row("", "target", {k: f"{op} {bound:g}{'x' if k == 'speedup' else ''}" for k, (op, bound) in goal.items()}))
        verdict = {}
        for k, (_, bound) in goal.items():
            if kin is None:
                verdict[k] = "FAIL"
            elif k == "speedup":
                if peer is None or rows[peer] is None:
                    continue
                verdict[k] = "PASS" if rows[peer]["sim"] / kin["sim"] >= bound else "FAIL"
            else:
                verdict[k] = "PASS" if kin[k] <= bound else "FAIL"  # NaN fails
        missed |= "FAIL" in verdict.values()
        print(table_row("", "kinema", verdict))
        for engine, rs in runs.items():
            ok = [r for r in rs if "error" not in r]
            if ok:
                extra = ", ".join(f"{k} {v:g}" for k, v in ok[0]["extra"].items())
                build = statistics.median(r["build"] for r in ok)
                told = f"; {ok[0]['told']}" if ok[0].get("told") else ""
                notes.append(f"{name} {engine}: build {build:.2f} s; {extra}{told}")

    for name, runs in results.items():
        slept = [r["sleep"] for r in runs["kinema"] if r.get("sleep")]
        if slept:
            asleep = statistics.median(x["asleep_ms"] for x in slept)
            awake = statistics.median(x["awake_ms"] for x in slept)
            word = "PASS" if asleep <= TARGET_SLEEP * awake else "FAIL"
            missed |= word == "FAIL"
            print(
                f"\n{name}, sleeping: {slept[0]['asleep']:,} of {runs['kinema'][0]['n']:,} particles asleep at the end; a step "
                f"{asleep:.2f} ms asleep, {awake:.2f} ms awake (sleep_time=None): {asleep / awake:.1%} (target <= {TARGET_SLEEP:.0%}) {word}"
            )

    if scaling[1] and scaling[2]:
        t1, t2 = (median_row(scaling[t]) for t in (1, 2))
        if t1 and t2:
            ratio = t1["sim"] / t2["sim"]
            word = "PASS" if ratio >= TARGET_THREADS else "FAIL"
            missed |= word == "FAIL"
            print(f"\npour3d, kinema threads: 1 thread {t1['sim']:.2f} s, 2 threads {t2['sim']:.2f} s: {ratio:.2f}x (target >= {TARGET_THREADS:g}x) {word}")
        else:
            print("\npour3d, kinema threads: a run failed, no ratio")
    print("\nper engine (first run): build time (not timed), and what the engine reports (kinema: collision_stats)")
    for line in notes:
        print(f"  {line}")
    print(f"kinema's targets: {'all met' if not missed else 'missed (FAIL above)'}")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
