"""The figures of Sect. 4 of the paper (Figs. 2–10, and Fig. 11 beyond it), drawn with matplotlib, PNG and PDF.

No pyplot: every figure is a `matplotlib.figure.Figure` rendered by the Agg canvas, so importing this
module changes no global matplotlib state. A deformed-configuration panel (a :class:`~.frames.Frame`) shows the
deformed body (filled, with its outline; its mesh too when it has at most `MESH_DRAWN_UP_TO`
triangles, finer meshes would be a grey block), the undeformed outline, the soft layer of
thickness g and the rigid base under it (the foundation conforms to Γ3: the layer lies between the
circle of radius 1 and that of radius 1 + g about (0, 1)), Γ3 coloured by the state of its nodes
(separated, in normal compliance, at the limit g), and the contact forces as arrows pointing at the
body (the force per unit length the foundation exerts, −(ρK p + λ/w) ν) at no more than `frames.ARROWS`
nodes evenly spaced along Γ3.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.tri import Triangulation

from ..laws.contact import AT_LIMIT
from ..results.plots import STATE_COLORS, STATE_LABELS  # Γ3 coloured by the state of its nodes, as in a run's figures
from .frames import MAGNIFICATION, Frame
from .paper import CONTACT_CONDITIONS, FIGURE_TIMES

DPI = 150
COLORS = {"beta+1": "C0", "beta-1": "C3", "alpha0_g0.2": "C2", "alpha0_g2000": "C1"}
ARROW = 0.3
"""Length (m) of the longest contact-force arrow of a figure."""
MESH_DRAWN_UP_TO = 2000
"""The mesh is drawn when it has at most this many triangles; a finer one (the figure mesh has
23,204) would be a grey block, so only the body's outline is drawn."""
BODY = "0.86"
"""Fill colour of the deformed body."""
ARROW_COLOR = "0.15"


def _save(figure: Figure, folder: Path, stem: str) -> dict:
    folder.mkdir(parents=True, exist_ok=True)
    png, pdf = folder / f"{stem}.png", folder / f"{stem}.pdf"
    figure.savefig(png, dpi=DPI)
    figure.set_layout_engine("none")  # the PDF keeps the PNG's layout instead of computing it again
    figure.savefig(pdf)
    return {"png": f"{folder.name}/{png.name}", "pdf": f"{folder.name}/{pdf.name}"}


def _nice(value: float) -> float:
    """A round number near value (1, 2 or 5 times a power of ten)."""
    exponent = math.floor(math.log10(value))
    return min((m * 10.0**exponent for m in (1, 2, 5, 10)), key=lambda v: abs(v - value))


def _foundation(ax, g: float) -> None:
    theta = np.linspace(-0.5 * np.pi, 0.0, 120)
    drawn = min(g, 0.45)
    outer, inner = 1.0 + drawn, 1.0
    x = np.concatenate([inner * np.cos(theta), outer * np.cos(theta[::-1])])
    y = np.concatenate([1.0 + inner * np.sin(theta), 1.0 + outer * np.sin(theta[::-1])])
    ax.fill(x, y, color="tan", alpha=0.35, lw=0, zorder=0)
    if g <= 0.45:
        ax.plot(outer * np.cos(theta), 1.0 + outer * np.sin(theta), color="saddlebrown", lw=2.0, zorder=1)
    else:
        ax.text(1.02, 1.08, f"rigid base at\ng = {g:g} m\n(off the figure)", fontsize=7, color="saddlebrown")


