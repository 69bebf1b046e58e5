"""Which history rows and fields are those of the time steps t_n.

Every converged time level is a row of the history and of the per-node arrays, in time order: a step
done whole is one row (``substep`` 1, ``k`` the case's step), a step cut into s sub-steps (its Newton
iteration failed: ``timeloop``) is s rows with the same ``step`` n, ``substep`` 1, …, s, their own
``t`` and ``k``, the last one at t_n. Fields are kept per step n, at t_n. Which rows are the steps t_n
is decided in one place, :func:`step_ends`, for a run in memory and for a run directory's tables alike.
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from ..errors import CaseError, shown


def step_ends(steps, completed: int) -> np.ndarray:
    """Per history row, given the step number n of each row (in time order): is it the row at t_n? It is
    the last row of its step, for the steps n ≤ ``completed`` (the steps reached): a step cut into
    sub-steps has several rows, its last one at t_n; the rows of a step not reached (a step that failed
    even after its cuts) are none."""
    steps = np.asarray(steps)
    last = np.append(steps[1:] != steps[:-1], True) if steps.size else np.zeros(0, dtype=bool)
    return last & (steps <= completed)


def end_of_step_rows(steps, completed: int) -> dict[int, int]:
    """Step n -> the index of its row at t_n (:func:`step_ends`), for the steps reached."""
    ends = np.flatnonzero(step_ends(steps, completed))
    return dict(zip(np.asarray(steps)[ends].astype(int).tolist(), ends.tolist()))


def field_step_numbers(field_steps, steps: int) -> Collection[int]:
    """The steps whose fields are kept, for ``output.field_steps`` ("all", "final", "none" or a list) in a
    run of ``steps`` steps (a range for "all": no set of every step is built)."""
    if isinstance(field_steps, str):
        return {"all": range(1, steps + 1), "final": range(steps, steps + 1), "none": range(0)}[field_steps]
    return frozenset(field_steps)


def step_rows(result, steps) -> dict[int, int]:
    """The history row at t_n of each step n of ``steps`` in ``result`` (CaseError for a step not done)."""
    wrong = [n for n in steps if isinstance(n, bool) or not isinstance(n, (int, np.integer))]
    if wrong:
        raise CaseError(f"step = {shown(repr(wrong[0]))}: expected a step number (an integer)")
    row_of = result.end_of_step_rows()
    missing = [n for n in steps if n not in row_of]
    if missing:
        done = f"steps 1 to {result.completed_steps}" if result.completed_steps else "no step"
        raise CaseError(f"step {missing[0]!r} is not a step the run has done ({done})")
    return {int(n): row_of[n] for n in steps}


def fields_at(result, step, purpose: str):
    """(step, Fields) of the field step ``step`` of ``result`` (None: the last one kept); the fields of the
    last step of a complete run are there whatever ``output.field_steps`` kept (``result.final``). CaseError
    when the run has no fields (the message ends with ``purpose``), or none at ``step``."""
    kept = dict(result.fields)
    if result.status == "complete" and result.final is not None:
        kept.setdefault(result.completed_steps, result.final)
    if not kept:
        raise CaseError(f"the run kept no fields (output.field_steps = \"none\", or it failed before a field step): "
                        f"there is {purpose}")
    step = max(kept) if step is None else step
    if step not in kept:
        raise CaseError(f"step {step!r} has no fields: the run kept them at steps {sorted(kept)} "
                        f"(output.field_steps)")
    return step, kept[step]
