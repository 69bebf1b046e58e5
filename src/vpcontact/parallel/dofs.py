"""The free dofs of one rank: those of its nodes (its rows of the stiffness matrix), and the ghosts, the other ranks'
dofs its rows reach; the exchange that brings the ghosts' values, and the reductions of the step solver.

``Dofs`` is what a step solver on all the dofs of one process uses (every exchange is the identity and every
reduction the value itself); ``RankDofs`` is one rank's share of them. A rank's vectors hold its own free dofs
first, then its ghosts (:meth:`RankDofs.ghosted`), so that its rows of a matrix, whose columns are numbered
that way, multiply a ghosted vector like a whole matrix a whole vector.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .partition import NodePartition


#: The norms whose sums of squares lose no digit to overflow or to subnormal numbers.
SQUARES_SAFE = (1e-140, 1e140)


def norm(x: np.ndarray) -> float:
    """‖x‖₂, accurate for every finite x: the sum of squares overflows from entries of about 1e154 on and
    underflows below 1e-154, and a norm of inf or 0 would make residuals relative to it 0 or a nonzero
    vector look null (false convergences), so the norm is then taken of x over its largest entry. inf or
    NaN only for an x that is not finite."""
    with np.errstate(over="ignore", under="ignore"):
        value = float(np.linalg.norm(x))
    if SQUARES_SAFE[0] < value < SQUARES_SAFE[1]:
        return value
    largest = float(np.max(np.abs(x), initial=0.0))
    if largest == 0.0 or not np.isfinite(largest):
        return largest
    return largest * float(np.linalg.norm(x / largest))


class Dofs:
    """All the free dofs, in one process."""

    def ghosted(self, x: np.ndarray) -> np.ndarray:
        """x with the ghosts' values appended (none here)."""
        return x

    def sum(self, value):
        """The sum over the ranks (here, the value)."""
        return value

    def norm(self, x: np.ndarray) -> float:
        """‖x‖₂ over every rank's x."""
        return float(np.linalg.norm(x))

    def safe_norm(self, x: np.ndarray) -> float:
        """‖x‖₂ over every rank's x, without overflow or underflow (:func:`vpcontact.solvers.base.norm`)."""
        return norm(x)

    def max(self, value: float) -> float:
        """The largest of ``value`` over the ranks."""
        return value

    def same(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether a and b are equal on every rank."""
        return bool(np.array_equal(a, b))


#: The dofs of a step solver in one process.
ALL_DOFS = Dofs()


class RankDofs(Dofs):
    """One rank's free dofs (``owned``: their positions among the free dofs, ascending, which is PETSc's order) and
    its ``ghosts`` (positions among the free dofs: every free dof of the other ranks' nodes that share an
    element with this rank's, grouped by their rank), for the free dofs ``free`` of a d-dimensional mesh
    partitioned by ``partition``; ``petsc`` is the PETSc index of each of this rank's local columns (owned, then
    ghosts) in the nodal layout."""

    def __init__(self, partition: NodePartition, free: np.ndarray, dim: int, A: sp.csr_matrix):
        """``A``: the stiffness on the free dofs, whose pattern says which dofs a rank's rows reach."""
        self.partition, self.ranks = partition, partition.ranks
        node_of_free = free // dim
        owner_of_free = partition.owner[node_of_free]
        rank = self.ranks.rank
        self.owned = np.flatnonzero(owner_of_free == rank)
        reached = np.unique(A[self.owned].indices)
        ghost_nodes = np.unique(node_of_free[reached[owner_of_free[reached] != rank]])
        # whole nodes: a contact node's frame turns all of its dofs together
        ghosts = np.flatnonzero(np.isin(node_of_free, ghost_nodes))
        self.ghosts = ghosts[np.argsort(owner_of_free[ghosts], kind="stable")]
        columns = np.concatenate([self.owned, self.ghosts])
        self.local = np.full(free.size, -1, dtype=np.int64)  # free position -> local column (−1: not here)
        self.local[columns] = np.arange(columns.size)
        self.petsc = dim * partition.numbered[node_of_free[columns]] + free[columns] % dim
        self._plan_exchange(owner_of_free)

    def _plan_exchange(self, owner_of_free: np.ndarray) -> None:
        """Which owned values go to which rank, and how many ghosts come from each: every rank tells each owner
        the dofs it needs of it (one all-to-all at set-up)."""
        comm, size = self.ranks.comm, self.ranks.size
        self._receive_counts = np.bincount(owner_of_free[self.ghosts], minlength=size)
        wanted = comm.alltoall(np.split(self.ghosts, np.cumsum(self._receive_counts)[:-1]))
        self._send_counts = np.array([piece.size for piece in wanted])
        self._send = self.local[np.concatenate(wanted)] if wanted else np.zeros(0, dtype=np.int64)

    def ghosted(self, x: np.ndarray) -> np.ndarray:
        """x (this rank's dofs) followed by the ghosts' values from their ranks."""
        x = np.asarray(x)
        received = np.empty(self.ghosts.size, dtype=x.dtype)
        sent = np.ascontiguousarray(x[self._send])
        if x.dtype == bool:
            received = received.view(np.uint8)
            sent = sent.view(np.uint8)
        self.ranks.comm.Alltoallv((sent, self._send_counts), (received, self._receive_counts))
        return np.concatenate([x, received.view(x.dtype)])

    def sum(self, value):
        return self.ranks.sum(value)

    def norm(self, x: np.ndarray) -> float:
        return float(np.sqrt(self.ranks.sum(float(x @ x))))

    def safe_norm(self, x: np.ndarray) -> float:
        largest = self.ranks.max(float(np.max(np.abs(x), initial=0.0)))
        if largest == 0.0 or not np.isfinite(largest):
            return largest
        scaled = x / largest
        return largest * float(np.sqrt(self.ranks.sum(float(scaled @ scaled))))

    def max(self, value: float) -> float:
        return self.ranks.max(value)

    def same(self, a: np.ndarray, b: np.ndarray) -> bool:
        return self.ranks.all(np.array_equal(a, b))

    def gather(self, x: np.ndarray, total: int) -> np.ndarray:
        """The whole vector over the ``total`` free dofs of which this rank holds x (its own dofs), on every rank."""
        return self.ranks.gather(np.asarray(x)[: self.owned.size], self.owned, total)
