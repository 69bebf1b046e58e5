"""Refusal of a mesh file whose elements do not describe a body covered once by them: what is refused, in
which order, and the pieces the checks of triangles and of tetrahedra share.

`vpcontact.mesh.read.read_mesh` refuses nodes with a coordinate that is not finite (`check_finite`), then
checks the triangles of a 2D mesh (`vpcontact.mesh.checks_2d.check_triangles`) or the tetrahedra of a 3D
one (`vpcontact.mesh.checks_3d.check_tetrahedra`). Each raises CaseError, naming the mesh file, a node or
element and the fix, for (in this order)

- a mesh longer than 1e100 or shorter than 1e-100: the nodes are moved and scaled into a box of diagonal
  1 (`in_unit_box`), where no check overflows or underflows;
- an element of zero area or volume (`check_measures`);
- a facet (edge, face) of more than two elements, or two elements on the same side of their common facet
  (a fold): the mesh covers a region twice;
- two distinct boundary nodes at one place: the mesh is cut along a seam there (a gmsh model whose
  surfaces do not share their common curves, or whose volumes do not share their common surfaces;
  `check_coincident_nodes`);
- in 2D, boundary edges that cross (parts lying on top of each other), or that overlap along a line (the
  meshes of two surfaces that do not match on their common curve);
- a node, or in 3D an edge, where parts of the body touch only there (a hinge), about which they could turn
  freely;
- in 2D, a boundary loop next to which the mesh covers the plane more than once.

The orientation of the elements in the file is not used: each one's side of a facet follows from the sign
of its area or volume. Every check is vectorized. Measured on the half disc with 580,000 triangles: 0.4 s,
against 2.5–3 s to read the same mesh from a gmsh file and 3–6 s to build it (`mesh.half_disc`); on the
quarter ball with 514,500 tetrahedra (`mesh.quarter_ball`): 0.8 s, against 4.1 s for meshio to read it from
a gmsh 2.2 file.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from ..errors import CaseError, point
from .cells import SIMPLICES
from .simplex import determinants, longest_edges

#: An element whose measure (area, volume) is at most ZERO_MEASURE × (its longest edge)^d is flat.
ZERO_MEASURE = 1e-12
#: Nodes or boundary edges closer than COINCIDENT × (the diagonal of the nodes' bounding box) touch.
COINCIDENT = 1e-9
#: Smallest and largest mesh size (diagonal of the bounding box) accepted: squares and products of
#: lengths must stay far from underflow and overflow in double precision.
LENGTHS = (1e-100, 1e100)


class Names:
    """Message pieces: nodes by their number in the file and coordinates, elements by their position among
    the file's elements (`element_numbers`, from 1; default: their column in t plus 1)."""

    def __init__(self, label: str, p: np.ndarray, node_numbers: np.ndarray, element_numbers: np.ndarray | None = None):
        self.label, self.p, self.numbers, self.element_numbers = label, p, node_numbers, element_numbers

    def element(self, k: int, t: np.ndarray) -> str:
        """Element k of the elements t (d + 1, m): "triangle 7 (nodes 3, 9, 4)"."""
        number = k + 1 if self.element_numbers is None else int(self.element_numbers[k])
        return f"{SIMPLICES[t.shape[0] - 1].name} {number} (nodes {', '.join(str(self.numbers[i]) for i in t[:, k])})"

    def node(self, i: int) -> str:
        return f"node {self.numbers[i]} at {point(self.p[:, i])}"

    def error(self, text: str) -> CaseError:
        return CaseError(f"{self.label}: {text}")


def more(count: int, what: str) -> str:
    """" (and 2 more nodes)" for count = 3 of what = "node"; "" for count = 1."""
    return f" (and {count - 1} more {what}{'s' if count > 2 else ''})" if count > 1 else ""


