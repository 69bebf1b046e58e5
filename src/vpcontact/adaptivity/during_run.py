"""Adapting the mesh during one run (``adapt.mode = "run"``): one pass through the history, the mesh refined
between time steps where the estimator asks for it.

After each time step t_n the estimator of ``adapt.estimator`` gives η_K(t_n) on every element, and the level is
accepted when

    η(t_n) = (Σ_K η_K²)^{1/2}  ≤  adapt.tolerance · max_{m ≤ n} ‖u_h(t_m)‖_E,     ‖u‖_E = (∫_Ω ℰε(u):ε(u))^{1/2},

the largest energy norm of the run so far: a load that is released brings ‖u_h‖_E near zero, not the error of
what the history left (ξ, z), which the mesh need not resolve better than at the peak.

Otherwise the mesh is refined towards the dofs the estimate asks for, by rounds of Dörfler marking (``adapt.theta``)
of η_K² and then of its predictions (:mod:`.marking`), the level t_{n−1} is carried to the new mesh
(:mod:`.transfer`: z and 𝒢 per element, ξ and the contact state on Γ3, u) and step n is solved again there, as
many times as it takes. A refinement that would pass ``adapt.max_dofs`` is not made: the level is accepted
above the tolerance (its row of adapt.csv says so) and the mesh stays for the rest of the run. The mesh is never
coarsened.

Not every level is estimated: an estimate costs the level's fields and the estimator's pass over the mesh, more
than a step of the condensed method. After an accepted level the next estimate waits twice as many steps as the last
(1, 2, 4, up to LONGEST_WAIT) when the estimate is predicted to stay within the tolerance until then (the trend of the
two last levels accepted on this mesh, extrapolated linearly; with one, when it is at most half the tolerance), else as
many steps as the prediction stays within it, at least one. The last step is always estimated. The levels in
between are accepted on the mesh of the estimate before them.

The steps solved on a mesh that was then refined are work done, and counted (the wall time and the solver's
counters); their levels are not kept. The result is the run's on its last mesh: its history rows, one per
accepted level; the per-node contact history and the fields of earlier steps carried to the last mesh (the
coarser solutions, drawn on it). ``adapt.csv`` has one row per estimated level, refined or accepted.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import CaseError
from ..estimate.estimators import ESTIMATORS
from ..estimate.indicators import Level
from ..problem.build import Problem, checked_problem
from ..progress import SILENT, Progress
from ..results.output_options import OutputOptions
from ..results.result import Result
from ..timeloop.loop import TimeLoop
from ..timeloop.snapshot import LoopSnapshot
from .cycles import check_start
from .marking import refine_towards, wanted_dofs
from .options import AdaptOptions
from .transfer import Transfer

#: The most steps from one estimated level to the next (the wait doubles while the estimate stays under half the
#: tolerance).
LONGEST_WAIT = 8
#: The columns of adapt.csv of a run that adapts during the run, one row per estimated level.
COLUMNS = ("step", "t", "dofs", "contact_nodes", "estimate", "energy_norm", "relative_estimate", "refined")


@dataclass
class RunAdaptation:
    """What `adapt_during_run` did: the rows of adapt.csv (:data:`COLUMNS`), the run on its last mesh
    (``result``, ``problem``), the status (the run's, or "failed" when a refined problem could not be made) and
    what happened (``message``)."""

    rows: list[dict] = field(default_factory=list)
    result: Result | None = None
    problem: Problem | None = None
    status: str = "complete"
    message: str = ""

    @property
    def mesh(self):
        """The last mesh."""
        return self.problem.mesh

    @property
    def refinements(self) -> int:
        """The refinements made."""
        return sum(row["refined"] for row in self.rows)


@dataclass
class _Refinement:
    """A refinement asked for after a step: the new problem, the level before the step carried to it."""

    problem: Problem
    snapshot: LoopSnapshot


class _Watcher:
    """The hook after each step of a time loop: estimates the level, and either accepts it or makes the refined
    problem and the level before the step on it (``pending``), which the loop's ``stop`` then ends the loop for."""

    def __init__(self, settings: AdaptOptions, adaptation: RunAdaptation, wanted, progress: Progress,
                 after_step: Callable[[TimeLoop], None] | None):
        self.settings, self.adaptation, self.wanted = settings, adaptation, wanted
        self.progress, self.after_step = progress, after_step
        self.pending: _Refinement | None = None
        self.capped = False  # adapt.max_dofs reached: no more refinements
        self.largest = 0.0  # the largest ‖u_h‖_E of the levels accepted so far
        self.wait = 1  # steps from one estimated level to the next
        self.last: tuple[int, float, int] | None = None  # (step, relative estimate, dofs) of the last level accepted

    def follow(self, loop: TimeLoop) -> None:
        """Watch ``loop`` (not run yet, or restored at the level before the step to solve again): its next step is
        estimated."""
        self.loop, self.pending, self.wait = loop, None, 1
        self.estimator = ESTIMATORS[self.settings.estimator].prepare(loop.problem)
        self._estimate_at(loop.state.step + 1)
        self._remember()

    def _estimate_at(self, step: int) -> None:
        """Estimate the level of ``step`` next (and the last one): the loop computes their fields."""
        self.due = step
        self.loop.result.field_steps = set(self.wanted) | {step, len(self.loop.problem.times)}

    def _remember(self) -> None:
        """The level the loop is at: what a refinement after the next step goes back to (its state, rows, the error
        estimate in time's companion and control)."""
        loop = self.loop
        companion = None if loop.companion is None else loop.companion.level
        self.before = (loop.state, len(loop.result.rows), companion, loop.time_control.meta(), loop.result.time_cuts)

    def __call__(self, loop: TimeLoop) -> None:
        step = loop.state.step
        if step < self.due and step < len(loop.problem.times):
            self._accept(loop, step)
            return
        problem, result = loop.problem, loop.result
        row = result.rows[-1]
        indicators = self.estimator(Level(problem, step, row["t"], row["k"], result.final, result.contact_row()))
        norm = energy_norm(problem, result.final.displacement)
        estimate, scale = indicators.total, max(self.largest, norm)
        relative = estimate / scale if scale > 0.0 else (0.0 if estimate == 0.0 else np.inf)
        refine = relative > self.settings.tolerance and not self.capped
        if refine:
            refine = self._refine(loop, indicators.squared, step, relative)
        self.adaptation.rows.append({"step": step, "t": row["t"], "dofs": problem.basis.N,
                                     "contact_nodes": problem.surface.size, "estimate": estimate,
                                     "energy_norm": norm, "relative_estimate": relative, "refined": refine})
        if refine:
            return
        self.largest = scale
        self.wait = self._next_wait(step, relative, problem.basis.N)
        self._accept(loop, step)

    def _next_wait(self, step: int, relative: float, dofs: int) -> int:
        """The steps from the level ``step`` just accepted (its η / max ‖u_h‖_E ``relative``, on a mesh of
        ``dofs``) to the next estimate: twice the last wait (at most LONGEST_WAIT) when the estimate is predicted to
        stay within the tolerance until then, else the most steps it is predicted to stay within it (at least 1). The
        prediction extrapolates linearly from the level accepted before on the same mesh; without one, the estimate
        stays within the tolerance when it is at most half of it."""
        tolerance, longer = self.settings.tolerance, min(2 * self.wait, LONGEST_WAIT)
        last, self.last = self.last, (step, relative, dofs)
        if last is None or last[2] != dofs or last[0] >= step:
            return longer if relative <= 0.5 * tolerance else 1
        growth = (relative - last[1]) / (step - last[0])
        if growth * longer <= tolerance - relative:
            return longer
        return max(1, min(longer, int((tolerance - relative) / growth)))

    def _accept(self, loop: TimeLoop, step: int) -> None:
        """Step ``step`` accepted: the next estimated step set, the fields the outputs do not want dropped."""
        if step >= self.due:
            self._estimate_at(step + self.wait)
        _drop_unwanted(loop.result, self.wanted, before=step + 1)
        self._remember()
        if self.after_step is not None:
            self.after_step(loop)

    def _refine(self, loop: TimeLoop, squared: np.ndarray, step: int, relative: float) -> bool:
        """Refine towards the dofs the estimate η_T² (``squared``) asks for (:mod:`.marking`) and carry the level
        before ``step`` to the new mesh (``pending``); False when no refinement fits in adapt.max_dofs (no
        refinement from then on)."""
        problem, settings = loop.problem, self.settings
        ratio = relative / settings.tolerance
        wanted = wanted_dofs(problem.basis.N, ratio, problem.mesh.dim)
        with self.progress.phase("refinement", f"step {step}: η/‖u‖ = {relative:.3g}, {ratio:.3g} times "
                                 f"adapt.tolerance; towards {wanted:,} dofs") as phase:
            refined = refine_towards(problem.mesh, squared, wanted, settings.max_dofs, settings.theta)
            phase.done(f"{refined[0].dim * refined[0].mesh.p.shape[1]:,} dofs" if refined is not None else
                       f"none within adapt.max_dofs = {settings.max_dofs:,}")
        if refined is None:
            self.capped = True
            self.adaptation.message = (f"at step {step} a refinement would have passed adapt.max_dofs = "
                                       f"{settings.max_dofs:,}: the mesh of {problem.basis.N:,} dofs was kept")
            return False
        mesh, lineage = refined
        new = problem.on(mesh, self.progress)
        self.pending = _Refinement(new, Transfer(problem, new, lineage).snapshot(self._before_step(loop)))
        return True

    def _before_step(self, loop: TimeLoop) -> LoopSnapshot:
        """The snapshot of ``loop`` at the level before its last step (the one remembered), with u there (which the
        condensed method computes only when asked)."""
        snapshot = loop.snapshot()
        state, rows, companion, control, time_cuts = self.before
        previous, basis = state.previous, loop.motions.basis
        if previous is not None and previous.u is None:
            previous = replace(previous, u=loop.solver.displacement(state.step_problem, previous))
        rigid = state.rigid
        if rigid is None:
            rigid = loop.solver.rigid_coordinates(state.step_problem, previous) if basis.shape[1] else np.zeros(0)
        arrays = {key: value for key, value in snapshot.arrays.items() if not key.startswith(("previous_", "trend_"))}
        arrays.update(replace(state, previous=previous).arrays(rigid, loop.elements))
        if companion is not None:
            arrays.update(loop.companion.arrays(companion))
        for key in list(arrays):
            if key.startswith(("row_", "contact_")):
                arrays[key] = arrays[key][:rows]
        fields = {n: values for n, values in snapshot.fields.items() if n <= state.step}
        return LoopSnapshot(arrays, {**snapshot.meta, **control, "time_cuts": time_cuts, "field_steps": sorted(fields)},
                            fields)


def energy_norm(problem: Problem, displacement: np.ndarray) -> float:
    """‖u‖_E = (∫_Ω ℰε(u):ε(u))^{1/2} = (uᵀAu)^{1/2} for the nodal ``displacement`` (nodes, d), exact for P1: the
    value of :func:`vpcontact.results.norms.energy_norm`, from the problem's assembled stiffness A (one product,
    where that one computes the strains of every element again; in one process, where A is whole)."""
    u = np.zeros(problem.basis.N)
    u[problem.basis.nodal_dofs] = displacement.T
    return float(np.sqrt(max(u @ (problem.A @ u), 0.0)))


def adapt_during_run(problem: Problem, settings: AdaptOptions, output: OutputOptions | None = None, *,
                     stop: Callable[[], str | None] | None = None, progress: Progress = SILENT,
                     after_step: Callable[[TimeLoop], None] | None = None,
                     rows: list[dict] | None = None) -> RunAdaptation:
    """One run of ``problem`` whose mesh is refined between its time steps (``settings``: a case's ``[adapt]``
    with ``mode = "run"``; see the module docstring), with the outputs ``output``; ``stop`` and ``after_step``
    (called after each accepted step) are the time loop's hooks, ``progress`` hears of every phase; ``rows``: the
    list the rows of adapt.csv are appended to as the run goes (default: a new one)."""
    check_start(checked_problem(problem), settings)
    output = OutputOptions() if output is None else output
    adaptation = RunAdaptation([] if rows is None else rows)
    loop = TimeLoop(problem, output, progress)
    wanted = loop.result.field_steps
    watcher = _Watcher(settings, adaptation, wanted, progress, after_step)
    watcher.follow(loop)
    while True:
        result = loop.run(after_step=watcher, stop=lambda: "refinement" if watcher.pending else
                          (stop() if stop is not None else None))
        pending = watcher.pending
        if pending is None:
            break
        try:
            loop = TimeLoop(pending.problem, output, progress)
        except CaseError as error:
            adaptation.status, adaptation.message = "failed", f"after a refinement: {error}"
            break
        resumed = list(pending.snapshot.meta["resumed_at"])
        loop.restore(_with_rigid(pending.snapshot, loop))
        loop.result.resumed_at = resumed  # a refinement is not a resumption
        watcher.follow(loop)
    _drop_unwanted(result, wanted, before=len(loop.problem.times) + 1)
    result.field_steps = wanted
    adaptation.result, adaptation.problem = result, loop.problem
    if adaptation.status == "complete":
        adaptation.status = result.status
        adaptation.message = adaptation.message or result.message or (
            f"{adaptation.refinements} refinement(s) during the run, last mesh {loop.problem.basis.N:,} dofs")
    return adaptation


def _drop_unwanted(result: Result, wanted, before: int) -> None:
    """Drop the fields of the steps before ``before`` that the outputs do not want."""
    for step in [n for n in result.fields if n < before and n not in wanted]:
        del result.fields[step]


def _with_rigid(snapshot: LoopSnapshot, loop: TimeLoop) -> LoopSnapshot:
    """``snapshot`` with Zᵀu on ``loop``'s rigid motions held only by contact (its ``previous_u``, when it has one)."""
    basis = loop.motions.basis
    u = snapshot.arrays.get("previous_u")
    rigid = basis.T @ u if u is not None and basis.shape[1] else np.zeros(basis.shape[1])
    return LoopSnapshot({**snapshot.arrays, "rigid": rigid}, snapshot.meta, snapshot.fields)
