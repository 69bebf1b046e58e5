"""Figures of a run, in 2D and 3D: the contact pressure and node states on Γ3 at a few times, the node
states with the penetration at one time, the deformed body coloured by a field (the von Mises stress by
default), and history columns against t. ``result.plot`` reaches them as methods of a run
(:mod:`vpcontact.results.result_plots`).

Each function takes a :class:`~vpcontact.results.result.Result` and returns a `matplotlib.figure.Figure`
(no pyplot: no global state, so it renders headless, and a notebook shows it as it is). matplotlib
is imported when a figure is drawn: ``import vpcontact`` does not load it. A run directory holds
these figures as PNG files with ``output.figures = true`` (:func:`run_figures`, written by
:mod:`vpcontact.io.writers`).
"""

from __future__ import annotations

import difflib
import math

import numpy as np

from ..laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED
from ..errors import CaseError, shown
from ..fem.space import coordinates

STATE_COLORS = {SEPARATED: "0.6", IN_COMPLIANCE: "#0072B2", AT_LIMIT: "#D55E00"}
"""The colour of a contact node by its state (told apart with red–green colour blindness too)."""
STATE_LABELS = {SEPARATED: "separated", IN_COMPLIANCE: "in normal compliance", AT_LIMIT: "at the limit g"}
STATE_MARKERS = {SEPARATED: "o", IN_COMPLIANCE: "o", AT_LIMIT: "s"}
"""Node states are told apart by their marker too: squares at the limit."""
PANELS = 4
"""Times shown by default in a contact-pressure figure."""
MARGIN = 0.1
"""Margin of the zoom around the contact region, as a share of its extent (at least a few facets)."""
DISPLACEMENT_SHARE = 0.1
"""Default magnification of a deformed body: its largest displacement drawn as this share of the
body's size (the diagonal of its bounding box), rounded to 1, 2 or 5 times a power of ten, never
below true scale."""
EDGES_DRAWN_UP_TO = 2000
"""Facet edges are drawn when a panel shows at most this many facets (more would hide the colours)."""
PANEL_HEIGHT = 2.8
"""Height (inches) of a contact-patch panel (less when it is more than twice as wide)."""
BODY_HEIGHT = 4.5
"""Height (inches) of a 2D deformed body (less when it is more than twice as wide)."""
PRESSURE_MAP = "viridis"
STRESS_MAP = "viridis"
DPI = 150
"""Resolution of the PNG files of a run directory."""
TIME_SERIES = ("K_probe", "penetration_probe")
"""Default history columns of :func:`time_series`."""
LOG_COLUMNS = ("residual", "complementarity")
"""History columns drawn on a logarithmic axis (they span orders of magnitude)."""
FIGURES = ("contact_pressure", "deformed", "time_series")
"""The figures of a run directory (``figures/<name>.png``), see :func:`run_figures`."""


# --- which steps -------------------------------------------------------------------------------
def default_steps(result, panels: int = PANELS) -> list[int]:
    """About ``panels`` steps spread evenly over the N steps done, the last one included: N, N − s, …
    with s = round(N / panels) ≥ 1 (N = 11: steps 2, 5, 8, 11, the paper's t = 0.2, 0.5, 0.8, 1.1)."""
    done = result.completed_steps
    spacing = max(1, round(done / panels))
    return sorted(range(done, 0, -spacing)[:panels])


def step_rows(result, steps) -> dict[int, int]:
    """The history row at t_n of each step n of ``steps`` (CaseError for a step not done)."""
    wrong = [n for n in steps if isinstance(n, bool) or not isinstance(n, (int, np.integer))]
    if wrong:
        raise CaseError(f"step = {shown(repr(wrong[0]))}: expected a step number (an integer)")
    row_of = result.end_of_step_rows()
    missing = [n for n in steps if n not in row_of]
    if missing:
        done = f"steps 1 to {result.completed_steps}" if result.completed_steps else "no step"
        raise CaseError(f"step {missing[0]!r} is not a step the run has done ({done})")
    return {int(n): row_of[n] for n in steps}


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
    handles = _state_handles()
    if limit is not None and result.dim == 2:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], color="0.25", lw=0.8, ls="--", label="limit g"))
    narrow = result.dim == 3 and len(rows) < 3  # a legend in one row would be wider than the panels
    figure.legend(handles=handles, loc="outside lower center", ncol=1 if narrow else len(handles), frameon=False,
                  fontsize=9)
    figure.suptitle(f"{title}\n(part{'s' * (len(surface.parts) > 1)} {parts}, {surface.size} nodes), {view}",
                    fontsize=10)
    return figure


