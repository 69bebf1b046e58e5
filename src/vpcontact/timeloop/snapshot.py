"""A time loop's snapshot: everything it carries at the end of a completed step, as plain arrays and JSON
values, what a checkpoint writes (:mod:`vpcontact.io.checkpoint`) and what ``TimeLoop.restore`` continues
from, bit for bit (tests/test_resume_matrix.py: every step method, after SIGTERM, SIGKILL or a full disk).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .state import LoopState


@dataclass
class LoopSnapshot:
    """A time loop at the end of its last completed step:

    - ``arrays``: the loop state (:meth:`~vpcontact.timeloop.state.LoopState.arrays`: the step reached, ξ,
      z and 𝒢 there, the last solution and its trend, the body's position on the rigid motions only the
      contact holds), the results so far (:meth:`~vpcontact.results.result.Result.arrays`: the history rows
      one array per column, their times, the per-node contact arrays) and what the step solver carries from
      step to step (``solver_method`` and ``solver_*``: its ``kept()``);
    - ``meta``: JSON values, the field steps kept, the step cuts, the steps where the run was resumed
      before, the wall time and the solver's counters of work so far (earlier sessions included);
    - ``fields``: the arrays of the Fields of each field step kept so far
      (:meth:`~vpcontact.results.result.Result.field_arrays`).
    """

    arrays: dict[str, np.ndarray]
    meta: dict
    fields: dict[int, dict[str, np.ndarray]]


def loop_snapshot(loop) -> LoopSnapshot:
    """The time loop ``loop`` (a :class:`~vpcontact.timeloop.loop.TimeLoop`) at the end of its last completed step:
    its state, its second-order companion's level, the results so far, the step solver's kept state, wall time and
    counters (a collective call on MPI ranks)."""
    result, solver = loop.result, loop.solver
    kept = {f"solver_{key}": value for key, value in solver.kept().items()}
    arrays = {**loop.state.arrays(loop.rigid_position(), loop.elements), **result.arrays(), **kept,
              **({} if loop.companion is None else loop.companion.arrays()), "solver_method": np.array(solver.name)}
    meta = {"field_steps": sorted(result.fields), "step_cuts": result.step_cuts, "time_cuts": result.time_cuts,
            **loop.time_control.meta(),
            "method_switch": None if loop.method.switch is None else loop.method.switch.as_dict(),
            "resumed_at": list(result.resumed_at), "elapsed_s": loop.elapsed(), **asdict(loop.work())}
    return LoopSnapshot(arrays, meta, result.field_arrays())


def restore_loop(loop, snapshot: LoopSnapshot) -> None:
    """Continue ``loop`` (not run yet, of the problem ``snapshot`` was taken from) from ``snapshot`` as if it had
    never stopped: its state and companion, its results so far (the step it ends becomes a step where the run was
    resumed), the step solver's kept state (a solver of another method rebuilds its own), and its wall time and
    counters as those of earlier sessions. KeyError for an array or value it lacks."""
    arrays, meta, result = snapshot.arrays, snapshot.meta, loop.result
    loop.state = LoopState.from_arrays(arrays, loop.elements)
    step = loop.state.step
    result.resume(arrays, snapshot.fields, step, int(meta["step_cuts"]), [*meta["resumed_at"], step])
    result.time_cuts = int(meta.get("time_cuts", 0))  # 0: a checkpoint of before time.adaptive
    loop.time_control.restore(meta)
    solver = loop.solver
    if "solver_method" in arrays and str(arrays["solver_method"]) == solver.name:
        solver.restore({key[7:]: value for key, value in arrays.items()
                        if key.startswith("solver_") and key != "solver_method"})
    if loop.companion is not None:
        loop.companion.restore(arrays)
    loop.earlier_time = float(meta["elapsed_s"])
    loop.method.restore(meta)
    loop.newton = sum(row["newton_iterations"] for row in result.rows)
    if loop.method.switch is not None:
        result.method_switch = loop.method.switch.as_dict()
    if loop.motions.held_by_contact_only:
        loop.motions.recall(result.contact)