def _panel(ax, frame: Frame, scale: float) -> None:
    """One deformed configuration: foundation, undeformed outline, deformed body (and mesh when
    coarse), Γ3 coloured by node state, contact forces at `Frame.arrow_nodes`."""
    _foundation(ax, frame.g)
    angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 200)
    ax.plot(
        np.concatenate([np.cos(angle), [0, 0]]),
        np.concatenate([1.0 + np.sin(angle), [2, 0]]),
        color="0.55",
        lw=0.8,
        ls="--",
        zorder=2.8,
    )
    p = frame.deformed().T
    body = Triangulation(p[:, 0], p[:, 1], frame.triangles.T)
    ax.tricontourf(body, np.zeros(len(p)), levels=[-1.0, 1.0], colors=[BODY], zorder=2)  # one polygon: the body
    edges, count = frame.edges
    if frame.triangles.shape[1] <= MESH_DRAWN_UP_TO:
        _segments(ax, p[edges.T], color="0.45", lw=0.3, zorder=2.5)
    _segments(ax, p[edges[:, count == 1].T], color="0.15", lw=0.9, zorder=3)

    # Γ3 by node state: each node colours the half of each of its segments next to it
    q = p[frame.nodes]
    first, second = frame.contact_segments()
    middle = 0.5 * (q[first] + q[second])
    halves = np.concatenate([np.stack([q[first], middle], axis=1), np.stack([middle, q[second]], axis=1)])
    state = np.concatenate([frame.status[first], frame.status[second]])
    for value, color in STATE_COLORS.items():
        _segments(ax, halves[state == value], color=color, lw=3.0, solid_capstyle="butt", zorder=4)

    shown = frame.arrow_nodes()
    force = -frame.normals[:, shown] * frame.pressure[shown]  # on the body, per unit length
    ax.quiver(
        q[shown, 0],
        q[shown, 1],
        force[0],
        force[1],
        angles="xy",
        scale_units="xy",
        scale=scale,
        pivot="tip",
        color=ARROW_COLOR,
        width=0.006,
        zorder=5,
    )
    ax.set_aspect("equal")
    ax.set_xlim(-0.08, 1.5)
    ax.set_ylim(-0.62, 2.08)
    ax.set_xlabel("$x_1$ (m)")
    limit = int(np.sum(frame.status == AT_LIMIT))
    ax.set_title(f"{frame.title}\n{limit}/{frame.nodes.size} nodes at the limit g", fontsize=9)


def deformed_panels(frames: list[Frame], title: str, scale: float | None = None) -> Figure:
    """A row of deformed-configuration panels with a shared force scale, a key and a legend."""
    largest = max(float(np.max(f.pressure, initial=0.0)) for f in frames) or 1.0
    scale = scale or largest / ARROW
    figure = Figure(figsize=(3.2 * len(frames), 5.9), layout="constrained")
    axes = figure.subplots(1, len(frames), sharey=True)
    for ax, frame in zip(np.atleast_1d(axes), frames):
        _panel(ax, frame, scale)
    first = np.atleast_1d(axes)[0]
    first.set_ylabel("$x_2$ (m)")
    key = _nice(0.5 * largest)
    first.quiverkey(
        _arrows(first), 0.22, 0.06, key, f"{key:g} N/m", labelpos="E", coordinates="axes", fontproperties={"size": 7}
    )
    sample = frames[0]
    elements = sample.triangles.shape[1]
    body = "deformed body and mesh" if elements <= MESH_DRAWN_UP_TO else f"deformed body ({elements:,} triangles)"
    handles = [
        Patch(color="tan", alpha=0.35, label="soft layer (thickness g)"),
        Line2D([], [], color="saddlebrown", lw=2, label="rigid base (penetration = g)"),
        Line2D([], [], color="0.55", ls="--", label="undeformed body"),
        Patch(facecolor=BODY, edgecolor="0.15", label=body),
        *[Line2D([], [], color=color, lw=3, label=f"Γ3: node {STATE_LABELS[s]}") for s, color in STATE_COLORS.items()],
        Line2D([], [], color=ARROW_COLOR, marker=r"$\uparrow$", ls="", ms=9, label="contact force on the body (N/m)"),
    ]
    figure.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    shown, nodes = sample.arrow_nodes().size, sample.nodes.size
    where = "every contact node" if shown == nodes else f"{shown} of the {nodes} contact nodes, evenly spaced along Γ3"
    figure.suptitle(
        f"{title}\ndisplacements at true scale (magnification {MAGNIFICATION:g}); arrows at {where}, "
        "length proportional to the force (key in the first panel)",
        fontsize=10,
    )
    return figure


def deformed_figure(frames: list[Frame], title: str, folder: Path, stem: str, scale: float | None = None) -> dict:
    """`deformed_panels` written as PNG and PDF."""
    return _save(deformed_panels(frames, title, scale), folder, stem)


def _segments(ax, segments: np.ndarray, **style) -> None:
    """Line segments (k, 2, 2) as one line broken by NaNs (one path: a PDF draws it at once)."""
    gaps = np.full((segments.shape[0], 1, 2), np.nan)
    xy = np.concatenate([segments, gaps], axis=1).reshape(-1, 2)
    ax.plot(xy[:, 0], xy[:, 1], **style)


def _arrows(ax):
    from matplotlib.quiver import Quiver

    return next(c for c in ax.collections if isinstance(c, Quiver))


def _with_start(t, values, start):
    """Prepend t = 0 (u_0 = 0, ξ(0) = 0) to a series."""
    return np.concatenate([[0.0], t]), np.concatenate([[start], values])


