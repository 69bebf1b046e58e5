"""The quasistatic time loop (Sect. 3 of the paper, DESIGN §2).

At t_n = t_0 + n k (k = (T − t_0) / steps, t_0 = ``time.start``, default 0)::

    z_n   = σ_0 − ℰε(u_0) + Σ_{j=0}^{n−1} k 𝒢(σ_j, ε(u_j))   (explicit viscoplastic history, per element)
    b_n   = F(t_n) − Bᵀ z_n
    (u_n, λ_n) solves the step problem with ξ^{n−1}             (one solver call)
    ξ_n   = ξ_{n−1} + k (d_n)⁺                                  (implicit rectangle rule for (2.15))
    σ_n   = ℰε(u_n) + z_n                                       (the discrete (2.28))

This is (2.28) as written, σ(t) = ℰε(u(t)) + ∫_0^t 𝒢(σ, ε(u)) ds + σ_0 − ℰε(u_0): z_0 = σ_0 − ℰε(u_0)
and the j = 0 term is k 𝒢(σ_0, ε(u_0)), so z_1 = σ_0 − ℰε(u_0) + k 𝒢(σ_0, ε(u_0)); ξ starts from ξ_0
(``problem.initial``: u_0 per node, σ_0 per element, ξ_0 per contact node, see :mod:`vpcontact.problem.initial`;
zero by default). The first step's Newton iteration starts from u_0 (from zero when u_0 = 0), the
second one's from the first level's solution, every later one's from the last level's solution
extrapolated linearly in time through the last two levels (u, λ, d: `LoopState.start`; on the
quarter ball, 100 steps, it saved 13 % of the Newton iterations and 26 % of the CG iterations). The bulk
operator is the same at every step; with 𝒢 ≠ 0, u_n is computed at every step (σ_n feeds z_{n+1}).

Step cuts: when the Newton iteration of a step fails (iteration limit, non-finite iterates, a
singular Newton matrix), the step is done as two sub-steps of length k/2, each of them cut again if
it fails, down to ``solver.max_step_cuts`` halvings. A sub-step of length h ending at t is an
ordinary step of the same scheme: loads at t, z advanced by h 𝒢 from the last converged level, ξ
by h d⁺ (the same rules with h for k), so a cut step is exactly the same scheme on a finer grid.
The state carried from level to level is a :class:`LoopState`; it is all a checkpoint needs.

With ``output.error_estimate`` the fields are computed at every level and the residual estimator
(:mod:`vpcontact.estimate.residual`) adds η(t) and its terms to the level's history row and η_K to its fields.
"""

from __future__ import annotations

import time as clock
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from ..fem.assembly import NonFiniteLoad, element_strain, stress_force
from ..case.schema import OutputSection, section
from ..laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED, node_status
from ..laws.elasticity import von_mises
from ..estimate.indicators import Level
from ..problem.build import Problem, checked_problem
from ..problem.discretization import Discretization
from ..progress import SILENT, Progress, StepReport, reporting
from ..estimate.residual import ResidualEstimator
from ..results.footprint import check_memory
from ..results.result import Fields, Result
from .resting import least_shift, unbalanced
from ..fem.rigid_modes import RigidModes
from ..solvers import DofLayout, StepData, StepSolution, make_solver
from ..solvers.errors import NotConvergedError, SingularMatrixError
from ..fem.space import coordinates
from ..solvers.time_estimate import estimate_seconds

#: The solver's counters of work in the time loop that summary.json reports (summed over the sessions of a
#: resumed run): solves with a factored matrix, Krylov iterations, Newton matrices factored.
COUNTERS = ("linear_solves", "krylov_iterations", "newton_factorizations")