def check_finite(label: str, points: np.ndarray, node_numbers: np.ndarray) -> None:
    """Refuse nodes (columns of `points`) with a coordinate that is NaN or infinite."""
    bad = np.flatnonzero(~np.isfinite(points).all(axis=0))
    if bad.size:
        i = bad[0]
        raise CaseError(f"{label}: node {node_numbers[i]} has the coordinates {point(points[:, i])}"
                        f"{more(bad.size, 'node')}: every coordinate must be a finite number; fix the program or "
                        f"edit that wrote the file")


def in_unit_box(names: Names, p: np.ndarray) -> np.ndarray:
    """The nodes p (d, n) moved and scaled so that their bounding box is centred at 0 with diagonal 1:
    the checks then neither overflow nor underflow. CaseError if the mesh's size is outside LENGTHS."""
    low, high = p.min(axis=1), p.max(axis=1)
    diameter = math.hypot(*(0.5 * high - 0.5 * low)) * 2.0  # halves: no overflow near the largest float
    if diameter > 0.0 and not LENGTHS[0] <= diameter <= LENGTHS[1]:  # (0: all nodes at one place, zero areas)
        raise names.error(f"the mesh is {diameter:.3g} long: element computations need a size between "
                          f"{LENGTHS[0]:g} and {LENGTHS[1]:g}; write it in another length unit")
    return (p - 0.5 * (low + high)[:, None]) / (diameter or 1.0)


def check_measures(names: Names, p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """det J of each element t (d + 1, m) on the nodes p (d, n) in the unit box: d! times its signed area or
    volume (`vpcontact.mesh.simplex.determinants`); CaseError if one is (relatively) zero."""
    d = p.shape[0]
    det = determinants(p, t)
    bad = np.flatnonzero(np.abs(det) <= math.factorial(d) * ZERO_MEASURE * longest_edges(p, t) ** d)
    if bad.size:
        k, simplex = bad[0], SIMPLICES[d]
        corners = ", ".join(point(names.p[:, i]) for i in t[:, k])
        raise names.error(f"{names.element(k, t)} has zero {simplex.measure}: its corners {corners} lie "
                          f"{simplex.flat}{more(bad.size, simplex.name)}; remove it or mesh the geometry again")
    return det


def check_coincident_nodes(names: Names, p: np.ndarray, boundary_nodes: np.ndarray, fix: str) -> None:
    """No two of the boundary nodes within the distance at which they touch (`touching_distance`): they cut
    the mesh along a seam. (Nodes inside the body at one place make a region covered twice, refused by the
    other checks.)"""
    nodes = np.unique(boundary_nodes)
    pairs = cKDTree(p[:, nodes].T).query_pairs(touching_distance(p), output_type="ndarray")
    if pairs.size:
        i, j = nodes[pairs[0]]
        raise names.error(f"nodes {names.numbers[i]} and {names.numbers[j]} are both at {point(names.p[:, i])}"
                          f"{more(len(pairs), 'pair')}: the mesh is cut along a seam there; {fix}")


def touching_distance(p: np.ndarray) -> float:
    """The distance below which nodes or boundary edges of the nodes p (d, n) touch: COINCIDENT × the
    diagonal of their bounding box."""
    return COINCIDENT * float(np.linalg.norm(p.max(axis=1) - p.min(axis=1)))


def match_facets(order: np.ndarray, same: np.ndarray, side: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Match the occurrences of the facets in the elements (occurrence: facet l of element j), given ``order``,
    the occurrences sorted so that those of one facet are adjacent (``same[i]``: order[i] and order[i + 1] are
    one facet), and ``side``, the side of its facet each occurrence's element lies on (±1). Returns the
    positions i in ``order`` where a facet has a third occurrence (an error: at most two elements share a
    facet), those i where the two elements of an inner facet lie on one side of it (order[i], order[i + 1]:
    a fold), and the occurrences of the facets of one element only: the boundary."""
    crowded = np.flatnonzero(same[1:] & same[:-1])
    inner = np.flatnonzero(same)
    folded = inner[side[order[inner]] == side[order[inner + 1]]]
    alone = np.ones(order.size, dtype=bool)
    alone[1:] &= ~same
    alone[:-1] &= ~same
    return crowded, folded, order[alone]
