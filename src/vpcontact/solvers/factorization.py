"""Sparse direct factorizations of the SPD matrix A0, behind one small interface:

    factorization = factorize(A0, N, backend)       # factors A0, ready to condense onto N's rows
    x = factorization.solve(b)                      # b: (n,) or (n, k)
    S = factorization.condensed_operator()          # the dense m × m matrix N A0⁻¹ Nᵀ
    split = factorization.split(b)                  # N A0⁻¹ b now (split.observed), then
    x = split.finish(q)                             # A0⁻¹ (b − Nᵀ q) for a q found from it

Backends, fastest first (measurements in docs/factorizations.md): "pardiso" (MKL PARDISO, SPD
Cholesky with METIS; S from its Schur complement on the contact dofs; needs the ``mkl`` wheel) and
"superlu" (SciPy, always installed; S by block solves).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CaseError, quoted
from ..memory import available_memory
from ..progress import SILENT, Progress, size
from .errors import SingularMatrixError, SolverMemoryError

#: Columns of Nᵀ solved at once when S is built by block solves.
BLOCK = 64


@dataclass(frozen=True)
class SplitSolve:
    """A0⁻¹ (b − Nᵀ q) for a q that is known only once N A0⁻¹ b is (a step of the condensed method: its
    contact problem needs N A0⁻¹ b, its displacement A0⁻¹ (b − Nᵀ q)): ``observed`` = N A0⁻¹ b,
    ``finish(q)`` the solution, ``finish_solves`` the solves with the factor that finishing costs (0 when
    the first half kept what the second needs: one solve's work in all)."""

    observed: np.ndarray
    finish: Callable[[np.ndarray], np.ndarray]
    finish_solves: int


def contact_dofs(N: sp.csr_matrix) -> np.ndarray:
    """The dofs N acts on: the columns of its nonzero entries, ascending. A contact node's row holds its normal's
    d components, stored even where they are zero (a flat face's normal (0, 0, −1)): only the nonzero ones
    count, so that a flat contact face condenses onto its m normal dofs and not onto all d · m (a Schur
    complement d² times smaller, its factorization d³ times cheaper)."""
    N = sp.csr_matrix(N)
    return np.unique(N.indices[N.data != 0.0])


def split_by_two_solves(solve, N: sp.csr_matrix, b: np.ndarray) -> SplitSolve:
    """A SplitSolve made of two solves: x = A0⁻¹ b for N x, then A0⁻¹ (b − Nᵀ q)."""
    return SplitSolve(N @ solve(b), lambda q: solve(b - N.T @ q), 1)


class PardisoFactorization:
    """MKL PARDISO; the Schur complement S_C of A0 on the contact dofs C comes with the factor, and
    S = N_C S_C⁻¹ N_Cᵀ (the C block of A0⁻¹ is S_C⁻¹).

    The factor computed in Schur mode also solves, but about 1.7 times slower than a plain one
    (0.15 s against 0.09 s at 470k DOFs, docs/factorizations.md). A run that needs few solves (an
    elastic body: one per new load and one per written step) keeps it; once ``PLAIN_AFTER`` solves
    have been done, and more of them than split solves, a plain factorization (3–4 s at 470k DOFs)
    replaces it for the rest of the run. A run that splits its solves (a viscoplastic body: the load
    changes everywhere at every step, and u is needed at every step) keeps it: its split solves are one
    solve's work in Schur mode (``split``), two solves with a plain factor.
    """

    name = "pardiso"
    label = "MKL PARDISO"
    PLAIN_AFTER = 50

    @staticmethod
    def available() -> bool:
        from .pardiso import library

        try:
            library()
        except OSError:
            return False
        return True

    def __init__(self, A: sp.spmatrix, N: sp.csr_matrix, progress: Progress = SILENT):
        from .pardiso import Pardiso

        self._A, self._N = A, N
        self._dofs = contact_dofs(N)
        self._N_contact = N[:, self._dofs].tocsr()  # sparse: d entries a row at most, c columns
        self._pardiso = Pardiso(A, self._dofs, analysed=lambda needed: progress.note(
            f"{self.label}'s analysis: the factor and the Schur complement take about {size(needed)} "
            f"({size(available_memory())} available)"))
        self.factor_nonzeros = self._pardiso.factor_nonzeros  # of the factor made here, in Schur mode
        self._schur_mode = self._dofs.size > 0
        self.solves = self.splits = 0

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self._schur_mode and self.solves >= self.PLAIN_AFTER and self.solves > self.splits:
            self._factor_plainly()
        self.solves += 1
        return self._pardiso.solve(b)

    def _factor_plainly(self) -> None:
        """Replace the Schur-mode factor by a plain one (for the rest of the run)."""
        from .pardiso import Pardiso

        self._pardiso = None  # release the Schur-mode factor before the plain one is made
        self._pardiso, self._schur_mode = Pardiso(self._A), False

    def kept(self) -> dict[str, np.ndarray]:
        """What decides the factor used from here on: the solves and split solves so far, the mode."""
        return {"solves": np.array(self.solves), "splits": np.array(self.splits),
                "schur_mode": np.array(self._schur_mode)}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of the factorization of the same A0 in an earlier process: with the
        factor that one had (the plain one made now if it had made it), so that the solves give the
        same bits."""
        if not arrays:
            return
        self.solves, self.splits = int(arrays["solves"]), int(arrays["splits"])
        if self._schur_mode and not bool(arrays["schur_mode"]):
            self._factor_plainly()

    def split(self, b: np.ndarray) -> SplitSolve:
        """In Schur mode, one solve's work (pardiso.py's docstring has the factorization): the forward
        substitution y of b leaves b reduced to the contact dofs C on them, the diagonal substitution of y
        gives x_C = (A0⁻¹ b)_C there, so N A0⁻¹ b = N_C x_C. Nᵀq lives on C, where L is the identity: the
        forward substitution of b − Nᵀ q is y with y_C − N_Cᵀ q on C, and its diagonal and backward
        substitutions give A0⁻¹ (b − Nᵀ q). With the plain factor: two solves."""
        self.splits += 1
        if not self._schur_mode:
            return split_by_two_solves(self.solve, self._N, b)
        pardiso, dofs, N_contact = self._pardiso, self._dofs, self._N_contact
        forward = pardiso.forward(b)

        def finish(q: np.ndarray) -> np.ndarray:
            reduced = forward.copy()
            reduced[dofs] -= N_contact.T @ q
            return pardiso.backward(pardiso.diagonal(reduced))

        return SplitSolve(N_contact @ pardiso.diagonal(forward)[dofs], finish, 0)

    def condensation_words(self) -> str:
        """How ``condensed_operator`` computes S, in words."""
        return f"from the Schur complement on the {self._dofs.size:,} contact dofs"

    def condensed_operator(self) -> np.ndarray:
        if self._dofs.size == 0:
            return np.zeros((self._N_contact.shape[0],) * 2)
        schur, self._pardiso.schur = self._pardiso.schur, None
        try:  # in place, from one triangle (Fortran order: the transpose's lower one), no copy of the c × c matrix
            factor = sla.cho_factor(schur.T, lower=True, overwrite_a=True, check_finite=False)
        except np.linalg.LinAlgError as error:
            raise SingularMatrixError(f"the Schur complement on the contact dofs is not positive definite ({error})") \
                from None
        S = self._N_contact @ sla.cho_solve(factor, self._N_contact.T.toarray())
        S = np.asarray(S)
        return 0.5 * (S + S.T)


class SuperLUFactorization:
    """SciPy's SuperLU with the symmetric mode (minimum degree on A + Aᵀ, diagonal pivots);
    ``factor_nonzeros`` counts L and U."""

    name = "superlu"
    label = "SciPy's SuperLU"

    def kept(self) -> dict[str, np.ndarray]:
        """Nothing changes from step to step (one factor for the run)."""
        return {}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Nothing to continue from."""

    @staticmethod
    def available() -> bool:
        return True

    def __init__(self, A: sp.spmatrix, N: sp.csr_matrix, progress: Progress = SILENT):
        self._N = N
        self._lu = splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                        options={"SymmetricMode": True})
        self.factor_nonzeros = self._lu.L.nnz + self._lu.U.nnz

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._lu.solve(b)

    def split(self, b: np.ndarray) -> SplitSolve:
        """Two solves (SuperLU has no partial substitutions)."""
        return split_by_two_solves(self.solve, self._N, b)

    def condensation_words(self) -> str:
        """How ``condensed_operator`` computes S, in words."""
        return f"by {self._N.shape[0]:,} solves with the factor, {BLOCK} at a time"

    def condensed_operator(self) -> np.ndarray:
        """S = N A0⁻¹ Nᵀ by block solves with BLOCK columns of Nᵀ at a time, symmetrized."""
        m = self._N.shape[0]
        S = np.empty((m, m))
        NT = self._N.T.tocsc()
        for start in range(0, m, BLOCK):
            stop = min(start + BLOCK, m)
            S[:, start:stop] = self._N @ self.solve(NT[:, start:stop].toarray())
        return 0.5 * (S + S.T)


