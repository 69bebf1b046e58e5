"""The paper's method: the generalized Newton method (3.6) on the whole system (3.5).

Iterate (u, λ). Each iteration solves the linearization of the step problem of ``base``:
    (A + Nᵀ diag(T) N) Δu + N_𝒜ᵀ Δλ_𝒜 = −R_u + N_ℐᵀ λ_ℐ,     N_𝒜 Δu = g − d_𝒜,     Δλ_ℐ = −λ_ℐ,
with 𝒜 = {λ + r(d − g) > 0} the nodes on the rigid base, ℐ the others and T_i the compliance
tangent w_i [K p'(d) + K'(ξ) k H(d) p(d)]. In the contact nodes' normal frame (:mod:`.normal_frame`)
this saddle-point system is a symmetric positive definite one with the active nodes' normal dofs
fixed, and one sparsity pattern for every active set. Two methods solve it:

- "full": a sparse direct solver of the linear-solver layer (:mod:`.linear`), the pattern analysed
  once and the values refactored at every iteration;
- "iterative": CG preconditioned by algebraic multigrid (:mod:`.amg`, pyamg's, or :mod:`.petsc_gamg`, PETSc's
  GAMG: ``solver.multigrid``), its hierarchy built once, each system solved only as accurately as the iteration
  needs (an inexact Newton method: the linear residual a fraction of the nonlinear one, down to a tenth of the
  tolerance; exact solves for the rest of a step once an iteration did not reduce the residual), and CG started
  along the last step's correction (``IterativeNewton._start``). On the quarter ball at 24k dofs, 100 steps:
  12.7 CG iterations a step from 0, 9.7 so started; on the cyclic punch of benchmarks/punch.py (30k dofs, 60
  steps) 12.4 and 8.4. Eisenstat and Walker's forcing terms were measured in place of FORCING and did not pay
  (docs/performance.md, "Fewer CG iterations a step").
"""

from __future__ import annotations

import time
from contextlib import nullcontext

import numpy as np
import scipy.sparse as sp

from ..progress import SILENT, Progress, duration, size
from .base import ContactState, DisplacementSolution, SolverWork, StepData, StepSolution
from .cost import iterative_memory
from .linear import direct_solver, multigrid_solver
from .newton import ROUNDOFF, Evaluation, SemismoothNewton
from .normal_frame import NormalFrame


