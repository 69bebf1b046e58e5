"""The paper's method: a generalized (semi-smooth) Newton method on the whole system (3.5)–(3.6).

Each iteration linearizes the step problem of ``base`` at (u, λ):
    (A + Nᵀ diag(T) N) Δu + N_𝒜ᵀ Δλ_𝒜 = −R_u + N_ℐᵀ λ_ℐ,     N_𝒜 Δu = g − d_𝒜,     Δλ_ℐ = −λ_ℐ,
where 𝒜 = {λ + r(d − g) > 0} is the active (rigid) set, ℐ the rest and T_i = w_i [K p'(d) + K'(ξ) k H(d) p]
the compliance tangent. The saddle-point matrix is factored by sparse LU at every iteration.

Globalization: when the full step leaves the active set unchanged (the smooth regime of the
compliance law) it is damped by backtracking on the merit ½(‖R_u‖² + ‖C‖²); a step that changes
the active set is taken whole, as in primal–dual active set methods.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .base import ContactState, StepData, StepSolution

#: Jacobian-only stiffness (relative to r) on inactive nodes with no compliance stiffness: keeps the
#: Newton matrix of a body held only by contact nonsingular; the converged solution is unchanged.
JACOBIAN_REGULARIZATION = 1e-10
ARMIJO = 1e-4
MAX_BACKTRACKS = 12


class FullNewton:
    """Semi-smooth Newton on (u, λ) with the whole stiffness matrix: the reference method."""

    name = "full"

    def __init__(self, A: sp.csr_matrix, N: sp.csr_matrix, weights: np.ndarray, gap0: np.ndarray, r: float,
                 tolerance: float, max_iterations: int, length_scale: float):
        self.A, self.N, self.weights, self.gap0, self.r = A, N.tocsr(), weights, gap0, r
        self.tolerance, self.max_iterations, self.length_scale = tolerance, max_iterations, length_scale

    def _residuals(self, step: StepData, u: np.ndarray, lam: np.ndarray):
        d = self.N @ u - self.gap0
        state = ContactState.evaluate(step, self.weights, d, lam, self.r)
        contact = self.N.T @ (state.force + lam)
        R_u = self.A @ u + contact - step.b
        scale = max(np.linalg.norm(step.b), np.linalg.norm(contact))
        return d, state, R_u, scale

    def solve(self, step: StepData, u: np.ndarray, lam: np.ndarray) -> StepSolution:
        """Newton iterations from (u, λ) until ‖R_u‖ ≤ tol·scale and |C/r| ≤ tol·L (L: body size)."""
        d, state, R_u, scale = self._residuals(step, u, lam)
        for iteration in range(self.max_iterations + 1):
            residual = np.linalg.norm(R_u) / scale if scale > 0 else np.linalg.norm(R_u)
            complementarity = float(np.max(np.abs(state.C), initial=0.0)) / self.r
            if not (np.isfinite(residual) and np.isfinite(complementarity)):
                return StepSolution(u, lam, d, state.active, iteration, residual, complementarity, False,
                                    "the iterates are not finite")
            if residual <= self.tolerance and complementarity <= self.tolerance * self.length_scale:
                return StepSolution(u, lam, d, state.active, iteration, residual, complementarity, True)
            if iteration == self.max_iterations:
                break
            du, dlam = self._direction(step, d, lam, state, R_u)
            u, lam, d, state, R_u, scale = self._line_search(step, u, lam, du, dlam, state, R_u)
        return StepSolution(u, lam, d, state.active, self.max_iterations, residual, complementarity, False,
                            f"no convergence in {self.max_iterations} Newton iterations")

    def _direction(self, step, d, lam, state: ContactState, R_u):
        """Solve the generalized Newton system for (Δu, Δλ)."""
        active = state.active
        tangent = np.where(~active & (state.tangent < JACOBIAN_REGULARIZATION * self.r),
                           JACOBIAN_REGULARIZATION * self.r, state.tangent)
        J = self.A + self.N.T @ sp.diags(tangent) @ self.N
        N_active = self.N[active]
        rhs_u = -R_u + self.N[~active].T @ lam[~active]
        rhs_lam = step.law.g - d[active]
        kkt = sp.bmat([[J, N_active.T], [N_active, None]], format="csc")
        solution = spla.splu(kkt).solve(np.concatenate([rhs_u, rhs_lam]))
        du = solution[: self.A.shape[0]]
        dlam = -lam.copy()
        dlam[active] = solution[self.A.shape[0]:]
        return du, dlam

    def _line_search(self, step, u, lam, du, dlam, state, R_u):
        """Full step if it changes the active set or decreases the merit; else backtrack (Armijo)."""
        merit = 0.5 * (R_u @ R_u + state.C @ state.C)
        alpha = 1.0
        for _ in range(MAX_BACKTRACKS + 1):
            trial_u, trial_lam = u + alpha * du, lam + alpha * dlam
            d, trial, R_trial, scale = self._residuals(step, trial_u, trial_lam)
            trial_merit = 0.5 * (R_trial @ R_trial + trial.C @ trial.C)
            if alpha == 1.0 and not np.array_equal(trial.active, state.active):
                break
            if trial_merit <= (1.0 - 2.0 * ARMIJO * alpha) * merit:
                break
            alpha *= 0.5
        else:  # no decrease along the direction: take the whole step
            trial_u, trial_lam = u + du, lam + dlam
            d, trial, R_trial, scale = self._residuals(step, trial_u, trial_lam)
        return trial_u, trial_lam, d, trial, R_trial, scale
