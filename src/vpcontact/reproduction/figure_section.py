"""The report's Figures section: Figs. 2–10 with their captions and the numbers they show.

The mesh the figures are drawn on beside the paper's, how the deformed bodies and the contact forces
are drawn, and under the figures the tables of their numbers: the contact nodes' states at the drawn
times (Figs. 2, 3), the distance to the Signorini solution u_* as ρ → 0 (Figs. 8, 9) and the error
of the h–k sequence with its local slopes (Fig. 10). Returns the section's blocks (:mod:`.markup`)
from the data of reproduce.json.
"""

from __future__ import annotations

from .figures import MESH_DRAWN_UP_TO
from .frames import ARROWS
from .markup import Heading, Paragraph, Picture, Table
from .paper import T


def figures_section(data: dict) -> list:
    """The section "Figures": Figs. 2–10 with their captions, the mesh and the drawing conventions, and the
    tables of the numbers they show (the nodes' contact states in Figs. 2, 3, the distance to u_* as ρ → 0,
    the h–k study)."""
    s, cases, states = data["settings"], data["cases"], data["node_states"]
    rho, hk = data["rho_study"], data["hk_study"]
    mesh = data["mesh"]
    state_rows = []
    for sign, label in (("beta+1", "β = 1"), ("beta-1", "β = −1")):
        for r in states[sign]:
            state_rows.append(
                [
                    label,
                    f"{r['t']:g}",
                    r["separated"],
                    r["in_compliance"],
                    r["at_limit"],
                    f"{100 * r['share_at_limit']:.0f} %",
                ]
            )
    rho_rows = [
        [f"{r:g}", f"{v:.3e}", f"{q:.3e}", f"{d:.3e}", f"{a}/{rho['contact_nodes']}"]
        for r, v, q, d, a in zip(rho["rho"], rho["V"], rho["Q"], rho["difference"], rho["nodes_at_limit"])
    ]
    rho_rows.append(
        ["K ≡ 0 (reference)", "0", "0", "0", f"{rho['signorini']['nodes_at_limit']}/{rho['contact_nodes']}"]
    )
    hk_rows = []
    for i, level in enumerate(hk["levels"]):
        hk_rows.append(
            [
                f"1/{level}",
                f"{hk['h'][i]:.5f}",
                f"{hk['k'][i]:.5f}",
                f"{hk['dofs'][i]:,}",
                hk["steps"][i],
                f"{hk['error_V'][i]:.4e}",
                f"{hk['local_slopes'][i - 1]:.2f}" if i else "–",
                f"{hk['wall_time_s'][i]:.2f}",
            ]
        )
    ref = hk["reference"]
    hk_rows.append(
        [
            f"1/{ref['level']} (reference)",
            f"{1 / ref['level']:.5f}",
            f"{T / ref['steps']:.5f}",
            f"{ref['dofs']:,}",
            ref["steps"],
            "0",
            "–",
            f"{ref['wall_time_s']:.2f}",
        ]
    )
    mesh_text = (
        f"Mesh: h = {s['figure_mesh_h']:g}, {mesh['elements']:,} triangles, {mesh['dofs']:,} DOFs, "
        f"{mesh['contact_nodes']} contact nodes ({mesh['contact_edges']} edges on Γ3); the paper's Fig. 1 mesh has "
        f"30,808 elements and 128 edges on Γ3."
    )
    return [
        Heading(2, "Figures"),
        Paragraph(
            mesh_text + " Displacements are drawn at true scale (magnification 1): the body mostly translates "
            "into the soft layer. The deformed body is filled, with its outline; its mesh is drawn when it has at "
            f"most {MESH_DRAWN_UP_TO:,} triangles (a finer one would be a grey block). Γ3 is coloured by the state "
            "of its nodes: separated (grey), in normal compliance (blue), at the limit g, on the rigid base "
            "(orange). Arrows: the force per unit length the foundation exerts on the body (compliance part "
            f"ρK(ξ)p(u_ν) plus the rigid multiplier), pointing at the body, at no more than {ARROWS} contact nodes "
            "evenly spaced along Γ3; the same arrow scale in Figs. 2, 3 and 5."
        ),
        Heading(3, "Figs. 2 and 3: deformed meshes and contact forces, β = ±1"),
        Picture(
            "fig02",
            "β = 1 (hardening), t = 0.2, 0.5, 0.8, 1.1 s, k = 0.1. The paper: all contact nodes in normal compliance.",
        ),
        Picture(
            "fig03", "β = −1 (softening), the same times. The paper: a large proportion of the nodes at the limit g."
        ),
        Table(["case", "t (s)", "separated", "in compliance", "at the limit g", "share at the limit"], state_rows),
        Heading(3, "Fig. 4: the stiffness coefficient at the bottom point"),
        Picture(
            "fig04",
            "K at (0, 0) against time for β = ±1, k = 0.1 (solid) and k ≈ 1/128 (dashed); stars: the paper's "
            "final values 323 and 21. K(0) = c_v = 100.",
        ),
        Heading(3, "Figs. 5–7: four contact conditions"),
        Picture(
            "fig05",
            "t = 1.1 s: β = 1; β = −1; α = 0, g = 0.2 (normal compliance with unilateral constraint); "
            "α = 0, g = 2000 (classical normal compliance).",
        ),
        Picture("fig06", "Penetration u_ν at the bottom point against time, k = 0.1."),
        Picture(
            "fig07",
            "Magnitude of the normal contact stress σ_ν at the bottom point (the nodal pressure, force per "
            "unit length of Γ3) against time, k = 0.1. The jumps are the bottom node reaching g: the "
            "rigid base then carries the increase of the load.",
        ),
        Heading(3, "Figs. 8 and 9: the perturbed problem P_V^ρ as ρ → 0"),
        Paragraph(
            f"K_ρ = ρK with the example's law (β = 1; the paper does not say which β), k = 0.1, mesh h = "
            f"{s['figure_mesh_h']:g}; u_* is the solution with K ≡ 0 (Signorini with gap g). The norms are "
            f"‖v‖_V = ‖ε(v)‖_{{L²(Ω)}} and ‖τ‖_Q = ‖τ‖_{{L²(Ω)}} (`vpcontact.results.norms.differences`). The distance "
            f"decreases monotonically and linearly in ρ (fitted slope {rho['slope']:.2f} for ρ ≤ 0.1)."
        ),
        Picture("fig08", "‖u_ρ − u_*‖_V + ‖σ_ρ − σ_*‖_Q at t = 1.1 s against ρ (log–log), and its two parts."),
        Table(["ρ", "‖u_ρ − u_*‖_V", "‖σ_ρ − σ_*‖_Q", "sum", "nodes at the limit"], rho_rows),
        Picture(
            "fig09",
            f"t = 1.1 s for ρ = {', '.join(f'{r:g}' for r in s['fig9_rho'])} (the paper does not list its "
            f"four values). The paper: ρ = 1 all nodes in compliance; ρ = 0.01 almost all at the limit.",
        ),
        Paragraph(
            f"With the calibrated load the Signorini limit K ≡ 0 itself has only {rho['signorini']['nodes_at_limit']} "
            f"of {rho['contact_nodes']} nodes on the rigid base (the others penetrate the layer, which offers no "
            f"resistance, by less than g), so no ρ can put almost all nodes at the limit. With the printed load, "
            f"ρ = 0.01 gives {cases['printed_rho0.01']['nodes_at_limit'][-1]}/"
            f"{cases['printed_rho0.01']['contact_nodes']} "
            f"at the limit — as the paper says — but then ρ = 1 is not in compliance either "
            f"({cases['printed_beta+1']['nodes_at_limit'][-1]} at the limit). No single load makes both of the "
            f"paper's Fig. 9 statements and its Figs. 2–4 hold."
        ),
        Heading(3, "Fig. 10: convergence in h and k"),
        Paragraph(
            f"h = k = 1/{hk['levels'][0]} … 1/{hk['levels'][-1]} against the 1/{ref['level']} solution: element "
            f"edge √2·h (which gives the paper's sizes) and steps = round(1.1/h), k = 1.1/steps; h + k with the "
            f"nominal h = 1/level. The error is ‖ε(u − u^{{hk}})‖_{{L²}} on the reference mesh, coarse solutions "
            f"interpolated onto it. Fitted slope (all levels) **{hk['slope']:.2f}**, finest three levels "
            f"{hk['slope_finest_three']:.2f}: linear convergence, as the paper concludes."
        ),
        Picture("fig10", "‖u − u^{hk}‖_V at t = 1.1 s against h + k (log–log), with the least-squares slope."),
        Table(["level", "h", "k", "DOFs", "steps", "‖u − u^{hk}‖_V", "local slope", "wall time (s)"], hk_rows),
    ]
