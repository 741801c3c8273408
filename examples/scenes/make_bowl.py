"""Writes bowl.obj beside this script: the open hemispherical bowl of bowl.toml.

The inside of a sphere of radius R = 0.5 m centred at (0, 0, 0.5), its lower half: the bottom
at the origin, the rim the circle z = 0.5 m. A UV sphere cut at the equator: the pole, then
RINGS rings of latitude (polar angle θ_i = i (π/2) / RINGS from the bottom, the last one the
rim at θ = π/2), each of SEGMENTS vertices at the longitudes φ_j = 2π j / SEGMENTS:

    vertex = c + R (sin θ cos φ, sin θ sin φ, −cos θ)

The pole is joined to the first ring by a fan of SEGMENTS triangles, each pair of rings by
SEGMENTS quads cut into two triangles: SEGMENTS (2 RINGS − 1) = 19,800 triangles on 10,001
shared vertices, one connected surface, open at the rim (so two-sided for the engine). Each
triangle runs counter-clockwise seen from the centre (its normal points into the bowl).

Every vertex lies on the sphere (to the 1e-9 m the file writes); the flat triangles lie inside
it by at most their chord sag, R − (the distance from c to the triangle's plane), 1.2e-4 m here
(printed): a ball of radius r rests in the bowl with its centre R − r from c, less up to that.

    python examples/scenes/make_bowl.py        # writes examples/scenes/bowl.obj
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

RADIUS = 0.5  # m, the inner radius
CENTER = (0.0, 0.0, 0.5)  # m, the sphere's centre: the bowl's rim is at z = 0.5
RINGS = 50  # rings of latitude from the bottom to the rim (θ steps of 1.8°)
SEGMENTS = 200  # vertices per ring (φ steps of 1.8°: the rim's quads are nearly square)


def bowl(radius: float = RADIUS, center=CENTER, rings: int = RINGS, segments: int = SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """The bowl's vertices (V, 3), m, and triangles (F, 3), 0-based vertex indices."""
    theta = np.arange(1, rings + 1) * (np.pi / 2) / rings
    phi = np.arange(segments) * 2 * np.pi / segments
    sin_t, cos_t = np.sin(theta), np.cos(theta)
    sin_t[-1], cos_t[-1] = 1.0, 0.0  # the rim exactly at z = c_z
    ring = np.stack(
        [np.outer(sin_t, np.cos(phi)), np.outer(sin_t, np.sin(phi)), -np.repeat(cos_t[:, None], segments, axis=1)],
        axis=-1,
    ).reshape(-1, 3)
    vertices = np.asarray(center) + radius * np.concatenate([[[0.0, 0.0, -1.0]], ring])

    def at(i: int, j: np.ndarray) -> np.ndarray:  # vertex of ring i (1-based), longitude j
        return 1 + (i - 1) * segments + j % segments

    j = np.arange(segments)
    faces = [np.stack([np.zeros(segments, dtype=np.int64), at(1, j), at(1, j + 1)], axis=1)]  # the pole's fan
    for i in range(1, rings):
        lower, upper = at(i, j), at(i + 1, j)
        lower_next, upper_next = at(i, j + 1), at(i + 1, j + 1)
        faces.append(np.stack([lower, upper, upper_next], axis=1))
        faces.append(np.stack([lower, upper_next, lower_next], axis=1))
    return vertices, np.concatenate(faces).astype(np.int64)


def chord_sag(vertices: np.ndarray, faces: np.ndarray, radius: float = RADIUS, center=CENTER) -> float:
    """The most a triangle lies inside the sphere: R − the distance from c to its plane, m."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return float(np.max(radius - np.abs(np.einsum("ij,ij->i", n, a - np.asarray(center)))))


def write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    lines = ["# kinema examples/scenes/make_bowl.py: an open hemispherical bowl, R = 0.5 m, centre (0, 0, 0.5), rim at z = 0.5 (m)"]
    lines += [f"v {x:.9f} {y:.9f} {z:.9f}" for x, y, z in vertices]
    lines += [f"f {i + 1} {j + 1} {k + 1}" for i, j, k in faces]
    path.write_text("\n".join(lines) + "\n", encoding="ascii")


def main() -> None:
    vertices, faces = bowl()
    # counter-clockwise seen from the centre: each normal points into the bowl
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), np.asarray(CENTER) - (a + b + c) / 3)
    assert np.all(inward > 0), "a triangle faces out of the bowl"
    path = Path(__file__).resolve().parent / "bowl.obj"
    write_obj(path, vertices, faces)
    print(f"{path}: {len(vertices)} vertices, {len(faces)} triangles, chord sag {chord_sag(vertices, faces):.3e} m")


if __name__ == "__main__":
    main()
