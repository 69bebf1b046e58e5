"""Adaptive meshes (a case's ``[adapt]``): solve the whole history, estimate, mark, refine; and again.

Each cycle c = 1, 2, … solves the problem's whole history on the current mesh (the ordinary ``TimeLoop``
path, the problem built again on each refined mesh by ``Problem.on``: every option of a case works) and, as the steps go, folds the element indicators
η_K²(t_n) of the estimator (``adapt.estimator``, one of :data:`~vpcontact.estimate.estimators.ESTIMATORS`) at
every step into one value per element, the time functional (``adapt.functional``):

    "max":  F_K = max_n η_K²(t_n),        "l2":  F_K = Σ_n k η_K²(t_n)   (k the time step);

a step's fields are dropped once folded, unless ``output.field_steps`` keeps them. The cycle's estimate is
(Σ_K F_K)^{1/2}. Dörfler marking takes the fewest elements (largest F_K first) whose F_K sum to at least
θ Σ_K F_K (``adapt.theta``), and `vpcontact.mesh.refinement.refine` refines them conformingly. The adaptation
stops after ``adapt.cycles`` cycles, before a cycle whose mesh would have more than ``adapt.max_dofs``
dofs, when the estimate is zero (nothing to mark), or when a cycle's run does not complete (its status and
message are then the adaptation's).
"""

from __future__ import annotations

import time as clock
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import CaseError
from ..estimate.estimators import ESTIMATORS
from ..estimate.indicators import Level
from ..mesh.mesh import Mesh
from ..problem.build import Problem, checked_problem
from ..progress import SILENT, Progress, duration, reporting
from ..mesh.refinement import refine
from ..results.output_options import OutputOptions
from ..results.result import Result
from ..timeloop.loop import TimeLoop
from .options import AdaptOptions

#: The columns of adapt.csv, one row per cycle.
COLUMNS = ("cycle", "dofs", "contact_nodes", "estimate", "wall_time_s")


@dataclass
class Cycle:
    """One cycle: its number (from 1), its run, the time functional F_K of its indicators (per element) and
    its wall time (seconds: refinement, assembly, time loop and estimation)."""

    number: int
    result: Result
    functional: np.ndarray
    wall_time_s: float

    @property
    def estimate(self) -> float:
        """(Σ_K F_K)^{1/2}."""
        return float(np.sqrt(self.functional.sum()))

    @property
    def row(self) -> dict:
        """The cycle's row of adapt.csv."""
        result = self.result
        return {"cycle": self.number, "dofs": int(result.dofs), "contact_nodes": int(result.contact_nodes),
                "estimate": self.estimate, "wall_time_s": self.wall_time_s}


@dataclass
class Adaptation:
    """What `adapt` did: the rows of its cycles (adapt.csv), the last cycle (its run and mesh), the status
    ("complete", or the last run's "failed" / "interrupted", or "failed" when a refinement or the problem
    on a refined mesh could not be made) and why it stopped."""

    rows: list[dict] = field(default_factory=list)
    last: Cycle | None = None
    status: str = "complete"
    message: str = ""

    @property
    def mesh(self) -> Mesh:
        """The mesh of the last cycle."""
        return self.last.result.discretization.mesh


def dorfler(values: np.ndarray, theta: float) -> np.ndarray:
    """The indices of the fewest entries of ``values`` (≥ 0), largest first, whose sum is at least θ times
    the sum of all (0 < θ ≤ 1); none when all are zero."""
    order = np.argsort(values, kind="stable")[::-1]
    running = np.cumsum(values[order])
    if running.size == 0 or not running[-1] > 0.0:
        return np.zeros(0, dtype=np.int64)
    count = int(np.searchsorted(running, theta * running[-1] * (1.0 - 1e-12))) + 1  # rounding of the sums
    return np.sort(order[:min(count, order.size)])


