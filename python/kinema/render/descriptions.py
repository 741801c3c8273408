"""Colliders as plain descriptions (the dicts ``Trajectory.colliders`` holds), the form the
engine's ``_core.Scenery`` takes them in."""

from __future__ import annotations

import numpy as np

_KIND = {"plane": ("point", "normal"), "box": ("lo", "hi"), "sphere": ("center", "radius")}


def _describe_colliders(colliders) -> list[dict]:
    """Plain descriptions of colliders (``kinema.Plane``, ``Box``, ``SphereObstacle`` or such
    descriptions already): {"type": "plane", "point": [3], "normal": [3]}, {"type": "box",
    "lo": [2 or 3], "hi": [2 or 3]} (bounds may be ±inf), {"type": "sphere", "center": [3],
    "radius": r}, with "restitution" and "friction" where the collider sets them."""
    from ..colliders import Box, Plane, SphereObstacle

    def floats(name, value, sizes=(3,)):
        a = np.asarray(value, dtype=np.float64).reshape(-1)
        if a.size not in sizes:
            raise ValueError(f"{name} = {value!r} is invalid: it must have {' or '.join(map(str, sizes))} values")
        return a.tolist()

    out = []
    for k, c in enumerate(colliders):
        if isinstance(c, Plane):
            d = {"type": "plane", "point": c.point, "normal": c.normal}
        elif isinstance(c, Box):
            d = {"type": "box", "lo": c.lo, "hi": c.hi}
        elif isinstance(c, SphereObstacle):
            d = {"type": "sphere", "center": c.center, "radius": c.radius}
        elif isinstance(c, dict) and c.get("type") in _KIND:
            d = dict(c)
        else:
            raise ValueError(
                f"colliders[{k}] = {c!r} is invalid: use kinema.Plane, Box or SphereObstacle, or a description "
                "{'type': 'plane' | 'box' | 'sphere', ...} (Trajectory.colliders)"
            )
        try:
            if d["type"] == "box":
                d["lo"], d["hi"] = floats(f"colliders[{k}].lo", d["lo"], (2, 3)), floats(f"colliders[{k}].hi", d["hi"], (2, 3))
            elif d["type"] == "sphere":
                d["center"], d["radius"] = floats(f"colliders[{k}].center", d["center"]), float(d["radius"])
            else:
                d["point"], d["normal"] = floats(f"colliders[{k}].point", d["point"]), floats(f"colliders[{k}].normal", d["normal"])
        except KeyError as e:
            raise ValueError(f"colliders[{k}] = {c!r} is invalid: a {d['type']} needs {' and '.join(_KIND[d['type']])}, it has no {e}") from None
        for name in ("restitution", "friction"):
            value = getattr(c, name, None) if not isinstance(c, dict) else c.get(name)
            if value is not None:
                d[name] = float(value)
            else:
                d.pop(name, None)
        out.append(d)
    return out
