"""kinema: particle systems that move by honest numerical methods.

The public API (everything else is private):

- ODEs: ``solve``, ``solve_second_order``, ``Solution``, ``DenseSolution``, ``ButcherTableau``, ``methods``,
  ``method_names``, ``MethodInfo``, ``SolverWarning``
- Stability on p' = λp: the module ``kinema.stability``
- Particle worlds: ``World``, the forces ``Gravity``, ``Drag``, ``Spring``, ``Attractor``,
  ``Wind``, ``PythonForce``, the force fields ``Turbulence`` (curl noise) and ``Vortex``
  shaped by a ``Falloff``, the recorded ``Trajectory`` and ``SimulationDiverged``
- Births and deaths: ``Emitter`` (``EmitterWarning``) and the kill volumes ``KillBox``, ``KillSphere``,
  ``KillPlane`` (added with ``World.add``), ``World.remove_particles``, ``World.ids``,
  ``Trajectory.alive``; the module ``kinema.emitter``
- Collisions: the colliders ``Plane``, ``Box``, ``SphereObstacle``, ``Mesh`` (a triangle
  mesh from a file or arrays; added with ``World.add``; ``MeshPlacementWarning``), moved by ``Motion`` (steady) or
  ``Keyframes`` (their ``motion=``, ``World.set_motion``); ``World.set_collisions``,
  ``World.collisions``, ``World.periodic``, ``World.contacts``, ``World.collision_stats``,
  ``World.collider_books``; per-particle ``restitution`` and ``friction`` in
  ``World.add_particles``
- Trajectory files: ``Trajectory.save`` (H5MD), ``load_trajectory``, ``Trajectory.export``
  (VTK, PLY, extended XYZ, CSV); the module ``kinema.io``
- Pictures: ``render_frames`` (2D discs, 3D shaded spheres, coloured by speed, id or a field,
  with a time stamp), ``write_video`` (H.264 MP4, GIF), ``Camera2D``, ``Camera3D``; the
  module ``kinema.render``
- Scene files (TOML): ``load_scene``, ``Scene``, ``SceneError``, ``World.to_scene``; the
  module ``kinema.scene`` (docs/scenes.md)
- Checkpoints: ``World.save_checkpoint``, ``World.load_checkpoint``, ``World.run(checkpoint=,
  checkpoint_every=)`` and ``resume_run``; the module ``kinema.checkpoint``
- Sweeps and ensembles on Dask: ``sweep``, ``SweepResult``; the module ``kinema.sweeps``
- Measured orders of accuracy: ``convergence``, ``ConvergenceResult``, the module
  ``kinema.problems`` (problems with exact solutions)
- Granular analysis: the module ``kinema.analysis`` (coordination number, fabric tensor,
  contact-force distribution, angle of repose, coarse-grained fields, Janssen's silo;
  docs/analysis.md)
"""

import importlib as _importlib
import os as _os
from typing import TYPE_CHECKING as _TYPE_CHECKING

from . import problems, stability
from ._core import __version__, _after_fork_in_child
from .colliders import Box, Keyframes, Mesh, MeshPlacementWarning, Motion, Plane, SphereObstacle
from .contact_time import ContactTimeWarning
from .convergence import ConvergenceResult, convergence
from .emitter import Emitter, EmitterWarning, KillBox, KillPlane, KillSphere
from .forces import Attractor, Drag, Falloff, Gravity, PythonForce, Spring, Turbulence, Vortex, Wind
from .ode import (
    ButcherTableau,
    DenseSolution,
    MethodInfo,
    Solution,
    SolverWarning,
    method_names,
    methods,
    solve,
    solve_second_order,
)
from .trajectory import Trajectory
from .world import PlacementWarning, SimulationDiverged, StabilityWarning, World

# Imported at first use (PEP 562): scene files (pydantic), checkpoints (h5py), pictures, analysis,
# and sweeps. A script that only steps a world does not pay for them: `import kinema`
# took 30 MB and 0.3 s with them, which at 10⁶ particles was 30 B a particle of the process's
# peak (issue 51; README "Performance").
_SUBMODULES = {"analysis", "io", "render", "scene", "sweeps", "checkpoint"}
_LAZY = {
    "resume_run": "checkpoint",
    "Camera2D": "render",
    "Camera3D": "render",
    "render_frames": "render",
    "write_video": "render",
    "Scene": "scene",  # (importing kinema.scene gives Scene its build method: kinema.scene.build)
    "SceneError": "scene",
    "load_scene": "scene",
    "SweepResult": "sweeps",
    "sweep": "sweeps",
}


if _TYPE_CHECKING:  # (what a type checker reads; at run time each is imported at first use)
    from . import analysis, io, render, scene
    from . import checkpoint as checkpoint
    from . import sweeps as sweeps
    from .checkpoint import resume_run
    from .render import Camera2D, Camera3D, render_frames, write_video
    from .scene import Scene, SceneError, load_scene
    from .sweeps import SweepResult, sweep


def __getattr__(name: str):
    """A submodule or a name of one, imported at its first use."""
    if name in _LAZY:
        value = getattr(_importlib.import_module(f".{_LAZY[name]}", __name__), name)
    elif name in _SUBMODULES:
        value = _importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'kinema' has no attribute {name!r}")
    globals()[name] = value  # (the next look is a plain one)
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | _SUBMODULES | set(_LAZY))


load_trajectory = Trajectory.load

__all__ = [
    "__version__",
    "analysis",
    "Attractor",
    "Box",
    "Camera2D",
    "Camera3D",
    "Drag",
    "Emitter",
    "EmitterWarning",
    "Falloff",
    "KillBox",
    "KillPlane",
    "KillSphere",
    "Gravity",
    "Keyframes",
    "Mesh",
    "MeshPlacementWarning",
    "Motion",
    "Plane",
    "Scene",
    "SceneError",
    "load_scene",
    "scene",
    "PythonForce",
    "SimulationDiverged",
    "SphereObstacle",
    "PlacementWarning",
    "StabilityWarning",
    "ContactTimeWarning",
    "Spring",
    "sweep",
    "SweepResult",
    "Trajectory",
    "Turbulence",
    "Vortex",
    "io",
    "load_trajectory",
    "render",
    "render_frames",
    "resume_run",
    "write_video",
    "Wind",
    "World",
    "ButcherTableau",
    "ConvergenceResult",
    "DenseSolution",
    "MethodInfo",
    "Solution",
    "SolverWarning",
    "convergence",
    "method_names",
    "methods",
    "problems",
    "solve",
    "solve_second_order",
    "stability",
]

# A child forked after the engine ran has none of its threads (fork copies only the thread that
# called it); the child's forking thread builds a pool of its own (docs/world.md, "Threads and processes").
_os.register_at_fork(after_in_child=_after_fork_in_child)
