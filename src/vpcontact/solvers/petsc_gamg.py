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
is given once (PETSc's COO preallocation) and each Newton matrix only replaces the values. The hierarchy is
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

import os
import sys
import time

import numpy as np
import scipy.sparse as sp

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


def petsc():
    """petsc4py's PETSc module, initialized the first time (a module the caller imported before is taken as it is):

    - without the process's command line and without PETSc's signal handlers: the run's own (a SIGTERM stops it
      after the step, :mod:`vpcontact.drivers.signals`) stay in place;
    - its library bound to the BLAS and LAPACK it was built with, whatever the process loaded before
      (``RTLD_DEEPBIND``; without it, as on macOS, a library is bound to its own dependencies anyway). MKL, which
      PARDISO loads, gives its BLAS to the whole process under the common names: PETSc's vector operations called
      MKL's in a session that had used PARDISO first and the reference BLAS in one that had not, and the same run
      differed in the last bits with what its process had done before (a run resumed in such a session was not
      the uninterrupted one);
    - as an MPI process of its own (Open MPI's isolated singleton; the backend needs no other process): Open MPI 4
      otherwise starts a daemon at initialization, in a session of its own, that holds the run's standard output
      and error, so that a signal to the run's process group does not reach it and whoever reads the run's
      output to its end waits for the daemon too."""
    if "petsc4py.PETSc" not in sys.modules:
        import petsc4py

        os.environ.setdefault("OMPI_MCA_ess_singleton_isolated", "1")
        flags = sys.getdlopenflags()
        sys.setdlopenflags(flags | getattr(os, "RTLD_DEEPBIND", 0))
        try:
            petsc4py.init(["vpcontact", "-no_signal_handler"])
        finally:
            sys.setdlopenflags(flags)
    from petsc4py import PETSc

    return PETSc


class GAMGConjugateGradient:
    """PETSc's CG preconditioned by GAMG in nodal blocks.

    ``free`` are the system's dofs among the d · nodes of the nodal layout (dof d · node + component),
    ``near_nullspace`` (free dofs, k) the rigid-body motions in the system's coordinates."""

    name = "gamg-cg"
    label = "PETSc's GAMG"

    def __init__(self, free: np.ndarray, dim: int, nodes: int, near_nullspace: np.ndarray,
                 progress: Progress = SILENT, expected: str = ""):
        """``progress`` hears of each hierarchy built (its start line ends with ``expected``: what is expected
        of it, in words)."""
        self.free, self.dim, self.size = np.asarray(free), dim, dim * nodes
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
        with self.progress.phase("multigrid", f"PETSc GAMG's smoothed-aggregation hierarchy of the Newton matrix"
                                 f"{again}, {A.shape[0]:,} dofs in {self.dim} x {self.dim} blocks"
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
        gamg = PETSc.PC().create(comm=PETSc.COMM_SELF)
        gamg.setOptionsPrefix(OPTIONS_PREFIX)
        gamg.setOperators(self._copy)
        gamg.setFromOptions()
        gamg.setUp()
        self._gamg = gamg
        self.levels = gamg.getMGLevels()
        entries = [gamg.getMGSmoother(level).getOperators()[0].getInfo()["nz_used"] for level in range(self.levels)]
        self.operator_complexity = float(sum(entries) / entries[-1])
        self.setups += 1
        self.stale = False
        self.setup_time += time.perf_counter() - started

    def _create(self, A: sp.csr_matrix, PETSc) -> None:
        """The PETSc matrix of the nodal layout on A's pattern (A on the free dofs, the Dirichlet diagonal), the
        near-null space, and the CG solver on the matrix with GAMG inside the preconditioner of
        :meth:`_precondition`."""
        A.sort_indices()
        n = A.shape[0]
        self._pattern = (A.indptr.copy(), A.indices.copy())
        dirichlet = np.setdiff1d(np.arange(self.size), self.free)
        rows = np.concatenate([self.free[np.repeat(np.arange(n), np.diff(A.indptr))], dirichlet])
        columns = np.concatenate([self.free[A.indices], dirichlet])
        self._dirichlet = dirichlet
        self._dirichlet_value = float(np.mean(A.diagonal())) if n else 1.0
        matrix = PETSc.Mat().create(comm=PETSc.COMM_SELF)
        matrix.setSizes((self.size, self.size), bsize=self.dim)
        matrix.setType(PETSc.Mat.Type.AIJ)
        matrix.setPreallocationCOO(rows.astype(PETSc.IntType), columns.astype(PETSc.IntType))
        self._matrix = matrix
        B = np.zeros((self.size, self.near_nullspace.shape[1]))
        B[self.free] = self.near_nullspace
        basis, _ = np.linalg.qr(B)  # PETSc wants the near-null space orthonormal
        vectors = []
        for column in basis.T:
            vector = PETSc.Vec().createSeq(self.size, bsize=self.dim, comm=PETSc.COMM_SELF)
            vector.array[:] = column
            vectors.append(vector)
        self._nullspace = PETSc.NullSpace().create(vectors=vectors, comm=PETSc.COMM_SELF)
        ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
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
        self._matrix.setValuesCOO(np.concatenate([A.data, np.full(self._dirichlet.size, self._dirichlet_value)]))
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
        if not np.any(b):
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
        converged = self._ksp.getConvergedReason() > 0 and np.all(np.isfinite(x))
        self.stale = count > REBUILD_AFTER or not converged
        if not converged:
            residual = self._matrix.createVecRight()
            self._matrix.mult(self._x, residual)
            reached = np.linalg.norm(residual.array - self._b.array) / np.linalg.norm(b)
            raise NotConvergedError(f"GAMG-preconditioned CG reached a relative residual of {reached:.1e} (asked "
                                    f"{rtol:.0e}) in {count} iterations")
        return x


class _Decoupled:
    """The Python context of the CG preconditioner: ``GAMGConjugateGradient._precondition``."""

    def __init__(self, solver: GAMGConjugateGradient):
        self._solver = solver

    def apply(self, pc, r, z) -> None:
        self._solver._precondition(r, z)