def _state_handles() -> list:
    from matplotlib.lines import Line2D

    return [Line2D([], [], ls="", marker=STATE_MARKERS[s], markersize=7, markerfacecolor=color, markeredgecolor="k",
                   markeredgewidth=0.5, label=f"node {STATE_LABELS[s]}") for s, color in STATE_COLORS.items()]


def _states(ax, x, y, status, size: float) -> None:
    """A scatter of the nodes of each state (one collection per state, in STATE_COLORS' order)."""
    for state, color in STATE_COLORS.items():
        chosen = status == state
        ax.scatter(x[chosen], y[chosen], s=size, c=color, marker=STATE_MARKERS[state], edgecolors="k",
                   linewidths=0.4, label=STATE_LABELS[state], zorder=3)


def _counts(status: np.ndarray) -> str:
    counts = np.bincount(status, minlength=3)
    return f"{counts[AT_LIMIT]} at the limit, {counts[SEPARATED]} separated"


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
    figure, axes = _grid(len(times), aspect=float(width / height))
    names = coordinates(3)
    for ax, t, value, s in zip(axes, times, values, status):
        image = ax.tripcolor(triangulation, value, shading="gouraud", cmap=PRESSURE_MAP, norm=norm, zorder=1)
        if shown_facets <= EDGES_DRAWN_UP_TO:
            ax.triplot(triangulation, color="w", lw=0.3, alpha=0.6, zorder=2)
        _states(ax, *points, s, size)
        ax.set(xlim=(low[0], high[0]), ylim=(low[1], high[1]), aspect="equal", xlabel=names[plane[0]])
        ax.set_title(f"t = {t:g}\n{_counts(s)}", fontsize=9)
    for ax in axes[::_columns(len(times))]:
        ax.set_ylabel(names[plane[1]])
    bar = axes[_columns(len(times)) - 1].inset_axes([1.06, 0.0, 0.06, 1.0])  # beside the first row's last panel
    figure.colorbar(image, cax=bar, label=label)
    return figure


def _profile_panels(surface, times, values, status, label, limit=None):
    """2D: one panel per time, ``values`` against the arc length along Γ3 (``label``: the y axis's), and
    ``limit`` (per node) dashed."""
    order, s, breaks = arc_length(surface.coordinates, surface.facets)
    figure = _figure(figsize=(7.0, 1.5 * len(times) + 1.4))
    axes = figure.subplots(len(times), 1, sharex=True, sharey=True, squeeze=False)[:, 0]
    size = float(np.clip(2000.0 / surface.size, 6.0, 30.0))
    for ax, t, value, state in zip(axes, times, values, status):
        ax.plot(np.insert(s, breaks, np.nan), np.insert(value[order], breaks, np.nan), color="0.25", lw=1.0, zorder=2)
        if limit is not None:
            ax.plot(np.insert(s, breaks, np.nan), np.insert(limit[order], breaks, np.nan), color="0.25", lw=0.8,
                    ls="--", zorder=1, label="limit g")
        _states(ax, s, value[order], state[order], size)
        ax.set_ylabel(label)
        ax.set_title(f"t = {t:g}: {_counts(state)}", fontsize=9, loc="left")
    axes[-1].set_xlabel("arc length s along Γ3")
    return figure