class FullNewton(DisplacementSolution, SemismoothNewton):
    """Semi-smooth Newton on (u, λ) with the whole stiffness matrix."""

    name = "full"

    def __init__(self, A: sp.csr_matrix, N: sp.csr_matrix, weights, gap0, r, tolerance, max_iterations, length_scale,
                 rigid: np.ndarray, factorization: str = "auto", progress: Progress = SILENT,
                 expected_seconds: float | None = None):
        """``progress`` hears of the linear solver's set-up (with ``expected_seconds``, the time the set-up is
        expected to take)."""
        super().__init__(weights, r, tolerance, max_iterations, length_scale, progress)
        self._expected = f"; expected: {duration(expected_seconds)}" if expected_seconds is not None else ""
        started = time.perf_counter()
        self.A, self.N, self.gap0, self.Z = A, N.tocsr(), gap0, rigid
        self._N_abs = abs(self.N)  # for the rounding level of the residual (|A|'s products: absolute_product)
        self.frame = NormalFrame(self.N)
        self.rotated = self._rotated(A)  # Q A Q
        framed = time.perf_counter()
        self.linear, self._analysed = self._linear_solver(factorization)
        self.setup_timings = {"normal_frame": framed - started, "linear_setup": time.perf_counter() - framed}
        self.solves = 0  # Newton systems solved, one per Newton iteration

    def _rotated(self, A: sp.csr_matrix) -> sp.csr_matrix:
        """Q A Q (:meth:`.normal_frame.NormalFrame.rotate`)."""
        return self.frame.rotate(A)

    def _linear_solver(self, factorization: str) -> tuple:
        """The linear solver, and whether it has been analysed: a direct one is, here, on the pattern
        every Newton matrix shares (Q A Q's; a factor that will not fit is refused now)."""
        solver = direct_solver(factorization, self.progress)
        with (self.progress.phase("analysis", f"{solver.analysis} of the Newton matrices' pattern, "
                                  f"{self.rotated.shape[0]:,} dofs, by {solver.label}{self._expected}")
              if solver.analysis else nullcontext()):
            solver.analyse(self.rotated)
        return solver, True

    @property
    def timings(self) -> dict[str, float]:
        """Seconds of the setup stages (the normal frame; the linear solver's, an AMG hierarchy's)."""
        return dict(self.setup_timings)

    def work(self) -> SolverWork:
        """Newton systems solved (one per Newton iteration), the linear solver's Krylov iterations (CG; none by a
        direct solver) and the Newton matrices it factored (every one by a direct solver, none by the iterative
        one)."""
        return SolverWork(self.solves, self.linear.iterations, self.linear.factorizations)

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
        dofs = self.dofs
        R_u = self.A @ dofs.ghosted(u - self.Z @ dofs.sum(self.Z.T @ u)) + contact - step.b
        scale = max(step.b_norm, dofs.safe_norm(contact))
        scale = scale if scale > 0 else 1.0
        magnitudes = (absolute_product(self.A, dofs.ghosted(np.abs(u)))
                      + self._N_abs.T @ (np.abs(state.force) + np.abs(lam)) + np.abs(step.b))
        return Evaluation(d, lam, state, np.concatenate([R_u, state.C]), dofs.norm(R_u) / scale,
                          self.complementarity(state), ROUNDOFF * dofs.norm(magnitudes) / scale,
                          np.linalg.norm(dofs.sum(self.Z.T @ R_u)) / scale)

    def direction(self, step: StepData, x: tuple, ev: Evaluation) -> tuple:
        """The Newton step from the SPD system of :mod:`.normal_frame`: the active nodes' normal dofs
        fixed at Δû_ν = (g − d) / s, the others solved for, Δλ_𝒜 from the fixed rows, Δλ_ℐ = −λ_ℐ."""
        u, lam = x
        frame = self.frame
        active = ev.state.active & frame.has_normal
        fixed = frame.normal_dofs(active)
        diagonal = frame.tangent_diagonal(self.jacobian_tangent(ev.state))
        rhs = frame.Q @ (-ev.merit_vector[: u.size] + self.N[~active].T @ lam[~active])
        held = np.zeros(u.size)
        held[frame.normal_dof[active]] = (step.law.limit(active) - ev.d[active]) / frame.scale[active]
        K = frame.constrained(diagonal, self.dofs.ghosted(fixed))
        self._system = (diagonal, fixed)  # what K is made of (the iterative method keeps it, see IterativeNewton)
        held_force = self.rotated @ self.dofs.ghosted(held) + diagonal * held
        system_rhs = np.where(fixed, K.diagonal() * held, rhs - held_force)
        if not self._analysed:
            self.linear.analyse(K)
            self._analysed = True
        self.linear.factor(K)
        self.solves += 1
        rotated_step = self._solve_system(K, system_rhs, self._linear_tolerance(ev, system_rhs), fixed, held)
        rotated_step[fixed] = held[fixed]
        dlam = -lam.copy()
        rows = frame.normal_dof[active]
        dlam[active] = ((rhs - self.rotated @ self.dofs.ghosted(rotated_step) - diagonal * rotated_step)[rows]
                        / frame.scale[active])
        return frame.Q @ rotated_step, dlam

    def _linear_tolerance(self, ev: Evaluation, rhs: np.ndarray) -> float:
        """How accurately the Newton system is solved: exactly (a direct solver)."""
        return 0.0

    def _solve_system(self, K: sp.csr_matrix, rhs: np.ndarray, rtol: float, fixed: np.ndarray,
                      held: np.ndarray) -> np.ndarray:
        """K x = rhs by the linear solver (to ``rtol``; the ``fixed`` dofs' x is ``held``)."""
        return self.linear.solve(rhs, rtol)

    def solution(self, step, x, ev: Evaluation, iterations, converged, message="", advice="") -> StepSolution:
        return StepSolution(x[0], x[1], ev.d, ev.state.active, iterations, ev.residual, ev.complementarity,
                            converged, message, advice)


