"""The run's second-order companion, which estimates its error in time (``output.error_estimate``, ``time.adaptive``).

The run integrates its two histories by first-order rules: ξ by the implicit rectangle rule ξ_n = ξ_{n−1} + k d_n⁺
(for (2.15)) and z by the explicit one z_n = z_{n−1} + k 𝒢_{n−1} (for (2.28)). Its companion takes the same loads,
u_D, mesh and step problem, and integrates both histories by the trapezoid rule, second order in k::

    ξ̃_n = ξ̃_{n−1} + (k/2)(d̃_{n−1}⁺ + d̃_n⁺)                     implicit: the step problem with ξ̃_{n−1} + (k/2) d̃_{n−1}⁺ and k/2
    z̃_n = z̃_{n−1} + (k/2)(𝒢̃_{n−1} + 𝒢̂_n),  𝒢̂_n = 𝒢_n + (𝒢̃_{n−1} − 𝒢_{n−1})

𝒢̃ = 𝒢(σ̃, ε(ũ)) with σ̃ = ℰε(ũ) + z̃; the end rate 𝒢̂_n is the run's 𝒢_n shifted by the last known difference
between the two, so that z̃ stays explicit (the difference changes by O(k²) over a step: the rule stays second order).
The companion starts from the run's level t_0 and follows it step by step, each of its steps one more solve of the
step problem, whose Newton iteration starts from the run's solution.

With the companion's error O(k²) and the run's O(k), D_n = ũ_n − u_n is the run's error in time at t_n to first
order, for the mesh's problem, and

    η_k(t_n) = ‖D_n‖_E                 (the history column ``time_estimate``)
    θ_n = ‖D_n − D_{n−1}‖_E            (``time_estimate_step``: how much the step added, ∝ k_n²)

with ‖v‖_E² = ∫_Ω ℰε(v):ε(v), the energy norm of the space estimate. Measured on the paper's example and on a
viscoplastic ball (docs/adaptivity.md), η_k / ‖u_n − u(t_n)‖_E is 0.9–1.15 from 4 to 80 steps, against a run
with 8× as many steps.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..parallel.elements import ElementShare
from ..solvers import StepSolution
from ..solvers.errors import NotConvergedError, SingularMatrixError
from .checks import LawShapeError, viscoplastic_rate


@dataclass(frozen=True)
class CompanionLevel:
    """The companion at a time level: ξ̃ and d̃ at the contact nodes, z̃ and 𝒢̃ on this rank's elements (None:
    the run has none), D = ũ − u at the free dofs, the estimates η_k = ‖D‖_E and θ = ‖D − D_before‖_E (NaN
    where the companion's Newton iteration failed: it then restarts from the run's level), and the run's ‖u‖_E."""

    xi: np.ndarray
    d: np.ndarray
    z: np.ndarray | None
    rate: np.ndarray | None
    difference: np.ndarray
    estimate: float = 0.0
    step_estimate: float = 0.0
    norm: float = 0.0

    @property
    def known(self) -> bool:
        """Whether the companion reached this level (its estimates are numbers)."""
        return bool(np.isfinite(self.estimate))