def _line_figure(title: str, xlabel: str, ylabel: str):
    figure = Figure(figsize=(6.4, 4.4), layout="constrained")
    ax = figure.subplots()
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    return figure, ax


def stiffness_figure(data: dict, folder: Path) -> dict:
    """Fig. 4: K at the bottom point against time, β = ±1, k = 0.1 and k ≈ 1/128, with the paper's values."""
    figure, ax = _line_figure("Fig. 4: stiffness coefficient at the bottom point (0, 0)", "t (s)", "K (N/m²)")
    c_v = data["paper"]["c_v"]
    for sign, label in (("+1", "β = 1"), ("-1", "β = −1")):
        color = COLORS[f"beta{sign}"]
        coarse, fine = data["cases"][f"beta{sign}_k0.1"], data["cases"][f"beta{sign}_k1_128"]
        ax.plot(*_with_start(coarse["t"], coarse["K_probe"], c_v), "o-", color=color, ms=4, label=f"{label}, k = 0.1")
        ax.plot(
            *_with_start(fine["t"], fine["K_probe"], c_v),
            "--",
            color=color,
            lw=1.2,
            label=f"{label}, k = 1.1/{fine['steps']} ≈ 1/128",
        )
    ax.plot(
        [1.1, 1.1], [data["paper"]["K_hardening"], data["paper"]["K_softening"]], "k*", ms=11, label="paper, t = 1.1 s"
    )
    ax.legend(fontsize=8)
    return _save(figure, folder, "fig04")


def probe_figure(data: dict, folder: Path, column: str, stem: str, title: str, ylabel: str, sign: float = 1.0) -> dict:
    """Figs. 6, 7: a bottom-point quantity against time for the four contact conditions (k = 0.1)."""
    figure, ax = _line_figure(title, "t (s)", ylabel)
    for name, (label, _) in CONTACT_CONDITIONS.items():
        record = data["cases"][f"{name}_k0.1"]
        ax.plot(
            *_with_start(record["t"], sign * np.asarray(record[column]), 0.0),
            "o-",
            ms=4,
            color=COLORS[name],
            label=label,
        )
    if column == "penetration_probe":
        ax.axhline(data["paper"]["g"], color="saddlebrown", ls=":", label="g = 0.2 m (rigid base)")
    ax.legend(fontsize=8)
    return _save(figure, folder, stem)


def rho_figure(data: dict, folder: Path) -> dict:
    """Fig. 8: ‖u_ρ − u_*‖_V + ‖σ_ρ − σ_*‖_Q at t = 1.1 against ρ (log–log)."""
    rho = data["rho_study"]
    figure, ax = _line_figure(
        "Fig. 8: distance to the Signorini solution (K ≡ 0) at t = 1.1 s",
        "ρ (–)",
        r"$\|u_\rho - u_*\|_V + \|\sigma_\rho - \sigma_*\|_Q$",
    )
    ax.loglog(rho["rho"], rho["difference"], "o-", color="k", label="sum (the paper's quantity)")
    ax.loglog(rho["rho"], rho["V"], "s--", color="C0", ms=4, lw=1, label=r"$\|\varepsilon(u_\rho - u_*)\|_{L^2}$ (m)")
    ax.loglog(rho["rho"], rho["Q"], "^--", color="C3", ms=4, lw=1, label=r"$\|\sigma_\rho - \sigma_*\|_{L^2}$ (N/m)")
    ax.text(0.05, 0.92, f"fitted slope (ρ ≤ 0.1): {rho['slope']:.2f}", transform=ax.transAxes, fontsize=9)
    ax.legend(fontsize=8, loc="lower right")
    return _save(figure, folder, "fig08")


def hk_figure(data: dict, folder: Path) -> dict:
    """Fig. 10: ‖u − u^{hk}‖_V at t = 1.1 against h + k (log–log), with the fitted slope."""
    hk = data["hk_study"]
    x, y = np.array(hk["h_plus_k"]), np.array(hk["error_V"])
    figure, ax = _line_figure(
        f"Fig. 10: error at t = 1.1 s against the 1/{hk['reference']['level']} solution",
        "h + k (h in m, k in s)",
        r"$\|u - u^{hk}\|_V$ (m)",
    )
    ax.loglog(x, y, "o-", color="k", label=f"h = k = 1/{hk['levels'][0]} … 1/{hk['levels'][-1]}")
    slope = hk["slope"]
    intercept = np.mean(np.log(y) - slope * np.log(x))
    ax.loglog(x, np.exp(intercept) * x**slope, "--", color="C3", label=f"fitted slope {slope:.2f}")
    ax.loglog(x, y[-1] * x / x[-1], ":", color="0.5", label="slope 1")
    for level, xi, yi in zip(hk["levels"], x, y):
        ax.annotate(f"1/{level}", (xi, yi), textcoords="offset points", xytext=(4, -10), fontsize=7)
    ax.legend(fontsize=8)
    return _save(figure, folder, "fig10")


