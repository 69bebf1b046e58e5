"""What the figures of a run share: the colours and markers of the contact nodes' states, the colour
maps, and figures (matplotlib Figures, no pyplot) with their panels laid out. matplotlib is imported when
a figure is made."""

from __future__ import annotations

import math

import numpy as np

from ...laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED

STATE_COLORS = {SEPARATED: "0.6", IN_COMPLIANCE: "#0072B2", AT_LIMIT: "#D55E00"}
"""The colour of a contact node by its state (told apart with red–green colour blindness too)."""
STATE_LABELS = {SEPARATED: "separated", IN_COMPLIANCE: "in normal compliance", AT_LIMIT: "at the limit g"}
STATE_MARKERS = {SEPARATED: "o", IN_COMPLIANCE: "o", AT_LIMIT: "s"}
"""Node states are told apart by their marker too: squares at the limit."""
PANELS = 4
"""Times shown by default in a contact-pressure figure."""
EDGES_DRAWN_UP_TO = 2000
"""Facet edges are drawn when a panel shows at most this many facets (more would hide the colours)."""
PANEL_HEIGHT = 2.8
"""Height (inches) of a contact-patch panel (less when it is more than twice as wide)."""
PRESSURE_MAP = "viridis"
STRESS_MAP = "viridis"


def state_handles() -> list:
    """The legend's entries of the node states (a marker each, as :func:`draw_states` draws them)."""
    from matplotlib.lines import Line2D

    return [Line2D([], [], ls="", marker=STATE_MARKERS[s], markersize=7, markerfacecolor=color, markeredgecolor="k",
                   markeredgewidth=0.5, label=f"node {STATE_LABELS[s]}") for s, color in STATE_COLORS.items()]


def draw_states(ax, x, y, status, size: float) -> None:
    """A scatter of the nodes of each state (one collection per state, in STATE_COLORS' order)."""
    for state, color in STATE_COLORS.items():
        chosen = status == state
        ax.scatter(x[chosen], y[chosen], s=size, c=color, marker=STATE_MARKERS[state], edgecolors="k",
                   linewidths=0.4, label=STATE_LABELS[state], zorder=3)


def state_counts(status: np.ndarray) -> str:
    """The nodes at the limit and the separated ones, in words (a panel's title)."""
    counts = np.bincount(status, minlength=3)
    return f"{counts[AT_LIMIT]} at the limit, {counts[SEPARATED]} separated"


def new_figure(figsize, layout: str = "constrained"):
    """A matplotlib Figure (no pyplot), its axes placed by ``layout``."""
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout=layout)


def drawing_size(width: float, height: float, tallest: float) -> tuple[float, float]:
    """Width and height (inches) of a drawing of ``width`` × ``height`` (equal aspect): ``tallest`` high
    but at most twice as wide, and at least 0.4 × ``tallest`` wide."""
    aspect = width / height
    drawn = tallest if aspect <= 2.0 else 2.0 * tallest / aspect
    return float(np.clip(drawn * aspect, 0.4 * tallest, 2.0 * tallest)), drawn


def panel_columns(panels: int) -> int:
    """Panels in a row of :func:`panel_grid`."""
    return min(panels, PANELS)


def panel_grid(panels: int, aspect: float):
    """A figure with ``panels`` axes of width/height ``aspect`` in rows of at most PANELS, sharing x and
    y, sized so that they fill it; the axes as a flat array (the unused places of the last row removed)."""
    columns = panel_columns(panels)
    rows = math.ceil(panels / columns)
    width, height = drawing_size(aspect, 1.0, PANEL_HEIGHT)
    figure = new_figure(figsize=(columns * (width + 0.2) + 1.6, rows * (height + 0.6) + 1.2), layout="compressed")
    axes = figure.subplots(rows, columns, sharex=True, sharey=True, squeeze=False).ravel()
    for ax in axes[panels:]:
        ax.remove()
    return figure, axes[:panels]
