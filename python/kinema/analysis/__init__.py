"""What a granular researcher measures, from particles and their contacts (docs/analysis.md).

- The contact table (``World.contacts()``'s dict of arrays) checked by
  :func:`contact_table`, or built from geometry alone by :func:`geometric_contacts`; a
  :class:`Snapshot` holds one moment of a World or a Trajectory frame.
- :func:`coordination`: the coordination number, rattlers removed (:class:`Coordination`).
- :func:`fabric`: the fabric tensor and its anisotropy (:class:`Fabric`).
- :func:`force_distribution`: P(f/⟨f⟩) (:class:`ForceDistribution`).
- :func:`angle_of_repose`: a heap's angle from its free surface (:class:`Repose`).
- :func:`slab_fields`, :func:`grid_fields`: coarse-grained density, velocity, kinetic and
  contact stress (:class:`Fields`) with the kernels :class:`Gaussian`, :class:`Lucy`.
- :func:`janssen_pressure`, :func:`janssen_wall_pressure` (closed forms) and
  :func:`wall_pressure` (measured on the walls, :class:`WallPressure`).

Each function takes arrays (positions (N, 3) m, masses kg, velocities m/s, the contact
table), so that it can be fed from a World, a trajectory, or another program's output."""

from .contacts import FIELDS, contact_table, geometric_contacts
from .coordination import Coordination, coordination
from .fabric import Fabric, fabric
from .fields import Fields, grid_fields, slab_fields
from .force_distribution import ForceDistribution, force_distribution
from .janssen import WallPressure, janssen_pressure, janssen_wall_pressure, wall_pressure
from .kernels import Binning, Gaussian, Lucy
from .repose import Repose, angle_of_repose
from .snapshot import Snapshot

__all__ = [
    "FIELDS",
    "Binning",
    "Coordination",
    "Fabric",
    "Fields",
    "ForceDistribution",
    "Gaussian",
    "Lucy",
    "Repose",
    "Snapshot",
    "WallPressure",
    "angle_of_repose",
    "contact_table",
    "coordination",
    "fabric",
    "force_distribution",
    "geometric_contacts",
    "grid_fields",
    "janssen_pressure",
    "janssen_wall_pressure",
    "slab_fields",
    "wall_pressure",
]
