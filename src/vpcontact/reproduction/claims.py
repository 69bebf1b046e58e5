"""What Sect. 4 of the paper states, measured: the ordering of the penetrations, the node states, and
every number or claim, paper against vpcontact, with a verdict (`assess`)."""

from __future__ import annotations

import numpy as np

from .paper import CONTACT_CONDITIONS, FIGURE_TIMES, PAPER
from .plan import Plan, figure_step


def penetration_ordering(cases: dict, suffix: str, tolerance: float = 1e-8) -> dict:
    """The penetration at the bottom point of the four contact conditions at every step, and where the
    paper's ordering β = 1 < (α = 0 cases) < β = −1 holds."""
    d = {name: np.array(cases[f"{name}_{suffix}"]["penetration_probe"]) for name in CONTACT_CONDITIONS}
    t = np.array(cases[f"beta+1_{suffix}"]["t"])
    hard = d["beta+1"] < np.minimum(d["alpha0_g0.2"], d["alpha0_g2000"]) - tolerance
    above_capped = d["beta-1"] > d["alpha0_g0.2"] + tolerance
    equal_capped = np.abs(d["beta-1"] - d["alpha0_g0.2"]) <= tolerance
    above_uncapped = d["beta-1"] > d["alpha0_g2000"] + tolerance
    fails = np.flatnonzero(~above_uncapped)
    return {
        "t": t.tolist(),
        **{name: values.tolist() for name, values in d.items()},
        "hardening_below_constant": hard.tolist(),
        "softening_above_capped": above_capped.tolist(),
        "softening_equal_capped": equal_capped.tolist(),
        "softening_above_uncapped": above_uncapped.tolist(),
        "hardening_below_constant_all_steps": bool(hard.all()),
        "softening_above_capped_or_equal_all_steps": bool((above_capped | equal_capped).all()),
        "softening_above_uncapped_all_steps": bool(above_uncapped.all()),
        "softening_below_uncapped_from_t": float(t[fails[0]]) if fails.size else None,
        "final": {name: float(values[-1]) for name, values in d.items()},
    }


def node_states(cases: dict, results: dict, plan: Plan) -> dict:
    """Node states at the figure times (Figs. 2, 3) and, node by node, β = 1 against β = −1."""
    states = {}
    for sign in ("+1", "-1"):
        record = cases[f"beta{sign}_k0.1"]
        rows = []
        for t in FIGURE_TIMES:
            i = figure_step(t, plan.steps_coarse) - 1
            rows.append(
                {
                    "t": t,
                    "separated": record["nodes_separated"][i],
                    "in_compliance": record["nodes_in_compliance"][i],
                    "at_limit": record["nodes_at_limit"][i],
                    "contact_nodes": record["contact_nodes"],
                    "share_at_limit": record["nodes_at_limit"][i] / record["contact_nodes"],
                }
            )
        states[f"beta{sign}"] = rows
    hard, soft = results["beta+1_k0.1"], results["beta-1_k0.1"]
    d1 = hard.contact_history("penetration", substeps=False)
    d2 = soft.contact_history("penetration", substeps=False)
    touching = (d1 > 0.0) | (d2 > 0.0)
    violations = touching & ~(d1 < d2)
    xy = results["beta+1_k0.1"].discretization.surface.coordinates
    t = hard.discretization.times
    where = [
        {
            "t": float(t[i]),
            "x": float(xy[0, j]),
            "y": float(xy[1, j]),
            "beta+1": float(d1[i, j]),
            "beta-1": float(d2[i, j]),
        }
        for i, j in zip(*np.nonzero(violations))
    ]
    states["hardening_below_softening_nodewise"] = {
        "pairs": int(touching.sum()),
        "violations": int(violations.sum()),
        "largest_violation": float((d1 - d2)[violations].max()) if violations.any() else 0.0,
        "largest_penetration_there": float(np.maximum(d1, d2)[violations].max()) if violations.any() else 0.0,
        "where": where[:50],
    }
    return states


