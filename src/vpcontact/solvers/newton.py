"""The generalized (semi-smooth) Newton iteration shared by the step solvers.

A solver supplies the iterate (what it solves for), the evaluation of the step problem at an
iterate and the Newton direction; this module runs the iteration, the globalization and the
stopping test. Globalization: a step that changes the active set is taken whole, as in primal–dual
active set methods; a step that keeps it (the smooth regime of the compliance law) is damped by
backtracking on the solver's merit function (Armijo). Stopping: the relative equilibrium residual
≤ tolerance and the complementarity error max|min(λ/r, g − d)| ≤ tolerance × body size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import ContactState, StepData, StepSolution

#: Jacobian-only stiffness (relative to r) on inactive nodes with no compliance stiffness: keeps the
#: Newton matrix of a body held only by contact nonsingular; the converged solution is unchanged.
JACOBIAN_REGULARIZATION = 1e-10
ARMIJO = 1e-4
MAX_BACKTRACKS = 12


@dataclass(frozen=True)
class Evaluation:
    """The step problem at an iterate: contact state, merit vector, and the two stopping measures."""

    d: np.ndarray
    lam: np.ndarray
    state: ContactState
    merit_vector: np.ndarray
    residual: float
    complementarity: float
    d_solution: np.ndarray | None = None  # penetration of the displacement the solver returns, if not d

    def __post_init__(self):
        if self.d_solution is None:
            object.__setattr__(self, "d_solution", self.d)

    @property
    def merit(self) -> float:
        return 0.5 * float(self.merit_vector @ self.merit_vector)


class SemismoothNewton:
    """The iteration; subclasses define ``initial``, ``evaluate``, ``direction`` and ``solution``."""

    def __init__(self, weights: np.ndarray, r: float, tolerance: float, max_iterations: int, length_scale: float):
        self.weights, self.r = weights, r
        self.tolerance, self.max_iterations, self.length_scale = tolerance, max_iterations, length_scale

    def jacobian_tangent(self, state: ContactState) -> np.ndarray:
        """The compliance tangent T_i used in the Newton matrix (regularized where it vanishes)."""
        floor = JACOBIAN_REGULARIZATION * self.r
        return np.where(~state.active & (state.tangent < floor), floor, state.tangent)

    def complementarity(self, state: ContactState) -> float:
        return float(np.max(np.abs(state.C), initial=0.0)) / self.r

    def solve(self, step: StepData, previous: StepSolution | None) -> StepSolution:
        """Newton iterations from the previous step's solution (or zero) until the stopping test holds."""
        x = self.initial(step, previous)
        ev = self.evaluate(step, x)
        for iteration in range(self.max_iterations + 1):
            if not (np.isfinite(ev.residual) and np.isfinite(ev.complementarity)):
                return self.solution(step, x, ev, iteration, False, "the iterates are not finite")
            if ev.residual <= self.tolerance and ev.complementarity <= self.tolerance * self.length_scale:
                return self.solution(step, x, ev, iteration, True)
            if iteration == self.max_iterations:
                break
            dx = self.direction(step, x, ev)
            x, ev = self._line_search(step, x, dx, ev)
        return self.solution(step, x, ev, self.max_iterations, False,
                             f"no convergence in {self.max_iterations} Newton iterations")

    def _line_search(self, step, x, dx, ev: Evaluation):
        alpha = 1.0
        for _ in range(MAX_BACKTRACKS + 1):
            trial_x = tuple(a + alpha * b for a, b in zip(x, dx))
            trial = self.evaluate(step, trial_x)
            if alpha == 1.0 and not np.array_equal(trial.state.active, ev.state.active):
                return trial_x, trial
            if trial.merit <= (1.0 - 2.0 * ARMIJO * alpha) * ev.merit:
                return trial_x, trial
            alpha *= 0.5
        trial_x = tuple(a + b for a, b in zip(x, dx))  # no decrease along the direction: the whole step
        return trial_x, self.evaluate(step, trial_x)

    # --- what a solver defines -----------------------------------------------------------------
    def initial(self, step: StepData, previous: StepSolution | None) -> tuple:
        raise NotImplementedError

    def evaluate(self, step: StepData, x: tuple) -> Evaluation:
        raise NotImplementedError

    def direction(self, step: StepData, x: tuple, ev: Evaluation) -> tuple:
        raise NotImplementedError

    def solution(self, step, x, ev: Evaluation, iterations: int, converged: bool, message: str = "") -> StepSolution:
        raise NotImplementedError