class Companion:
    """The second-order companion of a time loop (see the module docstring): ``level`` is its last accepted level,
    ``attempt`` solves its step to the run's attempted level, ``accept`` makes that its level."""

    def __init__(self, problem, share: ElementShare, state):
        self.problem, self.share = problem, share
        self.level = CompanionLevel(state.xi.copy(), _start_penetration(problem, state), state.z, state.rate,
                                    np.zeros(problem.free.size))

    def attempt(self, solver, attempt, u: np.ndarray, run_rate_before: np.ndarray | None,
                run_rate: np.ndarray | None) -> CompanionLevel:
        """The companion's level at the run's converged ``attempt`` (a step of length h from the run's last level,
        whose 𝒢 was ``run_rate_before``; u: the run's displacement at the attempt's level at every dof, 𝒢 there
        ``run_rate``), by one solve of the step problem with the companion's trapezoid histories. The level is not
        accepted."""
        problem, before, h = self.problem, self.level, attempt.h
        z = before.z
        if before.rate is not None:
            z = before.z + 0.5 * h * (2.0 * before.rate - run_rate_before + run_rate)
        solved = self._solve(solver, attempt, u, z, before.xi + 0.5 * h * np.maximum(before.d, 0.0))
        if solved is None:
            return self._restarted(attempt, u, run_rate)
        companion_u, solution = solved
        rate = None
        if before.rate is not None:
            strain = self.share.strain(companion_u)
            try:
                rate = viscoplastic_rate(self.share.viscoplastic, self.share.stress(strain, z), strain)
            except LawShapeError:
                return self._restarted(attempt, u, run_rate)
        difference = companion_u[problem.free] - u[problem.free]
        xi = before.xi + 0.5 * h * (np.maximum(before.d, 0.0) + np.maximum(solution.d, 0.0))
        return CompanionLevel(xi, solution.d.copy(), z, rate, difference, self.free_energy(difference),
                              self.free_energy(difference - before.difference), self.energy(u))

    def _solve(self, solver, attempt, u: np.ndarray, z: np.ndarray | None, xi_start: np.ndarray):
        """(u at every dof, the step solution) of the run's attempted step problem with the history z at its level
        and ξ = xi_start + (h/2) d⁺ (the implicit trapezoid rule); None where its Newton iteration fails."""
        problem, step = self.problem, attempt.step
        b = step.b if z is attempt.z else step.b + self.share.force(attempt.z - z)[problem.free]
        trapezoid = replace(step, b=b, xi_prev=xi_start, k=0.5 * attempt.h, support=None)
        try:
            with np.errstate(all="ignore"):
                solution = solver.solve(trapezoid, attempt.solution)
        except (SingularMatrixError, NotConvergedError):
            return None
        if not solution.converged:
            return None
        whole = u.copy()
        whole[problem.free] = solver.displacement(trapezoid, solution)
        return whole, solution

    def _restarted(self, attempt, u: np.ndarray, run_rate: np.ndarray | None) -> CompanionLevel:
        """The companion restarted at the run's level (its Newton iteration failed there): no estimate."""
        solution: StepSolution = attempt.solution
        xi = attempt.step.xi_prev + attempt.h * np.maximum(solution.d, 0.0)
        return CompanionLevel(xi, solution.d.copy(), attempt.z, run_rate, np.zeros(self.problem.free.size),
                              np.nan, np.nan, self.energy(u))

    def accept(self, level: CompanionLevel) -> None:
        """Make ``level`` the companion's last level."""
        self.level = level

    def free_energy(self, free_values: np.ndarray) -> float:
        """‖v‖_E of v given at the free dofs, 0 at the held ones (a difference of two displacements with the same u_D)."""
        v = np.zeros(self.problem.basis.N)
        v[self.problem.free] = free_values
        return self.energy(v)

    def energy(self, v: np.ndarray) -> float:
        """‖v‖_E = (∫_Ω ℰε(v):ε(v))^{1/2} of v at every dof, over every rank's elements."""
        share = self.share
        strain = share.strain(v)
        density = np.einsum("ij...,ij...->...", share.elasticity.stress(strain), strain)
        return float(np.sqrt(max(share.ranks.sum(float(share.geometry.volumes @ density)), 0.0)))

    # --- a checkpoint -----------------------------------------------------------------------------
    def arrays(self, level: CompanionLevel | None = None) -> dict[str, np.ndarray]:
        """The companion's level (default: its last) as named arrays (``companion_*``; z̃ and 𝒢̃ over all the
        elements: a collective call on several ranks)."""
        level, share = self.level if level is None else level, self.share
        arrays = {"companion_xi": level.xi, "companion_d": level.d, "companion_difference": level.difference}
        if level.z is not None:
            arrays["companion_z"] = share.whole(level.z)
        if level.rate is not None:
            arrays["companion_rate"] = share.whole(level.rate)
        return arrays

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """The companion's level of :meth:`arrays` (z̃ and 𝒢̃ taken at this rank's elements); KeyError for a
        missing one."""
        share = self.share
        self.level = CompanionLevel(arrays["companion_xi"], arrays["companion_d"], share.mine(arrays.get("companion_z")),
                                    share.mine(arrays.get("companion_rate")), arrays["companion_difference"])


def _start_penetration(problem, state) -> np.ndarray:
    """d at t_0: u_0's (the run's first Newton start), else 0."""
    return np.zeros(problem.surface.size) if state.previous is None else state.previous.d.copy()