def solve_and_estimate(problem: Problem, settings: AdaptOptions, output: OutputOptions | None = None, *,
                       stop: Callable[[], str | None] | None = None, progress: Progress = SILENT,
                       after_step: Callable[[TimeLoop], None] | None = None,
                       label: str = "time steps") -> tuple[Result, np.ndarray]:
    """Run the whole history of ``problem`` (with the outputs ``output``) and fold the indicators of
    ``settings.estimator`` at each step into the time functional ``settings.functional`` (see the module
    docstring): (the run, F_K per element); ``progress`` hears of the solver's set-up and of the steps
    (``label``: their name on a terminal's bar)."""
    estimator = ESTIMATORS[settings.estimator].prepare(problem)
    loop = TimeLoop(problem, output, progress)
    wanted = loop.result.field_steps
    loop.result.field_steps = range(1, len(problem.times) + 1)  # every step's fields, dropped once folded
    functional = np.zeros(problem.mesh.mesh.t.shape[1])

    def fold(loop: TimeLoop) -> None:
        step, result = loop.state.step, loop.result
        row = result.rows[-1]  # the step just done ends the history (Level.of would search all of it)
        level = Level(problem, step, row["t"], row["k"], result.final,
                      {name: np.asarray(values[-1]) for name, values in result.contact.items()})
        squared = estimator(level).squared
        if settings.functional == "max":
            np.maximum(functional, squared, out=functional)
        else:
            np.add(functional, row["k"] * squared, out=functional)
        if step not in wanted:
            loop.result.fields.pop(step, None)
        if after_step is not None:
            after_step(loop)

    result = loop.run(after_step=fold, stop=stop, label=label)
    result.field_steps = wanted
    return result, functional


def check_start(problem: Problem, settings: AdaptOptions) -> None:
    """CaseError unless the first mesh of the adaptation, ``problem``'s, is within ``adapt.max_dofs``."""
    limit = settings.max_dofs
    if problem.basis.N > limit:
        raise CaseError(f"adapt.max_dofs = {limit} is less than the {problem.basis.N} dofs of the first mesh: raise "
                        f"it, or start from a coarser mesh (mesh.h)")


def adapt(problem: Problem, settings: AdaptOptions, output: OutputOptions | None = None, *,
          after_cycle: Callable[[Cycle], None] | None = None, stop: Callable[[], str | None] | None = None,
          progress: bool | Progress = False, after_step: Callable[[TimeLoop], None] | None = None) -> Adaptation:
    """The adaptive cycles of ``settings`` (a case's ``[adapt]``,
    :class:`~vpcontact.adaptivity.options.AdaptOptions`; :func:`vpcontact.adapt` takes the table as a dict) from
    the mesh of ``problem``, each run with the outputs ``output`` (see the module docstring); ``after_cycle(cycle)``
    is called after each (its outputs), ``stop`` and ``after_step`` are the time loop's hooks; ``progress``: True
    for each cycle, its set-up, steps and refinement reported on stderr (:mod:`vpcontact.progress`), or a
    reporter."""
    with reporting(progress) as reporter:
        return _cycles(problem, settings, output, after_cycle, stop, reporter, after_step)


def _cycles(problem: Problem, settings: AdaptOptions, output: OutputOptions | None, after_cycle, stop,
            progress: Progress, after_step) -> Adaptation:
    """The cycles of `adapt`, reported to ``progress``."""
    check_start(checked_problem(problem), settings)
    adaptation = Adaptation()
    started = clock.perf_counter() - problem.timings["build"]
    for number in range(1, settings.cycles + 1):
        progress.note(f"adapt: cycle {number} of at most {settings.cycles}, {problem.basis.N:,} dofs")
        result, functional = solve_and_estimate(problem, settings, output, stop=stop, progress=progress,
                                                after_step=after_step, label=f"cycle {number}")
        now = clock.perf_counter()
        cycle = Cycle(number, result, functional, now - started)
        progress.note(f"adapt: cycle {number} {result.status}, estimate {cycle.estimate:.4g} "
                      f"({duration(cycle.wall_time_s)})")
        adaptation.rows.append(cycle.row)
        adaptation.last = cycle
        if after_cycle is not None:
            after_cycle(cycle)
        started = clock.perf_counter()  # the next cycle's time starts with its refinement
        if result.status != "complete":
            adaptation.status, adaptation.message = result.status, f"cycle {number}: {result.message}"
            break
        if number == settings.cycles:
            adaptation.message = f"{number} cycles done (adapt.cycles)"
            break
        marked = dorfler(functional, settings.theta)
        if not marked.size:
            adaptation.message = f"cycle {number}: the estimate is zero, nothing to refine"
            break
        try:
            with progress.phase("refinement", f"{marked.size:,} of {functional.size:,} elements marked "
                                f"(adapt.theta = {settings.theta:g})") as phase:
                mesh = refine(problem.mesh, marked)
                phase.done(f"{mesh.mesh.p.shape[1]:,} nodes, {mesh.mesh.t.shape[1]:,} elements")
            dofs = mesh.dim * mesh.mesh.p.shape[1]
            if dofs > settings.max_dofs:
                adaptation.message = (f"cycle {number}: the next mesh would have {dofs} dofs, more than adapt.max_dofs "
                                      f"= {settings.max_dofs}")
                break
            problem = problem.on(mesh, progress)
        except CaseError as error:
            adaptation.status, adaptation.message = "failed", f"after cycle {number}: {error}"
            break
    return adaptation
