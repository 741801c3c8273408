"""Writes drum.obj beside this script: the closed cylindrical drum of drum.toml.

A cylinder of radius R = 0.25 m and depth D = 0.08 m, its axis the y axis, centred at the
origin: the side a prism of SEGMENTS rectangular facets between two rings of SEGMENTS vertices
at y = ±D/2,

    vertex = (R cos φ_j, ±D/2, R sin φ_j),    φ_j = 2π j / SEGMENTS,

each facet cut into two triangles; each end cap a fan of SEGMENTS triangles from its centre
(0, ±D/2, 0). 4 SEGMENTS = 512 triangles on 2 SEGMENTS + 2 = 258 shared vertices; every edge is
shared by two triangles running along it in opposite directions (a closed mesh), each normal
pointing out of the drum, so that drum.toml can hold the grains inside it (``inside = true``).

Every side vertex lies on the circle of radius R; the facets lie inside it by at most their
chord sag R (1 − cos(π / SEGMENTS)), 7.5e-5 m here (printed): a grain of radius r touches the
side with its centre at most R − r from the axis.

    python examples/scenes/make_drum.py        # writes examples/scenes/drum.obj
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

RADIUS = 0.25  # m, the inner radius
DEPTH = 0.08  # m, between the end caps (y from −DEPTH/2 to DEPTH/2)
SEGMENTS = 128  # facets around the axis (2.8° each)


def drum(radius: float = RADIUS, depth: float = DEPTH, segments: int = SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """The drum's vertices (V, 3), m, and triangles (F, 3), 0-based vertex indices, each
    running counter-clockwise seen from outside (normals outwards)."""
    phi = np.arange(segments) * 2 * np.pi / segments
    x, z = radius * np.cos(phi), radius * np.sin(phi)
    back = np.stack([x, np.full(segments, -depth / 2), z], axis=1)  # ring j: index j
    front = np.stack([x, np.full(segments, depth / 2), z], axis=1)  # ring j: index segments + j
    centres = np.array([[0.0, -depth / 2, 0.0], [0.0, depth / 2, 0.0]])
    vertices = np.concatenate([back, front, centres])
    j = np.arange(segments)
    k = (j + 1) % segments
    b, f = j, segments + j
    b1, f1 = k, segments + k
    cb, cf = np.full(segments, 2 * segments), np.full(segments, 2 * segments + 1)
    # (b1 − b) × (f1 − b) ≈ ẑ × ŷ = −x̂ at φ = 0, inwards: so the side runs b, f1, b1; the back
    # cap's (b − cb) × (b1 − cb) ≈ x̂ × ẑ = −ŷ, outwards (main() checks every one)
    side = [np.stack([b, f1, b1], axis=1), np.stack([b, f, f1], axis=1)]
    caps = [np.stack([cb, b, b1], axis=1), np.stack([cf, f1, f], axis=1)]
    return vertices, np.concatenate(side + caps).astype(np.int64)


def chord_sag(radius: float = RADIUS, segments: int = SEGMENTS) -> float:
    """The most a side facet lies inside the circle: R (1 − cos(π / SEGMENTS)), m."""
    return radius * (1.0 - np.cos(np.pi / segments))


def write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    lines = [f"# kinema examples/scenes/make_drum.py: a closed drum, R = {RADIUS} m, depth {DEPTH} m, axis y through the origin (m)"]
    lines += [f"v {x:.9f} {y:.9f} {z:.9f}" for x, y, z in vertices]
    lines += [f"f {i + 1} {j + 1} {k + 1}" for i, j, k in faces]
    path.write_text("\n".join(lines) + "\n", encoding="ascii")


def main() -> None:
    vertices, faces = drum()
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    centroid = (a + b + c) / 3
    outward = np.einsum("ij,ij->i", normal, centroid)  # the drum's centre is the origin
    assert np.all(outward > 0), "a triangle faces into the drum"
    path = Path(__file__).resolve().parent / "drum.obj"
    write_obj(path, vertices, faces)
    print(f"{path}: {len(vertices)} vertices, {len(faces)} triangles, chord sag {chord_sag():.2e} m")


if __name__ == "__main__":
    main()
