"""Refusal of triangle meshes that do not describe a plane body covered once by its triangles.

`check_triangles` raises CaseError, naming the mesh file, a node or triangle and the fix, for (in
this order)

- a triangle of zero area;
- an edge of more than two triangles, or two triangles on the same side of their common edge (a
  fold): the mesh covers a region twice;
- two distinct boundary nodes at one place: the mesh is cut along a seam there (a gmsh model whose
  surfaces do not share their common curves);
- boundary edges that cross (parts lying on top of each other), or that overlap along a line (the
  meshes of two surfaces that do not match on their common curve);
- a node where parts of the body touch only at that node (a hinge);
- a boundary loop next to which the mesh covers the plane more than once.

Why this is enough: skfem sorts each triangle's nodes, so the file's orientation is not used; each
triangle is turned counter-clockwise by the sign of its area instead. Without folds, the two
triangles of an inner edge then run through it in opposite directions, so the number of triangles
over a point (the degree) is the winding number of the boundary edges around it. Without crossing
or touching boundary edges and hinges, the boundary is a set of disjoint simple loops; the degree
only changes across a loop, and a region of the largest degree lies on the body's side of each loop
around it, so the degree is at most 1 everywhere once it is 1 next to each loop.

Every check is vectorized. Measured on the half disc with 580,000 triangles: 0.4 s, against 2.5–3 s
to read the same mesh from a gmsh file and 3–6 s to build it (`mesh.half_disc`).

The message pieces (`Names`, `more`), `check_finite`, `in_unit_box` and `check_coincident_nodes`
serve the checks of tetrahedral meshes too (`vpcontact.mesh.checks_3d`).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import CaseError, point
from .simplex import determinants, squared_edge_lengths

#: A triangle whose area is at most ZERO_AREA × (its longest edge)² has zero area.
ZERO_AREA = 1e-12
#: Nodes or boundary edges closer than COINCIDENT × (the diagonal of the nodes' bounding box) touch.
COINCIDENT = 1e-9
#: Smallest and largest mesh size (diagonal of the bounding box) accepted: squares and products of
#: lengths must stay far from underflow and overflow in double precision.
LENGTHS = (1e-100, 1e100)
#: Winding numbers are computed for at most this many (point, edge) pairs at once.
CHUNK = 2**22

FIX_SEAM = ("merge the duplicate nodes: in gmsh build the surfaces on shared points and curves, or use "
            "Coherence (Geometry.AutoCoherence = 1, Mesh > Coherence), then mesh again")
FIX_OVERLAP = ("each region must be meshed once: in gmsh, the curves bounding a surface must not cross, surfaces "
               "must not overlap (split them with BooleanFragments so that they share their common curves) and no "
               "surface may be listed twice")


class Names:
    """Message pieces: nodes by their number in the file and coordinates, elements by their position among
    the file's elements (`element_numbers`, from 1; default: their column in t plus 1)."""

    def __init__(self, label: str, p: np.ndarray, node_numbers: np.ndarray, element_numbers: np.ndarray | None = None):
        self.label, self.p, self.numbers, self.element_numbers = label, p, node_numbers, element_numbers

    def element(self, k: int) -> int:
        return k + 1 if self.element_numbers is None else int(self.element_numbers[k])

    def node(self, i: int) -> str:
        return f"node {self.numbers[i]} at {point(self.p[:, i])}"

    def triangle(self, k: int, t: np.ndarray) -> str:
        return f"triangle {self.element(k)} (nodes {', '.join(str(self.numbers[i]) for i in t[:, k])})"

    def error(self, text: str) -> CaseError:
        return CaseError(f"mesh file '{self.label}': {text}")


def more(count: int, what: str) -> str:
    """" (and 2 more nodes)" for count = 3 of what = "node"; "" for count = 1."""
    return f" (and {count - 1} more {what}{'s' if count > 2 else ''})" if count > 1 else ""


