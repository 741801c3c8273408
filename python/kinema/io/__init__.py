"""Trajectory files: H5MD (HDF5) to save and load runs, and exports for other programs.

- `save_h5md(traj, path)` / `load_h5md(path)`: the H5MD 1.1 layout, read back exactly
  (needs h5py). Loading checks what it reads (shapes, types and the memory needed before
  any data is read, then the values) and names the file, the dataset and the bad value.
- `export(traj, path, format)`: VTK PolyData series with a .pvd collection and the
  colliders (ParaView, OVITO), PLY per frame (Blender, Houdini), extended XYZ (OVITO, ASE),
  CSV, GSD (HOOMD, OVITO), a LAMMPS dump (OVITO, ASE, VMD), and a trajectory's contacts
  as LAMMPS `dump local` files (`read_contacts_dump` reads them back) and VTK lines.
- `TrajectoryFileError`: a file that cannot be read, or a target refused before writing (a
  `ValueError` whose message is one line naming the file).
- `FileWriteError`: a write the system failed (a full disk, a file-size limit, an I/O
  error; an `OSError` with the system's `errno`, one line naming the file).

Births and deaths (`Trajectory.alive`) are written by every format: H5MD keeps one column
per particle with its `id` element's fill value where it does not exist (and reads it back,
with the springs), the exports write each frame's live particles with their ids.

Every writer writes under a temporary name and renames at the end: a failed write leaves no
partial file behind and the previous file as it was.
"""

from ._files import FileWriteError, TrajectoryFileError
from .exports import FORMATS, export
from .h5md import LoadedTrajectory, load_h5md, save_h5md
from .read_lammps import read_contacts_dump
from .units import UnitWarning

__all__ = ["FORMATS", "FileWriteError", "LoadedTrajectory", "TrajectoryFileError", "UnitWarning", "export", "load_h5md", "read_contacts_dump", "save_h5md"]
