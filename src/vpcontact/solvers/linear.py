"""The linear-solver layer: one small protocol for the symmetric positive definite Newton systems of
the full-system methods.

    solver.analyse(A)             the work that depends on A's sparsity pattern (or, for the
                                  iterative backend, on a reference operator): an ordering and
                                  symbolic factorization, or an AMG hierarchy
    solver.factor(A)              the work that depends on A's values (A has the analysed pattern)
    x = solver.solve(b, rtol)     A x = b; iterative backends stop at ‖A x − b‖ ≤ rtol ‖b‖
    x = solver.solve(b, rtol, start)   the iterative backends: CG from ``start`` instead of x = 0
    solver.iterations             Krylov iterations of all solves so far (0 for a direct backend)
    solver.factorizations         numeric factorizations so far (0 for the iterative backend)

Each backend has a ``label`` and, if it has a separate symbolic phase, its ``analysis`` in words
(progress reports). Backends: "pardiso" (MKL PARDISO: analysis once, a numeric refactorisation per matrix), "superlu"
(SciPy's LU, always installed) and the iterative ones, conjugate gradients preconditioned by smoothed
aggregation with the hierarchy built once: "amg-cg" (:mod:`.amg`, pyamg's, always installed) and "gamg-cg"
(:mod:`.petsc_gamg`, PETSc's GAMG, when petsc4py is installed), chosen by ``solver.multigrid``
(:func:`multigrid_solver`). Failures are typed (:mod:`.errors`). The Schur complement the condensed method
needs is PARDISO's too; it lives in :mod:`.factorization`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError
from ..memory import available_memory
from ..progress import SILENT, Progress, size
from . import petsc_gamg
from .amg import AMGConjugateGradient
from .factorization import installed_backends, splu


class PardisoSolver:
    """MKL PARDISO, SPD: METIS ordering and symbolic factorization once, numeric factorization per
    matrix (on one thread: see :class:`.pardiso.Pardiso`)."""

    name = "pardiso"
    label = "MKL PARDISO"
    analysis = "METIS ordering and symbolic factorization"

    def __init__(self, progress: Progress = SILENT):
        self._pardiso = None
        self.iterations = 0
        self.factorizations = 0
        self.progress = progress

    def analyse(self, A: sp.spmatrix) -> None:
        """Order A and analyse its factor's structure (and memory: SolverMemoryError if it will not fit; the
        progress reporter hears of it)."""
        from .pardiso import Pardiso

        self._pardiso = None  # release an earlier factor first
        self._pardiso = Pardiso(A, refactorable=True, analysed=lambda needed: self.progress.note(
            f"each factor of a Newton matrix will take about {size(needed)} ({size(available_memory())} "
            f"available)"))

    def factor(self, A: sp.spmatrix) -> None:
        self._pardiso.refactor(A)
        self.factorizations += 1

    def solve(self, b: np.ndarray, rtol: float = 0.0) -> np.ndarray:
        return self._pardiso.solve(b)


class SuperLUSolver:
    """SciPy's SuperLU in its symmetric mode (minimum degree on A + Aᵀ, diagonal pivots); it has no
    separate symbolic phase, so each matrix is ordered and factored anew."""

    name = "superlu"
    label = "SciPy's SuperLU"
    analysis = None  # none: each matrix is ordered and factored anew

    def __init__(self, progress: Progress = SILENT):
        self._lu = None
        self.iterations = 0
        self.factorizations = 0

    def analyse(self, A: sp.spmatrix) -> None:
        pass

    def factor(self, A: sp.spmatrix) -> None:
        self._lu = None
        self._lu = splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                        options={"SymmetricMode": True})
        self.factorizations += 1

    def solve(self, b: np.ndarray, rtol: float = 0.0) -> np.ndarray:
        return self._lu.solve(b)


DIRECT = {backend.name: backend for backend in (PardisoSolver, SuperLUSolver)}


def direct_solver(backend: str = "auto", progress: Progress = SILENT):
    """The direct backend ``backend`` ("auto": the fastest one installed); ``progress`` hears of what its
    analysis finds (the memory of a factor)."""
    return DIRECT[installed_backends()[0] if backend == "auto" else backend](progress)


#: The multigrid backends of the iterative method (``solver.multigrid``), by name: "auto" takes the first installed.
MULTIGRIDS = {"petsc": petsc_gamg.GAMGConjugateGradient, "pyamg": AMGConjugateGradient}
#: How to get PETSc's backend, for the message that refuses it where petsc4py is missing.
PETSC_INSTALL = 'pip install "vpcontact[petsc]" (it builds PETSc from source: a C compiler, MPI and about 30 minutes)'


def chosen_multigrid(multigrid: str = "auto") -> str:
    """The backend ``multigrid`` stands for ("auto": PETSc's GAMG where petsc4py is installed, else pyamg's)."""
    if multigrid != "auto":
        return multigrid
    return "petsc" if petsc_gamg.available() else "pyamg"


def check_multigrid(multigrid: str) -> None:
    """CaseError unless ``multigrid`` (``solver.multigrid``: "auto" or a name of MULTIGRIDS) works here."""
    if multigrid == "petsc" and not petsc_gamg.available():
        raise CaseError(f'solver.multigrid = "petsc": petsc4py is not installed here; install it with {PETSC_INSTALL}, '
                        f'or use "auto" or "pyamg"')


def multigrid_solver(multigrid: str, free: np.ndarray, dim: int, nodes: int, near_nullspace: np.ndarray,
                     progress: Progress = SILENT, expected: str = ""):
    """The iterative backend ``multigrid`` ("auto", "petsc" or "pyamg": :func:`chosen_multigrid`) for the dofs
    ``free`` of the nodal layout of ``nodes`` nodes in dimension ``dim``, the rigid motions ``near_nullspace``
    (free dofs, k) in the system's coordinates; ``progress`` hears of its hierarchies (their start lines end
    with ``expected``)."""
    return MULTIGRIDS[chosen_multigrid(multigrid)](free, dim, nodes, near_nullspace, progress, expected)
