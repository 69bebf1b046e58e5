"""Figures on Γ3: the contact pressure and the node states at a few steps (:func:`contact_pressure`), the
node states with the penetration at one step (:func:`node_states`), and several runs compared along Γ3
(:func:`along_contact`). 2D: against the arc length along Γ3; 3D: the contact patch seen along the axis
closest to its normal."""

from __future__ import annotations

import numpy as np

from ...errors import CaseError
from ...mesh.cells import coordinates
from ..steps import step_rows
from .curves import arc_length
from .layout import (EDGES_DRAWN_UP_TO, PANELS, PRESSURE_MAP, draw_states, new_figure, panel_columns, panel_grid,
                     state_counts, state_handles)

MARGIN = 0.1
"""Margin of the zoom around the contact region, as a share of its extent (at least a few facets)."""


def default_steps(result, panels: int = PANELS) -> list[int]:
    """About ``panels`` steps spread evenly over the N steps done, the last one included: N, N − s, …
    with s = round(N / panels) ≥ 1 (N = 11: steps 2, 5, 8, 11, the paper's t = 0.2, 0.5, 0.8, 1.1)."""
    done = result.completed_steps
    spacing = max(1, round(done / panels))
    return sorted(range(done, 0, -spacing)[:panels])


# --- contact pressure --------------------------------------------------------------------------
def contact_pressure(result, steps=None):
    """The contact pressure (compliance + rigid part) and the state of each contact node at the end of
    each of ``steps`` (step numbers; default :func:`default_steps`), one panel per time. 3D: the facets
    of Γ3 seen along the coordinate axis closest to its normal weighted by the contact force at the
    last time shown (z for a body pressed down: the (x, y) plane, the patch seen from below), coloured
    by the pressure interpolated between the nodes, with one colour bar from the least to the largest
    pressure shown, zoomed to where the pressure or the penetration is positive at the last time shown.
    2D: the pressure along Γ3 against the arc length s (from the end of Γ3 with the least x). The node
    states are markers (legend)."""
    surface = result.discretization.surface
    if surface.size == 0:
        raise CaseError("the run has no contact (no [contact] in its case): there is no contact pressure to draw")
    steps = default_steps(result) if steps is None else sorted(set(steps))
    if not steps:
        raise CaseError("the run has done no step: there is no contact pressure to draw")
    rows = list(step_rows(result, steps).values())
    pressure = (result.contact_history("pressure_compliance") + result.contact_history("pressure_rigid"))[rows]
    return _on_contact(result, rows, pressure, ("pressure", "contact pressure (compliance + rigid)"),
                       "Contact pressure and node states on Γ3")


def node_states(result, step=None):
    """The state of each contact node at the end of ``step`` (default: the last step done) with its
    penetration d = u·ν − g0, whose value sets the state: separated (d ≤ 0), in normal compliance
    (0 < d < g), at the limit (d = g). 2D: d against the arc length along Γ3, the limit g dashed; 3D:
    Γ3 as in :func:`contact_pressure`, coloured by d. The node states are markers (legend)."""
    surface = result.discretization.surface
    if surface.size == 0:
        raise CaseError("the run has no contact (no [contact] in its case): there are no node states to draw")
    if step is None and result.completed_steps == 0:
        raise CaseError("the run has done no step: there are no node states to draw")
    step = result.completed_steps if step is None else step
    rows = list(step_rows(result, [step]).values())
    limit = result.discretization.layer["g"]
    return _on_contact(result, rows, result.contact_history("penetration")[rows], ("penetration", "penetration d"),
                       "Node states and penetration on Γ3", limit=limit)