def check_finite(label: str, points: np.ndarray, node_numbers: np.ndarray) -> None:
    """Refuse nodes (columns of `points`) with a coordinate that is NaN or infinite."""
    bad = np.flatnonzero(~np.isfinite(points).all(axis=0))
    if bad.size:
        i = bad[0]
        raise CaseError(f"mesh file '{label}': node {node_numbers[i]} has the coordinates {point(points[:, i])}"
                        f"{more(bad.size, 'node')}: every coordinate must be a finite number; fix the program or "
                        f"edit that wrote the file")


def check_triangles(label: str, p: np.ndarray, t: np.ndarray, node_numbers: np.ndarray,
                    element_numbers: np.ndarray | None = None) -> None:
    """Raise CaseError unless the triangles `t` (3, m) on the finite nodes `p` (2, n), every node
    used, cover a plane region once (see the module docstring). `node_numbers` (n,): the nodes'
    numbers in the file; triangles are named by their position among the file's triangles (from 1;
    `element_numbers` (m,), default: their column in t plus 1)."""
    names = Names(label, p, node_numbers, element_numbers)
    p = in_unit_box(names, p)
    twice_area = _check_areas(names, p, t)
    start, end = _boundary_edges(names, p, t, twice_area)
    tol = COINCIDENT * float(np.linalg.norm(p.max(axis=1) - p.min(axis=1)))
    check_coincident_nodes(names, p, start, tol, FIX_SEAM)
    _check_boundary_crossings(names, p, start, end, tol)
    _check_hinges(names, start, end)
    _check_covered_once(names, p, start, end)


def in_unit_box(names: Names, p: np.ndarray) -> np.ndarray:
    """The nodes p (d, n) moved and scaled so that their bounding box is centred at 0 with diagonal 1:
    the checks then neither overflow nor underflow. CaseError if the mesh's size is outside LENGTHS."""
    low, high = p.min(axis=1), p.max(axis=1)
    diameter = math.hypot(*(0.5 * high - 0.5 * low)) * 2.0  # halves: no overflow near the largest float
    if diameter > 0.0 and not LENGTHS[0] <= diameter <= LENGTHS[1]:  # (0: all nodes at one place, zero areas)
        raise names.error(f"the mesh is {diameter:.3g} long: element computations need a size between "
                          f"{LENGTHS[0]:g} and {LENGTHS[1]:g}; write it in another length unit")
    return (p - 0.5 * (low + high)[:, None]) / (diameter or 1.0)


