"""Finding the simplices of a mesh: the facet (or element) with given nodes.
"""

from __future__ import annotations

import numpy as np


def find_columns(table: np.ndarray, query: np.ndarray) -> np.ndarray:
    """For each column of `query` (k, q), the index of the column of `table` (k, r) with the same
    numbers in any order, or -1 (the columns of `table` are distinct sets)."""
    both = np.sort(np.hstack((table, query)), axis=0)
    _, group = np.unique(both, axis=1, return_inverse=True)
    group = group.ravel()
    column = np.full(group.max() + 1 if group.size else 0, -1, dtype=np.int64)
    column[group[:table.shape[1]]] = np.arange(table.shape[1])
    return column[group[table.shape[1]:]]