def adaptive_figure(data: dict, folder: Path) -> dict:
    """Beyond the paper: ‖u − u_ref‖_E at t = 1.1 against DOFs, uniform and adaptive meshes (log–log)."""
    h, a = data["rates"]["h"], data["adaptive"]
    figure, ax = _line_figure(
        f"Adaptive and uniform meshes, against the 1/{data['settings']['h_reference_level']} solution",
        "DOFs",
        r"$\|u - u_{ref}\|_E$ at t = 1.1 s",
    )
    ax.loglog(h["dofs"], h["error_energy"], "o-", color="k", label="uniform, h = 1/4, 1/8, …")
    ax.loglog(a["dofs"], a["error_energy"], "s-", color="C3", label="adaptive (residual estimator)")
    ax.loglog(a["dofs"], a["estimate"], "s:", color="C3", mfc="none", lw=1, label="adaptive: the estimate η")
    dofs = np.array(h["dofs"], dtype=float)
    ax.loglog(dofs, h["error_energy"][-1] * np.sqrt(dofs[-1] / dofs), ":", color="0.5", label="DOFs$^{-1/2}$")
    ax.legend(fontsize=8)
    return _save(figure, folder, "fig11")


TITLES = {
    "fig02": "Fig. 2: deformed mesh and contact forces, β = 1",
    "fig03": "Fig. 3: deformed mesh and contact forces, β = −1",
    "fig04": "Fig. 4: K at the bottom point against time, β = ±1",
    "fig05": "Fig. 5: deformed mesh and contact forces at t = 1.1 s, four contact conditions",
    "fig06": "Fig. 6: penetration at the bottom point against time, four contact conditions",
    "fig07": "Fig. 7: normal contact stress at the bottom point against time, four contact conditions",
    "fig08": "Fig. 8: ‖u_ρ − u_*‖_V + ‖σ_ρ − σ_*‖_Q at t = 1.1 s against ρ",
    "fig09": "Fig. 9: deformed mesh and contact forces at t = 1.1 s for four values of ρ",
    "fig10": "Fig. 10: ‖u − u^{hk}‖_V at t = 1.1 s against h + k",
    "fig11": "Fig. 11 (beyond the paper): adaptive and uniform meshes, error against DOFs",
}


def draw_all(data: dict, frames: dict, folder: Path) -> dict:
    """Every figure into ``folder``; returns {id: {"title", "png", "pdf"}} (paths relative to its parent)."""
    folder = Path(folder)
    contact = [frames[f"beta{s}_t{t:g}"] for s in ("+1", "-1") for t in FIGURE_TIMES]
    contact += [frames[f"final_{name}"] for name in CONTACT_CONDITIONS]
    scale = max(float(np.max(f.pressure, initial=0.0)) for f in contact) / ARROW  # one scale for Figs. 2, 3, 5
    drawn = {
        "fig02": deformed_figure([frames[f"beta+1_t{t:g}"] for t in FIGURE_TIMES], TITLES["fig02"], folder, "fig02",
                                 scale),
        "fig03": deformed_figure([frames[f"beta-1_t{t:g}"] for t in FIGURE_TIMES], TITLES["fig03"], folder, "fig03",
                                 scale),
        "fig04": stiffness_figure(data, folder),
        "fig05": deformed_figure([frames[f"final_{name}"] for name in CONTACT_CONDITIONS], TITLES["fig05"], folder,
                                 "fig05", scale),
        "fig06": probe_figure(data, folder, "penetration_probe", "fig06",
                              "Fig. 6: penetration at the bottom point (0, 0)", r"penetration $u_\nu$ (m)"),
        "fig07": probe_figure(data, folder, "normal_stress_probe", "fig07",
                              "Fig. 7: normal contact stress at the bottom point (0, 0)", r"$|\sigma_\nu|$ (N/m)",
                              sign=-1.0),
        "fig08": rho_figure(data, folder),
        "fig09": deformed_figure([frames[f"rho_{rho:g}"] for rho in data["settings"]["fig9_rho"]], TITLES["fig09"],
                                 folder, "fig09"),
        "fig10": hk_figure(data, folder),
        "fig11": adaptive_figure(data, folder),
    }
    return {key: {"title": TITLES[key], **paths} for key, paths in drawn.items()}