def splu(A: sp.csc_matrix, **options):
    """SciPy's sparse LU with its failures typed: SingularMatrixError, SolverMemoryError."""
    try:
        return spla.splu(A, **options)
    except MemoryError:
        raise SolverMemoryError(f"not enough memory to factor a {A.shape[0]} x {A.shape[0]} matrix") from None
    except RuntimeError as error:  # SuperLU's only RuntimeError: an exactly singular factor
        raise SingularMatrixError(f"SuperLU: {error}") from None


BACKENDS = {backend.name: backend for backend in (PardisoFactorization, SuperLUFactorization)}
#: The names of the backends, fastest first (``solver.factorization``: the case's schema checks against them).
FACTORIZATIONS = tuple(BACKENDS)


def installed_backends() -> list[str]:
    """The backends that work here, fastest first."""
    return [name for name, backend in BACKENDS.items() if backend.available()]


def check_installed(backend: str) -> None:
    """CaseError unless ``backend`` (``solver.factorization``: "auto" or one of FACTORIZATIONS) works here."""
    if backend != "auto" and backend not in installed_backends():
        raise CaseError(f"solver.factorization = {quoted(backend)}: not installed here; expected \"auto\" or one of "
                        f"{', '.join(repr(b) for b in installed_backends())}")


def chosen_backend(backend: str = "auto") -> str:
    """The backend ``backend`` stands for ("auto": the fastest one installed)."""
    return installed_backends()[0] if backend == "auto" else backend


