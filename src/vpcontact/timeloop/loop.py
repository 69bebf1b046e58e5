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

Step cuts: a step whose Newton iteration fails (iteration limit, non-finite iterates, a singular Newton matrix) is
done as two sub-steps of length k/2, each cut again if it fails, down to ``solver.max_step_cuts`` halvings; one whose
time estimate is above its share (``time.adaptive``, :mod:`~vpcontact.timeloop.time_control`) too, down to
``time.max_halvings``. A sub-step of length h ending at t is an ordinary step of the scheme (loads at t, z + h 𝒢,
ξ + h d⁺).
The state carried from level to level is a :class:`~vpcontact.timeloop.state.LoopState`; with the
solver's kept state, the counters of work and the result so far it is the loop's snapshot
(``TimeLoop.snapshot``, :class:`~vpcontact.timeloop.snapshot.LoopSnapshot`), all a checkpoint needs:
``TimeLoop.restore`` continues from one as if the loop had never stopped.

The step solver is the run's :class:`~vpcontact.timeloop.method.RunMethod`'s: under ``solver.method = "auto"`` it
may switch once after a step, the loop's state unchanged (:mod:`vpcontact.solvers.switch`).

With ``output.error_estimate`` (or ``time.adaptive``) the fields are computed at every level, the estimator of every
level (:data:`~vpcontact.estimate.estimators.EVERY_LEVEL`, the residual one) adds η(t) and its terms to the level's
history row and η_K to its fields, and the second-order companion (:mod:`~vpcontact.timeloop.companion`) the
estimate in time η_k(t) and the step's share of it.
"""

from __future__ import annotations

import time as clock
from dataclasses import asdict, replace
from typing import Callable

import numpy as np

from ..fem.assembly import NonFiniteLoad
from ..laws.contact import node_status
from ..parallel.elements import ElementShare
from ..estimate.indicators import Level
from ..problem.build import Problem, checked_problem
from ..problem.discretization import Discretization
from ..progress import SILENT, Progress, StepReport, reporting
from ..estimate.estimators import ESTIMATORS, EVERY_LEVEL
from ..results.output_options import OutputOptions
from ..results.result import Result, level_contact
from ..fem.rigid_modes import RigidModes
from ..solvers import DofLayout, SolverWork, StepData
from ..solvers.errors import NotConvergedError, SingularMatrixError
from .checks import (LawShapeError, failed_solve, failure_message, history_failure, invalid_law, not_finite, pulled_off,
                     viscoplastic_rate)
from .companion import Companion
from .time_control import TimeControl
from .level_fields import level_fields
from .method import RunMethod
from .plan import free_operators, plan_run
from .reactions import Reactions
from .resting import FreeMotions
from .snapshot import LoopSnapshot, loop_snapshot, restore_loop
from .state import Attempt, LoopState, Trend


#: What ``TimeLoop._accept`` returns for a level whose time estimate is above its share (``time.adaptive``).
TOO_COARSE = object()


class TimeLoop:
    """The time loop of a problem: ``TimeLoop(problem, output).run()`` returns the :class:`Result`;
    ``output`` (:class:`~vpcontact.results.output_options.OutputOptions`, default: its defaults) says which steps
    keep their fields and whether the error is estimated at every step. The run's plan
    (:mod:`vpcontact.timeloop.plan`, ``self.plan``) is made here: what cannot run is refused before its first
    step, and the step solver is the plan's.

    ``run`` takes two hooks: ``after_step(loop)``, called after every completed time step (the checkpoints of
    :mod:`vpcontact.drivers.rundir`), and ``stop()``, asked before every step (a signal asked the run to stop: the
    status becomes "interrupted"). ``progress`` (:mod:`vpcontact.progress`; default: silent) hears of the solver's
    set-up phases here, of the time steps in ``run``. A problem shared among MPI ranks (``problem.ranks``) runs
    on all of them together, the step solver's algebra shared (:mod:`vpcontact.parallel`); ``stop`` must agree.
    """

    def __init__(self, problem: Problem, output: OutputOptions | None = None, progress: Progress = SILENT,
                 resumed_method: str | None = None):
        started = clock.perf_counter()
        self.problem, self.progress = checked_problem(problem), progress
        output = OutputOptions() if output is None else output
        time = problem.options.time
        if time.adaptive:  # balanced against the space estimate: both estimates at every level, as written
            output = replace(output, error_estimate=True)
        free, surface, options = problem.free, problem.surface, problem.solver
        mesh = problem.mesh.mesh
        A, N = free_operators(problem)
        self.plan = plan = plan_run(problem, output, A, N, resumed_method)  # the refusals, first
        modes = RigidModes.of_mesh(mesh.p, mesh.t, problem.basis.nodal_dofs)
        layout = DofLayout(free, mesh.dim(), mesh.nvertices, modes.matrix[free].toarray())
        rigid = modes.free_basis(free)
        self.motions = FreeMotions(rigid, surface.operator[:, free] @ rigid, surface.weights, options.tolerance)

        self.method = RunMethod(problem, plan, A, N, layout, rigid, progress)
        self.elements = ElementShare.of(problem, problem.partition)  # the elements whose z this rank holds
        self.max_cuts = options.max_step_cuts
        constraints = problem.constraints
        #: A_fh, the coupling of the free and the held dofs: b = F_f − Bᵀz − A_fh u_D(t) (prescribed displacements)
        self._coupling = problem.ranks.sum_matrix(problem.A[free][:, constraints.held]) if constraints.moves else None
        #: where b can be nonzero without z (positions among the free dofs): the loads' and the coupling's rows
        self._support = problem.loads.on(free).support
        if constraints.moves:
            moving = np.searchsorted(constraints.held, constraints.moving_dofs())
            self._support = np.union1d(self._support, np.unique(self._coupling[:, moving].tocoo().row))
        discretization = Discretization.of(problem)
        self.reactions = Reactions(problem, discretization.held_parts)
        self._functionals = None if self.reactions.M is None else self.solver.functionals(self.reactions.M)
        self.time_control = TimeControl(problem.times, time.balance if time.adaptive else None, time.max_halvings)
        estimator = ESTIMATORS[EVERY_LEVEL] if output.error_estimate else None
        self.result = Result.start(discretization, problem.basis.N, self.solver, output,
                                   () if estimator is None else estimator.terms)
        self.result.predicted, self.result.ranks = plan.predicted, problem.ranks.size
        self.estimator = None if estimator is None else estimator.prepare(problem)
        self._created = started
        self.setup_time = clock.perf_counter() - started
        self.earlier_time = 0.0  # wall time of earlier sessions (resumed)
        self.state = LoopState.initial(problem, rigid, self.elements)
        #: the second-order companion that estimates the error in time, with the estimate in space
        self.companion = None if estimator is None else Companion(problem, self.elements, self.state)
        # (u, ε, σ, z) of the last level if its Fields were not built: ``run`` makes them ``result.final``
        self._level_without_fields: tuple | None = None
        self._u = np.zeros(problem.basis.N)
        self.newton = 0  # Newton iterations of the levels so far (earlier sessions included)

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
                failure = history_failure(problem, self.state, n, self.elements)
                failure = failure or self._advance_step(n)
                if failure is not None:
                    result.fail(failure)
                    break
                self.state.step = n
                steps.finished(StepReport.of_rows(n, result.rows[-self._substep:], problem.surface.size > 0,
                                                  result.step_cuts - cuts, result.step_cuts,
                                                  clock.perf_counter() - step_started))
                self._weigh(n)
                if after_step is not None:
                    after_step(self)
        if self._level_without_fields is not None:  # the last level's fields, not kept at its step
            result.final = level_fields(problem, self.elements, *self._level_without_fields)
            self._level_without_fields = None
        now = clock.perf_counter()
        result.time_over_share = self.time_control.over_share
        for name, count in asdict(self.work()).items():
            setattr(result, name, count)
        result.ranks_detail, result.peak_memory_bytes = self.method.ranks(self.elements.count)
        seconds = self.method.switch_seconds
        switching = {} if seconds is None else {"method_switch": seconds}
        result.finish({**problem.timings, **self.solver.timings, **switching, "time_loop": now - started,
                       "total": problem.timings["build"] + self.setup_time + now - started,
                       **({"earlier_sessions": self.earlier_time} if result.resumed_at else {})})
        result.wall_time_s += self.earlier_time
        return result

    def work(self) -> SolverWork:
        """The step solver's work in the run so far, earlier sessions included (summary.json reports it)."""
        return self.method.work()

    def elapsed(self) -> float:
        """Wall time of the run so far, earlier sessions included (seconds)."""
        return self.earlier_time + self.problem.timings["build"] + clock.perf_counter() - self._created

    # --- a snapshot -------------------------------------------------------------------------------
    def snapshot(self) -> LoopSnapshot:
        """The loop at the end of its last completed step (:func:`~.snapshot.loop_snapshot`: what a checkpoint keeps;
        collective on MPI ranks)."""
        return loop_snapshot(self)

    def restore(self, snapshot: LoopSnapshot) -> None:
        """Continue from ``snapshot`` (of a loop of the same problem, not run yet) as if the loop had never stopped
        (:func:`~.snapshot.restore_loop`). KeyError for an array or value it lacks."""
        restore_loop(self, snapshot)

    @property
    def solver(self):
        """The step solver running (:class:`~vpcontact.timeloop.method.RunMethod`: the plan's, or the one switched to)."""
        return self.method.solver

    def _weigh(self, n: int) -> None:
        """After step n: under ``solver.method = "auto"``, the switch of method the work done calls for
        (:class:`~vpcontact.timeloop.method.RunMethod`), and what depends on the step solver made again."""
        if not self.method.weigh(n, self.newton, self.state):
            return
        if self.reactions.M is not None:
            self._functionals = self.solver.functionals(self.reactions.M)
        self.result.method, self.result.method_reason = self.solver.name, self.solver.reason
        self.result.method_switch = self.method.switch.as_dict()

    def _advance_step(self, n: int) -> str | None:
        """Reach t_n from t_{n−1}, in the sub-steps :class:`~.time_control.TimeControl` starts it with; None, or
        the failure's message."""
        halvings = self.time_control.halvings  # each sub-step's own estimate predicts the next step's anew
        for t, h in self.time_control.sub_steps(n):
            failure = self._advance(n, t, h, halvings, 0)
            if failure is not None:
                return failure
        return None

    def _advance(self, n: int, t: float, h: float, halvings: int, cuts: int) -> str | None:
        """Reach time t of step n from the current level by one step of length h (the step's length halved
        ``halvings`` times, ``cuts`` of them for a Newton iteration that failed), or by two halves if its Newton
        iteration fails or (``time.adaptive``) its time estimate is above its share (recursively); None, or the
        failure's message. A load that is not finite at t (only a sub-step time can hold one: the step times are
        checked before the run) ends the run: no cut can help."""
        try:
            attempt = self._attempt(t, h)
        except NonFiniteLoad as error:
            t_n = self.problem.times[n - 1]
            return f"step {n} (t = {t_n:g}) failed{'' if t == t_n else ' at a sub-step'}: {error}"
        if attempt.solution.converged:
            accepted = self._accept(n, t == self.problem.times[n - 1], attempt, halvings)
            if accepted is not TOO_COARSE:
                return accepted
            self.result.time_cuts += 1
        else:
            pulled = pulled_off(self.problem, self.motions, n, attempt)
            if pulled is not None:
                return pulled
            if cuts == self.max_cuts:
                return failure_message(self.problem, self.state, n, attempt, cuts, self.elements)
            self.result.step_cuts += 1
            cuts += 1
        failure = self._advance(n, t - 0.5 * h, 0.5 * h, halvings + 1, cuts)
        return failure if failure is not None else self._advance(n, t, 0.5 * h, halvings + 1, cuts)

    def _attempt(self, t: float, h: float) -> Attempt:
        """Solve the step problem of the level at time t, h after the last one (the state is unchanged)."""
        problem, state = self.problem, self.state
        z = state.z_after(h)
        load = problem.loads(t)  # F(t) at every dof: the free ones' is the step's, the held ones' the reactions'
        b, history_force = load[problem.free], None
        held = problem.constraints(t) if self._coupling is not None else None  # u_D(t) at the held dofs
        support = None if z is not None else self._support
        try:
            with np.errstate(all="ignore"):  # the solvers report iterates that are not finite
                if held is not None:
                    b -= self._coupling @ held
                if z is not None:
                    history_force = self.elements.force(z)
                    b -= history_force[problem.free]
                b, support, resultant = self.motions.without_rounding_resultant(b, support)
                step = StepData(b, problem.law, state.xi, h, support)
                solution = self.solver.solve(step, state.start(h))
        except SingularMatrixError as error:
            solution = failed_solve(self.problem, f"the Newton matrix is singular ({error})",
                                    "a part of the body held only by contact may have lost it: hold it with "
                                    "boundary.dirichlet entries, or try smaller time steps (time.steps)")
        except NotConvergedError as error:
            solution = failed_solve(self.problem, f"the Newton system was not solved ({error})",
                                    "try smaller time steps (time.steps), or solver.method = \"full\" "
                                    "(a direct solver)")
        return Attempt(t, h, step, z, solution, resultant, load=load, history_force=history_force, held=held)

    def _accept(self, n: int, ends_step: bool, attempt: Attempt, halvings: int) -> str | None | object:
        """Make a converged attempt (its step's length halved ``halvings`` times) the new level: ξ, fields, z and 𝒢
        there, the error estimates; record it. Values that are not finite there (float64 overflow: loads, moduli or
        laws in unsuitable units) are not recorded: the failure's message instead; nor is a level whose time
        estimate is above its share (``time.adaptive``) while the step can be cut again: TOO_COARSE instead."""
        with np.errstate(all="ignore"):  # values that are not finite are reported
            return self._accept_finite(n, ends_step, attempt, halvings)

    def _accept_finite(self, n: int, ends_step: bool, attempt: Attempt, halvings: int) -> str | None | object:
        problem, state, result = self.problem, self.state, self.result
        law, h = problem.law, attempt.h
        compliance, _ = law.pressure(attempt.solution.d, state.xi, h)
        if self.motions.held_by_contact_only and np.all(np.isfinite(compliance)):
            attempt, failure = self._resting(n, attempt, compliance)
            if failure is not None:
                return failure
            compliance, _ = law.pressure(attempt.solution.d, state.xi, h)
        solution = attempt.solution
        d = solution.d
        xi = state.xi + h * np.maximum(d, 0.0)
        invalid = invalid_law(problem, n, attempt.t, d, xi)
        if invalid is not None:
            return invalid
        K = law.K(xi)
        fields, rate, computed = None, None, None
        G = problem.viscoplastic
        wanted = self.estimator is not None or (ends_step and (n in result.field_steps or n == len(problem.times)))
        if G is not None or wanted:
            u = self._u
            u[problem.free] = self.solver.displacement(attempt.step, solution)
            if attempt.held is not None:
                u[problem.constraints.held] = attempt.held
            strain = self.elements.strain(u)  # ε, σ, z and 𝒢 on this rank's elements (all in one process)
            sigma = self.elements.stress(strain, attempt.z)  # σ = ℰε(u) + z
            computed = (u.copy(), strain, sigma, attempt.z)
            if wanted:
                fields = level_fields(problem, self.elements, *computed)
            if G is not None:
                try:
                    rate, shape_error = viscoplastic_rate(self.elements.viscoplastic, sigma, strain), None
                except LawShapeError as error:
                    shape_error = str(error)
                shape_error = self.elements.ranks.agreed(shape_error)  # a rank that fails alone stops every one
                if shape_error:
                    return f"step {n} (t = {problem.times[n - 1]:g}) failed: at t = {attempt.t:.10g} {shape_error}"
        wrong = not_finite(problem, n, attempt.t, self.elements, {"ξ": xi, "K": K, "the compliance pressure": compliance},
                           fields, computed)
        if wrong is not None:
            return wrong
        status = node_status(d, solution.active)
        estimate = companion = None
        if self.estimator is not None:
            contact = level_contact(problem.surface.weights, solution, xi, K, compliance, status)
            estimate = self.estimator(Level(problem, n, attempt.t, h, fields, contact))
            companion = self.companion.attempt(self.solver, attempt, computed[0], state.rate, rate)
            if self.time_control.too_coarse(estimate.total, companion, h, halvings):
                return TOO_COARSE
        self._substep += 1
        self.newton += solution.iterations
        functionals = None if self._functionals is None else self._functionals(attempt.step, solution)
        parts = self.reactions.row(functionals, compliance, solution.lam, attempt.load, attempt.history_force,
                                   attempt.held)
        result.record(n, attempt.t, solution, fields, xi=xi, K=K, compliance=compliance,
                      status=status, substep=self._substep, k=h, ends_step=ends_step, held=parts)
        self._level_without_fields = computed if fields is None else None
        if estimate is not None:
            result.record_estimate(estimate, fields, companion)
            self.companion.accept(companion)
        trend = None if state.previous is None else Trend.between(state.previous, solution, h)
        self.state = LoopState(state.step, xi, attempt.z, rate, solution, trend, attempt.step, attempt.rigid)
        if self.motions.held_by_contact_only:
            recorded = result.contact_row()
            self.motions.remember(recorded["pressure_compliance"], recorded["pressure_rigid"])
        return None

    def _resting(self, n: int, attempt: Attempt, compliance: np.ndarray) -> tuple[Attempt, str | None]:
        """A level of a body that only the contact holds, as accepted: the attempt itself while a contact node
        carries a force; where none does, the body placed where it changes least from the last level, its contact
        nodes unloaded (:mod:`vpcontact.timeloop.resting`); the failure's message instead when no such place exists."""
        if self.motions.pressed(attempt.solution, compliance):
            return attempt, None
        now = self.solver.rigid_coordinates(attempt.step, attempt.solution)
        return self.motions.rest(attempt, self.rigid_position(), now, self.problem.mesh.diameter,
                                 f"step {n} (t = {self.problem.times[n - 1]:g})")

    def rigid_position(self) -> np.ndarray:
        """Zᵀu at the last level: the coordinates of the body's displacement on the rigid motions held only by
        contact (empty when there are none); what a checkpoint keeps for the levels where nothing presses the
        body (see ``_resting``)."""
        state = self.state
        if state.rigid is None:
            known = self.motions.basis.shape[1] > 0
            state.rigid = self.solver.rigid_coordinates(state.step_problem, state.previous) if known else np.zeros(0)
        return state.rigid


def solve_problem(problem: Problem, *, output: OutputOptions | None = None,
                  progress: bool | Progress = False) -> Result:
    """Run the time loop of ``problem`` and return the result (status "failed" if a step fails); ``output``:
    the fields kept and the error estimate (:class:`~vpcontact.results.output_options.OutputOptions`, default:
    its defaults); ``progress``: True for the solver's set-up and the steps reported on stderr
    (:mod:`vpcontact.progress`), or a reporter."""
    with reporting(progress) as reporter:
        return TimeLoop(problem, output, reporter).run()
