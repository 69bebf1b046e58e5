"""Conjugate gradients preconditioned by algebraic multigrid: the iterative backend of the
linear-solver layer (:mod:`.linear`), the modern form of the paper's preconditioned CG.

The preconditioner is one V-cycle of pyamg's smoothed aggregation, built (``analyse``) on the first
Newton matrix and reused for the later ones of every step (``factor`` only records the matrix): the
Newton matrices differ only in the contact nodes' normal stiffness and in which of their normal dofs
are fixed, and one hierarchy serves them all (measured on the quarter ball at 24k dofs: 11–12 CG
iterations to 1e-8 for the first, fifth and thirtieth Newton matrix with the hierarchy of any of
them). A hierarchy built on the bulk operator with the reference stiffness r at every contact node
(the condensed method's A0) needed 33–42: r is the elastic normal stiffness, far above a soft
layer's. Should a solve need more than REBUILD_AFTER iterations, the hierarchy is built again on the
next matrix. Elasticity needs two things for aggregation to work, both given here:

- the block form: the dofs of a node are one d × d block (pyamg's BSR), so aggregates never split a
  node's components. The system lives on the free dofs; it is embedded in the nodal block layout
  with an identity row (scaled like the diagonal) at every Dirichlet dof. With a contact normal
  that is not a coordinate axis, the scalar form took 484 iterations where the block form took 20.
- the near-null space: the rigid-body motions (3 in 2D, 6 in 3D), in the system's coordinates.

A Newton matrix may hold unknowns reduced to their diagonal entry (the fixed dofs of
:mod:`.normal_frame`): the preconditioner solves those exactly and applies the V-cycle to the rest
(z = P M⁻¹ P r + D⁻¹ (I − P) r, SPD like M), so fixing dofs does not disturb it.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..progress import SILENT, Progress
from .errors import NotConvergedError

#: The prolongation smoothed by energy minimization, and one block Gauss–Seidel sweep before (forward)
#: and after (backward) each coarse correction: a symmetric V-cycle, as CG needs. Against pyamg's
#: default (Jacobi-smoothed prolongation, a symmetric sweep each side), on a 24k-dof Newton matrix of
#: the quarter ball: 11 CG iterations to 1e-8 either way, 17 ms each instead of 24 (the sweeps are
#: most of a V-cycle's time); setup 0.76 s instead of 0.44 s, once.
SMOOTHING = {"smooth": "energy", "presmoother": ("block_gauss_seidel", {"sweep": "forward"}),
             "postsmoother": ("block_gauss_seidel", {"sweep": "backward"})}
#: CG iterations at most per solve (a NotConvergedError beyond).
MAX_ITERATIONS = 500
#: A solve that needed more CG iterations than this has the hierarchy rebuilt on the next matrix.
REBUILD_AFTER = 40


def decoupled_rows(A: sp.csr_matrix) -> np.ndarray:
    """The unknowns A reduces to their diagonal entry (a mask): rows whose only nonzero is a positive diagonal, the
    normal frame's fixed dofs, which the preconditioners solve exactly around their V-cycle."""
    stored = np.diff(A.indptr)
    nonzeros = np.zeros(stored.size, dtype=np.int64)
    nonzeros[stored > 0] = np.add.reduceat(A.data != 0.0, A.indptr[:-1][stored > 0])
    return (nonzeros == 1) & (A.diagonal() > 0.0)


