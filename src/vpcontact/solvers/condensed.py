"""Factor once, solve on the contact nodes (DESIGN §4).

The bulk operator is the same linear elastic matrix at every step (𝒢 is explicit), so
A0 = A + Nᵀ diag(c0) N is factored once, with a reference stiffness c0 = r at each contact node that
makes A0 definite even for a body held only by contact; the same term is subtracted in the contact
law, so the solution is unchanged. With S = N A0⁻¹ Nᵀ (dense m × m) and d_free = N A0⁻¹ b − g0, the
step problem of ``base`` reduces to the m contact nodes:

    d = d_free − S q(d, λ),    q = f(d) + λ − c0 (d + g0),    C(d, λ) = 0,

solved by the same semi-smooth Newton iteration as the full system, now with a dense m × m matrix
(:class:`~.condensed_systems.NewtonSystems`: a dense LU per iteration for small m, GMRES preconditioned
by the inverse of an earlier iteration's matrix from KRYLOV_FROM contact nodes on); u = A0⁻¹ (b − Nᵀ q)
is recovered by one solve, only when it is asked for. Right-hand sides that are combinations of ones
already solved (loads proportional to t, for instance) cost no solve at all (:mod:`.solved_span`). A
new right-hand side (a viscoplastic body's b_n = F(t_n) − Bᵀz_n changes everywhere at every step) is
solved in two halves around the contact problem (``factorization.split``): with PARDISO's Schur-mode
factor, the forward substitution gives N A0⁻¹ b, and the recovery of u is the rest of the same solve,
so a step that needs u costs one solve instead of two.

A stiff body held only by a soft layer (E / K ≳ 1e6) is the one case where that is not enough: A
annihilates the body's rigid motions only to rounding, and A0's factor carries that rounding into
the layer's balance (a relative error of about ε E/K √n). There the iteration converges to rounding
level only, and the step is finished by iterative refinement: the whole system's residual is
evaluated with the rigid motions removed, R = A (u − Z Zᵀu) + Nᵀ(f + λ) − b, and the step solved
again with the load corrected by −R, until the net force and moment ‖ZᵀR‖ balance to the tolerance
or stop decreasing (one or two rounds, two solves each): the body's balance then holds to about
ε E/K relative, the rounding of the contact unknowns, instead of ε E/K √n.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError
from .base import ContactState, SolverWork, StepData, StepSolution, norm
from ..memory import available_memory
from ..progress import SILENT, Progress, duration, size
from .condensed_systems import NewtonSystems
from .factorization import BACKENDS, chosen_backend, condensation_dofs, contact_dofs, factorize_on_normals
from .newton import ROUNDOFF, STAGNATION, Evaluation, SemismoothNewton
from .solved_span import SolvedSpan


#: Rounds of iterative refinement at most (each multiplies the imbalance by about ε E/K √n; one or
#: two are needed).
MAX_REFINEMENTS = 4
#: Contact nodes from which the Newton systems are solved by GMRES rather than by a dense LU each. The
#: GMRES iterations are preconditioned by the inverse of an earlier Newton matrix (one matrix–vector
#: product each), and a run needs about 5 per Newton iteration (the paper's half disc, 2D) to 6 (the
#: quarter ball, 3D); one LU is m³ work. Measured on the paper's example (β = 1, CPU time of the time
#: loop, one BLAS thread, docs/performance.md): dense LU against GMRES 0.46 against 0.50 s at m = 144
#: (1/128), 1.47 against 1.13 s at 285 (1/256), 6.4 against 3.1 s at 570 (1/512).
KRYLOV_FROM = 200


class CondensedNewton(SemismoothNewton):
    """Semi-smooth Newton on the contact nodes with a once-factored stiffness.

    The Newton iterations run their dense m × m algebra on one BLAS thread (``SemismoothNewton.solve``).
    Their systems are solved by a dense LU each below ``krylov_from`` contact nodes, by preconditioned GMRES from there
    on (:class:`~.condensed_systems.NewtonSystems`; a parameter so that tests can run either path on any case).
    """

    name = "condensed"

    def __init__(self, A: sp.csr_matrix, N: sp.csr_matrix, weights, gap0, r, tolerance, max_iterations,
                 length_scale, rigid: np.ndarray, factorization: str = "auto", krylov_from: int = KRYLOV_FROM,
                 progress: Progress = SILENT, expected_seconds: float | None = None):
        """``progress`` hears of the factorization (with ``expected_seconds``, the time its set-up is expected
        to take, and the memory of its dense algebra) and of the condensation."""
        super().__init__(weights, r, tolerance, max_iterations, length_scale, progress)
        m = N.shape[0]
        check_condensed_memory(N, A.shape[0])
        self.A, self.N, self.gap0, self.Z = A, N.tocsr(), gap0, rigid
        #: Nᵀ on N's nonzero columns (the contact dofs): ‖Nᵀx‖ without a vector of every dof
        self._N_contact_T = self.N[:, contact_dofs(self.N)].T.tocsr()
        self.reference = np.full(m, r)
        started = time.perf_counter()
        backend = chosen_backend(factorization)
        expected = f"{duration(expected_seconds)} with the condensation, " if expected_seconds is not None else ""
        with progress.phase("factorization", f"A0 = A + r NᵀN, {A.shape[0]:,} dofs, by {BACKENDS[backend].label}; "
                            f"expected: {expected}{size(condensed_memory(self.N, A.shape[0]))} of dense algebra "
                            f"({size(available_memory())} available)", estimate=expected_seconds) as phase:
            self.factorization = factorize_on_normals(A + self.N.T @ sp.diags(self.reference) @ self.N, self.N,
                                                      backend, progress)
            phase.done(f"a factor of {self.factorization.factor_nonzeros:,} entries")
        factored = time.perf_counter()
        with progress.phase("condensation", f"S = N A0⁻¹ Nᵀ for {m:,} contact nodes "
                            f"{self.factorization.condensation_words()}"):
            self.S = self.factorization.condensed_operator()
            Y = self.factorization.solve(rigid) if rigid.shape[1] else np.zeros_like(rigid)
        #: (Y, N Y), Y = A0⁻¹ Z: the rigid motions held only by contact solved once, with the factor every run of
        #: the problem has at this point (a resumed one too: its numbers are the uninterrupted run's), for
        #: ``rigid_coordinates``; k columns, none when the Dirichlet conditions hold the body
        self._rigid_solved = (Y, self.N @ Y)
        self._S_row_sums = np.abs(self.S).sum(axis=1)  # bounds |S| |q| by its rows' sums times max |q|
        self.timings = {"factorization": factored - started, "condensation": time.perf_counter() - factored}
        self.systems, self.krylov_from = NewtonSystems(self.S, self._S_row_sums), krylov_from
        self.span = SolvedSpan(self._split, lambda split: split.observed, self.N.shape)
        self.recoveries = self.refinements = 0
        self._step, self._load_vector, self._d_free, self._b_norm = None, None, None, 0.0
        self._pending = None  # the split solve of this step's load, when N A0⁻¹ b came from one

    def kept(self) -> dict[str, np.ndarray]:
        """What this solver carries from step to step beyond the StepSolution, for a checkpoint: the
        solved span (``span_*``), the kept inverse of the Newton systems (``systems_*``, m × m) and
        which factor of A0 solves (``factorization_*``: PARDISO's Schur-mode one, or the plain one made
        after PLAIN_AFTER solves). Restored (``restore``) into the solver of a resumed run, it makes
        that run's numbers the bits of the uninterrupted one."""
        parts = {"span": self.span, "systems": self.systems, "factorization": self.factorization}
        return {f"{name}_{key}": value for name, part in parts.items() for key, value in part.kept().items()}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of the solver of the same problem in an earlier process."""
        for name, part in {"span": self.span, "systems": self.systems, "factorization": self.factorization}.items():
            part.restore({key[len(name) + 1:]: value for key, value in arrays.items() if key.startswith(f"{name}_")})

    def solve(self, step: StepData, previous: StepSolution | None) -> StepSolution:
        solution = super().solve(step, previous)
        if solution.converged and solution.residual > self.tolerance and self.Z.shape[1]:
            return self._refine(step, solution)
        return solution

    def _refine(self, step: StepData, solution: StepSolution) -> StepSolution:
        """Iterative refinement of a solution converged to rounding level (see the module's docstring),
        until the balance is within the tolerance or stops halving (the rounding of the contact
        unknowns themselves); the solution returned carries its displacement u."""
        last = np.inf
        for _ in range(MAX_REFINEMENTS):
            u = self._recover(solution)
            state = ContactState.evaluate(step, self.weights, solution.d, solution.lam, self.r)
            contact = self.N.T @ (state.force + solution.lam)
            R = self.A @ (u - self.Z @ (self.Z.T @ u)) + contact - step.b
            balance = np.linalg.norm(self.Z.T @ R) / (max(self._b_norm, norm(contact)) or 1.0)
            if balance <= self.tolerance or balance > STAGNATION * last:
                break
            last = balance
            self.refinements += 1
            self._load_vector, self._pending = self._load_vector - R, None
            self._d_free = self._d_free - self.N @ self.factorization.solve(R)
            refined = super().solve(step, solution)
            solution = replace(refined, iterations=solution.iterations + refined.iterations)
            if not solution.converged:
                return solution
        else:
            u = self._recover(solution)
        return replace(solution, u=u)

    def _free_penetration(self, step: StepData) -> np.ndarray:
        """d_free = N A0⁻¹ b − g0 of this step (computed once per step; b corrected by refinements)."""
        if self._step is not step:
            self._step, self._load_vector, self._pending = step, step.b, None
            self._d_free = self.span(step.b, step.support) - self.gap0
            self._b_norm = step.b_norm
        return self._d_free

    def _split(self, b: np.ndarray):
        """Start the solve of this step's load b, kept for the recovery of u (the span's solve)."""
        self._pending = self.factorization.split(b)
        return self._pending

    def _recover(self, solution: StepSolution) -> np.ndarray:
        """u = A0⁻¹ (b − Nᵀ q) at the free dofs for this step's (corrected) load b: the second half of its
        split solve when N A0⁻¹ b came from one (no further solve with PARDISO), else one solve."""
        state = ContactState.evaluate(self._step, self.weights, solution.d, solution.lam, self.r)
        q = self._load(state, solution.d, solution.lam)
        if self._pending is not None:
            self.recoveries += self._pending.finish_solves
            return self._pending.finish(q)
        self.recoveries += 1
        return self.factorization.solve(self._load_vector - self.N.T @ q)

    def work(self) -> SolverWork:
        """Solves with the factored A0 (new right-hand sides, a split solve counting once with PARDISO; recoveries
        of u; the corrections of refinements), and the GMRES iterations and LU factorizations of the Newton
        systems."""
        return SolverWork(self.span.solves + self.recoveries + self.refinements, self.systems.iterations,
                          self.systems.factorizations)

    def _load(self, state: ContactState, d, lam) -> np.ndarray:
        return state.force + lam - self.reference * (d + self.gap0)

    def initial(self, step: StepData, previous: StepSolution | None) -> tuple:
        if previous is None:
            return np.zeros(self.N.shape[0]), np.zeros(self.N.shape[0])
        return previous.d, previous.lam

    def evaluate(self, step: StepData, x: tuple) -> Evaluation:
        """At (d, λ): d_u = d_free − S q is the penetration of the displacement u = A0⁻¹(b − Nᵀq) the
        solver would return; the residual and complementarity reported are those of u (the full
        system's A u + Nᵀ(f(d_u) + λ) − b = Nᵀ[f(d_u) − f(d) − c0 (d_u − d)]). Rounding leaves
        d_u − d at about ROUNDOFF (|d_free| + |S| |q| + |d|), hence the residual's floor; the balance
        of the rigid motions is not measured here (it is as rounded as d_u − d) but by ``_refine``."""
        d, lam = x
        state = ContactState.evaluate(step, self.weights, d, lam, self.r)
        d_u = self._free_penetration(step) - self.S @ self._load(state, d, lam)
        recovered = ContactState.evaluate(step, self.weights, d_u, lam, self.r)
        R_u = self._N_contact_T @ (recovered.force - state.force - self.reference * (d_u - d))
        scale = max(self._b_norm, norm(self._N_contact_T @ (recovered.force + lam)))
        load_size = np.abs(state.force) + np.abs(lam) + self.reference * np.abs(d + self.gap0)
        d_size = np.abs(self._d_free) + self._S_row_sums * load_size.max(initial=0.0) + np.abs(d)
        floor = ROUNDOFF * np.linalg.norm((self.reference + np.abs(recovered.tangent)) * d_size)
        scale = scale if scale > 0 else 1.0
        merit = np.concatenate([self.r * (d - d_u), state.C])
        return Evaluation(d, lam, state, merit, np.linalg.norm(R_u) / scale, self.complementarity(recovered),
                          floor / scale, d_solution=d_u)

    def direction(self, step: StepData, x: tuple, ev: Evaluation) -> tuple:
        """Solve (I + S diag(T − c0)) Δd + S Δλ = −(d − d_u) with Δd_𝒜 = g − d_𝒜 and Δλ_ℐ = −λ_ℐ: with s = Δd_𝒜
        (zero on ℐ), K z = −(d − d_u) − s − S v for the node-ordered unknowns z of
        :class:`~.condensed_systems.NewtonSystems`, v = (T − c0) s on 𝒜 and −λ on ℐ."""
        d, lam = x
        active = ev.state.active
        inactive = ~active
        s = np.zeros_like(d)
        s[active] = step.law.limit(active) - d[active]
        tangent = self.jacobian_tangent(ev.state) - self.reference
        w = np.where(active, 1.0, tangent)
        rhs = -(d - ev.d_solution) - s - self.S @ np.where(active, tangent * s, -lam)
        solve = self.systems.solve_direct if d.size < self.krylov_from else self.systems.solve_iterative
        z = solve(inactive, w, rhs)
        return np.where(active, s, z), np.where(active, z, -lam)

    def solution(self, step, x, ev: Evaluation, iterations, converged, message="", advice="") -> StepSolution:
        """The penetration of the displacement returned, or, of an iteration that stopped on values that are not
        finite, the iterate's own d where it is finite (where the laws were evaluated: the failure names them)."""
        d = ev.d_solution if converged or np.all(np.isfinite(ev.d_solution)) else ev.d
        return StepSolution(None, x[1], d, ev.state.active, iterations, ev.residual, ev.complementarity, converged,
                            message, advice)

    def displacement(self, step: StepData, solution: StepSolution) -> np.ndarray:
        """u at the free dofs: the refined one, or u = A0⁻¹ (b − Nᵀ q) (at most one solve)."""
        if solution.u is not None:
            return solution.u
        self._free_penetration(step)
        return self._recover(solution)

    def functionals(self, M: sp.csr_matrix):
        """(step, solution) ↦ M u for a few rows M over the free dofs (the reactions of the Dirichlet parts),
        without recovering u: M A0⁻¹ (b − Nᵀq) = Yᵀ b − (N Y)ᵀ q with Y = A0⁻¹ Mᵀ, solved here once (as
        ``rigid_coordinates`` does for Zᵀu)."""
        Y = self.factorization.solve(M.T.toarray())
        NY = self.N @ Y

        def apply(step: StepData, solution: StepSolution) -> np.ndarray:
            if solution.u is not None:
                return M @ solution.u
            state = ContactState.evaluate(step, self.weights, solution.d, solution.lam, self.r)
            b = self._load_vector if step is self._step else step.b
            return Y.T @ b - NY.T @ self._load(state, solution.d, solution.lam)

        return apply

    def rigid_coordinates(self, step: StepData, solution: StepSolution) -> np.ndarray:
        """Zᵀu, the coordinates of the solution's displacement on the rigid motions held only by contact,
        without recovering u: Zᵀ A0⁻¹ (b − Nᵀq) = Yᵀ b − (N Y)ᵀ q with Y = A0⁻¹ Z (solved in the set-up)."""
        if solution.u is not None:
            return self.Z.T @ solution.u
        Y, NY = self._rigid_solved
        state = ContactState.evaluate(step, self.weights, solution.d, solution.lam, self.r)
        b = self._load_vector if step is self._step else step.b
        return Y.T @ b - NY.T @ self._load(state, solution.d, solution.lam)


def condensed_memory(N: sp.csr_matrix, n: int) -> int:
    """Bytes of the dense algebra of the condensed method for the contact operator N (m × n): the
    Schur complement of A0 on the c dofs of the condensation (:func:`.factorization.condensation_dofs`: c = m)
    and its Cholesky factor (PARDISO's route to S), S, the Newton matrix and its factor (m × m each), and the
    block solves (64 columns of n)."""
    m, c = N.shape[0], condensation_dofs(N)
    return 8 * (2 * c * c + 3 * m * m + 2 * 64 * n)


#: The share of the available memory the condensed method's dense algebra may take.
CONDENSED_SHARE = 0.5


def condensed_fits(N: sp.csr_matrix, n: int) -> tuple[bool, int, int]:
    """Does the condensed method's dense algebra fit in CONDENSED_SHARE of the available memory? With the
    bytes it needs and those available."""
    needed, available = condensed_memory(N, n), available_memory()
    return needed <= CONDENSED_SHARE * available, needed, available


def check_condensed_memory(N: sp.csr_matrix, n: int) -> None:
    """Refuse, before allocating, a condensed operator that would not fit in memory."""
    fits, needed, available = condensed_fits(N, n)
    if not fits:
        m, c = N.shape[0], condensation_dofs(N)
        raise CaseError(f"solver.method = \"condensed\" needs about {needed / 2**30:.1f} GiB for its dense "
                        f"{m} x {m} contact operator (and the {c} x {c} Schur complement on the contact dofs), more "
                        f"than half the {available / 2**30:.1f} GiB available; use solver.method = \"iterative\"")
