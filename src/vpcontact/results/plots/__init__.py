"""Figures of a run, in 2D and 3D: the contact pressure and node states on Γ3 at a few times, the node
states with the penetration at one time, the deformed body coloured by a field (the von Mises stress by
default), history columns against t, and several runs along Γ3. ``result.plot`` reaches them as methods of
a run (:mod:`vpcontact.results.result_plots`).

Each function takes a :class:`~vpcontact.results.result.Result` and returns a `matplotlib.figure.Figure`
(no pyplot: no global state, so it renders headless, and a notebook shows it as it is). matplotlib
is imported when a figure is drawn: ``import vpcontact`` does not load it. A run directory holds
these figures as PNG files with ``output.figures = true`` (:func:`run_figures`, written by
:mod:`vpcontact.io.figures`). One module per family: ``contact`` (on Γ3), ``body`` (the deformed body),
``history`` (time series, force–displacement), ``figures`` (a run directory's), ``curves`` (order and arc length along Γ3),
``layout`` (colours, panels).
"""

from .body import body_field, body_fields, deformed_body, magnification
from .contact import along_contact, contact_pressure, contact_zoom, default_steps, node_states
from .curves import along_curve, arc_length
from .figures import DPI, FIGURES, run_figures
from .history import TIME_SERIES, force_displacement, time_series
from .layout import STATE_COLORS, STATE_LABELS, STRESS_MAP

__all__ = ["DPI", "FIGURES", "STATE_COLORS", "STATE_LABELS", "STRESS_MAP", "TIME_SERIES", "along_contact",
           "along_curve", "arc_length", "body_field", "body_fields", "contact_pressure", "contact_zoom",
           "default_steps", "deformed_body", "force_displacement", "magnification", "node_states", "run_figures", "time_series"]
