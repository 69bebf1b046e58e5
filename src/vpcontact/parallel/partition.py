"""The mesh's nodes shared among the ranks of a run: METIS's partition of the node graph (pymetis), each node and
its dofs owned by one rank.

A contact node belongs to the rank of its node, with its dofs: its normal frame, its law's values, its multiplier
and its history ξ are that rank's in the step solver. The ranks' nodes are numbered one rank after the other
(PETSc's numbering: rank q owns the rows offset_q .. offset_{q+1} − 1 of the nodal layout, dof d · node +
component), each rank's nodes in the mesh's order. Rank 0 partitions and sends the owners to the others, so every
rank holds the same partition whatever its METIS build would do with ties.
"""

from __future__ import annotations

import signal
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .ranks import Ranks


def node_graph(elements: np.ndarray, nodes: int) -> sp.csr_matrix:
    """The graph of the nodes that share an element (nodes per element, elements), without its diagonal."""
    per = elements.shape[0]
    first = np.repeat(np.arange(per), per)
    second = np.tile(np.arange(per), per)
    keep = first != second
    rows, cols = elements[first[keep]].ravel(), elements[second[keep]].ravel()
    graph = sp.csr_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(nodes, nodes))
    graph.sum_duplicates()
    return graph


def metis_owners(elements: np.ndarray, nodes: int, parts: int) -> np.ndarray:
    """The part (0..parts − 1) of every node by METIS's k-way partition of the node graph, which balances the
    nodes of the parts and makes the edges between them few.

    SIGTERM is held while METIS runs and delivered when it returns: METIS's GKlib takes SIGTERM for its own error
    signal (its SIGERR), so a SIGTERM inside it made the partition fail ("RuntimeError: Caught an unknown
    exception!" from pymetis) instead of reaching the run's handler. MPI_Abort sends one to every rank: a rank
    stopped that way while partitioning printed a failure of its own beside the rank that failed (measured once in
    about ten runs of tests/test_mpi.py's failing-rank test)."""
    import pymetis

    graph = node_graph(elements, nodes)
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
    try:
        if hasattr(pymetis, "CSRAdjacency"):  # newer pymetis: xadj/adjncy deprecated, to be removed in 2027
            _, owners = pymetis.part_graph(parts, pymetis.CSRAdjacency(graph.indptr, graph.indices))
        else:
            _, owners = pymetis.part_graph(parts, xadj=graph.indptr, adjncy=graph.indices)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
    return np.asarray(owners, dtype=np.int64)


@dataclass(frozen=True)
class NodePartition:
    """Which rank owns each node (``owner``), and the nodes in PETSc's numbering (``numbered[node]``: rank by rank,
    each rank's nodes in the mesh's order; this rank's are ``offset .. offset + count − 1``)."""

    ranks: Ranks
    owner: np.ndarray
    numbered: np.ndarray
    offset: int
    count: int

    @classmethod
    def of(cls, elements: np.ndarray, nodes: int, ranks: Ranks) -> "NodePartition":
        """The partition of a mesh with ``elements`` (nodes per element, elements) and ``nodes`` nodes among
        ``ranks``: METIS's on rank 0, sent to the others."""
        owner = metis_owners(elements, nodes, ranks.size) if ranks.root else None
        owner = ranks.first(owner)
        order = np.lexsort((np.arange(nodes), owner))  # rank by rank, the mesh's order within each
        numbered = np.empty(nodes, dtype=np.int64)
        numbered[order] = np.arange(nodes)
        counts = np.bincount(owner, minlength=ranks.size)
        return cls(ranks, owner, numbered, int(counts[: ranks.rank].sum()), int(counts[ranks.rank]))
