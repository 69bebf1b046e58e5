"""The checks of a triangle mesh (what they refuse and in which order: `vpcontact.mesh.checks`):
`check_triangles`.

Why they are enough: skfem sorts each triangle's nodes, so the file's orientation is not used; each
triangle is turned counter-clockwise by the sign of its area instead. Without folds, the two
triangles of an inner edge then run through it in opposite directions, so the number of triangles
over a point (the degree) is the winding number of the boundary edges around it. Without crossing
or touching boundary edges and hinges, the boundary is a set of disjoint simple loops; the degree
only changes across a loop, and a region of the largest degree lies on the body's side of each loop
around it, so the degree is at most 1 everywhere once it is 1 next to each loop.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .checks import Names, check_coincident_nodes, check_measures, in_unit_box, match_facets, more, touching_distance

#: Winding numbers are computed for at most this many (point, edge) pairs at once.
CHUNK = 2**22

FIX_SEAM = ("merge the duplicate nodes: in gmsh build the surfaces on shared points and curves, or use "
            "Coherence (Geometry.AutoCoherence = 1, Mesh > Coherence), then mesh again")
FIX_OVERLAP = ("each region must be meshed once: in gmsh, the curves bounding a surface must not cross, surfaces "
               "must not overlap (split them with BooleanFragments so that they share their common curves) and no "
               "surface may be listed twice")


def check_triangles(label: str, p: np.ndarray, t: np.ndarray, node_numbers: np.ndarray,
                    element_numbers: np.ndarray | None = None) -> None:
    """Raise CaseError unless the triangles `t` (3, m) on the finite nodes `p` (2, n), every node
    used, cover a plane region once (see the module docstring). `node_numbers` (n,): the nodes'
    numbers in the file; triangles are named by their position among the file's triangles (from 1;
    `element_numbers` (m,), default: their column in t plus 1)."""
    names = Names(label, p, node_numbers, element_numbers)
    p = in_unit_box(names, p)
    start, end = _boundary_edges(names, p, t, check_measures(names, p, t))
    check_coincident_nodes(names, p, start, FIX_SEAM)
    _check_boundary_crossings(names, p, start, end, touching_distance(p))
    _check_hinges(names, start, end)
    _check_covered_once(names, p, start, end)


def _boundary_edges(names: Names, p: np.ndarray, t: np.ndarray, twice_area: np.ndarray):
    """(start, end) of the boundary edges, each oriented as in its triangle turned counter-clockwise;
    CaseError for an edge of more than two triangles or a fold."""
    n, m = p.shape[1], t.shape[1]
    # occurrence k·m + j: edge (t[k], t[k+1]) of triangle j; sorted by edge, equal edges are adjacent
    first, second = t.ravel(), t[[1, 2, 0]].ravel()
    keys = np.minimum(first, second).astype(np.int64) * n + np.maximum(first, second)
    order = np.argsort(keys)
    same = keys[order[1:]] == keys[order[:-1]]  # same[i]: occurrences order[i] and order[i + 1] share their edge
    # The triangle lies on side s of its edge directed from the lower to the higher node number; the two
    # triangles of an inner edge must lie on opposite sides.
    side = np.sign(np.tile(twice_area, 3)) * np.where(first < second, 1.0, -1.0)
    crowded, folded, single = match_facets(order, same, side)
    if crowded.size:
        a, b = first[order[crowded[0]]], second[order[crowded[0]]]
        many = np.count_nonzero(keys == keys[order[crowded[0]]])
        raise names.error(f"the edge from {names.node(a)} to {names.node(b)} belongs to {many} triangles "
                          f"(at most 2 can share an edge): the mesh covers a region twice; {FIX_OVERLAP}")
    if folded.size:
        one, other = order[folded[0]], order[folded[0] + 1]
        a, b = first[one], second[one]
        raise names.error(f"{names.element(one % m, t)} and {names.element(other % m, t)} lie on the same side of "
                          f"their common edge from {names.node(a)} to {names.node(b)}{more(folded.size, 'pair')}: "
                          f"the mesh is folded (tangled) there; {FIX_OVERLAP}")
    counter_clockwise = twice_area[single % m] > 0
    start = np.where(counter_clockwise, first[single], second[single])
    end = np.where(counter_clockwise, second[single], first[single])
    return start, end


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