def _on_contact(result, rows, values, labels, title, limit=None):
    """A figure of per-node ``values`` (one row per panel) at the history ``rows`` with the node states:
    3D: Γ3 seen along the coordinate axis closest to its normal weighted by the contact force at the last
    time shown (z for a body pressed down: the (x, y) plane, the patch seen from below), coloured by the
    values interpolated between the nodes, zoomed to where the pressure or the penetration is positive at
    the last time shown, with one colour bar from the least to the largest value there (``labels[1]``);
    2D: the values against the arc length s along Γ3 (``labels[0]``), and ``limit`` per node dashed."""
    surface = result.discretization.surface
    pressure = (result.contact_history("pressure_compliance") + result.contact_history("pressure_rigid"))[rows]
    status = result.contact_history("status")[rows].astype(int)
    penetration = result.contact_history("penetration")[rows]
    times = result.times[rows]
    if result.dim == 3:
        load = surface.weights * pressure[-1]  # where the foundation pushes at the last time (else all of Γ3)
        along = int(np.argmax(np.abs(surface.normals @ (load if load.any() else surface.weights))))
        plane = [c for c in range(3) if c != along]
        figure = _patch_panels(surface, plane, times, values, status, pressure, penetration, labels[1])
        names = coordinates(3)
        view = f"seen along {names[along]}, on the ({names[plane[0]]}, {names[plane[1]]}) plane"
    else:
        figure, view = _profile_panels(surface, times, values, status, labels[0], limit), "along Γ3"
    parts = ", ".join(repr(part) for part in surface.parts)
    handles = state_handles()
    if limit is not None and result.dim == 2:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], color="0.25", lw=0.8, ls="--", label="limit g"))
    narrow = result.dim == 3 and len(rows) < 3  # a legend in one row would be wider than the panels
    figure.legend(handles=handles, loc="outside lower center", ncol=1 if narrow else len(handles), frameon=False,
                  fontsize=9)
    figure.suptitle(f"{title}\n(part{'s' * (len(surface.parts) > 1)} {parts}, {surface.size} nodes), {view}",
                    fontsize=10)
    return figure


