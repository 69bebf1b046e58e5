"""The figures of a run directory (``output.figures = true``): ``figures/<name>.png`` for each of FIGURES
the run has data for (:func:`run_figures`), at DPI (written by :mod:`vpcontact.io.figures`)."""

from __future__ import annotations

from .body import deformed_body
from .contact import contact_pressure
from .history import time_series

DPI = 150
"""Resolution of the PNG files of a run directory."""
FIGURES = ("contact_pressure", "deformed", "time_series")
"""The figures of a run directory (``figures/<name>.png``), see :func:`run_figures`."""


def run_figures(result) -> dict:
    """The figures of a run directory by name (FIGURES): ``contact_pressure`` and ``time_series``
    (TIME_SERIES) when the run has contact and has done a step (without contact its history holds only
    the solver's counts), ``deformed`` at the last step whose fields it kept, if any."""
    figures = {}
    contact = result.completed_steps > 0 and result.discretization.surface.size > 0
    if contact:
        figures["contact_pressure"] = contact_pressure(result)
    if result.fields:
        figures["deformed"] = deformed_body(result)
    if contact:
        figures["time_series"] = time_series(result)
    return figures
