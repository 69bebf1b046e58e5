"""The plan of a run, made before its first step: its sizes, the step method and why, the memory and the time
it will take, and the refusals of what cannot run.

:func:`plan_run` computes it once from a problem and the output options; the time loop makes its step solver
by it (:class:`~vpcontact.timeloop.loop.TimeLoop`: the method, its reason and the augmentation r of the plan)
and ``vpcontact check`` prints it (:mod:`vpcontact.drivers.check`), so that the two cannot disagree. Every
refusal before the first step is made here, each one line (CaseError), in this order:

1. the outputs kept until they are written would not fit in the memory available
   (:func:`~vpcontact.results.footprint.check_memory`);
2. ``solver.augmentation`` far from the normal stiffness at the contact nodes
   (:func:`~vpcontact.solvers.augmentation_parameter`);
3. the chosen method's own algebra would not fit: the condensed method's dense algebra
   (:func:`~vpcontact.solvers.condensed.check_condensed_memory`) or the iterative method's peak
   (:func:`~vpcontact.solvers.choice.check_iterative_memory`).

Each method's time and memory are predicted by the cost model (:mod:`vpcontact.solvers.cost`: this machine's rates
probed now, the direct factor's work counted by PARDISO's analysis where the count may matter, else by laws);
the method for ``solver.method = "auto"`` is the fastest predicted that fits
(:func:`~vpcontact.solvers.choice.chosen_method`). Not planned: the step solver's set-up itself (the factorization
of the stiffness, the condensed operator, the multigrid hierarchy), whose failures the solver reports as it is
made.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError
from ..memory import available_memory
from ..problem.build import Problem
from ..problem.discretization import held_parts
from ..results.footprint import check_memory, memory_needed
from ..results.steps import field_step_numbers
from ..solvers import augmentation_parameter
from ..solvers.linear import chosen_multigrid
from ..solvers.choice import check_iterative_memory, chosen_method
from ..solvers.condensed import check_condensed_memory, condensed_fits, condensed_memory
from ..solvers.cost import FactorWork, MachineRates, factor_work, iterative_memory, predict, resident_memory


@dataclass(frozen=True)
class RunPlan:
    """What a run of a problem will be. Sizes are counts (``dofs``: all, ``free_dofs``: those no Dirichlet
    condition fixes); the time grid t_n = ``start`` + n ``k``, n = 1, …, ``steps`` up to ``T``, with the fields kept
    at ``field_steps`` of its steps; ``method`` the step method that runs and ``method_reason`` why (summary.json's
    solver_reason), ``augmentation`` its Alart–Curnier r; ``memory_bytes``: the outputs kept until written, by
    part (:func:`~vpcontact.results.footprint.memory_needed`: "history rows", "contact rows", "fields", "writing"),
    and the step method's own algebra ("solver": the condensed method's dense algebra or the iterative method's
    peak; None for the full method, not estimated), against ``memory_available_bytes`` when the plan was made;
    ``time_seconds``: "build" (mesh, assembly, checks) as measured (0 for a problem without a measured build),
    "solver setup", "time loop" and "total" predicted for the method that runs; ``memory_peak_bytes`` the peak
    predicted for the whole process (the problem, the method's algebra, the outputs); ``predicted``: each
    method's predicted cost (:meth:`~vpcontact.solvers.cost.MethodCost.as_dict`: seconds of set-up and time loop,
    bytes, whether it fits); ``factor``: the direct factor's work these predictions rest on
    (:class:`~vpcontact.solvers.cost.FactorWork`; None: the direct methods were not weighed), ``history``: a bulk
    solve at every step (a viscoplastic history); ``multigrid``: the iterative method's multigrid backend, as it would
    run (``solver.multigrid`` resolved: "petsc" or "pyamg")."""

    dim: int
    nodes: int
    elements: int
    dofs: int
    free_dofs: int
    contact_nodes: int
    start: float
    T: float
    steps: int
    k: float
    field_steps: int
    method: str
    method_reason: str
    augmentation: float
    memory_bytes: dict[str, int | None]
    memory_available_bytes: int
    memory_peak_bytes: int
    time_seconds: dict[str, float]
    predicted: dict[str, dict]
    factor: FactorWork | None
    history: bool
    multigrid: str

    @property
    def setup_seconds(self) -> float:
        """The seconds the step solver's set-up is expected to take."""
        return self.time_seconds["solver setup"]


