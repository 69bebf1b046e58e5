"""The report's section Beyond the paper: what the paper leaves open, measured.

The rates of convergence in h and in k separately (the paper's Fig. 10 refines both together), the
effectivity index of the residual a posteriori estimate on the runs of the rate in h (the paper
closes asking for such an estimate), and adaptive meshes against the uniform ones (Fig. 11). Returns
the section's blocks (:mod:`.markup`) from the data of reproduce.json.
"""

from __future__ import annotations

from .markup import Heading, Paragraph, Picture, Table, significant


def beyond_section(data: dict) -> list:
    """The section "Beyond the paper": what the paper leaves open, measured: the rates in h and in k
    separately (Fig. 10 has only h + k), then the residual estimator's effectivity and adaptive meshes."""
    s, rates = data["settings"], data["rates"]
    rows = []
    for name, label, unit in (("h", "h", "1/{}"), ("k", "k", "1.1/{}")):
        r = rates[name]
        sizes = s["h_levels"] if name == "h" else s["k_steps"]
        for i, size in enumerate(sizes):
            rows.append([label, unit.format(size), f"{r['dofs'][i]:,}", str(r["steps"][i]),
                         significant(r["error_V"][i]), significant(r["error_Q"][i])])
        rows.append([f"**slope in {label}**", "all / finest three", "", "",
                     f"**{r['slope_V']:.2f}** / {r['slope_V_finest_three']:.2f}",
                     f"**{r['slope_Q']:.2f}** / {r['slope_Q_finest_three']:.2f}"])
    return [
        Heading(2, "Beyond the paper"),
        Heading(3, "The rates in h and in k separately"),
        Paragraph(
            f"Fig. 10 refines h and k together. Here one varies and the other is held: h = 1/{s['h_levels'][0]} … "
            f"1/{s['h_levels'][-1]} against 1/{s['h_reference_level']}, every run with {s['h_steps']} steps (the error "
            f"is the spatial one of that time grid); k = 1.1/{s['k_steps'][0]} … 1.1/{s['k_steps'][-1]} against "
            f"1.1/{s['k_reference_steps']}, every run on the mesh of h = 1/{s['k_level']} (the error is the time "
            "discretization's on that mesh). Errors at t = 1.1 s in the norms of Fig. 8, ‖ε(·)‖_{L²} (V) and the "
            "stress's L² norm (Q), on the reference's mesh. The time rule is explicit in the viscoplastic history "
            "and implicit (rectangle rule) in ξ: first order in k is expected; P1/P0 elements: first order in h "
            "in both norms for a smooth solution."
        ),
        Table(["", "size", "DOFs", "steps", "‖u − u_ref‖_V", "‖σ − σ_ref‖_Q"], rows),
    ] + _effectivity(data)


def _effectivity(data):
    """The residual estimator's effectivity on the runs of the rate in h (same time grid as the reference)."""
    s, h = data["settings"], data["rates"]["h"]
    if "effectivity" not in h:
        return []
    rows = [[f"1/{level}", f"{dofs:,}", significant(error), significant(eta), f"{ratio:.2f}"]
            for level, dofs, error, eta, ratio in zip(s["h_levels"], h["dofs"], h["error_energy"], h["estimate"],
                                                      h["effectivity"])]
    low, high = min(h["effectivity"]), max(h["effectivity"])
    return [
        Heading(3, "The a posteriori error estimate and its effectivity"),
        Paragraph(
            "The paper closes asking for an a posteriori error estimate. The residual estimate η(t_n) of "
            "`output.error_estimate` (docs/adaptivity.md) on the runs of the rate in h, at t = 1.1 s, against the "
            "energy norm of the error ‖u − u_ref‖_E = (∫ ℰε(u − u_ref):ε(u − u_ref))^½ on the "
            f"1/{s['h_reference_level']} mesh (the same {s['h_steps']} time steps: the error is the spatial one "
            f"η estimates). Effectivity index η / ‖u − u_ref‖_E from {low:.2f} to {high:.2f} (a band of "
            f"{high / low:.2f}): η stays above the error by a factor that changes little with h."
        ),
        Table(["h", "DOFs", "‖u − u_ref‖_E", "η", "η / ‖u − u_ref‖_E"], rows),
    ] + _adaptive(data)


def _adaptive(data):
    """Adaptive meshes against the uniform ones of the rate in h (the same time grid and reference)."""
    s, a = data["settings"], data["adaptive"]
    rows = [[str(i + 1), f"{dofs:,}", significant(eta), significant(error)]
            for i, (dofs, eta, error) in enumerate(zip(a["dofs"], a["estimate"], a["error_energy"]))]
    finest = a["uniform_finest"]
    reached = a["dofs_at_uniform_error"]
    if reached == reached:  # not NaN
        answer = (f"The cycles reach the error of the uniform 1/{finest['level']} mesh ({finest['dofs']:,} DOFs, "
                  f"{significant(finest['error_energy'])}) at about **{reached:,.0f} DOFs**, "
                  f"{reached / finest['dofs']:.2f} of its DOFs.")
    else:
        answer = (f"The cycles did not reach the error of the uniform 1/{finest['level']} mesh ({finest['dofs']:,} "
                  f"DOFs, {significant(finest['error_energy'])}) within adapt.max_dofs = {s['adapt_max_dofs']:,}.")
    return [
        Heading(3, "Adaptive meshes"),
        Paragraph(
            f"`[adapt]` from h = 1/{s['adapt_level']} (residual estimator, the maximum over the steps of each "
            f"element's η_K², Dörfler θ = 0.5, conforming refinement; {s['h_steps']} time steps) against the uniform "
            f"meshes of the rate in h, both measured against the same 1/{s['h_reference_level']} solution in the "
            f"energy norm at t = 1.1 s. {answer} The estimator refines most at the point (1, 1) of the boundary "
            "where the applied traction ends (a stress singularity) and towards the contact zone (docs/adaptivity.md)."
        ),
        Picture("fig11", "‖u − u_ref‖_E at t = 1.1 s against DOFs: uniform and adaptive meshes, and the adaptive "
                "estimate η."),
        Table(["cycle", "DOFs", "estimate (max over steps)", "‖u − u_ref‖_E at t = 1.1 s"], rows),
    ]
