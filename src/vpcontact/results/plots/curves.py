"""The contact nodes of a 2D body in their order along Γ3, and the arc length there: the abscissa of the
figures along Γ3 and of ``result.contact_table()``'s ``arc_length``."""

from __future__ import annotations

import numpy as np


def along_curve(segments: np.ndarray, count: int) -> np.ndarray:
    """The nodes 0, …, count − 1 of a curve made of ``segments`` (2, s), in their order along it:
    each connected piece from one of its ends (any node of a closed piece), piece after piece."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components, depth_first_order

    graph = sp.coo_matrix((np.ones(segments.shape[1]), (segments[0], segments[1])), shape=(count, count)).tocsr()
    pieces, label = connected_components(graph, directed=False)
    degree = np.bincount(segments.ravel(), minlength=count)
    order = []
    for piece in range(pieces):
        members = np.flatnonzero(label == piece)
        ends = members[degree[members] == 1]
        start = ends[0] if ends.size else members[0]
        order.append(depth_first_order(graph, start, directed=False, return_predecessors=False))
    return np.concatenate(order)


def arc_length(coordinates: np.ndarray, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contact nodes in their order along a curve made of ``segments`` (2, s) (a curve of one open
    piece runs from its end of least x, then least y), the arc length at each (going on from one piece
    to the next), and the positions in that order where a new piece starts."""
    m = coordinates.shape[1]
    order = along_curve(segments, m)
    if tuple(coordinates[:, order[-1]]) < tuple(coordinates[:, order[0]]):
        order = order[::-1]
    keys = np.sort(segments, axis=0)
    pairs = np.sort(np.vstack([order[:-1], order[1:]]), axis=0)
    joined = np.isin(pairs[0] * m + pairs[1], keys[0] * m + keys[1])
    step = np.linalg.norm(np.diff(coordinates[:, order], axis=1), axis=0)
    return order, np.concatenate([[0.0], np.cumsum(np.where(joined, step, 0.0))]), np.flatnonzero(~joined) + 1
