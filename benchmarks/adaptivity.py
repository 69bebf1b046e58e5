"""Adaptive against uniform refinement on the paper's example, or on a flat punch (--punch): prints JSON
(docs/adaptivity.md, "Measured on the paper's example" and "Measured on a flat punch").

For each β, examples/paper_ball.toml is solved on a uniform reference mesh (h = 1/512: 477,194 dofs), on the
uniform meshes h = 1/8 … 1/256 and in the adaptive cycles of [adapt] from h = 1/8, all on the example's own
time grid (k = 0.1, 11 steps): the same time steps everywhere, so the errors compared are spatial. A mesh
"h = 1/n" has the element edge √2/n, the paper's sizes (`vpcontact.reproduction.plan.level_overrides`: its 1/512
is the paper's 472k-dof reference). For every uniform level and adaptive cycle it reports the dofs, the
estimate of the chosen estimator ((Σ_K F_K)^½ with the time functional of [adapt]) and the errors against
the reference at t = 0.5 and 1.1, on the reference mesh (the solution interpolated at its nodes):

    E = ‖I_ref u_h − u_ref‖_E   the energy norm (∫ ℰε:ε, vpcontact.results.norms.element_energies),
    V = ‖ε(I_ref u_h − u_ref)‖   and Q = ‖Π_ref σ_h − σ_ref‖, the paper's norms (vpcontact.results.norms.differences).

The effectivity η(t) / E(t) of every uniform level and adaptive cycle (η(t) = (Σ_K η_K²(t))^½ of the chosen
estimator at that step) is reported twice for the cycles: against the uniform reference, and against a nested
reference, the last cycle's mesh with at most --nested-max-dofs dofs refined uniformly twice (so four times finer
than every cycle up to it, everywhere: the uniform reference is coarser than the last cycles' meshes at the singular
point (1, 1), and misses their error there; docs/adaptivity.md, "The effectivity on adaptive meshes").

The adaptive cycles go on until the next mesh would have more than twice the dofs of the uniform 1/256 mesh
(or --cycles), so that the adaptive curve passes that mesh's dofs. The target is that mesh's error: for
each error the script reports the dofs the adaptive method needs to reach the target, interpolated linearly
in log error against log dofs between the two cycles around it, and its ratio to the uniform mesh's dofs
("target"; "reach": the same for every uniform level), and the convergence rates in dofs (least-squares
slopes of log error against log dofs over the meshes with at least the dofs of the uniform 1/32 mesh, all of
them without it in --levels; −1/2 is first order in h). The last adaptive mesh's element sizes are summarized
by region. With --out DIR it writes the JSON and a log–log figure of error against
dofs (DIR/adaptivity_<estimator>.png).

Then one run that adapts during the run (adapt.mode = "run", docs/adaptivity.md "Adapting during the run") for each
of --run-tolerances, from h = 1/--start: its last mesh's dofs, the steps it refined at, its errors against both
references, its wall time and that of one run on its last mesh (build and solve, the same outputs; in the same
process, after the other runs: no import is timed), their ratio, and the dofs it needs to reach each uniform
mesh's error ("run_nested_reach", interpolated between the tolerances' runs as for the cycles).

    python benchmarks/adaptivity.py --out docs/figures          # β = 1 and −1, residual estimator
    python benchmarks/adaptivity.py --estimator recovery --beta 1
    python benchmarks/adaptivity.py --punch --out docs/figures    # the punch of benchmarks/effectivity.py

The punch (benchmarks/effectivity.py: the unit square pressed onto a flat rigid punch under half its bottom, the
pressure growing like r^(−1/2) at the punch's edge) runs on the same time grid, its meshes with h = 1/n, and writes
adaptivity_punch_<estimator>.json and .png.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from dataclasses import dataclass

import numpy as np

import vpcontact
from vpcontact import adapt
from vpcontact.case.translate import adapt_options, output_options
from vpcontact.adaptivity.cycles import solve_and_estimate
from vpcontact.estimate.estimators import ESTIMATORS
from vpcontact.estimate.indicators import Level
from vpcontact.mesh.refinement import refine
from vpcontact.results.norms import differences, element_energies, transfer
from vpcontact import build_problem
from vpcontact.mesh.simplex import determinants
from vpcontact.reproduction.plan import level_overrides
from vpcontact.reproduction.records import dofs_reaching

from effectivity import punch_case

CASE = Path(__file__).resolve().parent.parent / "examples" / "paper_ball.toml"
TIMES = {5: 0.5, 11: 1.1}  # step → t on the example's grid
ERRORS = ("E(0.5)", "E(1.1)", "V(0.5)", "V(1.1)", "Q(0.5)", "Q(1.1)")
RATE_FROM = 32  # the rates are fitted over the meshes with at least the dofs of the uniform 1/32 mesh (all without it)


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


@dataclass(frozen=True)
class Example:
    """A problem compared: the paper's example with the layer's ``beta``, or (``beta`` None) the flat rigid punch of
    benchmarks/effectivity.py (the unit square, r^(−1/2) at the punch's edge), both on the paper's 11 steps."""

    beta: float | None

    @property
    def label(self) -> str:
        return "the punch" if self.beta is None else f"β = {self.beta:g}"

    @property
    def singular_point(self) -> tuple[float, float]:
        """Where the stress is singular: the end of Γ3 at (1, 1), or the punch's edge at (1/2, 0)."""
        return (0.5, 0.0) if self.beta is None else (1.0, 1.0)

    def load(self, level: int, settings: dict):
        """The example at h = 1/level (the paper's: element edge √2/level; the punch's square: h = 1/level), its
        fields kept at the compared steps, with [adapt] ``settings``."""
        if self.beta is None:
            data = punch_case(level, None, list(TIMES)).model_dump(exclude_none=True)
            return vpcontact.Case.model_validate({**data, "adapt": settings} if settings else data)
        return vpcontact.load_case(CASE, {"mesh.h": level_overrides(level)["mesh.h"], "contact.stiffness.beta": self.beta,
                                          "output.field_steps": list(TIMES), "output.progress": False,
                                          **{f"adapt.{key}": value for key, value in settings.items()}})


def complete(result):
    if result.status != "complete":
        raise SystemExit(f"the run failed: {result.message}")
    return result


class Reference:
    """The reference solution's snapshots at the compared steps, and the errors of a run against them."""

    def __init__(self, result):
        self.snapshots = {step: result.snapshot(step) for step in TIMES}
        self.lame = result.discretization.elasticity.lame

    def errors(self, result) -> dict[str, float]:
        found = {}
        for step, t in TIMES.items():
            theirs = self.snapshots[step]
            moved = transfer(result.snapshot(step), theirs.points, theirs.elements)
            energy = element_energies(theirs.points, theirs.elements, moved.displacement - theirs.displacement,
                                      self.lame)
            norms = differences(moved, theirs)
            found |= {f"E({t})": float(np.sqrt(energy.sum())), f"V({t})": norms["V"], f"Q({t})": norms["Q"]}
        return found


def estimates(result, example: Example, estimator: str) -> dict[str, float]:
    """η(t) = (Σ_K η_K²(t))^½ of ``estimator`` at the compared steps of ``result`` (a run of the example on its mesh)."""
    problem = build_problem(example.load(8, {}), mesh=result.discretization.mesh)
    prepared = ESTIMATORS[estimator].prepare(problem)
    return {f"eta({t})": float(np.sqrt(prepared(Level.of(result, step, problem)).squared.sum()))
            for step, t in TIMES.items()}


def effectivities(eta: dict[str, float], errors: dict[str, float]) -> dict[str, float]:
    """η(t) / E(t) at the compared times."""
    return {f"effectivity({t})": eta[f"eta({t})"] / errors[f"E({t})"] for t in TIMES.values()}


def nested_reference(cycles: list, example: Example, most: int) -> tuple[dict, "Reference"]:
    """The last of the adaptive ``cycles`` (their runs) with at most ``most`` dofs, its mesh refined uniformly twice
    and the example solved there: (its description, the reference)."""
    chosen = [c for c in cycles if c.dofs <= most][-1]
    mesh = chosen.discretization.mesh
    for _ in range(2):
        mesh = refine(mesh, np.arange(mesh.mesh.t.shape[1]))
    started = time.perf_counter()
    run = complete(vpcontact.solve(build_problem(example.load(8, {}), mesh=mesh), output={"field_steps": list(TIMES)}))
    described = {"from_cycle": cycles.index(chosen) + 1, "dofs": int(run.dofs), "solve_s": time.perf_counter() - started}
    return described, Reference(run)


def run_adaptive(example: Example, args, tolerance: float, reference: Reference, finer: Reference,
                 settings: dict) -> dict:
    """One run that adapts its mesh during the run (adapt.mode = "run", ``tolerance``) from h = 1/--start: its last
    mesh's dofs, refinements, errors against both references, wall time, and the wall time of one run on its last
    mesh (build and solve, the same outputs); the two timed in turn --time-repeat times, the least of each and the
    median of the pairs' ratios (pairs keep the ratio meaningful while the machine's speed drifts)."""
    case = example.load(args.start, {})
    passes, plains = [], []
    for _ in range(args.time_repeat):
        started = time.perf_counter()
        adaptation = adapt(build_problem(case), {"mode": "run", "tolerance": tolerance, "theta": settings["theta"],
                                                 "estimator": settings["estimator"]}, case.output)
        passes.append(time.perf_counter() - started)
        result = complete(adaptation.result)
        started = time.perf_counter()
        complete(vpcontact.solve(build_problem(case, mesh=adaptation.mesh), output=case.output))
        plains.append(time.perf_counter() - started)
    seconds, plain = min(passes), min(plains)
    row = {"tolerance": tolerance, "dofs": int(result.dofs), "contact_nodes": int(result.contact_nodes),
           "refinements": adaptation.refinements, "refined_at_steps": sorted({r["step"] for r in adaptation.rows
                                                                            if r["refined"]}),
           "estimate": max(r["estimate"] for r in adaptation.rows if not r["refined"]),
           "errors": reference.errors(result), "nested_errors": finer.errors(result), "wall_time_s": seconds,
           "one_run_on_last_mesh_s": plain,
           "time_ratio": float(np.median(np.array(passes) / np.array(plains))), "time_repeat": args.time_repeat,
           "last_mesh": where_fine(adaptation.mesh, example.singular_point)}
    log(f"  run-adaptive, tolerance {tolerance:g}: {row['dofs']} dofs ({row['refinements']} refinements at steps "
        f"{row['refined_at_steps']}), E(1.1) {row['nested_errors']['E(1.1)']:.4g} against the nested reference, "
        f"{seconds:.2f} s, {row['time_ratio']:.2f}× one run on its last mesh ({plain:.2f} s)")
    return row


def rates(rows: dict[str, list[dict]], least: int) -> dict:
    """The convergence rates in dofs of each error and of the estimate, for each kind of ``rows`` (uniform,
    adaptive), over the rows with at least ``least`` dofs."""
    found = {"from_dofs": least}
    for kind, chosen in rows.items():
        dofs = [r["dofs"] for r in chosen]
        found[kind] = {name: rate(dofs, [r["errors"][name] for r in chosen], least) for name in ERRORS}
        found[kind]["estimate"] = rate(dofs, [r["estimate"] for r in chosen], least)
    return found


def reach(uniform: dict, cycles: list[dict]) -> dict:
    """For each error: the uniform mesh's, the dofs the adaptive cycles need to reach it
    (`vpcontact.reproduction.records.dofs_reaching`; None if no cycle does) and their ratio to the uniform mesh's dofs."""
    found = {"uniform_level": uniform["level"], "uniform_dofs": uniform["dofs"], "errors": {}}
    for name in ERRORS:
        target = uniform["errors"][name]
        needed = dofs_reaching([c["dofs"] for c in cycles], [c["errors"][name] for c in cycles], target)
        needed = None if math.isnan(needed) else needed
        found["errors"][name] = {"uniform_error": target, "adaptive_dofs": needed,
                                 "ratio": None if needed is None else needed / uniform["dofs"]}
    return found


def rate(dofs: list[int], errors: list[float], least: int) -> float | None:
    """The least-squares slope of log error against log dofs over the entries with at least ``least`` dofs."""
    chosen = [(np.log(n), np.log(e)) for n, e in zip(dofs, errors) if n >= least]
    if len(chosen) < 2:
        return None
    x, y = np.array(chosen).T
    return float(np.polyfit(x, y, 1)[0])


def where_fine(mesh, point: tuple[float, float]) -> dict:
    """The median and least element size (√(2|K|), about the edge) in bands of height and near the singular
    ``point``."""
    size = np.sqrt(2.0 * np.abs(determinants(mesh.mesh.p, mesh.mesh.t)))
    x, y = mesh.centroids
    bands = {f"y in [{low}, {high})": (y >= low) & (y < high)
             for low, high in ((0.0, 0.1), (0.1, 0.3), (0.3, 0.6), (0.6, 1.0), (1.0, 2.0))}
    bands[f"within 0.05 of ({point[0]:g}, {point[1]:g})"] = np.hypot(x - point[0], y - point[1]) < 0.05
    return {name: {"elements": int(inside.sum()), "median_size": float(np.median(size[inside])),
                   "min_size": float(size[inside].min())} for name, inside in bands.items() if inside.any()}


def study(example: Example, args) -> dict:
    """Reference, uniform levels and adaptive cycles for one example."""
    settings = {"cycles": args.cycles, "theta": args.theta, "functional": args.functional,
                "estimator": args.estimator}
    started = time.perf_counter()
    reference_run = complete(vpcontact.solve(example.load(args.reference, {})))
    reference = Reference(reference_run)
    found = {"beta": example.beta, "example": example.label,
             "reference": {"level": args.reference, "dofs": int(reference_run.dofs),
                           "solve_s": time.perf_counter() - started}}
    log(f"{example.label}: reference h = 1/{args.reference}, {reference_run.dofs} dofs, "
        f"{found['reference']['solve_s']:.1f} s")
    del reference_run

    found["uniform"], uniform_runs = [], []
    for level in args.levels:
        started = time.perf_counter()
        case = example.load(level, settings)
        result, functional = solve_and_estimate(build_problem(case), adapt_options(case.adapt),
                                                output_options(case.output))
        row = {"level": level, "dofs": int(complete(result).dofs), "contact_nodes": int(result.contact_nodes),
               "estimate": float(np.sqrt(functional.sum())), "errors": reference.errors(result),
               "wall_time_s": time.perf_counter() - started, **estimates(result, example, args.estimator)}
        row |= effectivities(row, row["errors"])
        found["uniform"].append(row)
        uniform_runs.append(result)
        log(f"  uniform 1/{level}: {row['dofs']} dofs, estimate {row['estimate']:.4g}, "
            + ", ".join(f"{name} {value:.4g}" for name, value in row["errors"].items()))
    last = found["uniform"][-1]

    found["adaptive"], runs = [], []

    def report(cycle) -> None:
        row = {**cycle.row, "errors": reference.errors(complete(cycle.result)),
               **estimates(cycle.result, example, args.estimator)}
        row |= effectivities(row, row["errors"])
        found["adaptive"].append(row)
        runs.append(cycle.result)
        log(f"  cycle {row['cycle']}: {row['dofs']} dofs, estimate {row['estimate']:.4g}, "
            + ", ".join(f"{name} {value:.4g}" for name, value in row["errors"].items()) + f", {row['wall_time_s']:.1f} s")

    case = example.load(args.start, {**settings, "max_dofs": 2 * last["dofs"]})
    adaptation = adapt(build_problem(case), case.adapt, case.output, after_cycle=report)
    found["stopped"] = adaptation.message
    log(f"  {found['stopped']}")
    found["nested_reference"], finer = nested_reference(runs, example, args.nested_max_dofs)
    log(f"  nested reference: cycle {found['nested_reference']['from_cycle']} refined twice, "
        f"{found['nested_reference']['dofs']} dofs, {found['nested_reference']['solve_s']:.1f} s")
    compared = found["adaptive"][:found["nested_reference"]["from_cycle"]]
    for row, run in [*zip(found["uniform"], uniform_runs), *zip(compared, runs)]:
        row["nested_errors"] = finer.errors(run)
        row["nested_effectivity"] = effectivities(row, row["nested_errors"])
        log(f"  {row['dofs']} dofs: E(1.1) {row['nested_errors']['E(1.1)']:.4g} against the nested reference, "
            f"effectivity {row['effectivity(1.1)']:.2f} against the uniform reference, "
            f"{row['nested_effectivity']['effectivity(1.1)']:.2f} against the nested one")
    runs.clear()  # the runs' fields: no longer needed
    uniform_runs.clear()

    found["run_adaptive"] = [run_adaptive(example, args, tolerance, reference, finer, settings)
                             for tolerance in args.run_tolerances]
    del finer
    cycles = found["adaptive"]
    found["reach"] = [reach(uniform, cycles) for uniform in found["uniform"]]
    found["target"] = found["reach"][-1]
    least = min((u["dofs"] for u in found["uniform"] if u["level"] >= RATE_FROM), default=0)
    found["rates"] = rates({"uniform": found["uniform"], "adaptive": cycles}, least)

    def nested_rows(rows: list[dict]) -> list[dict]:
        return [{**row, "errors": row["nested_errors"]} for row in rows if "nested_errors" in row]

    nested = {"uniform": nested_rows(found["uniform"]), "adaptive": nested_rows(cycles)}
    found["nested_reach"] = [reach(uniform, nested["adaptive"]) for uniform in nested["uniform"]]
    found["nested_rates"] = rates(nested, least)
    passes = sorted(found["run_adaptive"], key=lambda row: row["dofs"])
    found["run_nested_reach"] = [reach(uniform, nested_rows(passes)) for uniform in nested["uniform"]]
    found["run_rates"] = rates({"run_adaptive": nested_rows(passes)}, least) if len(passes) > 1 else None
    found["last_mesh"] = where_fine(adaptation.mesh, example.singular_point)
    return found


def figure(studies: list[dict], estimator: str, path: Path) -> Path:
    """The energy error E(1.1) against the uniform and the nested reference, and the estimate, against dofs, uniform
    and adaptive, log–log, one panel per example."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(studies), figsize=(6.2 * len(studies), 4.6), squeeze=False)
    for ax, found in zip(axes[0], studies):
        for kind, marker in (("uniform", "o-"), ("adaptive", "s-")):
            rows = found[kind]
            dofs = [r["dofs"] for r in rows]
            ax.loglog(dofs, [r["errors"]["E(1.1)"] for r in rows], marker, ms=4, alpha=0.5,
                      label=f"{kind}: E(1.1), uniform reference")
            nested = [r for r in rows if "nested_errors" in r]
            ax.loglog([r["dofs"] for r in nested], [r["nested_errors"]["E(1.1)"] for r in nested], marker, ms=4, lw=2,
                      label=f"{kind}: E(1.1), nested reference")
            ax.loglog(dofs, [r["estimate"] for r in rows], marker.replace("-", ":"), ms=3, alpha=0.6,
                      label=f"{kind}: estimate ({estimator})")
        passes = sorted(found.get("run_adaptive", []), key=lambda row: row["dofs"])
        if passes:
            ax.loglog([r["dofs"] for r in passes], [r["nested_errors"]["E(1.1)"] for r in passes], "^-", ms=5, lw=2,
                      label="run-adaptive (adapt.mode = \"run\"): E(1.1), nested reference")
        target = found["target"]
        ax.axhline(target["errors"]["E(1.1)"]["uniform_error"], color="grey", lw=0.7, ls="--",
                   label=f"uniform 1/{target['uniform_level']} error")
        ax.set_xlabel("dofs")
        ax.set_ylabel("energy norm")
        ax.set_title(f"{found['example']}: uniform 1/{found['reference']['level']} and nested "
                     f"({found['nested_reference']['dofs']:,} dofs) references")
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--beta", type=float, nargs="+", default=[1.0, -1.0], help="the paper's example's β")
    parser.add_argument("--punch", action="store_true", help="the flat punch instead of the paper's example")
    parser.add_argument("--estimator", choices=("residual", "recovery"), default="residual")
    parser.add_argument("--functional", choices=("max", "l2"), default="max")
    parser.add_argument("--theta", type=float, default=0.5)
    parser.add_argument("--reference", type=int, default=512, help="1/h of the uniform reference mesh")
    parser.add_argument("--levels", type=int, nargs="+", default=[8, 16, 32, 64, 128, 256],
                        help="1/h of the uniform meshes; the last one's errors are the adaptive target")
    parser.add_argument("--start", type=int, default=8, help="1/h of the first adaptive mesh")
    parser.add_argument("--cycles", type=int, default=30, help="at most this many adaptive cycles")
    parser.add_argument("--nested-max-dofs", type=int, default=100_000,
                        help="the nested reference refines the last cycle's mesh with at most this many dofs twice")
    parser.add_argument("--run-tolerances", type=float, nargs="*", default=[0.2, 0.1, 0.07, 0.05, 0.035],
                        help="adapt.tolerance of the runs that adapt during the run (adapt.mode = \"run\")")
    parser.add_argument("--time-repeat", type=int, default=3,
                        help="each run that adapts during the run and one run on its last mesh timed in turn this many "
                             "times (default 3)")
    parser.add_argument("--out", type=Path, help="write adaptivity_<estimator>.json and .png there")
    args = parser.parse_args()
    if args.reference <= max(args.levels):
        parser.error(f"--reference 1/{args.reference} must be finer than the finest uniform level 1/{max(args.levels)}")

    started = time.perf_counter()
    examples = [Example(None)] if args.punch else [Example(beta) for beta in args.beta]
    studies = [study(example, args) for example in examples]
    report = {"case": "punch (benchmarks/effectivity.py)" if args.punch else "examples/paper_ball.toml",
              "time_steps": 11, "times": list(TIMES.values()),
              "estimator": args.estimator, "functional": args.functional, "theta": args.theta,
              "mesh_convention": "h = 1/n: the mesh's h" if args.punch else
              "h = 1/n: element edge √2/n (vpcontact.reproduction.plan.level_overrides)",
              "studies": studies, "wall_time_s": time.perf_counter() - started}
    text = json.dumps(report, indent=1)
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        name = f"adaptivity_{'punch_' if args.punch else ''}{args.estimator}"
        (args.out / f"{name}.json").write_text(text + "\n")
        log(f"wrote {figure(studies, args.estimator, args.out / f'{name}.png')}")


if __name__ == "__main__":
    main()