@dataclass
class LoopState:
    """What the time loop carries from the last converged time level to the next one."""

    step: int  # time steps t_n done
    xi: np.ndarray  # ξ at the last level
    z: np.ndarray | None  # z at the last level, σ = ℰε(u) + z there (d, d, elements); None: z ≡ 0
    rate: np.ndarray | None  # 𝒢(σ, ε) at the last level; None: 𝒢 = 0
    previous: StepSolution | None  # the last level's solution
    trend: Trend | None = None  # how it changed since the level before (None: no level before)
    step_problem: StepData | None = None  # the last level's step problem (None: the initial level, or a resumed run)
    rigid: np.ndarray | None = None  # Zᵀu at the last level, where known (see TimeLoop.rigid_position)
    _z_after: tuple = field(default=(None, None), init=False, repr=False, compare=False)  # (h, z_after(h))

    def z_after(self, h: float) -> np.ndarray | None:
        """z at the level h after the last one (explicit: z + h 𝒢), computed once per h (the loop checks it
        is finite after a step, the next step uses it)."""
        if self.rate is None:
            return self.z
        if self._z_after[0] != h:
            self._z_after = (h, self.z + h * self.rate)
        return self._z_after[1]

    def start(self, h: float) -> StepSolution | None:
        """The first Newton iterate of the level h after the last one: the last level's solution
        extrapolated linearly in time along its trend (λ kept ≥ 0); the last level's solution itself
        when it has no trend (the first step), None when there is none (start from zero)."""
        previous, trend = self.previous, self.trend
        if previous is None or trend is None:
            return previous
        u = None if previous.u is None or trend.u is None else previous.u + h * trend.u
        return replace(previous, u=u, lam=np.maximum(previous.lam + h * trend.lam, 0.0), d=previous.d + h * trend.d)


@dataclass
class Trend:
    """The rate of change in time of a level's solution: (x_n − x_{n−1}) / h_n for u, λ and d, from the
    level before it (u is None when a solver does not return it)."""

    u: np.ndarray | None
    lam: np.ndarray
    d: np.ndarray

    @classmethod
    def between(cls, before: StepSolution, after: StepSolution, h: float) -> "Trend":
        u = None if before.u is None or after.u is None else (after.u - before.u) / h
        return cls(u, (after.lam - before.lam) / h, (after.d - before.d) / h)


@dataclass
class _Attempt:
    """A (sub-)step tried from the current state; ``resultant``: ‖Zᵀb‖, the loads' resultant on the rigid
    motions held only by contact (0 when there are none); ``rigid``: Zᵀu where the time loop placed the
    body itself (a level where nothing presses it: :mod:`vpcontact.timeloop.resting`), else None."""

    t: float
    h: float
    step: StepData
    z: np.ndarray | None
    solution: StepSolution
    resultant: float = 0.0
    rigid: np.ndarray | None = None


