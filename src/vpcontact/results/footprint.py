"""The memory a run's outputs need until they are written: the history rows and the per-node contact rows
of every converged level, and the fields at the field steps (with the copies a checkpoint and solution.npz
make of them). A case whose outputs would not fit in the memory available is refused before its first
step (:func:`check_memory`, called by the time loop and by ``vpcontact check``).
"""

from __future__ import annotations

from ..errors import CaseError, quoted, shown
from ..memory import available_memory
from .columns import CONTACT_ARRAYS, history_columns
from .steps import field_step_numbers

#: Bytes of one history row in memory: a dict of its columns, ROW_BYTES + COLUMN_BYTES per column (CPython 3.11,
#: measured: a 2D row of 31 columns 2250 bytes, a 3D one of 55 columns, five held parts, 3700 bytes).
ROW_BYTES, COLUMN_BYTES = 400, 60
#: Bytes the columns of the estimates of output.error_estimate add to a history row in memory, and their number (the
#: residual estimator's η and six terms, measured on CPython 3.11: 7 float objects and the larger dict, 900 bytes;
#: with the estimate in time and its step's share, COLUMN_BYTES each).
ESTIMATE_ROW_BYTES, ESTIMATE_ROW_COLUMNS = 900 + 2 * COLUMN_BYTES, 9
#: Bytes of a NumPy array object besides its data.
ARRAY_BYTES = 112
#: Bytes the writers add while they write, whatever the run's length (contact.csv is written in blocks).
WRITING_BYTES = 2**24


def memory_needed(steps: int, field_steps: int, nodes: int, elements: int, contact_nodes: int,
                  history: bool, dim: int = 2, estimate: bool = False, held_parts: int = 0) -> dict[str, int]:
    """Bytes a run of ``steps`` steps keeps for its outputs until they are written, by part: the history
    rows, the per-node contact rows and the fields at ``field_steps`` steps (``history``: with the
    viscoplastic history z; ``estimate``: with the estimate's columns in every row and η_K in the fields;
    ``held_parts``: the parts, node sets and points held, each with its reaction and mean displacement columns),
    each with the copy a checkpoint or solution.npz makes of them, and what the writers add. A step cut
    into sub-steps adds rows: this is the least a run needs."""
    plain = len(history_columns(dim, tuple(map(str, range(held_parts)))))
    columns = plain + (ESTIMATE_ROW_COLUMNS if estimate else 0)
    copies = 8 * columns
    row = ROW_BYTES + COLUMN_BYTES * plain + (ESTIMATE_ROW_BYTES if estimate else 0)
    contact = len(CONTACT_ARRAYS) * ARRAY_BYTES + 2 * (8 * (len(CONTACT_ARRAYS) - 1) + 1) * contact_nodes
    tensor = dim * dim
    per_field = 5 * ARRAY_BYTES + 8 * (dim * nodes + (tensor + 2) * elements) + 8 * (dim * nodes + tensor * elements)
    if history:
        per_field += 2 * 8 * tensor * elements
    if estimate:
        per_field += ARRAY_BYTES + 2 * 8 * elements
    return {"history rows": steps * (row + copies), "contact rows": steps * contact,
            "fields": (field_steps + 1) * per_field, "writing": WRITING_BYTES}


def check_memory(steps: int, output, nodes: int, elements: int, contact_nodes: int, history: bool,
                 dim: int = 2, held_parts: int = 0) -> None:
    """Refuse, before anything per step is allocated, a run of ``steps`` steps whose outputs (``output``, the
    :class:`~vpcontact.results.output_options.OutputOptions`) would not fit in the memory available now: one line
    naming time.steps (and output.field_steps when the fields are the most)."""
    field_steps = len(field_step_numbers(output.field_steps, steps))
    parts = memory_needed(steps, field_steps, nodes, elements, contact_nodes, history, dim,
                          estimate=output.error_estimate, held_parts=held_parts)
    needed, available = sum(parts.values()), available_memory()
    if needed <= available:
        return
    gib = 2.0**30
    detail = (f"history rows {parts['history rows'] / gib:.3g} GiB, contact rows of {contact_nodes} nodes "
              f"{parts['contact rows'] / gib:.3g} GiB, fields at {field_steps} steps of {nodes} nodes and {elements} "
              f"elements {parts['fields'] / gib:.3g} GiB")
    key = f"time.steps = {steps}"
    fix = "use fewer steps"
    if parts["fields"] > parts["history rows"] + parts["contact rows"]:
        chosen = output.field_steps
        key += f" with output.field_steps = {quoted(chosen) if isinstance(chosen, str) else shown(repr(chosen))}"
        fix = "keep the fields at fewer steps (output.field_steps) or use fewer steps"
    raise CaseError(f"{key}: the run's outputs need about {needed / gib:.3g} GiB of memory ({detail}), more than "
                    f"the {available / gib:.3g} GiB available; {fix}")