def along_curve(segments: np.ndarray, count: int) -> np.ndarray:
    """The nodes 0, …, count − 1 of a curve made of ``segments`` (2, s), in their order along it:
    each connected piece from one of its ends (any node of a closed piece), piece after piece."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components, depth_first_order

    graph = sp.coo_matrix((np.ones(segments.shape[1]), (segments[0], segments[1])), shape=(count, count)).tocsr()
    pieces, label = connected_components(graph, directed=False)
    degree = np.bincount(segments.ravel(), minlength=count)
    order = []
    for piece in range(pieces):
        members = np.flatnonzero(label == piece)
        ends = members[degree[members] == 1]
        start = ends[0] if ends.size else members[0]
        order.append(depth_first_order(graph, start, directed=False, return_predecessors=False))
    return np.concatenate(order)


def arc_length(coordinates: np.ndarray, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contact nodes in their order along a curve made of ``segments`` (2, s) (a curve of one open
    piece runs from its end of least x, then least y), the arc length at each (going on from one piece
    to the next), and the positions in that order where a new piece starts."""
    m = coordinates.shape[1]
    order = along_curve(segments, m)
    if tuple(coordinates[:, order[-1]]) < tuple(coordinates[:, order[0]]):
        order = order[::-1]
    keys = np.sort(segments, axis=0)
    pairs = np.sort(np.vstack([order[:-1], order[1:]]), axis=0)
    joined = np.isin(pairs[0] * m + pairs[1], keys[0] * m + keys[1])
    step = np.linalg.norm(np.diff(coordinates[:, order], axis=1), axis=0)
    return order, np.concatenate([[0.0], np.cumsum(np.where(joined, step, 0.0))]), np.flatnonzero(~joined) + 1


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
    figure = _figure(figsize=(7.0, 2.2 * len(quantities) + 1.0))
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
                value = result.contact_history("pressure_compliance")[row] + result.contact_history("pressure_rigid")[row]
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


# --- deformed body -----------------------------------------------------------------------------
FIELD_LABELS = {"von_mises": "von Mises stress", "displacement": "displacement |u|"}
"""Colour-bar labels of the body fields that are not named by their component (see :func:`body_field`)."""


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


def body_fields(fields, dim: int) -> dict[str, tuple[np.ndarray, bool]]:
    """The scalar fields of ``fields`` (a :class:`~vpcontact.results.result.Fields` of a d-dimensional body) by
    name, each with True for one value per node, False for one per element: ``von_mises``;
    ``displacement`` (:math:`|u|`) and ``displacement_x``, …; the stress components ``sigma_xx``, ``sigma_xy``,
    … (i ≤ j; in 2D also ``sigma_zz``, σ33 of the elastic response, when the fields have it); with a
    viscoplastic history ``z_xx``, …; with an error estimate ``error_indicator`` (η_K)."""
    axes = coordinates(dim)
    pairs = [(i, j) for i in range(dim) for j in range(i, dim)]
    named = {"von_mises": (fields.von_mises, False),
             "displacement": (np.linalg.norm(fields.displacement, axis=1), True),
             **{f"displacement_{c}": (fields.displacement[:, i], True) for i, c in enumerate(axes)},
             **{f"sigma_{axes[i]}{axes[j]}": (fields.stress[:, i, j], False) for i, j in pairs}}
    if fields.stress33 is not None:
        named["sigma_zz"] = (fields.stress33, False)
    if fields.z is not None:
        named.update({f"z_{axes[i]}{axes[j]}": (fields.z[:, i, j], False) for i, j in pairs})
    if fields.error_indicator is not None:
        named["error_indicator"] = (fields.error_indicator, False)
    return named


