"""METIS's partition of the node graph (vpcontact.parallel.partition.metis_owners) through the pymetis installed,
without the calls pymetis deprecates (its xadj/adjncy keywords are to be removed in 2027: a run on two ranks would
then fail)."""

import warnings

import numpy as np
import pytest

from vpcontact.parallel.partition import metis_owners, node_graph


def test_metis_splits_a_square_into_two_balanced_connected_parts_without_deprecated_calls():
    pytest.importorskip("pymetis")
    n = 20  # a structured triangulation of the unit square, (n + 1)² nodes
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    corners = index[:-1, :-1].ravel(), index[:-1, 1:].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel()
    elements = np.hstack([np.vstack((corners[0], corners[1], corners[3])),
                          np.vstack((corners[0], corners[3], corners[2]))])
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        owners = metis_owners(elements, (n + 1) ** 2, 2)
    counts = np.bincount(owners, minlength=2)
    assert owners.shape == ((n + 1) ** 2,) and set(owners) == {0, 1}
    assert abs(counts[0] - counts[1]) <= 0.05 * counts.sum(), counts
    graph = node_graph(elements, (n + 1) ** 2).tocoo()
    cut = np.count_nonzero(owners[graph.row] != owners[graph.col]) // 2
    assert cut <= 3 * (n + 1), cut  # a cut across the square, not a scatter (a random split cuts about half the edges)
