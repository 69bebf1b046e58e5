"""A time loop's snapshot: everything it carries at the end of a completed step, as plain arrays and JSON
values, what a checkpoint writes (:mod:`vpcontact.io.checkpoint`) and what ``TimeLoop.restore`` continues
from, bit for bit (tests/test_resume_matrix.py: every step method, after SIGTERM, SIGKILL or a full disk).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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
