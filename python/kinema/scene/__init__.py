"""Scene files: a whole simulation (particles, forces, colliders, settings, outputs) in TOML.

``Scene.from_toml(path)`` reads and validates a file (pydantic models in strict mode: unknown
keys are errors, and no value is converted to another type but an integer to a float, so
``dt = "1e-3"``, ``mass = true`` or ``count = 2.0`` are refused; values nested more than
``MAX_NESTING`` deep are refused before validation); ``scene.build()`` makes the ``World``;
``load_scene(path)`` does both and keeps the scene on the world (``world.scene``) so that ``kinema run`` knows duration, fps and outputs.
``world.to_scene()`` describes a world as it is now, as one explicit particle list, and
``scene.to_toml(path)`` writes it (tomli-w); reading that file back gives an identical world.

The format, key by key with units, is in docs/scenes.md.

The package: ``tables`` (the value types and the models of the file's tables), ``schema``
(``Scene``, the whole file, with reading, writing and ``SceneError``'s messages), ``build``
(scene -> ``World``: ``build``, which ``Scene.build`` calls through ``schema.BUILDERS``, and ``load_scene``) and ``export`` (world -> scene:
``to_scene``, the body of ``World.to_scene``).
"""

from __future__ import annotations

from .build import load_scene
from .export import to_scene
from .schema import Scene, SceneError
from .schema import block_size as block_size  # kinema.runner's work estimate
from .tables import Isotropic, Maxwell, Uniform

__all__ = ["Isotropic", "Maxwell", "Scene", "SceneError", "Uniform", "load_scene", "to_scene"]