def assess(data: dict) -> list[dict]:
    """Every number or claim of Sect. 4, paper against vpcontact, with a verdict."""
    K = data["K_bottom_final"]
    claims = []

    def claim(figure, text, paper, ours, verdict):
        claims.append({"figure": figure, "claim": text, "paper": paper, "vpcontact": ours, "verdict": verdict})

    def off(value, target):
        return 100.0 * (value - target) / target

    def pct(value, target):
        change = off(value, target)
        return "0.00 %" if abs(change) < 0.005 else f"{change:+.2f} %"

    k1 = K["k0.1"]["beta=1"]
    claim(
        "4",
        "K at the bottom point, β = 1 (hardening), t = 0 → 1.1",
        "100 → 323 N/m²",
        f"100 → {k1:.2f} N/m² (k = 0.1; {pct(k1, 323)})",
        "calibration target (the load was fitted to it)",
    )
    km = K["k0.1"]["beta=-1"]
    claim(
        "4",
        "K at the bottom point, β = −1 (softening), t = 0 → 1.1",
        "100 → 21 N/m²",
        f"100 → {km:.2f} N/m² (k = 0.1; {pct(km, 21)})",
        "holds" if abs(off(km, 21)) <= 5 else "does not hold",
    )
    for sign, target in (("beta=1", 323.0), ("beta=-1", 21.0)):
        value = K["k1_128"][sign]
        claim(
            "4",
            f"the same, {sign.replace('beta=', 'β = ').replace('-', '−')}, with k ≈ 1/128 (Sect. 4.3)",
            f"{target:g} N/m²",
            f"{value:.2f} N/m² ({pct(value, target)})",
            "holds within 5 %" if abs(off(value, target)) <= 5 else "does not hold (off by more than 5 %)",
        )

    hard = data["node_states"]["beta+1"]
    all_compliance = all(r["in_compliance"] == r["contact_nodes"] for r in hard)
    claim(
        "2",
        "β = 1: all contact nodes in normal compliance (none at the limit g) at t = 0.2, 0.5, 0.8, 1.1",
        "all",
        ", ".join(f"{r['in_compliance']}/{r['contact_nodes']}" for r in hard) + " in compliance",
        "holds" if all_compliance else "does not hold",
    )
    soft = data["node_states"]["beta-1"]
    last = soft[-1]
    claim(
        "3",
        "β = −1: a large proportion of the contact nodes at the limit g (unilateral contact)",
        "a large proportion",
        "at the limit at t = 0.2, 0.5, 0.8, 1.1: "
        + ", ".join(f"{r['at_limit']}/{r['contact_nodes']} ({100 * r['share_at_limit']:.0f} %)" for r in soft),
        f"holds ({100 * last['share_at_limit']:.0f} % at t = 1.1)"
        if last["share_at_limit"] >= 0.25
        else f"questionable (only {100 * last['share_at_limit']:.0f} % at t = 1.1)",
    )
    nodewise = data["node_states"]["hardening_below_softening_nodewise"]
    where = nodewise["where"]
    nodes = sorted({(w["x"], w["y"]) for w in where})
    detail = (
        ""
        if not where
        else (
            f"; the exceptions: node{'s' if len(nodes) > 1 else ''} "
            f"{', '.join(f'({x:.3g}, {y:.3g})' for x, y in nodes)} at "
            f"t = {', '.join(f'{w_t:g}' for w_t in sorted({w['t'] for w in where}))}, "
            "where both penetrations are below "
            f"{nodewise['largest_penetration_there']:.1e} m"
        )
    )
    claim(
        "2, 3",
        "at each time the penetrations with β = 1 are smaller than with β = −1",
        "yes",
        f"smaller at {nodewise['pairs'] - nodewise['violations']} of {nodewise['pairs']} (node, step) pairs in "
        f"contact{detail}",
        "holds"
        if not where
        else (
            "holds except at the end of Γ3 (the equator node, normal horizontal: Poisson bulging, not contact)"
            if all(abs(y - 1.0) < 1e-9 for _, y in nodes)
            else f"fails at {nodewise['violations']} pairs"
        ),
    )

    order = data["penetration_ordering"]["k0.1"]
    claim(
        "5, 6",
        "β = 1 penetrates less than both constant-K cases (α = 0, g = 0.2 and g = 2000)",
        "yes",
        f"bottom point, every step: {'yes' if order['hardening_below_constant_all_steps'] else 'no'}; at t = 1.1: "
        f"{order['final']['beta+1']:.4f} m against {order['final']['alpha0_g0.2']:.4f} m "
        f"and {order['final']['alpha0_g2000']:.4f} m",
        "holds" if order["hardening_below_constant_all_steps"] else "does not hold",
    )
    equal_from = [t for t, e in zip(order["t"], order["softening_equal_capped"]) if e]
    larger = [t for t, a in zip(order["t"], order["softening_above_capped"]) if a]
    claim(
        "5, 6",
        "β = −1 penetrates more than the capped constant-K case (α = 0, g = 0.2)",
        "yes",
        f"larger at t = {larger[0]:g} … {larger[-1]:g}, then equal (both at g = 0.2 m) from t = {equal_from[0]:g}"
        if equal_from and larger
        else "larger at every step",
        "holds, but only as ≥ once both reach g"
        if equal_from and order["softening_above_capped_or_equal_all_steps"]
        else ("holds" if order["softening_above_capped_or_equal_all_steps"] else "does not hold"),
    )
    since = order["softening_below_uncapped_from_t"]
    claim(
        "5, 6",
        "β = −1 penetrates more than the uncapped normal-compliance case (α = 0, g = 2000)",
        "yes",
        "larger at every step"
        if since is None
        else f"smaller from t = {since:.1f}: at t = 1.1 {order['final']['beta-1']:.4f} m (capped at g) against "
        f"{order['final']['alpha0_g2000']:.4f} m",
        "holds" if since is None else f"does not hold from t = {since:.1f}",
    )

    rho = data["rho_study"]
    claim(
        "8",
        "‖u_ρ − u_*‖_V + ‖σ_ρ − σ_*‖_Q at t = 1.1 tends to 0 as ρ → 0 (ρ = 1 … 1e−6)",
        "converges to 0",
        f"{rho['difference'][0]:.3g} (ρ = {rho['rho'][0]:g}) → {rho['difference'][-1]:.3g} (ρ = {rho['rho'][-1]:g}), "
        f"monotone: {'yes' if rho['decreasing'] else 'no'}, slope {rho['slope']:.2f} in ρ",
        "holds" if rho["decreasing"] else "does not hold",
    )
    i1 = rho["rho"].index(1.0)
    m = rho["contact_nodes"]
    claim(
        "9",
        "ρ = 1: all contact nodes in normal compliance",
        "all",
        f"{rho['nodes_in_compliance'][i1]}/{m} in compliance, {rho['nodes_at_limit'][i1]} at the limit",
        "holds" if rho["nodes_in_compliance"][i1] == m else "does not hold",
    )
    if 0.01 in rho["rho"]:
        i2 = rho["rho"].index(0.01)
        printed = data["cases"]["printed_rho0.01"]
        claim(
            "9",
            "ρ = 0.01: almost all contact nodes at the limit g",
            "almost all",
            f"{rho['nodes_at_limit'][i2]}/{m} ({100 * rho['nodes_at_limit'][i2] / m:.0f} %) at the limit "
            "(K ≡ 0 itself: "
            f"{rho['signorini']['nodes_at_limit']}/{m}); with the printed load: {printed['nodes_at_limit'][-1]}/"
            f"{printed['contact_nodes']}",
            "does not hold with the calibrated load (see the load)" if rho["nodes_at_limit"][i2] < 0.8 * m else "holds",
        )
    hk = data["hk_study"]
    claim(
        "10",
        "‖u − u^{hk}‖_V at t = 1.1 converges linearly in h + k",
        "linear (slope 1)",
        f"fitted slope {hk['slope']:.2f} (levels 1/{hk['levels'][0]} … 1/{hk['levels'][-1]} "
        f"against 1/{hk['reference']['level']}); "
        f"finest three levels {hk['slope_finest_three']:.2f}",
        "holds" if hk["slope"] >= 0.8 else "does not hold",
    )
    ref = hk["reference"]
    if ref["level"] == 512:
        claim(
            "10",
            "the 1/512 reference: 472,074 DOFs, 470,252 elements",
            "472,074 / 470,252",
            f"{ref['dofs']:,} / {ref['elements']:,}" if ref["elements"] else f"{ref['dofs']:,} DOFs",
            f"{off(ref['dofs'], PAPER['dofs_512']):+.1f} % DOFs (mesh generator differs)",
        )
    mesh = data["mesh"]
    claim(
        "1",
        "the mesh of Figs. 1–7: 30,808 elements, 128 with a side on Γ3",
        "30,808 / 128",
        f"{mesh['elements']:,} / {mesh['contact_edges']}",
        f"differs (our calibrated example's mesh, h = {data['settings']['figure_mesh_h']:g})",
    )
    return claims


