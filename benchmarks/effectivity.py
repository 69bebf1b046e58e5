"""The residual estimator's effectivity index against a uniform reference: prints a table and JSON.

For each case and β, the same case is solved on uniform levels (mesh.h = 1/n) and on a reference
mesh two or more levels finer, all on the SAME time grid (the case's time.steps), so that the
difference measured is the spatial error the estimator estimates, not the time discretization's.
At each time t (a step time of the grid) and level:

    η(t)          the residual estimator (vpcontact.estimate.residual) of the level's solution,
    ‖e‖_E         = ‖I_ref u_h − u_ref‖_E, the energy norm (∫ ℰε:ε, vpcontact.results.norms.energy_norm) on the
                    reference mesh, u_h interpolated at its nodes (vpcontact.results.norms.transfer),
    effectivity   η / ‖e‖_E,

and the local picture: the energy of the error on each reference element, summed over the level's
element that contains the reference element's centroid (e_K), against η_K. The figure (written with
--out) plots η_K against e_K for every element of a level, and the two maps side by side.

Cases:
- "paper": examples/paper_ball.toml (the paper's half disc, β = 1 and β = −1), t = 0.5 and 1.1;
- "punch": a flat rigid punch's edge, the known singularity: the unit square pressed (traction −20 t on
  its top) onto a rigid flat punch under 0 < x < 1/2 of its bottom (gap 0 there, (x − 1/2)⁺ beside
  it: a punch whose edge is a 45° chamfer), symmetric about x = 0 (roller), a layer with K ≡ 0 and
  g = 10⁻³ (Signorini with a thin gap); the pressure grows like r^(−1/2) at the edge, the energy error
  converges like h^(1/2) under uniform refinement, and the error and the indicators concentrate there.

    python benchmarks/effectivity.py --out results/effectivity              # 1/8 … 1/64 against 1/256
    python benchmarks/effectivity.py --quick                                 # 1/4 … 1/16 against 1/32
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import vpcontact
from vpcontact.estimate.indicators import Level
from vpcontact.mesh.locate import containing_elements
from vpcontact.results.norms import element_energies, transfer
from vpcontact.estimate.residual import ResidualEstimator, TERMS

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SETTINGS = {
    "full": {"levels": (8, 16, 32, 64), "reference": 256},
    "quick": {"levels": (4, 8, 16), "reference": 32},
}


def paper_case(n: int, beta: float, steps: list[int]):
    return vpcontact.load_case(EXAMPLES / "paper_ball.toml", {"mesh.h": 1.0 / n, "contact.stiffness.beta": beta,
                                                              "output.field_steps": steps, "output.progress": False})


def punch_case(n: int, beta: float, steps: list[int]):
    case = vpcontact.load_case(EXAMPLES / "paper_ball.toml", {"output.field_steps": steps, "output.progress": False})
    data = case.model_dump(exclude_none=True)
    data["mesh"] = {"shape": "rectangle", "width": 1.0, "height": 1.0, "h": 1.0 / n}
    data["boundary"] = {"dirichlet": [{"part": "left", "components": ["x"]}],
                        "traction": [{"part": "top", "value": ["0", "-20*t"]}]}
    data["contact"] = {"part": "bottom", "gap": "max(x - 0.5, 0)", "g": 1e-3, "p": "positive_part",
                       "stiffness": {"law": "constant", "value": 0.0}, "probe": [0.0, 0.0]}
    return vpcontact.Case.model_validate(data)


CASES = {"paper": (paper_case, (1.0, -1.0)), "punch": (punch_case, (None,))}


def _solve(case):
    """(problem, result) of a run of ``case`` that completes (else SystemExit)."""
    problem = vpcontact.build_problem(case)
    result = vpcontact.solve(problem, output=case.output)
    if result.status != "complete":
        raise SystemExit(f"the run failed: {result.message}")
    return problem, result


def local_errors(level_mesh, reference_mesh, error_energy: np.ndarray) -> np.ndarray:
    """e_K² per element K of the level: the error energy of the reference elements whose centroid is in K."""
    centroids = reference_mesh.p[:, reference_mesh.t].mean(axis=1)
    owner = containing_elements(level_mesh.p, level_mesh.t, centroids)
    return np.bincount(owner, weights=error_energy, minlength=level_mesh.t.shape[1])


def study(name: str, levels: tuple[int, ...], reference: int, times: tuple[float, ...]) -> list[dict]:
    """The effectivity rows of one case: one per β, time and level."""
    make, betas = CASES[name]
    rows = []
    for beta in betas:
        grid = make(levels[0], beta, []).time  # every level's and the reference's: t_n = n T / steps
        steps = [int(round(t / grid.T * grid.steps)) for t in times]
        started = time.perf_counter()
        _, ref = _solve(make(reference, beta, steps))
        ref_time = time.perf_counter() - started
        ref_mesh = ref.discretization.mesh.mesh
        lame = ref.discretization.elasticity.lame
        for n in levels:
            started = time.perf_counter()
            problem, result = _solve(make(n, beta, steps))
            estimator = ResidualEstimator(problem)
            for t, step in zip(times, steps):
                indicators = estimator(Level.of(result, step, problem))
                mine = result.snapshot(step)
                theirs = ref.snapshot(step)
                moved = transfer(mine, theirs.points, theirs.elements)
                energy = element_energies(theirs.points, theirs.elements, moved.displacement - theirs.displacement, lame)
                local = local_errors(result.discretization.mesh.mesh, ref_mesh, energy)
                error = float(np.sqrt(energy.sum()))
                eta = indicators.total
                correlation = float(np.corrcoef(np.log(indicators.squared + 1e-300), np.log(local + 1e-300))[0, 1])
                rows.append({
                    "case": name, "beta": beta, "t": t, "step": step, "n": n, "h": 1.0 / n, "reference_n": reference,
                    "dofs": int(result.dofs), "estimate": eta, "error": error, "effectivity": eta / error,
                    "terms": {term: float(np.sqrt(values.sum())) for term, values in indicators.terms.items()},
                    "local_log_correlation": correlation,
                    "nodes_at_limit": int(result.series("nodes_at_limit", substeps=False)[step - 1]),
                    "solve_s": time.perf_counter() - started, "reference_solve_s": ref_time,
                    "_local": (result.discretization.mesh.mesh, indicators.squared, local),
                })
    return rows


def figure(rows: list[dict], out: Path) -> list[str]:
    """Per case: η_K against e_K on each level at the last time (first β), and the maps of the finest level."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    written = []
    for name in dict.fromkeys(row["case"] for row in rows):
        chosen = [r for r in rows if r["case"] == name]
        beta, t = chosen[0]["beta"], max(r["t"] for r in chosen)
        chosen = [r for r in chosen if r["beta"] == beta and r["t"] == t]
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
        for row in chosen:
            _, eta2, e2 = row["_local"]
            axes[0].loglog(np.sqrt(e2), np.sqrt(eta2), ".", ms=3, alpha=0.5, label=f"h = 1/{row['n']}")
        low = min(np.sqrt(r["_local"][2][r["_local"][2] > 0]).min() for r in chosen)
        high = max(np.sqrt(r["_local"][1]).max() for r in chosen)
        axes[0].loglog([low, high], [low, high], "k--", lw=0.8, label="η_K = e_K")
        axes[0].set_xlabel("element error e_K (energy, reference)")
        axes[0].set_ylabel("indicator η_K")
        axes[0].legend(fontsize=7)
        finest = chosen[-1]
        mesh, eta2, e2 = finest["_local"]
        triangulation = Triangulation(mesh.p[0], mesh.p[1], mesh.t.T)
        top = 0.5 * np.log10(max(e2.max(), eta2.max()))
        for ax, values, title in ((axes[1], e2, "log10 e_K"), (axes[2], eta2, "log10 η_K")):
            image = ax.tripcolor(triangulation, facecolors=0.5 * np.log10(values + 1e-300), cmap="viridis",
                                 vmin=top - 3, vmax=top)
            ax.set_aspect("equal")
            ax.set_title(f"{title}, h = 1/{finest['n']}")
            fig.colorbar(image, ax=ax, shrink=0.8)
        fig.suptitle(f"{name}: t = {t:g}" + ("" if beta is None else f", β = {beta:g}"))
        fig.tight_layout()
        path = out / f"effectivity_{name}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(str(path))
    return written