def contact_zoom(points: np.ndarray, facets: np.ndarray, pressure: np.ndarray,
                 penetration: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The box (lower corner, upper corner) of the ``points`` (2, m: Γ3 projected on a plane) whose
    pressure is nonzero or whose penetration is positive (all when none is), widened by MARGIN of its
    extent and at least by the longest projected facet edge, but not beyond the box of Γ3 widened by a
    fiftieth of the box shown."""
    corners = points[:, facets]
    edge = float(np.max(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=0), initial=0.0))
    touching = (pressure != 0) | (penetration > 0)
    chosen = points[:, touching] if touching.any() else points
    low, high = chosen.min(axis=1), chosen.max(axis=1)
    margin = max(MARGIN * float((high - low).max()), edge)
    low, high = np.maximum(low - margin, points.min(axis=1)), np.minimum(high + margin, points.max(axis=1))
    pad = max(float((high - low).max()), edge) / 50.0  # the markers on the edge of Γ3 are not cut
    return low - pad, high + pad


def _patch_panels(surface, plane, times, values, status, pressure, penetration, label):
    """3D: one panel per time, Γ3 projected on the coordinate ``plane`` (two axes), zoomed by the
    ``pressure`` and ``penetration`` at the last time, coloured by ``values`` on one scale from the least
    to the largest value in the zoom; ``label``: the colour bar's."""
    from matplotlib.colors import Normalize
    from matplotlib.tri import Triangulation

    points = surface.coordinates[plane]
    low, high = contact_zoom(points, surface.facets, pressure[-1], penetration[-1])
    inside = np.all((points.T >= low) & (points.T <= high), axis=1)
    shown_facets = int(np.sum(inside[surface.facets].any(axis=0)))
    size = float(np.clip(3000.0 / max(int(inside.sum()), 1), 3.0, 40.0))
    triangulation = Triangulation(*points, surface.facets.T)
    shown_values = values[:, inside] if inside.any() else values
    norm = Normalize(float(shown_values.min()), float(shown_values.max()))
    width, height = high - low
    figure, axes = panel_grid(len(times), aspect=float(width / height))
    names = coordinates(3)
    for ax, t, value, s in zip(axes, times, values, status):
        image = ax.tripcolor(triangulation, value, shading="gouraud", cmap=PRESSURE_MAP, norm=norm, zorder=1)
        if shown_facets <= EDGES_DRAWN_UP_TO:
            ax.triplot(triangulation, color="w", lw=0.3, alpha=0.6, zorder=2)
        draw_states(ax, *points, s, size)
        ax.set(xlim=(low[0], high[0]), ylim=(low[1], high[1]), aspect="equal", xlabel=names[plane[0]])
        ax.set_title(f"t = {t:g}\n{state_counts(s)}", fontsize=9)
    for ax in axes[::panel_columns(len(times))]:
        ax.set_ylabel(names[plane[1]])
    bar = axes[panel_columns(len(times)) - 1].inset_axes([1.06, 0.0, 0.06, 1.0])  # beside the first row's last panel
    figure.colorbar(image, cax=bar, label=label)
    return figure


def _profile_panels(surface, times, values, status, label, limit=None):
    """2D: one panel per time, ``values`` against the arc length along Γ3 (``label``: the y axis's), and
    ``limit`` (per node) dashed."""
    order, s, breaks = arc_length(surface.coordinates, surface.facets)
    figure = new_figure(figsize=(7.0, 1.5 * len(times) + 1.4))
    axes = figure.subplots(len(times), 1, sharex=True, sharey=True, squeeze=False)[:, 0]
    size = float(np.clip(2000.0 / surface.size, 6.0, 30.0))
    for ax, t, value, state in zip(axes, times, values, status):
        ax.plot(np.insert(s, breaks, np.nan), np.insert(value[order], breaks, np.nan), color="0.25", lw=1.0, zorder=2)
        if limit is not None:
            ax.plot(np.insert(s, breaks, np.nan), np.insert(limit[order], breaks, np.nan), color="0.25", lw=0.8,
                    ls="--", zorder=1, label="limit g")
        draw_states(ax, s, value[order], state[order], size)
        ax.set_ylabel(label)
        ax.set_title(f"t = {t:g}: {state_counts(state)}", fontsize=9, loc="left")
    axes[-1].set_xlabel("arc length s along Γ3")
    return figure


# --- several runs along Γ3 ------------------------------------------------------------------------
ALONG_CONTACT = ("pressure", "K")
"""Default quantities of :func:`along_contact`."""


def along_contact(results, quantities=ALONG_CONTACT, step=None):
    """Per-node quantities of several runs along Γ3 at the end of ``step`` (default: each run's last
    step), one panel per quantity, one curve per run: ``results`` is {label: Result}, a quantity
    ``"pressure"`` (compliance + rigid part) or a contact array (``penetration``, ``xi``, ``K``, ...).
    2D: against the arc length along Γ3 (from its end of least x); 3D: against the distance from the
    run's probe node (a point per node). Runs on different meshes or contact parts may be compared."""
    if not results:
        raise CaseError("along_contact: give at least one run ({label: result})")
    if len({result.dim for result in results.values()}) > 1:
        raise CaseError("along_contact: the runs mix 2D and 3D bodies; compare runs of one dimension")
    quantities = (quantities,) if isinstance(quantities, str) else tuple(quantities)
    figure = new_figure(figsize=(7.0, 2.2 * len(quantities) + 1.0))
    axes = figure.subplots(len(quantities), 1, sharex=True, squeeze=False)[:, 0]
    times = set()
    for color, (label, result) in enumerate(results.items()):
        surface = result.discretization.surface
        if surface.size == 0:
            raise CaseError(f"along_contact: the run {label!r} has no contact")
        n = result.completed_steps if step is None else step
        row = step_rows(result, [n])[n]
        times.add(float(result.times[row]))
        if result.dim == 2:
            order, s, breaks = arc_length(surface.coordinates, surface.facets)
        else:
            s = np.linalg.norm(surface.coordinates - surface.coordinates[:, [result.discretization.probe]], axis=0)
            order, breaks = np.argsort(s), np.zeros(0, dtype=int)
            s = s[order]
        for ax, quantity in zip(axes, quantities):
            if quantity == "pressure":
                value = (result.contact_history("pressure_compliance")[row]
                         + result.contact_history("pressure_rigid")[row])
            else:
                value = result.contact_history(quantity)[row]
            style = dict(lw=1.2) if result.dim == 2 else dict(ls="none", marker=".", markersize=3)
            ax.plot(np.insert(s, breaks, np.nan), np.insert(value[order], breaks, np.nan), color=f"C{color}",
                    label=label, **style)
    for ax, quantity in zip(axes, quantities):
        ax.set_ylabel(quantity)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, frameon=False)
    two_d = next(iter(results.values())).dim == 2
    axes[-1].set_xlabel("arc length s along Γ3" if two_d else "distance from the probe node")
    when = f"t = {times.pop():g}" if len(times) == 1 else "the last step of each run"
    figure.suptitle(f"Along Γ3 at {when}", fontsize=10)
    return figure
