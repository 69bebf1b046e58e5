"""Step solvers behind one interface.

``make_solver(method, ...)`` returns an object with
    solve(step, previous) -> StepSolution        (previous: the last step's solution or None)
    displacement(step, solution) -> u            (at the free dofs)
    r, name, timings
Methods: "full" (Newton on the whole system, the reference), "condensed" (factor once, Newton on
the contact nodes), "auto" (condensed when its dense contact operator fits in memory, else full);
``solver.reason`` says which method runs and why.
"""

from __future__ import annotations

from .base import StepData, StepSolution, default_augmentation
from .condensed import CondensedNewton, condensed_fits
from .full import FullNewton
from ..errors import CaseError
from .errors import SingularMatrixError, SolverMemoryError
from .factorization import installed_backends

SOLVERS = {FullNewton.name: FullNewton, CondensedNewton.name: CondensedNewton}
METHODS = ("auto", *SOLVERS)


def make_solver(method: str, A, N, weights, gap0, *, rigid, augmentation: float | None, tolerance: float,
                max_iterations: int, length_scale: float, factorization: str = "auto"):
    """The step solver ``method`` for stiffness A and contact operator N (both on the free dofs);
    ``rigid``: an orthonormal basis of the rigid motions held only by contact, (free dofs, k)."""
    r = default_augmentation(A, N)
    if augmentation is not None:
        if not 1e-12 <= augmentation / r <= 1e12:
            raise CaseError(f"solver.augmentation = {augmentation:g} is {augmentation / r:.1e} times the normal "
                            f"stiffness at the contact nodes ({r:.3g}): use \"auto\" or a value near it")
        r = augmentation
    method, reason = _chosen(method, A, N)
    common = (A, N, weights, gap0, r, tolerance, max_iterations, length_scale, rigid)
    if method != CondensedNewton.name:
        solver = FullNewton(*common)
    else:
        solver = _condensed(common, factorization, A)
    solver.reason = reason
    return solver


def _condensed(common: tuple, factorization: str, A) -> CondensedNewton:
    """The condensed solver, its failures to factor A as one-line CaseErrors."""
    try:
        return CondensedNewton(*common, factorization=factorization)
    except SingularMatrixError as error:
        raise CaseError(f"the stiffness matrix cannot be factored ({error}): the mesh has degenerate elements, or "
                        f"a part of the body is held by nothing") from None
    except SolverMemoryError as error:
        used = installed_backends()[0] if factorization == "auto" else factorization
        other = "" if used == "pardiso" else ", or solver.factorization = \"pardiso\" (MKL: smaller factors)"
        raise CaseError(f"not enough memory to factor the stiffness matrix ({A.shape[0]} dofs): {error}; use a "
                        f"coarser mesh{other}") from None


def _chosen(method: str, A, N) -> tuple[str, str]:
    """The step method to run for ``solver.method`` and why, in words (summary.json's solver_reason)."""
    if method != "auto":
        return method, f"solver.method = \"{method}\""
    fits, needed, available = condensed_fits(N, A.shape[0])
    return (CondensedNewton.name if fits else FullNewton.name,
            f"solver.method = \"auto\": the condensed method's dense algebra for {N.shape[0]} contact nodes "
            f"({needed / 2**30:.3g} GiB) {'fits in' if fits else 'exceeds'} half the {available / 2**30:.1f} GiB "
            f"available")


__all__ = ["METHODS", "SOLVERS", "StepData", "StepSolution", "make_solver"]
