"""Step solvers behind one interface.

``make_solver(method, ...)`` returns an object with
    solve(step, previous) -> StepSolution        (previous: the last step's solution or None)
    displacement(step, solution) -> u            (at the free dofs)
    functionals(M) -> (step, solution) ↦ M u    (a few rows over the free dofs: the reactions)
    work() -> SolverWork                         (its counters of work in the time loop)
    r, name, timings
Methods: "full" (Newton on the whole system, its SPD systems by a sparse direct solver),
"iterative" (the same Newton iteration, its systems by AMG-preconditioned CG, the multigrid PETSc's GAMG or
pyamg's: ``solver.multigrid``), "condensed" (factor
once, Newton on the contact nodes); ``solver.method = "auto"`` chooses one from the sizes and the memory
available (:mod:`.choice`, in the plan of a run: :mod:`vpcontact.timeloop.plan`), and weighs them again during the
run from the work counted (:mod:`.switch`); ``solver.reason`` says which method runs and why (and, for the iterative method, which multigrid).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import SolverWork, StepData, StepSolution, default_augmentation
from .condensed import CondensedNewton
from .distributed import DistributedNewton
from .full import FullNewton, IterativeNewton
from ..errors import CaseError
from ..parallel.ranks import ALONE, Ranks
from ..progress import SILENT, Progress
from .errors import SingularMatrixError, SolverMemoryError
from .factorization import installed_backends
from .linear import MULTIGRIDS, chosen_multigrid

SOLVERS = {solver.name: solver for solver in (FullNewton, IterativeNewton, CondensedNewton)}
METHODS = ("auto", *SOLVERS)


@dataclass(frozen=True)
class DofLayout:
    """Where the free dofs sit among the d · nodes nodal dofs (dof d · node + component), and the
    rigid-body motions on them (free dofs, k): what the iterative method's multigrid needs."""

    free: np.ndarray
    dim: int
    nodes: int
    rigid_motions: np.ndarray


def make_solver(method: str, A, N, weights, gap0, *, r: float, reason: str, rigid, tolerance: float,
                max_iterations: int, length_scale: float, factorization: str = "auto", multigrid: str = "auto",
                layout: DofLayout, progress: Progress = SILENT, expected_seconds: float | None = None,
                partition=None):
    """The step solver ``method`` ("full", "iterative" or "condensed": the method of a run's plan, whose
    memory the plan has checked, :mod:`vpcontact.timeloop.plan`; ``reason``: why it runs) for stiffness A and
    contact operator N (both on the free dofs), with the Alart–Curnier augmentation r; ``rigid``: an orthonormal
    basis of the rigid motions held only by contact, (free dofs, k); ``layout``: the dofs' nodal layout;
    ``progress`` (:mod:`vpcontact.progress`) hears of the method and of the set-up phases, each with
    ``expected_seconds``, the time its set-up is expected to take (:mod:`vpcontact.solvers.cost`). The iterative
    method's multigrid is ``multigrid`` (:func:`.linear.chosen_multigrid`), named in ``solver.reason``. With a
    ``partition`` of the nodes among MPI ranks (:class:`vpcontact.parallel.partition.NodePartition`) the iterative
    method's solve is shared among them (:mod:`.distributed`)."""
    if method == IterativeNewton.name:
        reason = f"{reason}; {multigrid_reason('petsc' if partition is not None else multigrid)}"
    progress.note(f"method: {method} ({reason})")
    common = (A, N, weights, gap0, r, tolerance, max_iterations, length_scale, rigid)
    if method == CondensedNewton.name:
        solver = _built(lambda: CondensedNewton(*common, factorization=factorization, progress=progress,
                                                expected_seconds=expected_seconds), factorization, A)
    elif method == IterativeNewton.name and partition is not None:
        solver = DistributedNewton(*common, partition=partition, free=layout.free, dim=layout.dim,
                                   near_nullspace=layout.rigid_motions, progress=progress,
                                   expected_seconds=expected_seconds)
    elif method == IterativeNewton.name:
        solver = IterativeNewton(*common, near_nullspace=layout.rigid_motions, free=layout.free, dim=layout.dim,
                                 nodes=layout.nodes, multigrid=multigrid, progress=progress,
                                 expected_seconds=expected_seconds)
    else:
        solver = _built(lambda: FullNewton(*common, factorization, progress=progress,
                                           expected_seconds=expected_seconds), factorization, A)
    solver.reason = reason
    return solver


def multigrid_reason(multigrid: str) -> str:
    """Which multigrid the iterative method runs for ``solver.multigrid`` = ``multigrid``, and why, in words."""
    label = MULTIGRIDS[chosen_multigrid(multigrid)].label
    if multigrid != "auto":
        return f"its CG preconditioned by {label} (solver.multigrid = \"{multigrid}\")"
    installed = "installed" if chosen_multigrid(multigrid) == "petsc" else "not installed"
    return f"its CG preconditioned by {label} (solver.multigrid = \"auto\": petsc4py is {installed})"


def augmentation_parameter(A, N, augmentation: float | None, ranks: Ranks = ALONE) -> float:
    """The Alart–Curnier r: ``augmentation`` (solver.augmentation) or, for None, the median normal stiffness
    at the contact nodes; CaseError for an ``augmentation`` more than 10¹² times away from that stiffness. On MPI
    ranks (``ranks``), A is this rank's rows of the stiffness (r is the same on every rank)."""
    r = default_augmentation(A, N, ranks)
    if augmentation is None:
        return r
    if not 1e-12 <= augmentation / r <= 1e12:
        raise CaseError(f"solver.augmentation = {augmentation:g} is {augmentation / r:.1e} times the normal "
                        f"stiffness at the contact nodes ({r:.3g}): use \"auto\" or a value near it")
    return augmentation


def _built(make, factorization: str, A):
    """The solver ``make()`` returns, its failures to factor (or analyse) A as one-line CaseErrors."""
    try:
        return make()
    except SingularMatrixError as error:
        raise CaseError(f"the stiffness matrix cannot be factored ({error}): the mesh has degenerate elements, or "
                        f"a part of the body is held by nothing") from None
    except SolverMemoryError as error:
        used = installed_backends()[0] if factorization == "auto" else factorization
        other = "" if used == "pardiso" else ", or solver.factorization = \"pardiso\" (MKL: smaller factors)"
        raise CaseError(f"not enough memory to factor the stiffness matrix ({A.shape[0]} dofs): {error}; use a "
                        f"coarser mesh{other}") from None


__all__ = ["METHODS", "SOLVERS", "DofLayout", "SolverWork", "StepData", "StepSolution", "augmentation_parameter",
           "make_solver"]