def body_field(fields, dim: int, name: str) -> tuple[np.ndarray, bool]:
    """The field ``name`` of :func:`body_fields` (values, per node?); CaseError naming the valid ones for
    another name, and what computes a field the run has not (z, the error indicator)."""
    named = body_fields(fields, dim)
    if isinstance(name, str) and name in named:
        return named[name]
    valid = ", ".join(named)
    if name == "error_indicator":
        raise CaseError(f"field 'error_indicator': the run has no error estimate (output.error_estimate = true "
                        f"computes it); valid fields: {valid}")
    if isinstance(name, str) and name.startswith("z_") and fields.z is None:
        raise CaseError(f"field {name!r}: the run has no viscoplastic history z (z = 0: no viscoplastic law and no "
                        f"initial stress); valid fields: {valid}")
    head, _, pair = str(name).rpartition("_")
    transposed = f"{head}_{pair[::-1]}"  # the stored component of a symmetric tensor: sigma_xy, not sigma_yx
    close = [transposed] if transposed in named else difflib.get_close_matches(str(name), list(named), n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    raise CaseError(f"unknown field {shown(repr(name))} to colour the body by; {hint}valid fields: {valid}")


def deformed_body(result, step=None, scale=None, field="von_mises"):
    """The body deformed at the end of ``step`` (a step whose fields the run kept, see
    ``output.field_steps``; default: the last one), its displacement magnified ``scale`` times
    (default: see DISPLACEMENT_SHARE), coloured by ``field`` (a name of :func:`body_fields`; default the
    von Mises stress) with a colour bar: an element field flat on each element, a node field
    interpolated (2D) or averaged over each facet (3D). 3D: the boundary facets seen obliquely; 2D: the
    deformed mesh, its outline, and the undeformed outline dashed."""
    step, fields = fields_at(result, step, "no deformed body to draw")
    values, at_nodes = body_field(fields, result.dim, field)
    mesh = result.discretization.mesh
    t = float(result.discretization.times[step - 1])
    largest = float(np.linalg.norm(fields.displacement, axis=1).max(initial=0.0))
    scale = magnification(largest, mesh.diameter) if scale is None else float(scale)
    if not (math.isfinite(scale) and scale > 0):
        raise CaseError(f"scale = {scale!r}: expected a positive finite magnification")
    deformed = mesh.mesh.p + scale * fields.displacement.T
    draw = _body_3d if result.dim == 3 else _body_2d
    label = FIELD_LABELS.get(field, field)
    figure = draw(mesh.mesh, deformed, values, at_nodes, label)
    magnified = "at true scale" if scale == 1 else f"magnified × {scale:g}"
    figure.suptitle(f"Deformed body at t = {t:g}, coloured by {'the ' * (field in FIELD_LABELS)}{label}\ndisplacements "
                    f"{magnified} (the largest, {largest:.3g}, is {largest / mesh.diameter:.1%}\nof the body's size, "
                    f"the diagonal of its bounding box)", fontsize=10)
    return figure


def magnification(largest: float, size: float) -> float:
    """The default magnification of a largest displacement ``largest`` in a body of size ``size``: see
    DISPLACEMENT_SHARE (1 when nothing moves)."""
    if not largest > 0:
        return 1.0
    wanted = DISPLACEMENT_SHARE * size / largest
    if wanted <= 1:
        return 1.0
    exponent = math.floor(math.log10(wanted))
    return max(m * 10.0**exponent for m in (1, 2, 5, 10) if m * 10.0**exponent <= wanted)


def _body_2d(mesh, deformed, values, at_nodes, label):
    from matplotlib.collections import LineCollection
    from matplotlib.tri import Triangulation

    both = np.hstack([mesh.p, deformed])
    width, height = _size(*(both.max(axis=1) - both.min(axis=1)), BODY_HEIGHT)
    figure = _figure(figsize=(max(width + 1.9, 5.0), height + 1.8))
    ax = figure.subplots()
    triangulation = Triangulation(*deformed, mesh.t.T)
    if at_nodes:
        image = ax.tripcolor(triangulation, values, shading="gouraud", cmap=STRESS_MAP)
        if mesh.t.shape[1] <= EDGES_DRAWN_UP_TO:
            ax.triplot(triangulation, color="0.3", lw=0.15)
    else:
        edges = "face" if mesh.t.shape[1] > EDGES_DRAWN_UP_TO else "0.3"
        image = ax.tripcolor(triangulation, facecolors=values, cmap=STRESS_MAP, edgecolors=edges, linewidth=0.15)
    outline = mesh.facets[:, mesh.boundary_facets()]
    ax.add_collection(LineCollection(np.transpose(mesh.p[:, outline], (2, 1, 0)), colors="0.45", linewidths=0.8,
                                     linestyles="--", label="undeformed outline"))
    ax.add_collection(LineCollection(np.transpose(deformed[:, outline], (2, 1, 0)), colors="k", linewidths=0.9,
                                     label="deformed outline"))
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    figure.legend(loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    figure.colorbar(image, cax=ax.inset_axes([1.05, 0.0, 0.05, 1.0]), label=label)
    return figure


def _body_3d(mesh, deformed, values, at_nodes, label):
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    boundary = mesh.boundary_facets()
    triangles = np.moveaxis(deformed[:, mesh.facets[:, boundary]], 0, -1).transpose(1, 0, 2)  # (nb, 3, 3)
    facets = values[mesh.facets[:, boundary]].mean(axis=0) if at_nodes else values[mesh.f2t[0, boundary]]
    norm = Normalize(float(values.min()), float(values.max()))
    mappable = ScalarMappable(norm, STRESS_MAP)
    figure = _figure(figsize=(6.4, 6.0), layout="none")  # placed by hand: the layout engines cut 3D axis labels
    ax = figure.add_axes((0.0, 0.04, 0.8, 0.8), projection="3d")
    many = boundary.size > EDGES_DRAWN_UP_TO
    colors = mappable.to_rgba(facets)
    ax.add_collection3d(Poly3DCollection(triangles, facecolors=colors, edgecolors=colors if many else (0, 0, 0, 0.35),
                                         linewidths=0.2))
    low, high = deformed.min(axis=1), deformed.max(axis=1)
    ax.set(xlim=(low[0], high[0]), ylim=(low[1], high[1]), zlim=(low[2], high[2]), xlabel="x", ylabel="y")
    ax.set_box_aspect(np.maximum(high - low, 1e-3 * (high - low).max()), zoom=0.9)
    ax.view_init(elev=20, azim=-125)
    for axis in (ax.xaxis, ax.yaxis):  # their first labels would meet at the front corner
        axis.set_major_locator(MaxNLocator(4, prune="lower"))
    ax.zaxis.set_major_locator(MaxNLocator(4))
    ax.tick_params(labelsize=8)
    ax.set_zlabel("z", labelpad=-2)
    figure.colorbar(mappable, cax=figure.add_axes((0.82, 0.2, 0.03, 0.55)), label=label)
    return figure


# --- history -----------------------------------------------------------------------------------
def time_series(result, columns=TIME_SERIES):
    """The history ``columns`` (see ``Result.columns``) against t, one panel each, every converged time
    level a marker (sub-steps of a cut step included); LOG_COLUMNS on a logarithmic axis."""
    columns = (columns,) if isinstance(columns, str) else tuple(columns)
    if not columns:
        raise CaseError("time_series: give at least one history column")
    values = {column: result.series(column) for column in columns}
    t = result.times
    figure = _figure(figsize=(6.4, 1.9 * len(columns) + 1.0))
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
    figure.suptitle(f"History of the run ({result.status}, {result.completed_steps} of {len(result.discretization.times)} "
                    f"steps)", fontsize=10)
    return figure


# --- a run directory's figures -----------------------------------------------------------------
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


# --- layout ------------------------------------------------------------------------------------
def _figure(figsize, layout: str = "constrained"):
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout=layout)


def _size(width: float, height: float, tallest: float) -> tuple[float, float]:
    """Width and height (inches) of a drawing of ``width`` × ``height`` (equal aspect): ``tallest`` high
    but at most twice as wide, and at least 0.4 × ``tallest`` wide."""
    aspect = width / height
    drawn = tallest if aspect <= 2.0 else 2.0 * tallest / aspect
    return float(np.clip(drawn * aspect, 0.4 * tallest, 2.0 * tallest)), drawn


def _columns(panels: int) -> int:
    return min(panels, PANELS)


def _grid(panels: int, aspect: float):
    """A figure with ``panels`` axes of width/height ``aspect`` in rows of at most PANELS, sharing x and
    y, sized so that they fill it; the axes as a flat array (the unused places of the last row removed)."""
    columns = _columns(panels)
    rows = math.ceil(panels / columns)
    width, height = _size(aspect, 1.0, PANEL_HEIGHT)
    figure = _figure(figsize=(columns * (width + 0.2) + 1.6, rows * (height + 0.6) + 1.2), layout="compressed")
    axes = figure.subplots(rows, columns, sharex=True, sharey=True, squeeze=False).ravel()
    for ax in axes[panels:]:
        ax.remove()
    return figure, axes[:panels]
