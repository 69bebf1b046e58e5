"""History columns against t (:func:`time_series`), and a Dirichlet part's reaction against its displacement
(:func:`force_displacement`)."""

from __future__ import annotations

import numpy as np

from ...errors import CaseError, shown
from ...mesh.cells import coordinates
from .layout import new_figure

TIME_SERIES = ("K_probe", "penetration_probe")
"""Default history columns of :func:`time_series`."""
LOG_COLUMNS = ("residual", "complementarity")
"""History columns drawn on a logarithmic axis (they span orders of magnitude)."""


def time_series(result, columns=TIME_SERIES):
    """The history ``columns`` (see ``Result.columns``) against t, one panel each, every converged time
    level a marker (sub-steps of a cut step included); LOG_COLUMNS on a logarithmic axis."""
    columns = (columns,) if isinstance(columns, str) else tuple(columns)
    if not columns:
        raise CaseError("time_series: give at least one history column")
    values = {column: result.series(column) for column in columns}
    t = result.times
    figure = new_figure(figsize=(6.4, 1.9 * len(columns) + 1.0))
    axes = figure.subplots(len(columns), 1, sharex=True, squeeze=False)[:, 0]
    marker = "o" if t.size <= 60 else None
    for ax, (column, value) in zip(axes, values.items()):
        ax.plot(t, value, marker=marker, markersize=3, lw=1.2, color="C0")
        finite = value[np.isfinite(value)]
        if column in LOG_COLUMNS and np.all(finite > 0):
            ax.set_yscale("log")
        elif finite.size and np.ptp(finite) <= 1e-9 * np.abs(finite).max():  # constant but for rounding
            middle = float(finite.mean())
            ax.set_ylim(middle - 0.1 * abs(middle) - (middle == 0), middle + 0.1 * abs(middle) + (middle == 0))
        ax.set_ylabel(column)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t")
    start, end = result.discretization.times.start, float(result.discretization.times[-1])
    axes[0].set_xlim(start, end + 0.02 * (end - start))  # room for the last marker
    planned = len(result.discretization.times)
    figure.suptitle(f"History of the run ({result.status}, {result.completed_steps} of {planned} steps)", fontsize=10)
    return figure


def force_displacement(result, part: str, force: str, displacement: str):
    """The reaction of the Dirichlet ``part`` in the component ``force`` (``reaction_<part>_<force>``) against its
    mean displacement in the component ``displacement`` (``displacement_<part>_<displacement>``), every converged
    time level a marker: the force–displacement curve of the part (a component it holds has no displacement: draw
    its reaction against a component it leaves free). CaseError for a part that is not held or a component that
    is not a coordinate."""
    parts = result.discretization.held_parts
    if str(part) not in parts:
        raise CaseError(f"force_displacement: {shown(repr(part))} is not a Dirichlet part of the run; its Dirichlet "
                        f"parts: {', '.join(parts) or 'none'}")
    names = coordinates(result.dim)
    for name, value in (("force", force), ("displacement", displacement)):
        if value not in names:
            raise CaseError(f"force_displacement: {name} = {shown(repr(value))}: expected one of {', '.join(names)}")
    x = result.series(f"displacement_{part}_{displacement}")
    y = result.series(f"reaction_{part}_{force}")
    figure = new_figure(figsize=(5.6, 4.2))
    ax = figure.subplots()
    ax.plot(x, y, marker="o" if x.size <= 60 else None, markersize=3, lw=1.2, color="C0")
    ax.set_xlabel(f"displacement_{part}_{displacement} (mean over the part)")
    ax.set_ylabel(f"reaction_{part}_{force}")
    ax.grid(alpha=0.3)
    figure.suptitle(f"Force–displacement of '{part}' ({result.status}, {result.completed_steps} steps)", fontsize=10)
    return figure
