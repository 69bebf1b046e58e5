"""The step method of a run: its step solver, made as the run's plan says, and, with ``solver.method = "auto"``,
the methods weighed again after each step and the one switch it may make (:mod:`vpcontact.solvers.switch`).

A switch hands the time loop's state, unchanged, to the new step solver: ξ, z and the results are the loop's, not
the solver's. The last level's solution is completed with its displacement (the condensed method's solution has
none: one solve with its factor), so that every method can start from it. The new solver is set up while the old
one still exists (the switch was weighed with the old one's memory in use), and a method that cannot be set up
after all (CaseError: a factor that does not fit) leaves the old one running, and the methods are not weighed
again.
"""

from __future__ import annotations

import resource
import time as clock
from dataclasses import replace

from ..errors import CaseError
from ..progress import SILENT, Progress
from ..solvers import SolverWork, make_solver
from ..solvers.switch import MethodWeighing, Switch


class RunMethod:
    """The step solver of a run of ``problem`` by its ``plan`` (:mod:`.plan`), for the stiffness A and contact
    operator N on the free dofs, the dofs' nodal ``layout`` and the rigid motions ``rigid`` held only by contact;
    ``progress`` hears of the set-up and of a switch. ``earlier_work``: the work of earlier sessions (a resumed
    run) and of the method switched from; ``switch``: the switch made (None: none), ``switch_seconds`` what it took
    in this session."""

    def __init__(self, problem, plan, A, N, layout, rigid, progress: Progress = SILENT):
        """On the MPI ranks a problem is shared among (``problem.ranks``, :mod:`vpcontact.parallel`) the method is
        never switched."""
        options, surface = problem.solver, problem.surface
        partition = problem.partition  # the nodes shared among the ranks (None: one process)

        def solver_of(method: str, reason: str):
            return make_solver(method, A, N, surface.weights, surface.gap0, r=plan.augmentation, reason=reason,
                               rigid=rigid, tolerance=options.tolerance, max_iterations=options.max_iterations,
                               length_scale=problem.mesh.diameter, factorization=options.factorization,
                               multigrid=options.multigrid, layout=layout, progress=progress,
                               expected_seconds=plan.predicted[method]["setup_s"], partition=partition)

        self._solver_of, self.progress, self._ranks = solver_of, progress, problem.ranks
        self._entries = problem.A.nnz  # the entries of the stiffness this rank assembled
        self.solver = solver_of(plan.method, plan.method_reason)
        if partition is not None:  # never switched: the rows of A the ranks' solver has copied are released
            self._solver_of = None
        self.weighing = (MethodWeighing(A, N, problem.mesh.dim, plan.history, len(problem.times), plan.factor,
                                        plan.multigrid) if options.method == "auto" and partition is None else None)
        self.switch: Switch | None = None
        self.switch_seconds: float | None = None
        self.earlier_work = SolverWork()

    def ranks(self, elements: int) -> tuple[dict | None, list[int]]:
        """Each MPI rank's share of the solve (:attr:`~vpcontact.solvers.distributed.DistributedNewton.shares`) with
        its ``elements`` (those whose history it holds) and the entries of its rows of the stiffness it assembled (None
        in one process), and each one's peak resident memory so far, in bytes: a collective call, every rank makes
        it."""
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux gives kilobytes
        shares = None if self._ranks.size == 1 else {**self.solver.shares, "elements": self._ranks.each(elements),
                                                     "stiffness_entries": self._ranks.each(self._entries)}
        return shares, self._ranks.each(peak)

    def work(self) -> SolverWork:
        """The step solvers' work in the run so far, earlier sessions included."""
        return self.earlier_work + self.solver.work()

    def restore(self, meta: dict) -> None:
        """The work counted and the switch made in earlier sessions, from a checkpoint's ``meta``."""
        self.earlier_work = SolverWork.from_counts(meta)
        if meta.get("method_switch") is not None:
            self.switch = Switch.from_dict(meta["method_switch"])

    def weigh(self, n: int, newton: int, state) -> bool:
        """After step n (``newton`` Newton iterations so far, the loop's ``state``): switch to another method if the
        work done says it will finish clearly sooner; whether it switched (what depends on the solver is then
        made again by the caller)."""
        if self.weighing is None or self.switch is not None:
            return False
        switch = self.weighing.consider(self.solver.name, n, self.work(), newton)
        if switch is None:
            return False
        started = clock.perf_counter()
        self.progress.note(f"switching to the {switch.after} method: {switch.reason}")
        try:
            solver = self._solver_of(switch.after, f"solver.method = \"auto\", switched: {switch.reason}")
        except CaseError as error:
            self.progress.note(f"the {switch.after} method cannot be set up ({error}): the {switch.before} method "
                               f"goes on")
            self.weighing = None
            return False
        if state.previous is not None and state.previous.u is None:
            state.previous = replace(state.previous, u=self.solver.displacement(state.step_problem, state.previous))
        self.earlier_work = self.earlier_work + self.solver.work()
        self.solver, self.switch = solver, switch
        self.switch_seconds = clock.perf_counter() - started
        return True
