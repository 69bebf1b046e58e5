"""The Python API's entry points: what a user writes (a case file's path, a dict, a :class:`~vpcontact.Case`; a
:class:`~vpcontact.Problem`; the ``[output]`` and ``[adapt]`` tables as dicts) checked and handed to the core.

    >>> import vpcontact
    >>> result = vpcontact.solve("examples/paper_ball.toml")                  # a case: built, then solved
    >>> problem = vpcontact.build_problem(vpcontact.load_case("examples/paper_ball.toml"))
    >>> result = vpcontact.solve(problem, output={"field_steps": "all"})       # a problem, with its outputs
    >>> adaptation = vpcontact.adapt(problem, {"cycles": 3})                   # adaptive meshes from it

Like the command line (:mod:`vpcontact.drivers`), they are the only callers of the case's translation besides
:func:`~vpcontact.compose`: the problem, the time loop and the adaptation below them take plain options.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from .case.load import load_case
from .case.model import Case, Model
from .case.translate import adapt_options, output_options, problem_options, translate
from .errors import CaseError, brief, flag
from .problem.build import Problem
from .problem.build import build_problem as build
from .progress import SILENT, Progress, reporting
from .results.result import Result
from .timeloop.loop import TimeLoop, solve_problem

if TYPE_CHECKING:
    from .adaptivity.cycles import Adaptation
    from .adaptivity.during_run import RunAdaptation


def build_problem(case, *, mesh=None, progress: Progress = SILENT, **laws) -> Problem:
    """The discrete problem of ``case`` (a :class:`~vpcontact.Case`, a case file's path or a dict for
    :func:`~vpcontact.load_case`, or a :class:`~vpcontact.Model`, which needs ``mesh``), assembled on ``mesh``
    (default: the one the case's ``[mesh]`` makes); ``laws`` replace parts of the case by Python objects (see
    :func:`vpcontact.problem.build.build_problem`); ``progress`` (:mod:`vpcontact.progress`) hears of the mesh and
    the assembly."""
    if not isinstance(case, Model):
        case = load_case(case)
    return build(problem_options(case), mesh=mesh, progress=progress, **laws)


def solve(case, *, output=None, progress=False, **laws) -> Result:
    """Solve a case (a :class:`~vpcontact.Case`, or a path or dict for :func:`~vpcontact.load_case`), or a
    :class:`~vpcontact.Problem` already built (:func:`~vpcontact.compose`, :func:`build_problem`).

    ``laws`` replace parts of the case by Python objects (see :func:`build_problem`): ``p`` and
    ``stiffness_law`` (functions of a NumPy array; with a ``derivative`` method, or a central difference is
    used; f(r, x) of the contact nodes' coordinates x too), ``tractions`` ({part: f(x, y, t) -> (fx, fy)}:
    replaces the case's traction on that part), ``body_force`` (f(x, y, t) -> (fx, fy): replaces the case's
    body forces), ``viscoplastic`` (𝒢(σ, ε)) and the initial state's arrays ``initial_displacement``
    (nodes, d), ``initial_stress`` (elements, d, d) or (d, d), ``initial_xi`` (contact nodes,); a problem has
    its laws already. ``output``: the ``[output]`` table (a dict; default: a case's own, for a problem the
    table's defaults). Bad objects are a
    :class:`~vpcontact.errors.CaseError` before the first step. Nothing is printed, unless ``progress`` is
    True (the set-up phases and the steps reported on stderr, as the command line does) or a reporter
    (:mod:`vpcontact.progress`).
    """
    progress = flag("progress", progress)
    if isinstance(case, Problem):
        if laws:
            raise CaseError(f"{next(iter(laws))} = {brief(next(iter(laws.values())))}: a problem has its laws already; "
                            f"give them to vpcontact.build_problem or vpcontact.compose")
        output = output_options(output)
        with reporting(progress) as reporter:
            return solve_problem(case, output=output, progress=reporter)
    options = translate(case if isinstance(case, Case) else load_case(case))
    output = options.output if output is None else output_options(output)
    with reporting(progress) as reporter:
        return solve_problem(build(options.problem, progress=reporter, **laws), output=output, progress=reporter)


def adapt(problem: Problem, settings, output=None, *, after_cycle: Callable | None = None,
          stop: Callable[[], str | None] | None = None, progress=False,
          after_step: Callable[[TimeLoop], None] | None = None) -> Adaptation | RunAdaptation:
    """The adaptive meshes of ``settings`` (the ``[adapt]`` table: a dict, or a case's ``case.adapt``) from the
    mesh of ``problem``, run with the outputs ``output`` (the ``[output]`` table; default: its defaults). With
    ``mode = "cycles"`` (the default) the cycles of :func:`vpcontact.adaptivity.cycles.adapt`, whose hooks
    ``after_cycle``, ``stop`` and ``after_step`` these are (an Adaptation); with ``mode = "run"`` one run that
    refines its mesh between steps, :func:`vpcontact.adaptivity.during_run.adapt_during_run` (a RunAdaptation;
    ``after_step`` is called after each accepted step). ``progress``: True for every phase reported on stderr,
    or a reporter."""
    settings, output = adapt_options(settings), output_options(output)
    if settings.mode == "run":
        if after_cycle is not None:
            raise CaseError("after_cycle is a hook of adapt.mode = \"cycles\": a run that adapts during the run has "
                            "no cycles (after_step is called after each accepted step)")
        from .adaptivity.during_run import adapt_during_run

        with reporting(progress) as reporter:
            return adapt_during_run(problem, settings, output, stop=stop, progress=reporter, after_step=after_step)
    from .adaptivity.cycles import adapt as cycles  # adaptive runs only: refinement is not loaded for the others

    return cycles(problem, settings, output, after_cycle=after_cycle, stop=stop, progress=progress,
                  after_step=after_step)
