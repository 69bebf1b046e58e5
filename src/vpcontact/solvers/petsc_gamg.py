"""Conjugate gradients preconditioned by PETSc's algebraic multigrid (GAMG, smoothed aggregation) through
petsc4py: the iterative method's second multigrid backend, beside pyamg's (:mod:`.amg`), with its protocol
and its choices (``solver.multigrid``, :mod:`.linear`).

As in :mod:`.amg`, the system on the free dofs is embedded in the nodal block layout (an identity row, scaled
like the diagonal, at every Dirichlet dof), the matrix has block size d so that aggregates are whole nodes,
and the rigid-body motions in the system's coordinates are GAMG's near-null space. The hierarchy is built
once (``analyse``) and kept for the later Newton matrices and time steps; a solve that needed more than
REBUILD_AFTER iterations has it built again on the next matrix.

PETSc holds the Newton matrix as one matrix for the whole run: the Newton matrices share one sparsity
pattern (the fixed dofs of :mod:`.normal_frame` keep their rows and columns as explicit zeros), so the pattern
is given once (PETSc's CSR preallocation, in every PETSc since 3.18 at least) and each Newton matrix only replaces
the values, row by row. The hierarchy is
built on a copy of the matrix as it was then (same pattern, its values replaced at each rebuild), like
pyamg's: the preconditioner depends only on the matrix it was built on, so a resumed run
(``IterativeNewton.restore``) rebuilds the uninterrupted run's. GAMG on the Newton matrix itself
(``setReusePreconditioner``, no copy) took about as many iterations over the quarter ball's 11 steps (268
against 260 at 71k dofs), but on a Newton matrix with ten times the contact stiffness and a third of the
normal dofs fixed (3.8k dofs) its CG stopped after 2 iterations at a relative residual of 1.1, where the copy's
converged. A solve that fails (not converged, or an indefinite preconditioner) also has the hierarchy built
again on the next matrix.

Unknowns reduced to their diagonal entry (the fixed dofs, the Dirichlet rows of the embedding) are solved
exactly and the V-cycle applied to the rest, z = P M⁻¹ P r + D⁻¹ (I − P) r (a Python preconditioner around
GAMG's), so fixing dofs does not disturb the hierarchy. CG stops on the unpreconditioned residual,
‖A x − b‖ ≤ rtol ‖b‖, or after MAX_ITERATIONS, never because the residual grew: PETSc's divergence test (a
residual above 10⁵ times the first) is off, as SciPy's CG (pyamg's) has none. A Newton matrix nearly singular
in a rigid motion (a body held only by contact, its contact nodes separated: their stiffness is the Newton
iteration's regularization) has CG's residual rise by 10⁴ and more before it falls; the test stopped the 2D block of
tests/test_uniaxial_reference.py after 3 iterations (a step cut), where pyamg's CG converged.

PETSc's options are set here, on a private prefix, and never read from the command line: the run's
arguments are not PETSc's.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..parallel.petsc import petsc
from ..parallel.ranks import ALONE, Ranks
from ..progress import SILENT, Progress
from .amg import MAX_ITERATIONS, REBUILD_AFTER, decoupled_rows  # the limits both multigrids keep
from .errors import NotConvergedError

#: The prefix of the options database entries this backend sets and reads.
OPTIONS_PREFIX = "vpcontact_"
#: GAMG's options: smoothed aggregation, every nonzero connection kept in the aggregation graph (threshold
#: 0), two Chebyshev/Jacobi smoothing steps each side (PETSc's defaults). One Newton system of the quarter ball
#: at 69k free dofs (h = 0.07, a third of the contact nodes' normal dofs fixed), CG to 1e-8, BLAS on one thread
#: as in the Newton iteration, median of 3 on a loaded 2-core machine: 15 iterations of 32–38 ms, set-up
#: 2.3–2.8 s; threshold 0.01: the same (set-up 1.9 s); 0.05: 16 of 34 ms, set-up 3.2 s; SOR instead of Jacobi:
#: 12 of 105 ms; three smoothing steps: 13 of 53 ms. pyamg (:mod:`.amg`): 13 of 64 ms, set-up 4.1 s.
GAMG_OPTIONS = {"pc_type": "gamg", "pc_gamg_type": "agg", "pc_gamg_threshold": 0.0,
                "mg_levels_ksp_type": "chebyshev", "mg_levels_pc_type": "jacobi"}


def available() -> bool:
    """Whether petsc4py can be imported here."""
    try:
        import petsc4py  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass(frozen=True)
class NodalBlocks:
    """Where a process's rows of the system sit in PETSc's nodal layout (dof d · node + component, rows
    ``offset`` .. ``offset + size`` − 1 of ``total`` on this process): ``free``, the system's rows among them
    (positions from ``offset``); ``columns``, the PETSc index of each column of the process's rows; ``ranks``, the
    processes sharing the matrix (:mod:`vpcontact.parallel`)."""

    free: np.ndarray
    columns: np.ndarray
    size: int
    offset: int
    total: int
    ranks: Ranks = ALONE

    @classmethod
    def whole(cls, free: np.ndarray, dim: int, nodes: int) -> "NodalBlocks":
        """The whole system in one process: rows and columns are the free dofs."""
        free = np.asarray(free)
        return cls(free, free, dim * nodes, 0, dim * nodes)


class GAMGConjugateGradient:
    """PETSc's CG preconditioned by GAMG in nodal blocks.

    ``free`` are the system's dofs among the d · nodes of the nodal layout (dof d · node + component),
    ``near_nullspace`` (free dofs, k) the rigid-body motions in the system's coordinates; ``blocks``: one MPI
    rank's share of the system (:class:`NodalBlocks`; None: all of it, in one process, ``free`` and ``nodes``
    the whole mesh's), ``free`` and ``near_nullspace`` then its rows'."""

    name = "gamg-cg"
    label = "PETSc's GAMG"

    def __init__(self, free: np.ndarray, dim: int, nodes: int, near_nullspace: np.ndarray,
                 progress: Progress = SILENT, expected: str = "", blocks: NodalBlocks | None = None):
        """``progress`` hears of each hierarchy built (its start line ends with ``expected``: what is expected
        of it, in words)."""
        self.blocks = NodalBlocks.whole(free, dim, nodes) if blocks is None else blocks
        self.free, self.dim, self.size = self.blocks.free, dim, self.blocks.size
        self.near_nullspace = near_nullspace
        self.progress, self._expected = progress, expected
        self.iterations = 0  # CG iterations of all solves
        self.factorizations = 0  # none: the hierarchy is built (``setups``), never a factor
        self.most_iterations = 0  # of one solve
        self.setups = 0  # hierarchies built
        self.setup_time = 0.0
        self.levels = 0
        self.operator_complexity = 0.0
        self.stale = False  # the last solve needed more than REBUILD_AFTER iterations: build again on the next matrix
        self._matrix = None  # the current Newton matrix in the nodal layout, its pattern given once
        self._copy = None  # its copy when the hierarchy was built, the hierarchy's matrix
        self._pattern = None  # (indptr, indices) of the Newton matrices on the free dofs
        self._gamg = None

    def analyse(self, A: sp.spmatrix) -> None:
        """GAMG's hierarchy of A (free dofs), in nodal blocks; A's pattern is the one of every later matrix."""
        again = " again (the last solve failed or needed too many iterations)" if self.setups else ""
        dofs = int(self.blocks.ranks.sum(A.shape[0]))
        shared = f" on {self.blocks.ranks.size} ranks" if self.blocks.ranks.size > 1 else ""
        with self.progress.phase("multigrid", f"PETSc GAMG's smoothed-aggregation hierarchy of the Newton matrix"
                                 f"{again}, {dofs:,} dofs in {self.dim} x {self.dim} blocks{shared}"
                                 f"{self._expected}") as phase:
            self._analyse(A)
            phase.done(f"{self.levels} levels, operator complexity {self.operator_complexity:.2f}")

    def _analyse(self, A: sp.spmatrix) -> None:
        PETSc = petsc()
        started = time.perf_counter()
        if self._matrix is None:
            self._create(sp.csr_matrix(A), PETSc)
        self._set_values(A)
        if self._gamg is not None:  # release the earlier hierarchy first
            self._gamg.destroy()
            self._gamg = None
        if self._copy is None:
            self._copy = self._matrix.duplicate(copy=True)
            self._copy.setNearNullSpace(self._nullspace)
        else:
            self._matrix.copy(self._copy, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        options = PETSc.Options(OPTIONS_PREFIX)
        for key, value in GAMG_OPTIONS.items():
            options[key] = value
        gamg = PETSc.PC().create(comm=self._comm)
        gamg.setOptionsPrefix(OPTIONS_PREFIX)
        gamg.setOperators(self._copy)
        gamg.setFromOptions()
        gamg.setUp()
        self._gamg = gamg
        self.levels = gamg.getMGLevels()
        entries = [gamg.getMGSmoother(level).getOperators()[0].getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"]
                   for level in range(self.levels)]
        self.operator_complexity = float(sum(entries) / entries[-1])
        self.setups += 1
        self.stale = False
        self.setup_time += time.perf_counter() - started

    def _create(self, A: sp.csr_matrix, PETSc) -> None:
        """The PETSc matrix of the nodal layout on A's pattern (A on the free dofs, the Dirichlet diagonal), the
        near-null space, and the CG solver on the matrix with GAMG inside the preconditioner of
        :meth:`_precondition`."""
        A.sort_indices()
        n, blocks = A.shape[0], self.blocks
        ranks = blocks.ranks
        self._comm = PETSc.COMM_SELF if ranks.comm is None else PETSc.Comm(ranks.comm)
        self._pattern = (A.indptr.copy(), A.indices.copy())
        dirichlet = np.setdiff1d(np.arange(self.size), self.free)
        rows = np.concatenate([self.free[np.repeat(np.arange(n), np.diff(A.indptr))], dirichlet]) + blocks.offset
        columns = np.concatenate([blocks.columns[A.indices], dirichlet + blocks.offset])
        self._dirichlet = dirichlet
        counted = ranks.sum(np.array([A.diagonal().sum(), n]))
        self._dirichlet_value = float(counted[0] / counted[1]) if counted[1] else 1.0
        self._order = np.lexsort((columns, rows))  # the entries (A's, then the Dirichlet rows') in rows of PETSc's CSR
        self._csr = (np.concatenate([[0], np.cumsum(np.bincount(rows - blocks.offset, minlength=self.size))]
                                    ).astype(PETSc.IntType), columns[self._order].astype(PETSc.IntType))
        matrix = PETSc.Mat().create(comm=self._comm)
        matrix.setSizes(((self.size, blocks.total), (self.size, blocks.total)), bsize=self.dim)
        matrix.setType(PETSc.Mat.Type.AIJ)
        matrix.setPreallocationCSR(self._csr)
        self._matrix = matrix
        B = np.zeros((self.size, self.near_nullspace.shape[1]))
        B[self.free] = self.near_nullspace
        vectors = []
        for column in orthonormal(B, ranks).T:  # PETSc wants the near-null space orthonormal
            vector = matrix.createVecRight()
            vector.array[:] = column
            vectors.append(vector)
        self._nullspace = PETSc.NullSpace().create(vectors=vectors, comm=self._comm)
        ksp = PETSc.KSP().create(comm=self._comm)
        ksp.setType(PETSc.KSP.Type.CG)
        ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
        ksp.setOperators(matrix)
        preconditioner = ksp.getPC()
        preconditioner.setType(PETSc.PC.Type.PYTHON)
        preconditioner.setPythonContext(_Decoupled(self))
        self._ksp = ksp
        self._b, self._x, self._masked = matrix.createVecRight(), matrix.createVecRight(), matrix.createVecRight()

    def _set_values(self, A: sp.spmatrix) -> None:
        """Replace the PETSc matrix's values by A's (A has the analysed pattern); find its unknowns reduced to their
        diagonal entry."""
        A = sp.csr_matrix(A)
        A.sort_indices()
        indptr, indices = self._pattern
        if not (np.array_equal(A.indptr, indptr) and np.array_equal(A.indices, indices)):
            raise ValueError("the matrix's pattern is not the analysed one: GAMG's matrix keeps one pattern")
        values = np.concatenate([A.data, np.full(self._dirichlet.size, self._dirichlet_value)])[self._order]
        self._matrix.setValuesCSR(*self._csr, values)
        self._matrix.assemble()
        diagonal = A.diagonal()
        decoupled = decoupled_rows(A)
        self._decoupled = np.concatenate([self.free[decoupled], self._dirichlet])
        self._decoupled_inverse = 1.0 / np.concatenate([diagonal[decoupled],
                                                        np.full(self._dirichlet.size, self._dirichlet_value)])

    def factor(self, A: sp.spmatrix) -> None:
        """Replace the matrix's values by A's (and rebuild the hierarchy on it if the last solve found it stale);
        find its unknowns reduced to their diagonal entry."""
        if self.stale:
            self.analyse(A)
        else:
            self._set_values(A)

    def _precondition(self, r, z) -> None:
        """z = P M⁻¹ P r + D⁻¹ (I − P) r: GAMG's V-cycle on the coupled unknowns, the decoupled ones solved."""
        residual = r.array_r
        masked = self._masked.array
        masked[:] = residual
        masked[self._decoupled] = 0.0
        self._gamg.apply(self._masked, z)
        z.array[self._decoupled] = self._decoupled_inverse * residual[self._decoupled]

    def solve(self, b: np.ndarray, rtol: float = 1e-10, start: np.ndarray | None = None) -> np.ndarray:
        """A x = b by preconditioned CG from ``start`` (None: x = 0), to ‖A x − b‖ ≤ rtol ‖b‖."""
        if not self.blocks.ranks.sum(float(np.any(b))):
            return np.zeros_like(b)
        self._b.array[:] = 0.0
        self._b.array[self.free] = b
        self._x.array[:] = 0.0  # the Dirichlet rows' solution, and the start where none is given
        if start is not None:
            self._x.array[self.free] = start
        self._ksp.setInitialGuessNonzero(start is not None)
        self._ksp.setTolerances(rtol=rtol, atol=0.0, divtol=np.inf, max_it=MAX_ITERATIONS)
        self._ksp.solve(self._b, self._x)
        count = self._ksp.getIterationNumber()
        x = self._x.array[self.free].copy()
        self.iterations += count
        self.most_iterations = max(self.most_iterations, count)
        converged = self._ksp.getConvergedReason() > 0 and self.blocks.ranks.all(np.all(np.isfinite(x)))
        self.stale = count > REBUILD_AFTER or not converged
        if not converged:
            residual = self._matrix.createVecRight()
            self._matrix.mult(self._x, residual)
            residual.axpy(-1.0, self._b)
            reached = residual.norm() / self._b.norm()
            raise NotConvergedError(f"GAMG-preconditioned CG reached a relative residual of {reached:.1e} (asked "
                                    f"{rtol:.0e}) in {count} iterations")
        return x


def orthonormal(B: np.ndarray, ranks: Ranks) -> np.ndarray:
    """An orthonormal basis of the columns of B (full column rank), whose rows are shared among ``ranks``: one
    process's by QR, several ranks' from the Cholesky factor of the Gram matrix BᵀB summed over them."""
    if ranks.comm is None:
        return np.linalg.qr(B)[0]
    factor = np.linalg.cholesky(ranks.sum(B.T @ B))
    return np.linalg.solve(factor, B.T).T


class _Decoupled:
    """The Python context of the CG preconditioner: ``GAMGConjugateGradient._precondition``."""

    def __init__(self, solver: GAMGConjugateGradient):
        self._solver = solver

    def apply(self, pc, r, z) -> None:
        self._solver._precondition(r, z)
