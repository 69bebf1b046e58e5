"""Factor once, solve on the contact nodes (DESIGN §4).

The bulk operator is the same linear elastic matrix at every step (𝒢 is explicit), so
A0 = A + Nᵀ diag(c0) N is factored once, with a reference stiffness c0 = r at each contact node that
makes A0 definite even for a body held only by contact; the same term is subtracted in the contact
law, so the solution is unchanged. With S = N A0⁻¹ Nᵀ (dense m × m) and d_free = N A0⁻¹ b − g0, the
step problem of ``base`` reduces to the m contact nodes:

    d = d_free − S q(d, λ),    q = f(d) + λ − c0 (d + g0),    C(d, λ) = 0,

solved by the same semi-smooth Newton iteration as the full system, now with a dense m × m matrix
(:class:`NewtonSystems`: a dense LU per iteration for small m, GMRES preconditioned by the inverse of
an earlier iteration's matrix from KRYLOV_FROM contact nodes on); u = A0⁻¹ (b − Nᵀ q) is recovered by
one solve, only when it is asked for. Right-hand sides that are combinations of ones already solved
(loads proportional to t, for instance) cost no solve at all. A new right-hand side (a viscoplastic
body's b_n = F(t_n) − Bᵀz_n changes everywhere at every step) is solved in two halves around the
contact problem (``factorization.split``): with PARDISO's Schur-mode factor, the forward substitution
gives N A0⁻¹ b, and the recovery of u is the rest of the same solve, so a step that needs u costs one
solve instead of two.

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
import warnings
from dataclasses import replace

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from ..errors import CaseError
from .base import ContactState, StepData, StepSolution, norm
from .errors import NotConvergedError, SingularMatrixError
from ..memory import available_memory
from ..progress import SILENT, Progress, duration, size
from .factorization import BACKENDS, chosen_backend, factorize
from .gmres import gmres
from .newton import ROUNDOFF, STAGNATION, Evaluation, SemismoothNewton


class SolvedSpan:
    """N A0⁻¹ b, reusing the solutions of earlier right-hand sides when b lies in their span.

    ``solve`` is b ↦ A0⁻¹ b (or what stands for it: the condensed method's split solve) and ``observe``
    gives N A0⁻¹ b from what it returns; the span keeps an orthonormal basis Q of the right-hand sides
    solved (rows, at most ``capacity``) and N A0⁻¹ of each, so a right-hand side in their span (loads
    proportional to t, for instance) costs two products with Q and no solve: about five passes over n
    entries instead of a solve with the factor.
    """

    def __init__(self, solve, observe, shape: tuple[int, int], capacity: int = 4, tolerance: float = 1e-13):
        """``shape``: (m, n) of N."""
        self._solve, self._observe, self.tolerance = solve, observe, tolerance
        self._basis = np.empty((capacity, shape[1]))  # orthonormal right-hand sides (the first ``size`` rows)
        self._images = np.empty((capacity, shape[0]))  # N A0⁻¹ of each
        self.size = 0
        self._support = None  # the support every right-hand side in the basis had (None: not one)
        self._restored_support = None  # that support as a checkpoint kept it (see ``restore``)
        self.solves = 0

    def kept(self) -> dict[str, np.ndarray]:
        """What the span carries from step to step: the basis, its images and the support they share."""
        arrays = {"basis": self._basis[: self.size], "images": self._images[: self.size]}
        return arrays if self._support is None else {**arrays, "support": self._support}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of an earlier span of the same operator (a resumed run): right-hand
        sides then cost what they did and give the same bits. The shared support is adopted at the
        next call whose support has the same positions (a new array of the resumed loop)."""
        self.size = arrays["basis"].shape[0]
        self._basis[: self.size], self._images[: self.size] = arrays["basis"], arrays["images"]
        self._restored_support = arrays.get("support")

    def __call__(self, b: np.ndarray, support: np.ndarray | None = None) -> np.ndarray:
        """N A0⁻¹ b; ``support``: the positions where b may be nonzero (None: anywhere). While every
        right-hand side solved had the same support, the basis vanishes off it, and the products
        with Q only run over it."""
        if self._restored_support is not None:
            if support is not None and np.array_equal(support, self._restored_support):
                self._support = support
            self._restored_support = None
        on = support if support is not None and support is self._support else slice(None)
        b_on = b[on]
        size = norm(b_on)
        basis = self._basis[: self.size, on]
        coefficients = basis @ b_on
        combination = coefficients @ self._images[: self.size]
        if size == 0.0:
            return combination
        remainder = b_on - coefficients @ basis
        rest = norm(remainder)
        if rest <= self.tolerance * size:
            return combination
        observed = self._observe(self._solve(b))
        self.solves += 1
        if self.size < self._basis.shape[0]:
            if self.size == 0:
                self._support = support
            elif support is not self._support:
                self._support = None  # the basis may no longer vanish off one support
            self._basis[self.size] = 0.0
            self._basis[self.size, on] = remainder / rest
            self._images[self.size] = (observed - combination) / rest
            self.size += 1
        return observed


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
#: Nodes whose change of state the kept inverse follows at once by a low-rank update (O(m² k) each time,
#: against O(m³) for a new inverse: 64 of 570 nodes cost about a fifth of one).
MAX_STATE_UPDATE = 64
#: GMRES iterations at most with the inverse of an earlier Newton matrix; a system that needs more is
#: solved again with the inverse of its own matrix (which then serves the next systems).
MAX_KRYLOV_ITERATIONS = 20
#: Relative residual ‖r − K z‖ ≤ KRYLOV_TOLERANCE ‖r‖ at which GMRES stops: the directions are those of
#: the dense LU to about this relative accuracy, far below what changes a Newton iteration (the
#: condensed results agree with the dense path's to 1e-12, the Newton iterations are the same:
#: tests/test_condensed_krylov.py).
KRYLOV_TOLERANCE = 1e-12
#: GMRES also stops at ‖r − K z‖ ≤ KRYLOV_TOLERANCE ‖r‖ + KRYLOV_ROUNDING ‖K‖ ‖z‖: the rounding level of
#: the product K z (m-term sums; a normwise backward error of 64 ε), where a nearly singular K stops (a
#: body held only by contact, its separated nodes held by the Jacobian's regularization alone:
#: cond(K) ≈ 1e12, and the dense LU's own relative residual is 3e-5).
KRYLOV_ROUNDING = 64 * np.finfo(float).eps


class NewtonSystems:
    """The condensed Newton systems K z = r, in node order: node i's unknown z_i is Δd_i when it is
    inactive and Δλ_i when it is active (at the limit), its column of K is e_i + S_i (T_i − c0) or S_i:

        K = diag(1_ℐ) + S diag(w),    w_i = T_i − c0 (i ∈ ℐ),  w_i = 1 (i ∈ 𝒜).

    ``solve_direct`` factors K (an LU, O(m³)); ``solve_iterative`` runs GMRES on K applied as
    z ↦ 1_ℐ z + S (w z) (O(m²) per iteration, S being formed), preconditioned by the inverse of the
    K of an earlier iteration (from its LU), kept across Newton iterations and time steps, updated by a
    low-rank formula for the nodes that change state since (``_follow_changes_of_state``), and made again
    only when GMRES needed more than MAX_KRYLOV_ITERATIONS with it (the system is then solved with the
    inverse of its own K).

    Why node order: the dense path's layout [inactive columns | active columns] is a permutation that
    changes with the active set, so a factor made for one layout is no preconditioner for another. In
    node order a change of state of k nodes, or of the compliance tangent T at k nodes, changes k
    columns of K and nothing else: K = K₀ + U Vᵀ with U, V of k columns, K₀⁻¹ K = I + K₀⁻¹ U Vᵀ, and
    GMRES preconditioned by K₀ converges in at most k + 1 iterations whatever the layouts of K and K₀
    (fewer when the changes are small: the tangents of nodes in compliance drift from step to step).
    On the quarter ball the inverse of the first Newton matrix (no node in contact yet) serves every
    Newton iteration of the run, at about 6 GMRES iterations each; on the paper's half disc at 1/512, at
    about 5, for β = −1 too (its nodes reach the limit one after another: the updates follow them, where
    without them GMRES needed 9.2 iterations and 22 new inverses; docs/performance.md).
    """

    def __init__(self, S: np.ndarray, S_row_sums: np.ndarray, max_iterations: int = MAX_KRYLOV_ITERATIONS):
        self.S, self._S_row_sum = S, S_row_sums.max(initial=0.0)  # the largest row sum of |S|
        self.max_iterations = max_iterations
        self._inverse = None  # K⁻¹ of an earlier iteration's K, updated for the changes of state since
        self._kept = None  # (1_ℐ, w) of the K the kept inverse is of, at the nodes whose state it follows
        self.updates = 0  # low-rank updates of the kept inverse for changes of state
        self.iterations = 0  # GMRES iterations, in total
        self.factorizations = 0  # LU factorizations of Newton matrices (dense solves included)

    def kept(self) -> dict[str, np.ndarray]:
        """What the systems carry from step to step: the kept inverse and the (1_ℐ, w) it follows."""
        if self._inverse is None:
            return {}
        return {"inverse": self._inverse, "inactive": self._kept[0], "w": self._kept[1]}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of earlier systems of the same S (a resumed run)."""
        if "inverse" in arrays:
            self._inverse = np.array(arrays["inverse"], order="F")
            self._kept = (arrays["inactive"].copy(), arrays["w"].copy())

    def matrix(self, inactive: np.ndarray, w: np.ndarray) -> np.ndarray:
        """K = diag(1_ℐ) + S diag(w) (Fortran order: LAPACK factors it in place)."""
        K = np.multiply(self.S, w[None, :], order="F")
        K[np.diag_indices_from(K)] += inactive
        return K

    def solve_direct(self, inactive: np.ndarray, w: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """z = K⁻¹ r by a dense LU of K."""
        self.factorizations += 1
        try:
            return np.linalg.solve(self.matrix(inactive, w), rhs)
        except np.linalg.LinAlgError as error:
            raise SingularMatrixError(f"the condensed Newton matrix is singular ({error})") from None

    def solve_iterative(self, inactive: np.ndarray, w: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """z with ‖r − K z‖ ≤ KRYLOV_TOLERANCE ‖r‖ + KRYLOV_ROUNDING ‖K‖ ‖z‖ by GMRES, preconditioned by the
        kept inverse, or by the inverse of this K when the kept one needs more than ``max_iterations`` (or
        there is none). NotConvergedError when even that one does not reach the tolerance (an LU too
        unstable for GMRES to correct in so few iterations); a K or r that is not finite: z is not finite,
        as the dense solve's (the Newton iteration reports iterates that are not finite)."""
        if not (np.all(np.isfinite(w)) and np.all(np.isfinite(rhs))):
            return np.full_like(rhs, np.nan)

        def K(z):
            return inactive * z + self.S @ (w * z)

        norm_K = 1.0 + np.abs(w).max(initial=0.0) * self._S_row_sum  # ≥ ‖K‖₁ and ‖K‖∞ (S symmetric), so ≥ ‖K‖₂
        floor = KRYLOV_ROUNDING * norm_K
        if self._inverse is not None:
            self._follow_changes_of_state(inactive, w)
            solution = self._gmres(K, rhs, floor)
            if solution.converged:
                return solution.x
        self._factorize(inactive, w)
        solution = self._gmres(K, rhs, floor)
        if not solution.converged:
            raise NotConvergedError(f"GMRES preconditioned by the inverse of the condensed Newton matrix itself "
                                    f"did not reach the relative residual {KRYLOV_TOLERANCE:g} (nor the rounding "
                                    f"level of the matrix) in {self.max_iterations} iterations")
        return solution.x

    def _factorize(self, inactive: np.ndarray, w: np.ndarray) -> None:
        """Keep the inverse of K, from its LU factors (SingularMatrixError for an exactly zero pivot, as
        the dense solve): applying it is one matrix–vector product, faster than the two triangular
        solves with the factors, and as good a preconditioner."""
        self.factorizations += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", la.LinAlgWarning)  # an exactly zero pivot: checked below
            lu, piv = la.lu_factor(self.matrix(inactive, w), overwrite_a=True, check_finite=False)
        if np.any(np.diagonal(lu) == 0.0):
            self._inverse = None
            raise SingularMatrixError("the condensed Newton matrix is singular (an exactly zero pivot)")
        self._inverse, _ = la.lapack.dgetri(lu, piv, overwrite_lu=True)
        self._kept = (inactive.astype(float), w.copy())

    def _follow_changes_of_state(self, inactive: np.ndarray, w: np.ndarray) -> None:
        """Update the kept inverse for the nodes whose state (inactive or at the limit) changed since it was
        made: their columns of K changed, K = K₀ + U E_cᵀ with U = (K − K₀)[:, c], and by the Sherman–Morrison–
        Woodbury formula K⁻¹ = K₀⁻¹ − K₀⁻¹U (I + E_cᵀ K₀⁻¹ U)⁻¹ E_cᵀ K₀⁻¹: O(m² k) for k nodes instead of
        O(m³) for a new inverse. Nodes reach the rigid limit one after another (β = −1 at 1/512: 22 new
        inverses without this); GMRES is then left with the tangents' drift only, as when no state
        changes. Up to MAX_STATE_UPDATE nodes at once; more, or a capacitance matrix that is singular to
        working precision, and the inverse stays as it is (GMRES, and a new inverse if it needs too many
        iterations, see ``solve_iterative``)."""
        kept_inactive, kept_w = self._kept
        changed = np.flatnonzero(inactive != kept_inactive)
        if changed.size == 0 or changed.size > MAX_STATE_UPDATE:
            return
        U = self.S[:, changed] * (w[changed] - kept_w[changed])
        U[changed, np.arange(changed.size)] += inactive[changed] - kept_inactive[changed]
        PU = self._inverse @ U
        capacitance = np.eye(changed.size) + PU[changed]
        # singular with K: when every contact node of a body held only by contact is separated (w = −c0 on all),
        # K = I − S c0 annihilates N r for each free rigid motion r (S c0 N r = N r, as A r = 0), and cond(K) is
        # 1e14–1e16 in float64. The step problem leaves that motion free there; an inverse of K cannot be
        # followed, the kept one stays and GMRES, whose residual is measured, decides (see solve_iterative).
        if not np.linalg.cond(capacitance) < 1.0 / np.finfo(float).eps:
            return
        try:
            with warnings.catch_warnings():  # the conditioning is checked above (LAPACK's estimate of it differs)
                warnings.simplefilter("ignore", la.LinAlgWarning)
                correction = la.solve(capacitance, self._inverse[changed], check_finite=False)
        except (la.LinAlgError, ValueError):
            return
        if not np.all(np.isfinite(correction)):
            return
        self._inverse -= PU @ correction
        kept_inactive[changed], kept_w[changed] = inactive[changed], w[changed]
        self.updates += 1

    def _gmres(self, K, rhs: np.ndarray, floor: float):
        """GMRES preconditioned by the kept inverse, at most ``max_iterations`` iterations (counted)."""
        solution = gmres(K, self._inverse.__matmul__, rhs, KRYLOV_TOLERANCE, self.max_iterations, floor)
        self.iterations += solution.iterations
        return solution


class CondensedNewton(SemismoothNewton):
    """Semi-smooth Newton on the contact nodes with a once-factored stiffness.

    The Newton iterations run their dense m × m algebra on one BLAS thread (``SemismoothNewton.solve``).
    Their systems are solved by a dense LU each below ``krylov_from`` contact nodes, by preconditioned GMRES from there
    on (:class:`NewtonSystems`; a parameter so that tests can run either path on any case).
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
        self._N_contact_T = self.N[:, np.unique(self.N.indices)].T.tocsr()
        self.reference = np.full(m, r)
        started = time.perf_counter()
        backend = chosen_backend(factorization)
        expected = f"{duration(expected_seconds)} with the condensation, " if expected_seconds is not None else ""
        with progress.phase("factorization", f"A0 = A + r NᵀN, {A.shape[0]:,} dofs, by {BACKENDS[backend].label}; "
                            f"expected: {expected}{size(condensed_memory(self.N, A.shape[0]))} of dense algebra "
                            f"({size(available_memory())} available)", estimate=expected_seconds) as phase:
            self.factorization = factorize(A + self.N.T @ sp.diags(self.reference) @ self.N, self.N, backend, progress)
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

    @property
    def krylov_iterations(self) -> int:
        return self.systems.iterations

    @property
    def newton_factorizations(self) -> int:
        return self.systems.factorizations

    @property
    def solves(self) -> int:
        """Solves with the factored A0 in the time loop: new right-hand sides (a split solve counts once
        with PARDISO), recoveries of u and the corrections of refinements."""
        return self.span.solves + self.recoveries + self.refinements

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
        (zero on ℐ), K z = −(d − d_u) − s − S v for the node-ordered unknowns z of :class:`NewtonSystems`,
        v = (T − c0) s on 𝒜 and −λ on ℐ."""
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
    Schur complement of A0 on the c contact dofs (c = d m) and its Cholesky factor (PARDISO's route to
    S), S, the Newton matrix and its factor (m × m each), and the block solves (64 columns of n)."""
    m, c = N.shape[0], np.unique(sp.csr_matrix(N).indices).size
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
        m, c = N.shape[0], np.unique(sp.csr_matrix(N).indices).size
        raise CaseError(f"solver.method = \"condensed\" needs about {needed / 2**30:.1f} GiB for its dense "
                        f"{m} x {m} contact operator (and the {c} x {c} Schur complement on the contact dofs), more "
                        f"than half the {available / 2**30:.1f} GiB available; use solver.method = \"iterative\"")
