"""The shape and size of a mesh's elements: what ``vpcontact check`` reports before a run.

The quality of a simplex T of dimension d is its mean ratio, from its measure |T| and its edge lengths l:

    q = 4 √3 |T| / Σ l²               (triangles)
    q = 12 (3 |T|)^(2/3) / Σ l²       (tetrahedra)

1 for the equilateral triangle and the regular tetrahedron, → 0 as the element flattens (Liu and Joe,
"Relationship between tetrahedron shape measures", BIT 34, 1994: the mean ratio is equivalent to the
other usual measures, the radius ratio and the minimum solid angle). The size of an element is its
longest edge (the h of ``Mesh.h``, here per element: `vpcontact.mesh.simplex.longest_edges`).
"""

from __future__ import annotations

import math

import numpy as np

from .simplex import measures, squared_edge_lengths


def mean_ratio(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """The quality q in [0, 1] of each simplex (see the module's docstring)."""
    d = points.shape[0]
    squares = squared_edge_lengths(points, cells).sum(axis=0)
    volume = measures(points, cells)
    if d == 2:
        return 4.0 * math.sqrt(3.0) * volume / squares
    return 12.0 * (3.0 * volume) ** (2.0 / 3.0) / squares


def smallest_angles(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The smallest interior angle (radians) of each triangle (3, elements) of the nodes ``points`` (2, nodes)."""
    corners = points[:, triangles]  # (2, 3, elements)
    angles = []
    for a in range(3):
        u = corners[:, (a + 1) % 3] - corners[:, a]
        v = corners[:, (a + 2) % 3] - corners[:, a]
        angles.append(np.arctan2(np.abs(u[0] * v[1] - u[1] * v[0]), (u * v).sum(axis=0)))
    return np.min(angles, axis=0)
