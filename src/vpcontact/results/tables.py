"""A run's numbers as pandas DataFrames: the history (the table of history.csv) and the contact nodes at
one step (the rows of contact.csv at that step, with the arc length along Γ3 and σ_ν).

pandas is imported when a table is made: ``import vpcontact`` does not load it. The values are those
the writers write, to the last bit (floats are written as their repr): reading history.csv or
contact.csv with ``pandas.read_csv`` gives the same numbers.
"""

from __future__ import annotations

import numpy as np

from ..errors import CaseError
from ..mesh.cells import coordinates
from ..laws.contact import STATUS_NAMES
from .columns import CONTACT_ARRAYS, INTEGER_COLUMNS
from .plots.curves import arc_length
from .steps import step_rows


def history_table(result):
    """The history of ``result`` as a DataFrame: one row per converged time level, sub-steps of a cut step
    included (see :mod:`vpcontact.results.steps`), the columns of history.csv (``result.columns``), integers
    as int64 (INTEGER_COLUMNS), the others float64. ``table[result.ends_step()]`` keeps the rows at the
    step times t_n, those of ``result.series(..., substeps=False)``."""
    import pandas as pd

    columns = list(result.columns)
    types = {column: "int64" if column in INTEGER_COLUMNS else "float64" for column in columns}
    return pd.DataFrame.from_records(result.rows, columns=columns).astype(types)


def contact_table(result, step: int | None = None):
    """The contact nodes at the end of ``step`` (the history row at t_n; default: the last step done) as
    a DataFrame, one row per contact node in the order of ``result.contact_history``: ``node`` (its
    index in the mesh), its coordinates ``x, y(, z)``, its unit normal ``normal_x, …``, its weight
    w_i = ∫_Γ3 φ_i, in 2D ``arc_length`` (the arc length s along Γ3 from its end of least x, as the
    contact-pressure figure draws it), the contact arrays ``penetration, xi, K, pressure_compliance,
    pressure_rigid`` (see :mod:`vpcontact.results.columns`), ``normal_stress`` σ_ν = −(compliance + rigid),
    ``status`` (a category: separated, in_compliance, at_limit) and, with several contact parts, ``part``
    (a category of their names). ``table.attrs`` holds the ``step`` and its time ``t``."""
    import pandas as pd

    row = step_row(result, step)
    surface = result.discretization.surface
    axes = coordinates(result.dim)
    values = {name: np.asarray(result.contact[name][row]) for name in CONTACT_ARRAYS}
    columns = {"node": surface.nodes.astype(np.int64),
               **dict(zip(axes, surface.coordinates)),
               **{f"normal_{c}": normal for c, normal in zip(axes, surface.normals)},
               "weight": surface.weights}
    if result.dim == 2:
        columns["arc_length"] = arc_lengths(surface)
    columns.update({name: values[name].astype(float) for name in CONTACT_ARRAYS[:-1]})
    columns["normal_stress"] = -(values["pressure_compliance"] + values["pressure_rigid"])
    columns["status"] = pd.Categorical.from_codes(values["status"].astype(int), categories=STATUS_NAMES)
    if len(surface.parts) > 1:
        columns["part"] = pd.Categorical.from_codes(surface.owner, categories=surface.parts)
    table = pd.DataFrame(columns)
    table.attrs.update(step=int(result.series("step")[row]), t=float(result.times[row]))
    return table


def step_row(result, step: int | None) -> int:
    """The history row at t_n of step n = ``step`` (default: the last step done); CaseError for a step the
    run has not done."""
    if step is None:
        if result.completed_steps == 0:
            raise CaseError("the run has done no step: there is no contact table")
        step = result.completed_steps
    return step_rows(result, [step])[step]


def arc_lengths(surface) -> np.ndarray:
    """The arc length along Γ3 (2D) of each contact node, in their order (see
    :func:`vpcontact.results.plots.curves.arc_length`)."""
    lengths = np.zeros(surface.size)
    if surface.size:
        order, s, _ = arc_length(surface.coordinates, surface.facets)
        lengths[order] = s
    return lengths
