"""Step solvers behind one interface: ``make_solver(name, ...)`` returns an object whose
``solve(step, u, λ)`` returns a :class:`~vpcontact.solvers.base.StepSolution`."""

from __future__ import annotations

from .base import StepData, StepSolution, default_augmentation
from .full import FullNewton

SOLVERS = {FullNewton.name: FullNewton}


def make_solver(method: str, A, N, weights, gap0, *, augmentation: float | None, tolerance: float,
                max_iterations: int, length_scale: float):
    """The step solver ``method`` for stiffness A and contact operator N (both on the free dofs)."""
    r = default_augmentation(A, N) if augmentation is None else augmentation
    return SOLVERS[method](A, N, weights, gap0, r, tolerance, max_iterations, length_scale)


__all__ = ["SOLVERS", "StepData", "StepSolution", "make_solver"]