def table(rows: list[dict]) -> str:
    lines = [f"{'case':6} {'beta':>5} {'t':>4} {'h':>7} {'dofs':>7} {'eta':>10} {'error':>10} {'eff':>6} {'corr':>5}"]
    for r in rows:
        beta = "-" if r["beta"] is None else f"{r['beta']:g}"
        lines.append(f"{r['case']:6} {beta:>5} {r['t']:>4g} {'1/' + str(r['n']):>7} {r['dofs']:>7} {r['estimate']:>10.4g} "
                     f"{r['error']:>10.4g} {r['effectivity']:>6.3f} {r['local_log_correlation']:>5.2f}")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="coarse levels (seconds)")
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    parser.add_argument("--times", nargs="+", type=float, default=[0.5, 1.1])
    parser.add_argument("--out", type=Path, help="folder for the figures and effectivity.json")
    arguments = parser.parse_args(argv)
    setting = SETTINGS["quick" if arguments.quick else "full"]
    started = time.perf_counter()
    rows = [row for name in arguments.cases
            for row in study(name, setting["levels"], setting["reference"], tuple(arguments.times))]
    figures = []
    if arguments.out is not None:
        arguments.out.mkdir(parents=True, exist_ok=True)
        figures = figure(rows, arguments.out)
    bands = {}
    for name in arguments.cases:
        values = [r["effectivity"] for r in rows if r["case"] == name]
        bands[name] = {"min": min(values), "max": max(values), "ratio": max(values) / min(values)}
    report = {"levels": setting["levels"], "reference": setting["reference"], "times": arguments.times,
              "terms": TERMS, "rows": [{k: v for k, v in r.items() if not k.startswith("_")} for r in rows],
              "bands": bands, "figures": figures, "wall_time_s": time.perf_counter() - started}
    if arguments.out is not None:
        (arguments.out / "effectivity.json").write_text(json.dumps(report, indent=1))
    print(table(rows), file=sys.stderr)
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