class RotatedFactorization:
    """The factorization of A0 made in the contact nodes' normal frame (:mod:`.normal_frame`): Q A0 Q factored with
    N Q = diag(s) E, which has one entry a row, so that S = N A0⁻¹ Nᵀ = (N Q)(Q A0 Q)⁻¹(N Q)ᵀ condenses onto the
    m normal dofs instead of the d · m dofs a curved contact face's normals touch (the quarter ball: 3,997 normal
    dofs instead of 11,845; the dense Schur complement 9 times smaller, its Cholesky 27 times cheaper). Every
    solve is the rotated one between two products with Q (Q = Qᵀ = Q⁻¹): A0⁻¹ b = Q (Q A0 Q)⁻¹ Q b."""

    def __init__(self, Q: sp.csr_matrix, rotated):
        self.Q, self._rotated = Q, rotated
        self.name, self.label, self.factor_nonzeros = rotated.name, rotated.label, rotated.factor_nonzeros

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.Q @ self._rotated.solve(self.Q @ b)

    def split(self, b: np.ndarray) -> SplitSolve:
        """The rotated factor's split of Q b: its N Q (Q A0 Q)⁻¹ Q b is N A0⁻¹ b, its finish rotated back."""
        rotated = self._rotated.split(self.Q @ b)
        return SplitSolve(rotated.observed, lambda q: self.Q @ rotated.finish(q), rotated.finish_solves)

    def condensation_words(self) -> str:
        return self._rotated.condensation_words().replace("contact dofs", "contact nodes' normal dofs")

    def condensed_operator(self) -> np.ndarray:
        return self._rotated.condensed_operator()

    def kept(self) -> dict[str, np.ndarray]:
        return self._rotated.kept()

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        self._rotated.restore(arrays)


def rotates(N: sp.csr_matrix) -> bool:
    """Is the condensation made in the normal frame (:class:`RotatedFactorization`)? Where a node's normal has more
    than one nonzero component (a face not along the axes), so that the contact dofs outnumber the nodes."""
    return contact_dofs(N).size > N.shape[0]


def condensation_dofs(N: sp.csr_matrix) -> int:
    """The dofs the condensed method's Schur complement is on: the contact nodes' normal dofs (one a node with a
    free normal) when it rotates, else the contact dofs."""
    if rotates(N):
        from .normal_frame import NormalFrame

        return int(NormalFrame(N).has_normal.sum())
    return contact_dofs(N).size


def factorize_on_normals(A: sp.spmatrix, N: sp.csr_matrix, backend: str = "auto", progress: Progress = SILENT):
    """The condensed method's factorization of A0 with N (:func:`factorize`), made in the normal frame where that
    condenses onto fewer dofs (:func:`rotates`)."""
    if not rotates(N):
        return factorize(A, N, backend, progress)
    from .normal_frame import NormalFrame

    frame = NormalFrame(N)
    return RotatedFactorization(frame.Q, factorize(frame.rotate(A), frame.normal_operator(), backend, progress))


def factorize(A: sp.spmatrix, N: sp.csr_matrix, backend: str = "auto", progress: Progress = SILENT):
    """Factor the SPD matrix A with ``backend`` ("auto": the fastest one installed); ``progress`` hears of the
    memory the factor takes when the backend knows it before (MKL PARDISO's analysis)."""
    return BACKENDS[chosen_backend(backend)](A, N, progress)
