"""The deformed body coloured by a field (:func:`deformed_body`), and the scalar fields it may be coloured
by (:func:`body_fields`). 2D: the deformed mesh and its outlines; 3D: the boundary facets seen obliquely."""

from __future__ import annotations

import difflib
import math

import numpy as np

from ...errors import CaseError, shown
from ...mesh.cells import coordinates
from ..steps import fields_at
from .layout import EDGES_DRAWN_UP_TO, STRESS_MAP, drawing_size, new_figure

DISPLACEMENT_SHARE = 0.1
"""Default magnification of a deformed body: its largest displacement drawn as this share of the
body's size (the diagonal of its bounding box), rounded to 1, 2 or 5 times a power of ten, never
below true scale."""
BODY_HEIGHT = 4.5
"""Height (inches) of a 2D deformed body (less when it is more than twice as wide)."""


FIELD_LABELS = {"von_mises": "von Mises stress", "displacement": "displacement |u|"}
"""Colour-bar labels of the body fields that are not named by their component (see :func:`body_field`)."""


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
    width, height = drawing_size(*(both.max(axis=1) - both.min(axis=1)), BODY_HEIGHT)
    figure = new_figure(figsize=(max(width + 1.9, 5.0), height + 1.8))
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
    figure = new_figure(figsize=(6.4, 6.0), layout="none")  # placed by hand: the layout engines cut 3D axis labels
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