class AMGConjugateGradient:
    """CG preconditioned by smoothed aggregation in nodal blocks.

    ``free`` are the system's dofs among the d · nodes of the nodal layout (dof d · node + component),
    ``near_nullspace`` (free dofs, k) the rigid-body motions in the system's coordinates."""

    name = "amg-cg"
    label = "pyamg's smoothed aggregation"

    def __init__(self, free: np.ndarray, dim: int, nodes: int, near_nullspace: np.ndarray,
                 progress: Progress = SILENT, expected: str = ""):
        """``progress`` hears of each hierarchy built (its start line ends with ``expected``: what is expected
        of it, in words)."""
        self.free, self.dim, self.size = np.asarray(free), dim, dim * nodes
        self.near_nullspace = near_nullspace
        self.progress, self._expected = progress, expected
        self.hierarchy = None
        self.iterations = 0  # CG iterations of all solves
        self.factorizations = 0  # none: the hierarchy is built (``setups``), never a factor
        self.most_iterations = 0  # of one solve
        self.setups = 0  # hierarchies built
        self.setup_time = 0.0
        self.levels = 0
        self.operator_complexity = 0.0
        self.stale = False  # the last solve needed more than REBUILD_AFTER iterations: build again on the next matrix

    def analyse(self, A: sp.spmatrix) -> None:
        """The smoothed-aggregation hierarchy of A (free dofs), in nodal blocks."""
        again = " again (the last solve needed too many iterations)" if self.setups else ""
        with self.progress.phase("multigrid", f"the smoothed-aggregation hierarchy of the Newton matrix{again}, "
                                 f"{A.shape[0]:,} dofs in {self.dim} x {self.dim} blocks{self._expected}") as phase:
            self._analyse(A)
            phase.done(f"{self.levels} levels, operator complexity {self.operator_complexity:.2f}")

    def _analyse(self, A: sp.spmatrix) -> None:
        import pyamg

        started = time.perf_counter()
        n = A.shape[0]
        embed = sp.csr_matrix((np.ones(n), (self.free, np.arange(n))), shape=(self.size, n))
        fixed = np.ones(self.size, dtype=bool)
        fixed[self.free] = False
        scale = float(np.mean(A.diagonal())) if n else 1.0
        blocked = (embed @ A @ embed.T + sp.diags(np.where(fixed, scale, 0.0))).tobsr(blocksize=(self.dim, self.dim))
        B = np.zeros((self.size, self.near_nullspace.shape[1]))
        B[self.free] = self.near_nullspace
        self.hierarchy = None  # release the earlier one first
        self.hierarchy = pyamg.smoothed_aggregation_solver(blocked, B=B, coarse_solver="splu", **SMOOTHING)
        self.levels = len(self.hierarchy.levels)
        self.operator_complexity = float(self.hierarchy.operator_complexity())
        self._cycle = self.hierarchy.aspreconditioner(cycle="V")
        self.setups += 1
        self.stale = False
        self.setup_time += time.perf_counter() - started

    def factor(self, A: sp.spmatrix) -> None:
        """Record the matrix (and rebuild the hierarchy on it if the last solve found it stale); find
        its unknowns reduced to their diagonal entry."""
        if self.stale:
            self._A = None  # the earlier Newton matrix is not kept while the hierarchy is built
            self.analyse(A)
        self._A = sp.csr_matrix(A)
        diagonal = self._A.diagonal()
        self._decoupled = decoupled_rows(self._A)
        self._decoupled_inverse = np.where(self._decoupled, 1.0 / np.where(self._decoupled, diagonal, 1.0), 0.0)

    def _precondition(self, r: np.ndarray) -> np.ndarray:
        embedded = np.zeros(self.size)
        embedded[self.free] = np.where(self._decoupled, 0.0, r)
        z = self._cycle.matvec(embedded)[self.free]
        return np.where(self._decoupled, self._decoupled_inverse * r, z)

    def solve(self, b: np.ndarray, rtol: float = 1e-10, start: np.ndarray | None = None) -> np.ndarray:
        """A x = b by preconditioned CG from ``start`` (None: x = 0), to ‖A x − b‖ ≤ rtol ‖b‖."""
        n = b.size
        count = [0]

        def counted(_):
            count[0] += 1

        preconditioner = spla.LinearOperator((n, n), matvec=self._precondition, dtype=float)
        x, info = spla.cg(self._A, b, x0=start, rtol=rtol, atol=0.0, M=preconditioner, maxiter=MAX_ITERATIONS,
                          callback=counted)
        self.iterations += count[0]
        self.most_iterations = max(self.most_iterations, count[0])
        self.stale = count[0] > REBUILD_AFTER
        if info != 0 or not np.all(np.isfinite(x)):
            reached = np.linalg.norm(self._A @ x - b) / (np.linalg.norm(b) or 1.0)
            raise NotConvergedError(f"AMG-preconditioned CG reached a relative residual of {reached:.1e} (asked "
                                    f"{rtol:.0e}) in {count[0]} iterations")
        return x
