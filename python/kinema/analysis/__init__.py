"""What a granular researcher measures, from particles and their contacts (docs/analysis.md).

- The contact table (``World.contacts()``'s dict of arrays) checked by
  :func:`contact_table`, or built from geometry alone by :func:`geometric_contacts`; a
  :class:`Snapshot` holds one moment of a World or a Trajectory frame.
- :func:`coordination`: the coordination number, rattlers removed (:class:`Coordination`).
- :func:`fabric`: the fabric tensor and its anisotropy (:class:`Fabric`).
- :func:`force_distribution`: P(f/⟨f⟩) (:class:`ForceDistribution`).
- :func:`angle_of_repose`: a heap's angle from its free surface (:class:`Repose`).
- :func:`janssen_pressure`, :func:`janssen_wall_pressure` (closed forms) and
  :func:`wall_pressure` (measured on the walls, :class:`WallPressure`).

Each function takes arrays (positions (N, 3) m, masses kg, velocities m/s, the contact
table), so that it can be fed from a World, a trajectory, or another program's output."""

from .contacts import FIELDS, contact_table, geometric_contacts
from .coordination import Coordination, coordination
from .fabric import Fabric, fabric
from .force_distribution import ForceDistribution, force_distribution
from .janssen import WallPressure, janssen_pressure, janssen_wall_pressure, wall_pressure
from .repose import Repose, angle_of_repose
from .snapshot import Snapshot

__all__ = [
    "FIELDS",
    "Coordination",
    "Fabric",
    "ForceDistribution",
    "Repose",
    "Snapshot",
    "WallPressure",
    "angle_of_repose",
    "contact_table",
    "coordination",
    "fabric",
    "force_distribution",
    "geometric_contacts",
    "janssen_pressure",
    "janssen_wall_pressure",
    "wall_pressure",
]
