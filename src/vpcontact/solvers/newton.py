"""The generalized (semi-smooth) Newton iteration shared by the step solvers.

A solver supplies the iterate (what it solves for), the evaluation of the step problem at an
iterate and the Newton direction; this module runs the iteration, the globalization and the
stopping test. Globalization: a step that changes the active set is taken whole, as in primal–dual
active set methods; a step that keeps it (the smooth regime of the compliance law) is damped by
backtracking on the solver's merit function (Armijo). Stopping: the relative equilibrium residual
≤ tolerance (or, when rounding does not allow that, once it is below the level rounding leaves in
it, :attr:`Evaluation.residual_floor`, and has stopped decreasing) and the complementarity error
max|min(λ/r, g − d)| ≤ tolerance × body size. Every threshold is relative to a scale of the problem
(forces, r, the body's size), so
the iteration does not depend on the units or on the ratio of the body's and the layer's stiffness.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from threadpoolctl import ThreadpoolController

from ..parallel.dofs import ALL_DOFS, Dofs
from ..progress import SILENT, Progress
from .base import ContactState, SolverWork, StepData, StepSolution

#: Jacobian-only stiffness (relative to r) on inactive nodes with no compliance stiffness at all (a
#: separated node, K = 0): keeps the Newton matrix of a body held only by contact nonsingular; the
#: converged solution is unchanged. Nodes with a compliance tangent keep it however small it is
#: against r: a stiff body on a soft layer (E / K up to 1e9 and more) needs its exact Jacobian.
JACOBIAN_REGULARIZATION = 1e-12
#: The rounding level of a computed residual, relative to the sum of the magnitudes of its terms: no
#: iteration reduces a residual below it. Measured on the half disc with E / K from 1 to 1e9: the
#: residual stagnates at 0.2–0.3 units of the last place of that sum; 4 units leave a margin of 15.
ROUNDOFF = 4 * np.finfo(float).eps
ARMIJO = 1e-4
#: Below its rounding floor, a residual that an iteration reduces by less than this factor has stagnated.
STAGNATION = 0.5
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
    residual_floor: float = 0.0  # the residual that rounding alone leaves (same scale as ``residual``)
    balance: float = 0.0  # ‖Zᵀ R‖ (same scale): net force and moment on the rigid motions held only by contact
    d_solution: np.ndarray | None = None  # penetration of the displacement the solver returns, if not d

    def __post_init__(self):
        if self.d_solution is None:
            object.__setattr__(self, "d_solution", self.d)

    @property
    def merit(self) -> float:
        return 0.5 * float(self.merit_vector @ self.merit_vector)


class SemismoothNewton:
    """The iteration; subclasses define ``initial``, ``evaluate``, ``direction`` and ``solution``, and report
    their work in the time loop (``work``). ``dofs`` are the unknowns it holds (:mod:`vpcontact.parallel.dofs`):
    all of them, or one MPI rank's share, whose reductions make every rank take the same decisions."""

    _threads = ThreadpoolController()
    reason = ""  # why this method runs: the case's solver.method, or what "auto" weighed (set by make_solver)
    dofs: Dofs = ALL_DOFS

    def __init__(self, weights: np.ndarray, r: float, tolerance: float, max_iterations: int, length_scale: float,
                 progress: Progress = SILENT):
        self.weights, self.r = weights, r
        self.tolerance, self.max_iterations, self.length_scale = tolerance, max_iterations, length_scale
        self.progress = progress  # hears of each iterate (vpcontact.progress: what a long step is doing)

    def kept(self) -> dict[str, np.ndarray]:
        """What this solver carries from one step to the next beyond the StepSolution (a checkpoint keeps
        it, see :mod:`vpcontact.io.checkpoint`): nothing, unless a solver keeps something."""
        return {}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of the solver of the same problem in an earlier process."""

    def jacobian_tangent(self, state: ContactState) -> np.ndarray:
        """The compliance tangent T_i used in the Newton matrix (regularized where it vanishes)."""
        return np.where(~state.active & (state.tangent <= 0.0), JACOBIAN_REGULARIZATION * self.r, state.tangent)

    def converged(self, ev: Evaluation, last_residual: float | None) -> bool:
        """Complementarity to the tolerance times the body's size, and equilibrium to the tolerance, or
        to rounding when the tolerance is below what rounding allows (a stiff body held by a soft
        layer): the residual is under its floor, the last iteration no longer halved it, and the
        net force and moment on the motions held only by contact balance to the tolerance."""
        if ev.complementarity > self.tolerance * self.length_scale:
            return False
        if ev.residual <= self.tolerance:
            return True
        return (ev.residual <= ev.residual_floor and ev.balance <= self.tolerance and last_residual is not None
                and ev.residual > STAGNATION * last_residual)

    def complementarity(self, state: ContactState) -> float:
        return self.dofs.max(float(np.max(np.abs(state.C), initial=0.0))) / self.r

    def solve(self, step: StepData, previous: StepSolution | None) -> StepSolution:
        """Newton iterations from the previous step's solution (or zero) until the stopping test holds,
        their dense and vector algebra on one BLAS thread: at these sizes threads only contend on two
        busy cores (a 286 × 286 solve took 57 ms on two threads, 1 ms on one; a norm of 24k entries
        7 ms against 10 µs)."""
        with self._threads.limit(limits=1, user_api="blas"):
            return self._iterate(step, previous)

    def _iterate(self, step: StepData, previous: StepSolution | None) -> StepSolution:
        x = self.initial(step, previous)
        ev, last_residual = self.evaluate(step, x), None
        for iteration in range(self.max_iterations + 1):
            self.progress.newton(iteration, ev.residual)
            if not (np.isfinite(ev.residual) and np.isfinite(ev.complementarity)):
                return self.solution(step, x, ev, iteration, False, "the iterates are not finite",
                                     "try smaller time steps (time.steps), and check that the contact laws stay finite")
            if self.converged(ev, last_residual):
                return self.solution(step, x, ev, iteration, True)
            if iteration == self.max_iterations:
                break
            dx = self.direction(step, x, ev)
            last_residual = ev.residual
            x, ev = self._line_search(step, x, dx, ev)
        return self.solution(step, x, ev, self.max_iterations, False,
                             f"no convergence in {self.max_iterations} Newton iterations",
                             f"try solver.max_iterations = {2 * self.max_iterations}, smaller time steps (time.steps), "
                             f"or solver.tolerance = {10 * self.tolerance:g}")

    def _line_search(self, step, x, dx, ev: Evaluation):
        alpha = 1.0
        for _ in range(MAX_BACKTRACKS + 1):
            trial_x = tuple(a + alpha * b for a, b in zip(x, dx))
            trial = self.evaluate(step, trial_x)
            if alpha == 1.0 and not self.dofs.same(trial.state.active, ev.state.active):
                return trial_x, trial
            if self.dofs.sum(trial.merit) <= (1.0 - 2.0 * ARMIJO * alpha) * self.dofs.sum(ev.merit):
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

    def solution(self, step, x, ev: Evaluation, iterations: int, converged: bool, message: str = "",
                 advice: str = "") -> StepSolution:
        raise NotImplementedError

    def work(self) -> SolverWork:
        """The solver's counters of work so far (:class:`~.base.SolverWork`)."""
        raise NotImplementedError