def free_operators(problem: Problem) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The stiffness A and the contact operator N on the free dofs: what the step solver is made of."""
    free = problem.free
    return problem.A[free][:, free].tocsr(), problem.surface.operator[:, free].tocsr()


def plan_run(problem: Problem, output, A: sp.csr_matrix, N: sp.csr_matrix,
             resumed_method: str | None = None) -> RunPlan:
    """The plan of a run of ``problem`` with the output options ``output`` (``output.field_steps`` and
    ``output.error_estimate``), whose stiffness and contact operator on the free dofs are A and N
    (:func:`free_operators`); CaseError for a run that cannot be made (see the module's docstring). A run resumed
    from a checkpoint made by ``resumed_method`` keeps it for ``solver.method = "auto"`` (the prediction weighs
    this machine's speed now: another session could choose another method, and the resumed run would then not
    be the uninterrupted one bit for bit). For a problem shared among MPI ranks (``problem.ranks``), whose A is this
    rank's rows, the method is the iterative one with PETSc's GAMG, the one that shares a solve among ranks
    (:func:`ranks_method`), and the costs and memory predicted are this rank's."""
    ranks = problem.ranks.size
    mesh, surface, times = problem.mesh, problem.surface, problem.times
    nodes, elements = mesh.mesh.p.shape[1], mesh.mesh.t.shape[1]
    history = problem.viscoplastic is not None or bool(np.any(problem.initial_history != 0.0))
    held = len(held_parts(problem))
    check_memory(len(times), output, nodes, elements, surface.size, history, mesh.dim, held)
    r = augmentation_parameter(A, N, problem.solver.augmentation, problem.ranks)
    field_steps = len(field_step_numbers(output.field_steps, len(times)))
    multigrid = chosen_multigrid(problem.solver.multigrid) if ranks == 1 else "petsc"
    asked = problem.solver.method if ranks == 1 else "iterative"
    deciding, costs, factor = predicted_costs(asked, A, N, mesh.dim, len(times), history, field_steps, multigrid)
    method, reason = chosen_method(problem.solver.method, deciding) if ranks == 1 else ranks_method(problem, ranks)
    if ranks == 1 and problem.solver.method == "auto" and resumed_method in costs and resumed_method != method:
        method, reason = resumed_method, (f"solver.method = \"auto\": the {resumed_method} method of the run resumed "
                                          f"(this session predicts the {method} method fastest)")
    solver_memory = None
    if method == "condensed":
        check_condensed_memory(N, A.shape[0])
        solver_memory = condensed_memory(N, A.shape[0])
    elif method == "iterative":
        check_iterative_memory(A, problem.ranks)
        solver_memory = iterative_memory(A)
    outputs = memory_needed(len(times), field_steps, nodes, elements, surface.size, history, mesh.dim,
                            estimate=output.error_estimate, held_parts=held)
    build = problem.timings.get("build", 0.0)
    cost = costs[method]
    return RunPlan(
        dim=mesh.dim, nodes=nodes, elements=elements, dofs=int(problem.basis.N), free_dofs=problem.free.size,
        contact_nodes=surface.size, start=float(times.start), T=float(times.T), steps=len(times), k=float(times.k),
        field_steps=field_steps, method=method, method_reason=reason, augmentation=r,
        memory_bytes={**outputs, "solver": solver_memory}, memory_available_bytes=available_memory(),
        memory_peak_bytes=int(cost.memory_bytes + sum(outputs.values())),
        time_seconds={"build": build, "solver setup": cost.setup_s, "time loop": cost.loop_s,
                      "total": build + cost.total_s},
        predicted={name: cost.as_dict() for name, cost in costs.items()}, factor=factor, history=history,
        multigrid=multigrid)


def ranks_method(problem: Problem, ranks: int) -> tuple[str, str]:
    """The method of a run on ``ranks`` MPI ranks, and why: the iterative method with PETSc's GAMG, the one whose
    solve the ranks share; CaseError for another method or multigrid asked for."""
    options = problem.solver
    if options.method not in ("auto", "iterative"):
        raise CaseError(f"solver.method = \"{options.method}\" runs in one process: on {ranks} MPI ranks use "
                        f"\"iterative\" or \"auto\" (the iterative method shares its solve among the ranks)")
    if options.multigrid == "pyamg":
        raise CaseError(f"solver.multigrid = \"pyamg\" runs in one process: on {ranks} MPI ranks use \"petsc\" or "
                        f"\"auto\" (PETSc's GAMG shares the multigrid among the ranks)")
    return "iterative", (f"solver.method = \"{options.method}\" on {ranks} MPI ranks: the iterative method, its "
                         f"solve shared among them")


def predicted_costs(method: str, A: sp.csr_matrix, N: sp.csr_matrix, dim: int, steps: int, history: bool,
                    field_steps: int, multigrid: str = "pyamg") -> tuple[dict, dict, FactorWork | None]:
    """The methods' predicted costs (:func:`~vpcontact.solvers.cost.predict`) for ``solver.method = method``, twice: at
    this machine kind's reference rates (:meth:`~vpcontact.solvers.cost.MachineRates.reference`), by which "auto"
    chooses (the same case gets the same method on every run, whatever else the machine is doing, and whichever
    fields it writes: the solves of the ``field_steps`` written are left out), and at the rates probed now, which
    ``vpcontact check`` and summary.json report. The direct factor's work is counted by PARDISO's analysis only
    where the count may matter (else the laws of :func:`~vpcontact.solvers.cost.factor_work` stand): for "auto",
    where it could change the choice (:func:`count_may_change_the_choice`); for an explicit direct method, where the
    method would not fit with COUNT_WITHIN times the laws' memory of the factor. An analysis of a factor that cannot
    win is not made (at 2M dofs it would take a minute), nor one of a factor that wins anyway or is asked for with
    memory to spare: the factorization makes the same analysis again (in 2D 0.2 s of a 0.8 s run at 33k dofs, 2.5 s
    at 526k). Third, the direct factor's work the predictions rest on (None: not weighed). The iterative method is
    predicted with the ``multigrid`` backend it would run (:data:`~vpcontact.solvers.cost.MULTIGRID_SPEEDS`)."""
    reference, probed, resident = MachineRates.reference(A), MachineRates.probe(A), resident_memory()

    def costs(factor, rates, written=0):
        return predict(A, N, dim, steps, history=history, field_steps=written, rates=rates, factor=factor,
                       resident=resident, multigrid=multigrid)

    factor = None
    if method != "iterative":
        factor = factor_work(A, N, dim, count=False)
        estimated = costs(factor, reference)
        larger = costs(replace(factor, bytes=COUNT_WITHIN * factor.bytes), reference)
        if method != "auto" and not larger[method].fits:
            factor = factor_work(A, N, dim)  # the memory is short: the report of the method asked for counts it
        elif method == "auto" and condensed_fits(N, A.shape[0])[0] and count_may_change_the_choice(estimated, larger):
            factor = factor_work(A, N, dim)
    return costs(factor, reference), costs(factor, probed, field_steps), factor


def count_may_change_the_choice(estimated: dict, larger: dict) -> bool:
    """Whether counting the direct factor (PARDISO's analysis) may change the choice of "auto", from the costs
    ``estimated`` with the factor's work by the laws and those ``larger`` with COUNT_WITHIN times the laws' memory:
    the condensed method is within COUNT_WITHIN of the iterative method's time (else it cannot win), and it is not
    COUNT_WITHIN times below every other method's or it would not fit with that much more memory (in 2D the laws
    are within 3% of the count's flops, but their memory was 0.72 of it at 476k dofs)."""
    condensed = estimated["condensed"].total_s
    if condensed > COUNT_WITHIN * estimated["iterative"].total_s:
        return False
    others = min(cost.total_s for name, cost in estimated.items() if name != "condensed")
    return COUNT_WITHIN * condensed > others or not larger["condensed"].fits


#: "auto" counts the direct factor's work (PARDISO's analysis) when the condensed method's cost by the laws is
#: within this factor of the iterative method's, and more than its inverse times every other method's or not
#: fitting with this factor times the laws' memory of the factor; an explicit direct method, when it would not fit
#: with this factor times the laws' memory.
COUNT_WITHIN = 4.0
