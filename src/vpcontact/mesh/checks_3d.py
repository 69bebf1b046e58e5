"""The checks of a tetrahedral mesh (what they refuse and in which order: `vpcontact.mesh.checks`):
`check_tetrahedra`. A mesh of several pieces passes (a piece is then one more body to hold).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .checks import Names, check_coincident_nodes, check_measures, in_unit_box, match_facets, more

FIX_SEAM = ("merge the duplicate nodes: in gmsh build the volumes on shared points, curves and surfaces, or use "
            "Coherence (Geometry.AutoCoherence = 1, or BooleanFragments on all volumes), then mesh again")
FIX_OVERLAP = ("each region must be meshed once: in gmsh, volumes must not overlap (split them with BooleanFragments "
               "so that they share their common surfaces) and no volume may be listed twice")
FIX_HINGE = "join them along a surface or move them apart"

#: The faces of a tetrahedron (its local nodes), face l opposite node l.
FACES = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
#: The node opposite face l lies on the side (−1)^(l + 1) · sign(volume) of the face's nodes in FACES order.
FACE_SIDE = np.array([-1.0, 1.0, -1.0, 1.0])


def check_tetrahedra(label: str, p: np.ndarray, t: np.ndarray, node_numbers: np.ndarray,
                     element_numbers: np.ndarray | None = None) -> None:
    """Raise CaseError unless the tetrahedra `t` (4, m) on the finite nodes `p` (3, n), every node used,
    cover a body once (see the module docstring). `node_numbers` (n,): the nodes' numbers in the file;
    tetrahedra are named by their position among the file's tetrahedra (from 1; `element_numbers` (m,),
    default: their column in t plus 1)."""
    names = Names(label, p, node_numbers, element_numbers)
    p = in_unit_box(names, p)
    faces = _boundary_faces(names, t, check_measures(names, p, t))
    check_coincident_nodes(names, p, faces.ravel(), FIX_SEAM)
    _check_hinges(names, faces)


def _boundary_faces(names: Names, t: np.ndarray, six_volume: np.ndarray) -> np.ndarray:
    """The boundary faces (3, k): node triples, each ordered so that its tetrahedron lies on its negative
    side (right-hand rule: the normal points out of the body); CaseError for a face of more than two
    tetrahedra or a fold."""
    m = t.shape[1]
    # occurrence l·m + j: face l of tetrahedron j, its nodes sorted; equal faces are adjacent once sorted
    listed = t[FACES].transpose(1, 0, 2).reshape(3, -1)  # (3, 4m), column l·m + j
    order_in_face = np.argsort(listed, axis=0, kind="stable")
    nodes = np.take_along_axis(listed, order_in_face, axis=0)
    inversions = (order_in_face[0] > order_in_face[1]).astype(int) + (order_in_face[0] > order_in_face[2]) \
        + (order_in_face[1] > order_in_face[2])
    side = np.repeat(FACE_SIDE, m) * np.sign(np.tile(six_volume, 4)) * (1 - 2 * (inversions % 2))
    order = np.lexsort(nodes[::-1])
    sorted_nodes = nodes[:, order]
    same = (sorted_nodes[:, 1:] == sorted_nodes[:, :-1]).all(axis=0)  # occurrences order[i], order[i + 1]

    def face(occurrence: int) -> str:
        return ", ".join(str(names.numbers[i]) for i in nodes[:, occurrence])

    crowded, folded, single = match_facets(order, same, side)
    if crowded.size:
        first = order[crowded[0]]
        many = np.count_nonzero((nodes == nodes[:, [first]]).all(axis=0))
        raise names.error(f"the face with nodes {face(first)} belongs to {many} tetrahedra (at most 2 can share a "
                          f"face): the mesh covers a region twice; {FIX_OVERLAP}")
    if folded.size:
        one, other = order[folded[0]], order[folded[0] + 1]
        raise names.error(f"{names.element(one % m, t)} and {names.element(other % m, t)} lie on the "
                          f"same side of their common face with nodes {face(one)}{more(folded.size, 'pair')}: the "
                          f"mesh is folded (tangled) there; {FIX_OVERLAP}")
    faces = nodes[:, single]
    inward = side[single] > 0  # the tetrahedron on the positive side: swap two nodes
    faces[1:, inward] = faces[2:0:-1, inward]
    return faces


def _check_hinges(names: Names, faces: np.ndarray) -> None:
    """Each boundary edge is an edge of exactly two boundary faces, and the boundary faces around each
    boundary node form one fan (faces joined through their common edges at that node)."""
    k = faces.shape[1]
    # occurrence r·k + f: edge (faces[r], faces[r + 1 mod 3]) of face f, its nodes sorted
    first, second = faces.ravel(), faces[[1, 2, 0]].ravel()
    low, high = np.minimum(first, second), np.maximum(first, second)
    order = np.lexsort((high, low))
    same = (low[order[1:]] == low[order[:-1]]) & (high[order[1:]] == high[order[:-1]])
    starts = np.flatnonzero(np.concatenate(([True], ~same)))
    count = np.diff(np.append(starts, order.size))
    bad = np.flatnonzero(count != 2)  # a closed boundary has an even number of faces at each edge
    if bad.size:
        e = order[starts[bad[0]]]
        raise names.error(f"along the edge from {names.node(low[e])} to {names.node(high[e])} parts of the body "
                          f"touch only at that edge (a hinge: {count[bad[0]]} boundary faces meet there)"
                          f"{more(bad.size, 'edge')}: {FIX_HINGE}")
    # Corner c·k + f: node faces[c, f] in face f. The two faces of a boundary edge join their corners at
    # each end of the edge; a node whose corners fall into more than one group is a hinge.
    one, other = order[starts], order[starts + 1]
    corner = np.arange(3 * k).reshape(3, k)

    def corner_at(occurrence: np.ndarray, node: np.ndarray) -> np.ndarray:
        r, f = occurrence // k, occurrence % k
        here = faces[r, f] == node
        return np.where(here, corner[r, f], corner[(r + 1) % 3, f])

    i = np.concatenate((corner_at(one, low[one]), corner_at(one, high[one])))
    j = np.concatenate((corner_at(other, low[one]), corner_at(other, high[one])))
    graph = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(3 * k, 3 * k))
    _, group = connected_components(graph, directed=False)
    node_of_group = np.zeros(group.max() + 1, dtype=np.int64)
    node_of_group[group] = faces.ravel()
    fans = np.bincount(node_of_group)
    hinge = np.flatnonzero(fans > 1)
    if hinge.size:
        raise names.error(f"at {names.node(hinge[0])} parts of the body touch only at that node (a hinge: the "
                          f"boundary around it is {fans[hinge[0]]} separate fans of faces){more(hinge.size, 'node')}: "
                          f"{FIX_HINGE}")
