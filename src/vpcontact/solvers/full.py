"""The paper's method: the generalized Newton method (3.6) on the whole system (3.5).

Iterate (u, λ). Each iteration solves the linearization of the step problem of ``base``:
    (A + Nᵀ diag(T) N) Δu + N_𝒜ᵀ Δλ_𝒜 = −R_u + N_ℐᵀ λ_ℐ,     N_𝒜 Δu = g − d_𝒜,     Δλ_ℐ = −λ_ℐ,
with 𝒜 = {λ + r(d − g) > 0} the nodes on the rigid base, ℐ the others and T_i the compliance
tangent w_i [K p'(d) + K'(ξ) k H(d) p(d)]. The saddle-point matrix is factored by sparse LU at every
iteration: the reference method, simple and general, and slow on large meshes.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .base import ContactState, StepData, StepSolution
from .factorization import splu
from .newton import ROUNDOFF, Evaluation, SemismoothNewton


class FullNewton(SemismoothNewton):
    """Semi-smooth Newton on (u, λ) with the whole stiffness matrix."""

    name = "full"

    def __init__(self, A: sp.csr_matrix, N: sp.csr_matrix, weights, gap0, r, tolerance, max_iterations, length_scale,
                 rigid: np.ndarray):
        super().__init__(weights, r, tolerance, max_iterations, length_scale)
        self.A, self.N, self.gap0, self.Z = A, N.tocsr(), gap0, rigid
        self._A_abs, self._N_abs = abs(self.A), abs(self.N)  # for the rounding level of the residual
        self.timings: dict[str, float] = {}
        self.solves = 0  # sparse LU factorizations and solves, one per Newton iteration

    def initial(self, step: StepData, previous: StepSolution | None) -> tuple:
        if previous is None:
            return np.zeros(self.A.shape[0]), np.zeros(self.N.shape[0])
        return previous.u, previous.lam

    def evaluate(self, step: StepData, x: tuple) -> Evaluation:
        """The residual R_u = A u + Nᵀ(f + λ) − b relative to the larger of ‖b‖ and ‖Nᵀ(f + λ)‖, with
        A u evaluated as A (u − Z Zᵀu): the rigid motions Z held only by contact strain nothing, and
        a large one (a stiff body sinking into a soft layer) would cost digits, since A annihilates it
        only to rounding. Also the level rounding leaves in R_u, ROUNDOFF ‖|A||u| + |Nᵀ|(|f| + |λ|) +
        |b|‖, and the balance ‖Zᵀ R_u‖, on the same scale."""
        u, lam = x
        d = self.N @ u - self.gap0
        state = ContactState.evaluate(step, self.weights, d, lam, self.r)
        contact = self.N.T @ (state.force + lam)
        R_u = self.A @ (u - self.Z @ (self.Z.T @ u)) + contact - step.b
        scale = max(np.linalg.norm(step.b), np.linalg.norm(contact))
        scale = scale if scale > 0 else 1.0
        magnitudes = self._A_abs @ np.abs(u) + self._N_abs.T @ (np.abs(state.force) + np.abs(lam)) + np.abs(step.b)
        return Evaluation(d, lam, state, np.concatenate([R_u, state.C]), np.linalg.norm(R_u) / scale,
                          self.complementarity(state), ROUNDOFF * np.linalg.norm(magnitudes) / scale,
                          np.linalg.norm(self.Z.T @ R_u) / scale)

    def direction(self, step: StepData, x: tuple, ev: Evaluation) -> tuple:
        u, lam = x
        active = ev.state.active
        self.solves += 1
        J = self.A + self.N.T @ sp.diags(self.jacobian_tangent(ev.state)) @ self.N
        N_active = self.N[active]
        rhs_u = -ev.merit_vector[: u.size] + self.N[~active].T @ lam[~active]
        if active.any():
            kkt = sp.bmat([[J, N_active.T], [N_active, None]], format="csc")
            solution = splu(kkt).solve(np.concatenate([rhs_u, step.law.limit(active) - ev.d[active]]))
        else:
            solution = splu(J.tocsc()).solve(rhs_u)
        dlam = -lam.copy()
        dlam[active] = solution[u.size:]
        return solution[: u.size], dlam

    def solution(self, step, x, ev: Evaluation, iterations, converged, message="", advice="") -> StepSolution:
        return StepSolution(x[0], x[1], ev.d, ev.state.active, iterations, ev.residual, ev.complementarity,
                            converged, message, advice)

    def displacement(self, step: StepData, solution: StepSolution) -> np.ndarray:
        """u at the free dofs (the iterate itself)."""
        return solution.u