def _check_areas(names: Names, p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Twice the signed area of each triangle; CaseError if one is (relatively) zero."""
    twice_area = determinants(p, t)
    longest = squared_edge_lengths(p, t).max(axis=0)
    bad = np.flatnonzero(np.abs(twice_area) <= 2.0 * ZERO_AREA * longest)
    if bad.size:
        k = bad[0]
        corners = ", ".join(point(names.p[:, i]) for i in t[:, k])
        raise names.error(f"{names.triangle(k, t)} has zero area: its corners {corners} lie on one line"
                          f"{more(bad.size, 'triangle')}; remove it or mesh the geometry again")
    return twice_area


def _boundary_edges(names: Names, p: np.ndarray, t: np.ndarray, twice_area: np.ndarray):
    """(start, end) of the boundary edges, each oriented as in its triangle turned counter-clockwise;
    CaseError for an edge of more than two triangles or a fold."""
    n, m = p.shape[1], t.shape[1]
    # occurrence k·m + j: edge (t[k], t[k+1]) of triangle j; sorted by edge, equal edges are adjacent
    first, second = t.ravel(), t[[1, 2, 0]].ravel()
    keys = np.minimum(first, second).astype(np.int64) * n + np.maximum(first, second)
    order = np.argsort(keys)
    same = keys[order[1:]] == keys[order[:-1]]  # same[i]: occurrences order[i] and order[i + 1] share their edge
    bad = np.flatnonzero(same[1:] & same[:-1])
    if bad.size:
        a, b = first[order[bad[0]]], second[order[bad[0]]]
        many = np.count_nonzero(keys == keys[order[bad[0]]])
        raise names.error(f"the edge from {names.node(a)} to {names.node(b)} belongs to {many} triangles "
                          f"(at most 2 can share an edge): the mesh covers a region twice; {FIX_OVERLAP}")
    # The triangle lies on side s of its edge directed from the lower to the higher node number; the two
    # triangles of an inner edge must lie on opposite sides.
    side = np.sign(np.tile(twice_area, 3)) * np.where(first < second, 1.0, -1.0)
    inner = np.flatnonzero(same)
    folded = np.flatnonzero(side[order[inner]] == side[order[inner + 1]])
    if folded.size:
        one, other = order[inner[folded[0]]], order[inner[folded[0]] + 1]
        a, b = first[one], second[one]
        raise names.error(f"{names.triangle(one % m, t)} and {names.triangle(other % m, t)} lie on the same side of "
                          f"their common edge from {names.node(a)} to {names.node(b)}{more(folded.size, 'pair')}: "
                          f"the mesh is folded (tangled) there; {FIX_OVERLAP}")
    alone = np.ones(keys.size, dtype=bool)
    alone[1:] &= ~same
    alone[:-1] &= ~same
    single = order[alone]
    counter_clockwise = twice_area[single % m] > 0
    start = np.where(counter_clockwise, first[single], second[single])
    end = np.where(counter_clockwise, second[single], first[single])
    return start, end


def check_coincident_nodes(names: Names, p: np.ndarray, boundary_nodes: np.ndarray, tol: float, fix: str) -> None:
    """No two of the boundary nodes within `tol`: they cut the mesh along a seam. (Nodes inside the body
    at one place make a region covered twice, refused by the later checks.)"""
    nodes = np.unique(boundary_nodes)
    pairs = cKDTree(p[:, nodes].T).query_pairs(tol, output_type="ndarray")
    if pairs.size:
        i, j = nodes[pairs[0]]
        raise names.error(f"nodes {names.numbers[i]} and {names.numbers[j]} are both at {point(names.p[:, i])}"
                          f"{more(len(pairs), 'pair')}: the mesh is cut along a seam there; {fix}")


def _check_hinges(names: Names, start: np.ndarray, end: np.ndarray) -> None:
    """Two boundary edges meet at a boundary node; more: parts of the body touch only there."""
    ends = np.bincount(np.concatenate((start, end)))
    hinge = np.flatnonzero(ends > 2)
    if hinge.size:
        raise names.error(f"at {names.node(hinge[0])} parts of the body touch only at that node (a hinge: "
                          f"{ends[hinge[0]]} boundary edges meet there){more(hinge.size, 'node')}: join them along "
                          f"a curve or move them apart")


def _check_boundary_crossings(names: Names, p: np.ndarray, start: np.ndarray, end: np.ndarray, tol: float) -> None:
    """No two boundary edges cross or touch, except consecutive ones at their common node."""
    i, j = _nearby_segments(p[:, start], p[:, end], tol)
    a, b, c, d = p[:, start[i]], p[:, end[i]], p[:, start[j]], p[:, end[j]]

    def orient(x, y, z):
        return (y[0] - x[0]) * (z[1] - x[1]) - (y[1] - x[1]) * (z[0] - x[0])

    def distance(x, y, z):  # from point z to segment x–y
        s = y - x
        f = np.clip(((z - x) * s).sum(axis=0) / (s * s).sum(axis=0), 0.0, 1.0)
        return np.linalg.norm(z - x - f * s, axis=0)

    shares = (start[i] == start[j]) | (start[i] == end[j]) | (end[i] == start[j]) | (end[i] == end[j])
    crossing = ~shares & (orient(a, b, c) * orient(a, b, d) < 0) & (orient(c, d, a) * orient(c, d, b) < 0)
    # an end of one edge on the other edge, unless that end is a node of the other edge
    touching = np.zeros_like(crossing)
    for z, node, x, y, own in ((c, start[j], a, b, i), (d, end[j], a, b, i),
                               (a, start[i], c, d, j), (b, end[i], c, d, j)):
        touching |= (node != start[own]) & (node != end[own]) & (distance(x, y, z) <= tol)
    # touching along a common line: two meshes of one curve that do not match; across: an overlap
    along = np.abs(orient(a, b, a + d - c)) <= 1e-9 * np.linalg.norm(b - a, axis=0) * np.linalg.norm(d - c, axis=0)
    for bad, what in ((crossing | (touching & ~along),
                       f"cross: parts of the mesh lie on top of each other; {FIX_OVERLAP}"),
                      (touching & along, f"overlap along a line: the mesh is not joined there (the meshes of two "
                                         f"surfaces do not match on their common curve); {FIX_SEAM}")):
        if bad.any():
            k = np.argmax(bad)
            raise names.error(f"the boundary edges from {names.node(start[i[k]])} to {names.node(end[i[k]])} and "
                              f"from {names.node(start[j[k]])} to {names.node(end[j[k]])}"
                              f"{more(np.count_nonzero(bad), 'pair')} {what}")


def _nearby_segments(a: np.ndarray, b: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j), i ≠ j, of segments a–b (columns) that may be within `tol` of each other.

    Segments are grouped by length in powers of two; a segment of the group of lengths up to L is
    paired with every segment no longer than L whose midpoint is within L + tol of its own."""
    mid, length = 0.5 * (a + b), np.linalg.norm(b - a, axis=0)
    group = np.floor(np.log2(length / length.min())).astype(np.int64)
    pairs = []
    for g in np.unique(group):
        longer, shorter = np.flatnonzero(group == g), np.flatnonzero(group <= g)
        found = cKDTree(mid[:, longer].T).sparse_distance_matrix(
            cKDTree(mid[:, shorter].T), 2.0 ** (g + 1) * length.min() + tol, output_type="ndarray")
        i, j = shorter[found["j"]], longer[found["i"]]
        keep = (group[i] < g) | (i < j)
        pairs.append(np.vstack((i[keep], j[keep])))
    i, j = np.hstack(pairs)
    return i, j


def _check_covered_once(names: Names, p: np.ndarray, start: np.ndarray, end: np.ndarray) -> None:
    """Just inside the body next to one edge of each boundary loop, the winding number of the
    boundary (the number of triangles over that point) is 1.

    It is the limit at the edge's midpoint from its left (the body's side): 1/2 for the edge itself,
    plus the angles the other boundary edges subtend at the midpoint over 2π."""
    n = p.shape[1]
    graph = sp.coo_matrix((np.ones(start.size), (start, end)), shape=(n, n))
    _, loop = connected_components(graph, directed=False)
    _, first = np.unique(loop[start], return_index=True)
    points = 0.5 * (p[:, start[first]] + p[:, end[first]])  # (2, loops)
    winding = np.empty(first.size)
    rows = max(1, CHUNK // start.size)
    for s in range(0, first.size, rows):
        q = points[:, s:s + rows, None]
        u, v = p[:, None, start] - q, p[:, None, end] - q
        angle = np.arctan2(u[0] * v[1] - u[1] * v[0], (u * v).sum(axis=0))
        angle[np.arange(angle.shape[0]), first[s:s + rows]] = np.pi
        winding[s:s + rows] = angle.sum(axis=1) / (2.0 * np.pi)
    bad = np.flatnonzero(np.abs(winding - 1.0) > 1e-6)
    if bad.size:
        k = bad[0]
        raise names.error(f"the part of the mesh along the boundary through {names.node(start[first[k]])} lies on "
                          f"top of other triangles (covered {winding[k]:.3g} times){more(bad.size, 'boundary loop')}; "
                          f"{FIX_OVERLAP}")