class TimeLoop:
    """The time loop of a problem: ``TimeLoop(problem, output).run()`` returns the :class:`Result`;
    ``output`` (:class:`~vpcontact.case.schema.OutputSection`, default: its defaults) says which steps keep their
    fields and whether the error is estimated at every step. A run whose outputs would not fit in memory
    is refused here, before its first step.

    ``run`` takes two hooks: ``after_step(loop)``, called after every completed time step (the
    checkpoints of :mod:`vpcontact.drivers.rundir`), and ``stop()``, asked before every step (a signal
    asked the run to stop: the status becomes "interrupted").

    ``progress`` (:mod:`vpcontact.progress`; default: silent) hears of the solver's set-up phases here, of
    the time steps in ``run``.
    """

    def __init__(self, problem: Problem, output: OutputSection | None = None, progress: Progress = SILENT):
        started = clock.perf_counter()
        self.problem, self.progress = checked_problem(problem), progress
        output = section(OutputSection, output, "output")  # a dict is the [output] table
        free, surface, options = problem.free, problem.surface, problem.solver
        mesh = problem.mesh.mesh
        history = problem.viscoplastic is not None or bool(np.any(problem.initial_history != 0.0))
        check_memory(problem.times.steps, output, mesh.p.shape[1], mesh.t.shape[1], surface.size, history,
                     mesh.dim())
        modes = RigidModes.of_mesh(mesh.p, mesh.t, problem.basis.nodal_dofs)
        layout = DofLayout(free, mesh.dim(), mesh.nvertices, modes.matrix[free].toarray())
        rigid = modes.free_basis(free)
        self._held_by_contact_only = rigid.shape[1] > 0 and surface.size > 0  # see _resting
        self._rigid = rigid  # Z: an orthonormal basis of the rigid motions held only by contact (free dofs, k)
        self._rigid_at_contact = surface.operator[:, free] @ rigid  # N Z: how they move the contact nodes (m, k)
        # the largest contact pressure, and resultant ‖Zᵀb‖ of the loads, of the levels so far (see _resting)
        self._largest_pressure = self._largest_resultant = None
        self._tolerance = options.tolerance
        self.solver = make_solver(options.method, problem.A[free][:, free].tocsr(), surface.operator[:, free].tocsr(),
                                  surface.weights, surface.gap0, rigid=rigid,
                                  augmentation=options.augmentation, tolerance=options.tolerance,
                                  max_iterations=options.max_iterations, length_scale=problem.mesh.diameter,
                                  factorization=options.factorization, layout=layout, progress=progress,
                                  setup_estimate=self._setup_estimate(history))
        self.max_cuts = options.max_step_cuts
        self._loads = problem.loads.on(free)  # F(t) at the free dofs
        self.result = Result.start(Discretization.of(problem), problem.basis.N, self.solver, output)
        self.estimator = ResidualEstimator(problem) if output.error_estimate else None
        self._created = started
        self.setup_time = clock.perf_counter() - started
        self.earlier_time = 0.0  # wall time of earlier sessions (resumed)
        self.earlier_counts = dict.fromkeys(COUNTERS, 0)  # the counters of earlier sessions (resumed)
        self.state = self._initial_state()
        # (u at the free dofs, ε, σ, z) of the last level when its Fields were not built (a viscoplastic body
        # computes them at every level, keeps them at the field steps): ``run`` makes them ``result.final``.
        self._level_without_fields: tuple | None = None
        self._u = np.zeros(problem.basis.N)

    def _setup_estimate(self, history: bool) -> Callable[[str], float] | None:
        """The seconds the set-up of a method is expected to take (:mod:`vpcontact.solvers.time_estimate`, from the
        problem's build time), for the progress lines; None for a problem without a build time."""
        problem = self.problem
        build = problem.timings.get("build")
        if build is None:
            return None
        return lambda method: estimate_seconds(method, problem.mesh.dim, problem.free.size, len(problem.times), history,
                                               build)["solver setup"]

    def _initial_state(self) -> LoopState:
        """The level t_0: ξ_0, z_0 = σ_0 − ℰε(u_0) and 𝒢(σ_0, ε(u_0)) (the j = 0 term of z), and u_0 with
        its penetrations as the start of the first Newton iteration (none when u_0 = 0)."""
        problem = self.problem
        initial = problem.initial
        u0 = initial.dofs(problem.basis)
        strain0, z0 = problem.initial_strain, problem.initial_history
        G = problem.viscoplastic
        history = G is not None or np.any(z0 != 0.0)  # z ≠ 0 possible: the right-hand side carries Bᵀz
        rate = viscoplastic_rate(G, initial.stress, strain0) if G is not None else None  # the j = 0 term
        start = None
        if initial.moves:
            surface = problem.surface
            d0 = surface.operator @ u0 - surface.gap0
            start = StepSolution(u0[problem.free], np.zeros(surface.size), d0, np.zeros(surface.size, dtype=bool), 0,
                                 np.nan, np.nan, True)
        return LoopState(0, initial.xi.copy(), z0 if history else None, rate, start,
                         rigid=self._rigid.T @ u0[problem.free])

    # --- the loop ---------------------------------------------------------------------------------
    def run(self, *, progress: bool | Progress | None = None, after_step: Callable[["TimeLoop"], None] | None = None,
            stop: Callable[[], str | None] | None = None, label: str = "time steps") -> Result:
        """Advance from the current state to T (or to a failure, or until ``stop()`` returns a reason);
        ``progress``: the reporter of the steps (default: the loop's; True: lines on stderr), ``label``: their
        name on a terminal's bar."""
        started = clock.perf_counter()
        problem, result = self.problem, self.result
        times = problem.times
        with (reporting(self.progress if progress is None else progress) as reporter,
              reporter.steps(len(times), self.state.step, label) as steps):
            for n in range(self.state.step + 1, len(times) + 1):
                reason = stop() if stop is not None else None
                if reason:
                    result.status = "interrupted"
                    result.message = (f"{reason} after step {n - 1} (t = {times[n - 2] if n > 1 else times.start:g}) "
                                      f"of {len(times)}")
                    break
                steps.started(n, times[n - 1])
                step_started, cuts = clock.perf_counter(), result.step_cuts
                self._substep = 0
                failure = self._history_failure(n) or self._advance(n, times[n - 1], problem.k, 0)
                if failure is not None:
                    result.fail(failure)
                    break
                self.state.step = n
                steps.finished(self._report(n, clock.perf_counter() - step_started, result.step_cuts - cuts))
                if after_step is not None:
                    after_step(self)
        if self._level_without_fields is not None:  # the last level's fields, not kept at its step
            result.final, self._level_without_fields = self._fields(*self._level_without_fields), None
        now = clock.perf_counter()
        for name, count in self.counts().items():
            setattr(result, name, count)
        result.finish({**problem.timings, **self.solver.timings, "time_loop": now - started,
                       "total": problem.timings["build"] + self.setup_time + now - started,
                       **({"earlier_sessions": self.earlier_time} if result.resumed_at else {})})
        result.wall_time_s += self.earlier_time
        return result

    def _report(self, n: int, seconds: float, cuts: int) -> StepReport:
        """Step n, just done in ``seconds`` with ``cuts`` step cuts, for the progress reporter."""
        rows = self.result.rows[-self._substep:]
        contact = self.problem.surface.size > 0
        return StepReport(n, rows[-1]["t"], sum(row["newton_iterations"] for row in rows), rows[-1]["residual"],
                          rows[-1]["nodes_at_limit"] if contact else None,
                          rows[-1]["nodes_in_compliance"] if contact else None, cuts, self.result.step_cuts, seconds)

    def counts(self) -> dict[str, int]:
        """The COUNTERS of the run so far, earlier sessions included."""
        solver = self.solver
        now = {"linear_solves": solver.solves, "krylov_iterations": solver.krylov_iterations,
               "newton_factorizations": solver.newton_factorizations}
        return {name: self.earlier_counts[name] + now[name] for name in COUNTERS}

    def elapsed(self) -> float:
        """Wall time of the run so far, earlier sessions included (seconds)."""
        return self.earlier_time + self.problem.timings["build"] + clock.perf_counter() - self._created

    def _history_failure(self, n: int) -> str | None:
        """The failure of step n when the history it starts from, z_n = z_{n−1} + k 𝒢 (explicit), is not
        finite (no step cut can help: the sub-steps' z lie between z_{n−1} and z_n); None when it is."""
        with np.errstate(all="ignore"):  # a history that is not finite is reported
            finite = self.state.rate is None or np.all(np.isfinite(self.state.z_after(self.problem.k)))
        if finite:
            return None
        return (f"step {n} (t = {self.problem.times[n - 1]:g}) failed: the viscoplastic history is not finite at its "
                f"start (is the explicit step k = {self.problem.k:g} small against the law's relaxation time?)")

    def _advance(self, n: int, t: float, h: float, cuts: int) -> str | None:
        """Reach time t of step n from the current level by one step of length h, or by two halves if
        its Newton iteration fails (recursively); None, or the failure's message. A load that is not
        finite at t (only a sub-step time can hold one: the step times are checked before the run)
        ends the run: no cut can help."""
        try:
            attempt = self._attempt(t, h)
        except NonFiniteLoad as error:
            t_n = self.problem.times[n - 1]
            return f"step {n} (t = {t_n:g}) failed{'' if t == t_n else ' at a sub-step'}: {error}"
        if attempt.solution.converged:
            return self._accept(n, t == self.problem.times[n - 1], attempt)
        pulled = self._pulled_off(n, attempt)
        if pulled is not None:
            return pulled
        if cuts == self.max_cuts:
            return self._failure_message(n, attempt, cuts)
        self.result.step_cuts += 1
        failure = self._advance(n, t - 0.5 * h, 0.5 * h, cuts + 1)
        return failure if failure is not None else self._advance(n, t, 0.5 * h, cuts + 1)

    def _attempt(self, t: float, h: float) -> _Attempt:
        """Solve the step problem of the level at time t, h after the last one (the state is unchanged)."""
        problem, state = self.problem, self.state
        z = state.z_after(h)
        b = self._loads(t)
        support = None if z is not None else self._loads.support
        try:
            with np.errstate(all="ignore"):  # the solvers report iterates that are not finite
                if z is not None:
                    b -= stress_force(problem.basis, z)[problem.free]
                b, support, resultant = self._without_rounding_resultant(b, support)
                step = StepData(b, problem.law, state.xi, h, support)
                solution = self.solver.solve(step, state.start(h))
        except SingularMatrixError as error:
            solution = self._failed(f"the Newton matrix is singular ({error})",
                                    "a part of the body held only by contact may have lost it: hold it with "
                                    "boundary.dirichlet entries, or try smaller time steps (time.steps)")
        except NotConvergedError as error:
            solution = self._failed(f"the Newton system was not solved ({error})",
                                    "try smaller time steps (time.steps), or solver.method = \"full\" (a direct solver)")
        return _Attempt(t, h, step, z, solution, resultant)

    def _without_rounding_resultant(self, b: np.ndarray, support: np.ndarray | None) -> tuple:
        """(b, its support, ‖Zᵀb‖) for a body that only the contact holds: a resultant of the loads on its free
        rigid motions that is within ``solver.tolerance`` of zero, relative to the largest one of the run so far
        (a load that passes through zero, evaluated at a time that misses the zero by a rounding: log(t) at
        t = 1 + 2e-16), is the rounding of a zero resultant, and is removed, b − Z Zᵀb: no contact force can
        pull, so a body pulled by a rounding error would have no solution."""
        if not self._held_by_contact_only:
            return b, support, 0.0
        Z = self._rigid
        r = Z.T @ b if support is None else Z[support].T @ b[support]
        size = float(np.linalg.norm(r))
        if 0.0 < size <= self._tolerance * self._largest_so_far()[1]:
            return b - Z @ r, None, 0.0
        return b, support, size

    def _failed(self, message: str, advice: str) -> StepSolution:
        """The record of a step whose Newton iteration stopped on a failed linear solve."""
        m = self.problem.surface.size
        return StepSolution(None, np.zeros(m), np.full(m, np.nan), np.zeros(m, dtype=bool), 0, np.nan, np.nan, False,
                            message, advice)

    def _accept(self, n: int, ends_step: bool, attempt: _Attempt) -> str | None:
        """Make a converged attempt the new level: ξ, fields, z and 𝒢 there; record it. Values that are
        not finite there (float64 overflow: loads, moduli or laws in unsuitable units) are not recorded:
        the failure's message instead."""
        with np.errstate(all="ignore"):  # values that are not finite are reported
            return self._accept_finite(n, ends_step, attempt)

    def _accept_finite(self, n: int, ends_step: bool, attempt: _Attempt) -> str | None:
        problem, state, result = self.problem, self.state, self.result
        law, h = problem.law, attempt.h
        compliance, _ = law.pressure(attempt.solution.d, state.xi, h)
        if self._held_by_contact_only and np.all(np.isfinite(compliance)):
            attempt, failure = self._resting(n, attempt, compliance)
            if failure is not None:
                return failure
            compliance, _ = law.pressure(attempt.solution.d, state.xi, h)
        solution = attempt.solution
        d = solution.d
        xi = state.xi + h * np.maximum(d, 0.0)
        invalid = self._invalid_law(n, attempt.t, d, xi)
        if invalid is not None:
            return invalid
        K = law.K(xi)
        fields, rate, computed = None, None, None
        G = problem.viscoplastic
        wanted = self.estimator is not None or (ends_step and (n in result.field_steps or n == len(problem.times)))
        if G is not None or wanted:
            u = self._u
            u_free = u[problem.free] = self.solver.displacement(attempt.step, solution)
            strain = element_strain(problem.basis, u)
            z = attempt.z
            sigma = problem.elasticity.stress(strain) + (0.0 if z is None else z)  # σ = ℰε(u) + z
            computed = (u_free, strain, sigma, z)
            if wanted:
                fields = self._fields(*computed)
            if G is not None:
                rate = viscoplastic_rate(G, sigma, strain)
        values = {"ξ": xi, "K": K, "the compliance pressure": compliance}
        if fields is not None:
            values.update({"the displacement": fields.displacement, "the stress": fields.von_mises})
        elif computed is not None:
            values.update({"the displacement": u_free, "the stress": sigma})
        wrong = [name for name, value in values.items() if not np.all(np.isfinite(value))]
        if wrong:
            cause = (f"the viscoplastic history blows up: is the explicit step k = {problem.k:g} small against the "
                     f"law's relaxation time?" if G is not None else
                     "float64 overflow: state the loads, moduli and laws in units that keep them far from 1e308")
            return (f"step {n} (t = {problem.times[n - 1]:g}) failed: {wrong[0]} is not finite at t = "
                    f"{attempt.t:.10g} ({cause})")
        self._substep += 1
        result.record(n, attempt.t, solution, fields, xi=xi, K=K, compliance=compliance,
                      status=node_status(d, solution.active), substep=self._substep, k=h, ends_step=ends_step)
        self._level_without_fields = computed if fields is None else None
        if self.estimator is not None:
            level = Level(problem, n, attempt.t, h, fields, result.contact_row())
            result.record_estimate(self.estimator(level), fields)
        trend = None if state.previous is None else Trend.between(state.previous, solution, h)
        self.state = LoopState(state.step, xi, attempt.z, rate, solution, trend, attempt.step, attempt.rigid)
        if self._held_by_contact_only:
            recorded = result.contact_row()
            self._remember_largest(recorded["pressure_compliance"], recorded["pressure_rigid"])
        return None

    def _resting(self, n: int, attempt: _Attempt, compliance: np.ndarray) -> tuple[_Attempt, str | None]:
        """A level of a body that only the contact holds, as accepted: the attempt itself while a contact node
        carries a force (its pressure above ``solver.tolerance`` times the largest pressure of the run so far;
        below is the rounding of a zero force); where none does, nothing presses the body on the foundation and
        its position is not determined by the step problem (any rigid motion that keeps the nodes unloaded
        solves it: the Newton iteration returns the one its start holds), so the body is placed where it
        changes least from the last level (:mod:`vpcontact.timeloop.resting`), its contact nodes unloaded. The failure's
        message instead when no such place exists (a node that no free motion moves, beyond its room)."""
        solution = attempt.solution
        largest_pressure = self._largest_so_far()[0]
        w = self.problem.surface.weights
        rigid = np.divide(solution.lam, w, out=np.zeros_like(w), where=w > 0)
        if np.max(compliance + rigid, initial=0.0) > self._tolerance * largest_pressure:
            return attempt, None
        NZ = self._rigid_at_contact
        before = self.rigid_position()
        now = self.solver.rigid_coordinates(attempt.step, solution)
        room = self._room(attempt.step)
        allowance = self._tolerance * self.problem.mesh.diameter  # the complementarity the Newton iteration allows
        shift = least_shift(NZ, solution.d + NZ @ (before - now), room, allowance)
        if shift is None:
            return attempt, (f"step {n} (t = {self.problem.times[n - 1]:g}) failed: at t = {attempt.t:.10g} no "
                             f"contact node carries a force, the Dirichlet conditions leave a rigid motion of the body "
                             f"free, and no such motion takes every contact node off the layer: hold that motion with "
                             f"boundary.dirichlet entries")
        place = before + shift
        m = solution.d.size
        d = np.minimum(solution.d + NZ @ (place - now), room)  # the nodes placed at their room: exactly there
        placed = replace(solution, u=None if solution.u is None else solution.u + self._rigid @ (place - now), d=d,
                         lam=np.zeros(m), active=np.zeros(m, dtype=bool))
        return replace(attempt, solution=placed, rigid=place), None

    def _room(self, step: StepData) -> np.ndarray:
        """The largest penetration at which each contact node carries no force: g where the layer carries none
        up to g (K = 0: the Signorini condition with gap g), else 0 (the layer's surface)."""
        law, m = step.law, step.xi_prev.size
        g = np.broadcast_to(np.asarray(law.g, dtype=float), (m,))
        room = np.zeros(m)
        finite = np.isfinite(g)
        if np.any(finite):
            pressure, _ = law.pressure(np.where(finite, g, 0.0), step.xi_prev, step.k)
            unloaded = finite & (pressure == 0.0)
            room[unloaded] = g[unloaded]
        return room

    def rigid_position(self) -> np.ndarray:
        """Zᵀu at the last level: the coordinates of the body's displacement on the rigid motions held only by
        contact (empty when there are none); what a checkpoint keeps for the levels where nothing presses the
        body (see ``_resting``)."""
        state = self.state
        if state.rigid is None:
            known = self._rigid.shape[1] > 0
            state.rigid = self.solver.rigid_coordinates(state.step_problem, state.previous) if known else np.zeros(0)
        return state.rigid

    def _largest_so_far(self) -> tuple[float, float]:
        """The largest contact pressure and the largest resultant of the contact forces on the rigid motions held
        only by contact (which balances the loads' ‖Zᵀb‖), over the levels so far (of a new run: none; of a
        resumed one: from its recorded contact pressures, so that it decides as the uninterrupted run does)."""
        if self._largest_pressure is None:
            self._largest_pressure = self._largest_resultant = 0.0
            contact = self.result.contact
            for compliance, rigid in zip(contact["pressure_compliance"], contact["pressure_rigid"]):
                self._remember_largest(compliance, rigid)
        return self._largest_pressure, self._largest_resultant

    def _remember_largest(self, compliance: np.ndarray, rigid: np.ndarray) -> None:
        """Take a level, its compliance and rigid-base pressures as recorded, into the largest pressure and
        resultant so far (see ``_largest_so_far``)."""
        largest_pressure, largest_resultant = self._largest_so_far()
        pressure = compliance + rigid
        resultant = float(np.linalg.norm(self._rigid_at_contact.T @ (self.problem.surface.weights * pressure)))
        self._largest_pressure = max(largest_pressure, float(np.max(pressure, initial=0.0)))
        self._largest_resultant = max(largest_resultant, resultant)

    def _pulled_off(self, n: int, attempt: _Attempt) -> str | None:
        """The failure of a step whose loads have a resultant on the rigid motions held only by contact that no
        contact pressures can balance, by more than ``solver.tolerance`` relative to the loads (they pull the
        body off the foundation: no time step, however short, has a solution); None otherwise."""
        if not self._held_by_contact_only or attempt.resultant == 0.0:
            return None
        step = attempt.step
        Z = self._rigid
        resultant = Z.T @ step.b if step.support is None else Z[step.support].T @ step.b[step.support]
        pull = unbalanced(self._rigid_at_contact, resultant)
        if not pull > self._tolerance * step.b_norm:
            return None
        motions = "a rigid motion" if Z.shape[1] == 1 else f"{Z.shape[1]} rigid motions"
        it, that = ("it", "that motion") if Z.shape[1] == 1 else ("them", "those motions")
        return (f"step {n} (t = {self.problem.times[n - 1]:g}) failed: at t = {attempt.t:.10g} the loads pull the body "
                f"off the foundation: the Dirichlet conditions leave {motions} of the body free, and {pull:.3g} of the "
                f"loads' resultant on {it} ({pull / attempt.resultant:.0%}) is a pull that no contact pressure can "
                f"balance, so nothing holds the body; keep the loads pressing it on the foundation, or hold {that} with "
                f"boundary.dirichlet entries")

    def _invalid_law(self, n: int, t: float, d: np.ndarray, xi: np.ndarray) -> str | None:
        """The failure of a level where the contact laws K(ξ) or p(r) are not finite numbers ≥ 0 at some contact
        node (a layer cannot pull: a user's law that turns negative, or one evaluated beyond its range); None when
        they are valid everywhere."""
        wrong = self._law_violation(d, xi)
        if wrong is None:
            return None
        return f"step {n} (t = {self.problem.times[n - 1]:g}) failed: at t = {t:.10g} {wrong}"

    def _law_violation(self, d: np.ndarray, xi: np.ndarray) -> str | None:
        """Where the contact laws are not finite numbers ≥ 0 (see ContactLaw.violation), in words: the law, its
        value, the node, where it is and the law's argument there, and what to check; None if nowhere."""
        violation = self.problem.law.violation(d, xi)
        if violation is None:
            return None
        law, i, value, argument, at = violation
        surface = self.problem.surface
        names = ", ".join(coordinates(surface.coordinates.shape[0]))
        where = ", ".join(f"{c:.6g}" for c in surface.coordinates[:, i])
        key = "contact.stiffness" if law.startswith("K") else "contact.p"
        return (f"the contact law {law} is {value:.6g} at contact node {i} ({names}) = ({where}), where {argument} = "
                f"{at:.6g}; it must be a finite number >= 0 (a layer cannot pull): check {key} at this {argument}")

    def _fields(self, u_free: np.ndarray, strain: np.ndarray, sigma: np.ndarray, z: np.ndarray | None) -> Fields:
        """The Fields of a level from its displacement at the free dofs, ε, σ and z (elements last)."""
        problem = self.problem
        u = np.zeros(problem.basis.N)
        u[problem.free] = u_free
        sigma33 = problem.elasticity.out_of_plane_stress(strain)
        return Fields(displacement=u[problem.basis.nodal_dofs].T.copy(), stress=np.moveaxis(sigma, -1, 0),
                      stress33=sigma33, von_mises=von_mises(sigma, sigma33),
                      z=None if z is None else np.moveaxis(z, -1, 0).copy())

    def _failure_message(self, n: int, attempt: _Attempt, cuts: int) -> str:
        """One line: the step, its time, where the cuts ended, the residuals, the contact counts and what to try."""
        t_n = self.problem.times[n - 1]
        s = attempt.solution
        where = (f" after {cuts} step cut{'s' if cuts != 1 else ''} (sub-step of length {attempt.h:g} ending at "
                 f"t = {attempt.t:.10g})" if cuts else "")
        counts = ""
        if s.d.size and np.all(np.isfinite(s.d)):
            status = node_status(s.d, s.active)
            counts = (f"; contact nodes separated/in compliance/at limit = {int(np.sum(status == SEPARATED))}/"
                      f"{int(np.sum(status == IN_COMPLIANCE))}/{int(np.sum(status == AT_LIMIT))}")
        advice = f"; {s.advice}" if s.advice else ""
        if s.d.size and np.all(np.isfinite(s.d)):
            wrong = self._law_violation(s.d, self.state.xi + attempt.h * np.maximum(s.d, 0.0))
            advice = f"; at the last iterate {wrong}" if wrong is not None else advice
        if attempt.z is not None and not np.isfinite(s.residual) and self.state.rate is not None:
            advice = (f"; the viscoplastic history reaches |z| = {np.abs(attempt.z).max():.3g}: is the explicit step "
                      f"k = {self.problem.k:g} small against the law's relaxation time?")
        return (f"step {n} (t = {t_n:g}) failed{where}: {s.message}; residual {s.residual:.3e}, "
                f"complementarity {s.complementarity:.3e}{counts}{advice}")


def solve_problem(problem: Problem, *, output: OutputSection | None = None,
                  progress: bool | Progress = False) -> Result:
    """Run the time loop of ``problem`` and return the result (status "failed" if a step fails); ``output``:
    the fields kept and the error estimate (:class:`~vpcontact.case.schema.OutputSection`, default: its defaults);
    ``progress``: True for the solver's set-up and the steps reported on stderr (:mod:`vpcontact.progress`),
    or a reporter."""
    with reporting(progress) as reporter:
        return TimeLoop(problem, output, reporter).run()


def viscoplastic_rate(G, sigma: np.ndarray, strain: np.ndarray) -> np.ndarray:
    """𝒢(σ, ε) per element, checked: an array of the shape of σ, (d, d, nelements)."""
    rate = G(sigma.copy(), strain.copy())  # a law may not change the stored fields
    try:
        rate = np.broadcast_to(np.asarray(rate, dtype=float), sigma.shape)
    except (TypeError, ValueError):
        raise ValueError(f"the viscoplastic law returned an array of shape {np.shape(rate)}; expected "
                         f"{sigma.shape} (d, d, elements), like its arguments") from None
    return rate