#: Rows of |A| made at once by absolute_product.
ABSOLUTE_ROWS = 2**16


def absolute_product(A: sp.csr_matrix, x: np.ndarray) -> np.ndarray:
    """|A| x, with |A| the entrywise absolute value of A, made ABSOLUTE_ROWS rows at a time: never held whole (it
    would be two thirds of A's memory for the whole run), the same numbers as the product with |A| held."""
    y = np.empty(A.shape[0])
    for start in range(0, A.shape[0], ABSOLUTE_ROWS):
        stop = min(start + ABSOLUTE_ROWS, A.shape[0])
        first, last = A.indptr[start], A.indptr[stop]
        rows = sp.csr_matrix((np.abs(A.data[first:last]), A.indices[first:last], A.indptr[start:stop + 1] - first),
                             shape=(stop - start, A.shape[1]))
        y[start:stop] = rows @ x
    return y


#: The inexact Newton method's forcing: the linear residual is at most this fraction of the nonlinear
#: residual squared (superlinear convergence), and never needs to be below a tenth of the tolerance.
FORCING = 1e-2


class IterativeNewton(FullNewton):
    """The full-system Newton iteration with its SPD systems solved by AMG-preconditioned CG."""

    name = "iterative"

    def __init__(self, *args, near_nullspace: np.ndarray, free: np.ndarray, dim: int, nodes: int,
                 multigrid: str = "auto", progress: Progress = SILENT, expected_seconds: float | None = None):
        """``multigrid``: the multigrid backend (``solver.multigrid``, :func:`.linear.multigrid_solver`)."""
        self._layout = (free, dim, nodes, near_nullspace)
        self._multigrid = multigrid
        super().__init__(*args, progress=progress, expected_seconds=expected_seconds)
        self._hierarchy_system = None  # (diagonal, fixed) of the Newton matrix the AMG hierarchy was built on
        self._correction = None  # the last converged step's solution minus its first iterate (see _start)
        self._last_direction = None  # this step's last Newton direction (rotated)
        self._step_residuals = []  # the residuals of this step's iterates so far
        self._tightened = False  # an iteration of this step did not reduce the residual (see _linear_tolerance)

    def solve(self, step: StepData, previous: StepSolution | None) -> StepSolution:
        """FullNewton's, keeping the step's whole correction (its solution minus its first iterate) where it
        converged: the next step's first CG solve starts along it (:meth:`_start`)."""
        self._last_direction, self._step_residuals, self._tightened = None, [], False
        start = self.initial(step, previous)[0]
        solution = super().solve(step, previous)
        if solution.converged:
            self._correction = solution.u - start
        return solution

    def direction(self, step: StepData, x: tuple, ev: Evaluation) -> tuple:
        """FullNewton's, remembering what the Newton matrix was made of when the hierarchy was built on it."""
        setups = self.linear.setups
        found = super().direction(step, x, ev)
        if self.linear.setups != setups:
            self._hierarchy_system = self._system
        return found

    def _solve_system(self, K: sp.csr_matrix, rhs: np.ndarray, rtol: float, fixed: np.ndarray,
                      held: np.ndarray) -> np.ndarray:
        """CG from :meth:`_start`."""
        self._last_direction = self.linear.solve(rhs, rtol, self._start(K, rhs, fixed, held))
        return self._last_direction

    def _start(self, K: sp.csr_matrix, rhs: np.ndarray, fixed: np.ndarray, held: np.ndarray) -> np.ndarray | None:
        """CG's first iterate (None: zero): the fixed dofs at their values, the others α v along the last
        Newton direction of this step, or at a step's first iteration along the last step's whole
        correction (rotated), α = vᵀrhs / vᵀKv: the multiple of v nearest to the solution in K's energy
        norm, so that the start is never farther from it than 0 in that norm. Consecutive steps of a
        smooth load need similar corrections of the extrapolated start: on the quarter ball (24k dofs, 100
        steps) this start alone reduced the first solve's residual about 250-fold (3.2e-4 to 1.2e-6 at step
        49) and the CG iterations from 12.7 to 9.7 a step. None after an iteration that did not reduce the
        residual (see :meth:`_linear_tolerance`)."""
        v = self._last_direction
        if v is None and self._correction is not None:
            v = self.frame.Q @ self._correction
        if self._tightened or v is None:
            return None
        v = np.where(fixed, 0.0, v)
        energy = float(self.dofs.sum(float(v @ (K @ self.dofs.ghosted(v)))))
        if not energy > 0.0:
            return None
        return np.where(fixed, held, (float(self.dofs.sum(float(v @ rhs))) / energy) * v)

    def kept(self) -> dict[str, np.ndarray]:
        """What the iteration carries from step to step: the Newton matrix the AMG hierarchy was built on
        (its tangent diagonal and fixed dofs in the normal frame: two vectors, not the matrix), whether
        it is to be built again, and the last step's correction that CG starts from (:meth:`_start`).
        Restored (``restore``), the resumed run's preconditioner and CG starts are the uninterrupted run's,
        and so are its numbers, bit for bit."""
        kept = {} if self._correction is None else {"correction": self._correction}
        if self._hierarchy_system is None:
            return kept
        diagonal, fixed = self._hierarchy_system
        return {**kept, "hierarchy_diagonal": diagonal, "hierarchy_fixed": fixed,
                "hierarchy_stale": np.array(self.linear.stale)}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Build the hierarchy on the Newton matrix ``kept()`` names, as the earlier process had it; take its
        last correction."""
        self._correction = arrays.get("correction")
        if "hierarchy_diagonal" not in arrays:
            return
        diagonal, fixed = arrays["hierarchy_diagonal"], arrays["hierarchy_fixed"].astype(bool)
        self._hierarchy_system = (diagonal, fixed)
        self.linear.analyse(self.frame.constrained(diagonal, self.dofs.ghosted(fixed)))
        self.linear.stale = bool(arrays["hierarchy_stale"])
        self._analysed = True

    @property
    def timings(self) -> dict[str, float]:
        return {**self.setup_timings, "amg_setup": self.linear.setup_time}

    def _linear_solver(self, factorization: str) -> tuple:
        """AMG-preconditioned CG (the ``multigrid`` backend), the rigid motions in the normal frame as near-null
        space."""
        free, dim, nodes, near_nullspace = self._layout
        memory = f"{size(iterative_memory(self.A))} at the method's peak"
        expected = f"{self._expected}, {memory}" if self._expected else f"; expected: {memory}"
        return multigrid_solver(self._multigrid, free, dim, nodes, self.frame.Q @ near_nullspace, self.progress,
                                expected), False

    def _linear_tolerance(self, ev: Evaluation, rhs: np.ndarray) -> float:
        """Relative to ‖rhs‖: a linear residual of FORCING × the nonlinear residual squared, at least a
        tenth of the tolerance (both on the residual's scale, ‖R_u‖ / residual); only that tenth of the
        tolerance once an iteration of this step has not reduced the residual (``_tightened``): inexact
        directions with a state of the contact that changes can cycle (the punch of benchmarks/punch.py, where
        it presses the layer again after lifting off), exact ones do not."""
        residuals = self._step_residuals
        self._tightened = self._tightened or (bool(residuals) and not ev.residual < residuals[-1])
        residuals.append(ev.residual)
        rhs_norm = self.dofs.norm(rhs)
        if rhs_norm == 0.0 or ev.residual == 0.0:
            return 1e-12
        scale = self.dofs.norm(ev.merit_vector[: rhs.size]) / ev.residual
        forcing = 0.0 if self._tightened else FORCING * ev.residual ** 2
        target = scale * max(0.1 * self.tolerance, forcing)
        return float(np.clip(target / rhs_norm, 1e-14, FORCING))
