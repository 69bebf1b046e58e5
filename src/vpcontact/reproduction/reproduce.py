"""Every numerical result of Sect. 4 of the paper, regenerated: the runs, the measurements, the claims.

    vpcontact reproduce --out DIR [--quick]

The runs are a plain list, in the order of the paper:

- Figs. 2–7: the four contact conditions (β = 1; β = −1; α = 0, g = 0.2; α = 0, g = 2000) on the
  calibrated example, with k = 0.1 (the paper's data, N = 11) and with k ≈ 1/128 (what its Sect. 4.3
  says the figures used), solved in this process (`CONTACT_CONDITIONS`, `figure_cases`);
- the load: the printed load (1000 t N/m) for β = ±1 and ρ = 0.01, and the load recalibrated for
  k ≈ 1/128 (`load_cases`, `calibrate`);
- Figs. 8, 9: the study ρ = 1, …, 1e−6 against K ≡ 0 (`rho_study_text`, run by `studies.run_study`);
- Fig. 10: the study h = k = 1/4, …, 1/256 against 1/512 (`hk_study_text`, `studies.run_study`);
- beyond the paper: the rates in h alone and in k alone (`h_study_text`, `k_study_text`, `rate_record`), the
  residual error estimate's effectivity, and adaptive meshes against uniform ones (`adaptive_record`).

Each run writes the standard outputs under DIR/cases/ or DIR/studies/ (a study can be rerun with
``vpcontact study DIR/studies/NAME.toml --out DIR/studies/NAME``). `run` measures what the paper
states (`assess`), draws the figures (:mod:`.figures`) and writes DIR/reproduce.json and the
report (:mod:`.report`).
"""

from __future__ import annotations

import csv
import json
import math
import multiprocessing
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable

import numpy as np
import tomli_w

from .. import __version__, directory, writers
from ..case import load_case
from ..norms import differences
from ..writers import json_safe

#: The paper's example with the calibrated load: the content of examples/paper_ball.toml (a test
#: checks that the two resolve to the same case), carried by the package so that `reproduce` does not
#: depend on a source checkout.
PAPER_CASE = """\
# The paper's example (Barboteu, Han, Sofonea, Sect. 4.1), load calibrated (README, "The paper's load").
[mesh]
shape = "half_disc"
h = 0.0125

[material]
E = 1000.0
nu = 0.3
hypothesis = "plane_strain"

[[boundary.dirichlet]]
part = "axis"
components = ["x"]

[[boundary.traction]]
part = "top_arc"
value = ["0", "-17.977*t"]

[contact]
part = "bottom_arc"
g = 0.2
p = "positive_part"
rho = 1.0
probe = [0.0, 0.0]

[contact.stiffness]
law = "power"
c_v = 100.0
alpha = 20.0
beta = 1.0

[time]
T = 1.1
steps = 11

[solver]
method = "auto"

[output]
field_steps = [2, 5, 8, 11]
"""
PRINTED_LOAD = 1000.0
"""N/m: the magnitude of f2 printed in the paper (Sect. 4.1)."""
CALIBRATED_LOAD = 17.977
"""N/m: the magnitude in PAPER_CASE, calibrated so that β = 1 gives K = 323 at the bottom point at t = 1.1."""
T = 1.1
FIGURE_TIMES = (0.2, 0.5, 0.8, 1.1)
"""The times of the paper's Figs. 2 and 3 (steps 2, 5, 8, 11 with k = 0.1)."""
PAPER = {
    "K_hardening": 323.0,
    "K_softening": 21.0,
    "c_v": 100.0,
    "g": 0.2,
    "dofs_512": 472_074,
    "elements_512": 470_252,
    "figure_elements": 30_808,
    "figure_contact_edges": 128,
}
"""The numbers the paper states in Sect. 4."""

CONTACT_CONDITIONS = {
    "beta+1": ("β = 1 (hardening)", {"contact.stiffness.beta": 1.0}),
    "beta-1": ("β = −1 (softening)", {"contact.stiffness.beta": -1.0}),
    "alpha0_g0.2": ("α = 0, g = 0.2 m (normal compliance + unilateral constraint)", {"contact.stiffness.alpha": 0.0}),
    "alpha0_g2000": ("α = 0, g = 2000 m (normal compliance)", {"contact.stiffness.alpha": 0.0, "contact.g": 2000.0}),
}
"""The four contact conditions of Figs. 5–7: name -> (label, overrides of the paper case)."""
SHORT_LABELS = {
    "beta+1": "β = 1",
    "beta-1": "β = −1",
    "alpha0_g0.2": "α = 0, g = 0.2 m",
    "alpha0_g2000": "α = 0, g = 2000 m",
}


def _load(c: float) -> dict:
    return {"boundary.traction[0].value": ["0", f"-{c!r}*t"]}


@dataclass(frozen=True)
class Plan:
    """The sizes of a reproduction: the full one, or the coarse `--quick` one."""

    quick: bool
    figure_h: float
    """Element size of the mesh of Figs. 2–9 (the example's 0.0125; quick: 0.05)."""
    steps_coarse: int = 11
    """k = 0.1: the paper's data (N = 11)."""
    steps_fine: int = 141
    """k = 1.1/141 ≈ 1/128 (1.1·128 = 140.8 is not an integer; the h–k study rounds the same way)."""
    rho: tuple = (1.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
    fig9_rho: tuple = (1.0, 1e-1, 1e-2, 1e-3)
    levels: tuple = (4, 8, 16, 32, 64, 128, 256)
    """h = k = 1/level: the levels compared with the reference."""
    reference_level: int = 512
    h_levels: tuple = (4, 8, 16, 32, 64)
    """The rate in h alone: h = 1/level, every level and the reference with ``h_steps`` steps."""
    h_reference_level: int = 256
    h_steps: int = 35
    k_steps: tuple = (4, 9, 18, 35, 70, 141)
    """The rate in k alone: k = 1.1/steps, every run and the reference on the mesh of ``k_level``."""
    k_reference_steps: int = 563
    k_level: int = 32
    adapt_level: int = 8
    """Adaptive meshes from h = 1/adapt_level, on the rate in h's time grid and against its reference."""
    adapt_cycles: int = 12
    adapt_max_dofs: int = 20_000

    @property
    def mode(self) -> str:
        return "quick" if self.quick else "full"


def make_plan(quick: bool) -> Plan:
    if quick:
        return Plan(True, figure_h=0.05, rho=(1.0, 1e-1, 1e-2, 1e-3, 1e-4), levels=(4, 8, 16, 32), reference_level=64,
                    h_levels=(4, 8, 16), h_reference_level=64, h_steps=9, k_steps=(4, 9, 18, 35),
                    k_reference_steps=141, k_level=16, adapt_level=4, adapt_cycles=6, adapt_max_dofs=1_500)
    return Plan(False, figure_h=0.0125)


@dataclass(frozen=True)
class CaseSpec:
    """One run solved in this process: its name (a directory under DIR/cases), label and overrides."""

    name: str
    label: str
    overrides: dict
    group: str


def figure_cases(plan: Plan) -> list[CaseSpec]:
    """Figs. 2–7: the four contact conditions, with k = 0.1 (fields at t = 0.2, 0.5, 0.8, 1.1) and k ≈ 1/128."""
    specs = []
    for steps, suffix in ((plan.steps_coarse, "k0.1"), (plan.steps_fine, "k1_128")):
        fields = [round(t / (T / steps)) for t in FIGURE_TIMES] if steps == plan.steps_coarse else "final"
        for name, (label, overrides) in CONTACT_CONDITIONS.items():
            specs.append(
                CaseSpec(
                    f"{name}_{suffix}",
                    label,
                    {"mesh.h": plan.figure_h, "time.steps": steps, "output.field_steps": fields, **overrides},
                    suffix,
                )
            )
    return specs


def load_cases(plan: Plan) -> list[CaseSpec]:
    """The printed load 1000 t N/m, k = 0.1: β = ±1 (against Figs. 2–4) and ρ = 0.01 (against Fig. 9)."""
    common = {
        "mesh.h": plan.figure_h,
        "time.steps": plan.steps_coarse,
        "output.field_steps": "final",
        **_load(PRINTED_LOAD),
    }
    return [
        CaseSpec("printed_beta+1", "printed load, β = 1", {**common, "contact.stiffness.beta": 1.0}, "printed"),
        CaseSpec("printed_beta-1", "printed load, β = −1", {**common, "contact.stiffness.beta": -1.0}, "printed"),
        CaseSpec("printed_rho0.01", "printed load, β = 1, ρ = 0.01", {**common, "contact.rho": 0.01}, "printed"),
    ]


def rho_study_text(plan: Plan) -> str:
    """Figs. 8, 9: K_ρ = ρK for each ρ against K ≡ 0 (the Signorini problem with gap g), at t = 1.1."""
    lines = [
        "# Figs. 8 and 9 of the paper, written by `vpcontact reproduce`.",
        'base = "../cases/paper_ball.toml"',
        "",
        "[set]",
        f'"mesh.h" = {plan.figure_h!r}',
        f'"time.steps" = {plan.steps_coarse}',
        '"output.field_steps" = "final"',
        "",
    ]
    for rho in plan.rho:
        lines += ["[[runs]]", f'id = "rho={rho:g}"', f'"contact.rho" = {rho!r}', ""]
    lines += [
        "[[runs]]",
        'id = "signorini"',
        '"contact.stiffness" = { law = "constant", value = 0.0 }',
        "",
        "[compare]",
        'reference = "signorini"',
        f"times = [{T!r}]",
        "",
    ]
    return "\n".join(lines)


def level_overrides(level: int) -> dict:
    """h = 1/level: element edge √2·h (the paper's sizes), steps = round(1.1/h) (benchmarks/scaling.py)."""
    h = 1.0 / level
    return {"mesh.h": math.sqrt(2.0) * h, "time.steps": round(T / h)}


def convergence_study_text(title: str, runs: list[tuple[str, dict]], settings: dict | None = None) -> str:
    """A study of the paper case's runs (id, overrides), each compared at t = 1.1 with the first one,
    the reference; ``settings``: overrides of every run. The reference is listed first: the longest run
    starts at once, and the other workers run the others meanwhile (listed last, it ran alone after them)."""
    common = {"output.field_steps": "final", **(settings or {})}
    lines = [f"# {title}, written by `vpcontact reproduce`.", 'base = "../cases/paper_ball.toml"', "", "[set]",
             *(f'"{key}" = {_toml(value)}' for key, value in common.items()), ""]
    for run_id, overrides in runs:
        lines += ["[[runs]]", f'id = "{run_id}"', *(f'"{key}" = {_toml(value)}' for key, value in overrides.items()),
                  ""]
    lines += ["[compare]", f'reference = "{runs[0][0]}"', f"times = [{T!r}]", ""]
    return "\n".join(lines)


def _toml(value) -> str:
    """A value as TOML writes it."""
    return tomli_w.dumps({"value": value}).partition("=")[2].strip()


def hk_study_text(plan: Plan) -> str:
    """Fig. 10: ‖u − u^{hk}‖_V at t = 1.1 for h = k = 1/level against the reference level."""
    return convergence_study_text("Fig. 10 of the paper", [(_level_id(level, plan), level_overrides(level))
                                                           for level in (plan.reference_level, *plan.levels)])


def h_study_text(plan: Plan) -> str:
    """The error in h alone: h = 1/level against 1/h_reference_level, all with the same time steps and
    the residual error estimate (the effectivity of the estimator: the spatial error of one time grid)."""
    levels = (plan.h_reference_level, *plan.h_levels)
    return convergence_study_text(
        f"The rate in h and the estimator's effectivity: every run with {plan.h_steps} time steps",
        [(f"h=1_{level}", {"mesh.h": level_overrides(level)["mesh.h"], "time.steps": plan.h_steps}) for level in levels],
        {"output.error_estimate": True})


def k_study_text(plan: Plan) -> str:
    """The error in k alone: k = 1.1/steps against k_reference_steps, all on the mesh of 1/k_level."""
    h = level_overrides(plan.k_level)["mesh.h"]
    return convergence_study_text(
        f"The rate in k: every run on the mesh of h = 1/{plan.k_level}",
        [(f"steps={steps}", {"mesh.h": h, "time.steps": steps}) for steps in (plan.k_reference_steps, *plan.k_steps)])


def _level_id(level: int, plan: Plan) -> str:
    return f"reference-1_{level}" if level == plan.reference_level else f"h=1_{level}"


# --- running -------------------------------------------------------------------------------------
class ReproduceError(RuntimeError):
    """A run of the reproduction failed."""


class OutputError(ValueError):
    """--out cannot be used (nothing was run)."""


def clock() -> tuple[float, float, float]:
    """Now: wall time, CPU time of this process, CPU time of its ended child processes (s)."""
    cpu = os.times()
    return time.perf_counter(), cpu.user + cpu.system, cpu.children_user + cpu.children_system


@dataclass
class Timer:
    """Wall time and CPU time of the named parts of the reproduction. A part's CPU time is this
    process's; the study workers' CPU time is known once their pool has closed (`totals`)."""

    started: tuple = field(default_factory=clock)
    wall: dict = field(default_factory=dict)
    cpu: dict = field(default_factory=dict)

    def part(self, name: str, began: tuple) -> str:
        """Record part ``name``, begun at ``began`` (a `clock()`); returns its times as text."""
        now = clock()
        self.wall[name], self.cpu[name] = now[0] - began[0], now[1] - began[1]
        return f"{self.wall[name]:.1f} s (CPU {self.cpu[name]:.1f} s)"

    def totals(self) -> tuple[dict, dict]:
        """(wall time, CPU time) of the parts and in total since the start; the CPU time also
        has the study workers' ("study workers")."""
        now = clock()
        workers = now[2] - self.started[2]
        wall = {**self.wall, "total": now[0] - self.started[0]}
        cpu = {**self.cpu, "study workers": workers, "total": now[1] - self.started[1] + workers}
        return wall, cpu


RUN_FOLDERS = ("cases/*", "studies/*/runs/*")
"""Where `run` keeps its runs (each a run directory: writers.OUTPUTS)."""
OUTPUTS = (*[f"{folder}/{name}" for folder in (*RUN_FOLDERS, "studies/*")
             for name in (*writers.OUTPUTS, *writers.TEMPORARIES, directory.LOCK)],
           "cases/paper_ball.toml", "studies/*.toml", "studies/*/study.csv", "studies/*/.study.tmp-[0-9]*.csv",
           "figures/fig[0-9][0-9].png", "figures/fig[0-9][0-9].pdf", "report.md", "report.html", "reproduce.json")
"""What `run` writes in DIR, as glob patterns: overwrite=True removes these (and the folders that this
leaves empty), nothing else."""


def prepare(out: Path, overwrite: bool) -> None:
    """Refuse a non-empty DIR unless overwrite; with overwrite remove only what `run` writes."""
    if out.exists() and not out.is_dir():
        raise OutputError(f"--out '{out}' exists and is not a directory")
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise OutputError(f"--out '{out}' is not empty (use --overwrite to replace its reproduction)")
        writers.remove_files(out, OUTPUTS)
    out.mkdir(parents=True, exist_ok=True)


def run(
    out: str | os.PathLike,
    *,
    quick: bool = False,
    workers: int | None = None,
    overwrite: bool = False,
    log: Callable[[str], None] = print,
) -> dict:
    """The whole reproduction into ``out``; returns the content of reproduce.json."""
    from . import figures, report

    timer = Timer()
    out = Path(out)
    prepare(out, overwrite)
    plan = make_plan(quick)
    (out / "cases").mkdir()
    base = out / "cases" / "paper_ball.toml"
    base.write_text(PAPER_CASE, encoding="utf-8")
    data = {
        "vpcontact_version": __version__,
        "mode": plan.mode,
        "started": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "machine": machine(),
        "settings": settings(plan),
        "paper": PAPER,
    }
    workers = workers or os.cpu_count() or 1

    context = multiprocessing.get_context("spawn")  # the MKL threads of this process are not fork-safe
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as executor:
        log(f"reproduce ({plan.mode}): Figs. 2–7, the four contact conditions with k = 0.1 and k ≈ 1/128, and in "
            f"{workers} workers beside them the printed load and the load recalibrated for k ≈ 1/128 ...")
        t0 = clock()
        printed = {spec.name: executor.submit(recorded_case, base, spec, out / "cases" / spec.name)
                   for spec in load_cases(plan)}
        calibration = executor.submit(calibrate, base, plan)
        specs = figure_cases(plan)
        results = {spec.name: solve_case(base, spec, out / "cases" / spec.name) for spec in specs}
        data["cases"] = {spec.name: case_record(spec, results[spec.name]) for spec in specs}
        frames = figure_frames(results, plan)
        log(f"  {timer.part('Figs. 2–7: contact conditions (8 runs)', t0)}")
        t0 = clock()
        data["cases"].update({name: future.result() for name, future in printed.items()})
        data["calibration"] = {
            "printed_load": PRINTED_LOAD,
            "calibrated_load": CALIBRATED_LOAD,
            "k_fine": calibration.result(),
        }
        log(f"  {timer.part('load: printed load (3 runs), recalibration for k ≈ 1/128 (after Figs. 2–7)', t0)}")

        log(f"Figs. 8, 9: ρ study ({len(plan.rho) + 1} runs, {workers} workers) ...")
        t0 = clock()
        rho_rows = run_named_study(out, "rho_sweep", rho_study_text(plan), executor)
        data["rho_study"] = rho_record(rho_rows, plan)
        frames.update(rho_frames(out / "studies" / "rho_sweep", plan))
        log(f"  {timer.part(f'Figs. 8, 9: ρ study ({len(plan.rho) + 1} runs)', t0)}")

        log(f"Fig. 10: h–k study (1/{plan.levels[0]} … 1/{plan.levels[-1]}, reference 1/{plan.reference_level}) ...")
        t0 = clock()
        hk_rows = run_named_study(out, "hk_convergence", hk_study_text(plan), executor)
        data["hk_study"] = hk_record(hk_rows, plan, out / "studies" / "hk_convergence")
        log(f"  {timer.part(f'Fig. 10: h–k study ({len(plan.levels) + 1} runs)', t0)}")

        log("beyond the paper: the rates in h and in k separately ...")
        t0 = clock()
        h_rows = run_named_study(out, "h_convergence", h_study_text(plan), executor)
        k_rows = run_named_study(out, "k_convergence", k_study_text(plan), executor)
        data["rates"] = {
            "h": rate_record(h_rows, [f"h=1_{level}" for level in plan.h_levels], [1.0 / level for level in plan.h_levels]),
            "k": rate_record(k_rows, [f"steps={steps}" for steps in plan.k_steps], [T / steps for steps in plan.k_steps]),
        }
        runs = len(plan.h_levels) + len(plan.k_steps) + 2
        log(f"  {timer.part(f'beyond the paper: rates in h and in k ({runs} runs)', t0)}")

        log("beyond the paper: adaptive meshes against uniform ones ...")
        t0 = clock()
        data["adaptive"] = adaptive_record(base, plan, out, data["rates"]["h"])
        cycles = len(data["adaptive"]["dofs"])
        log(f"  {timer.part(f'beyond the paper: adaptive meshes ({cycles} cycles)', t0)}")

        data["mesh"] = mesh_record(results["beta+1_k0.1"])
        data["K_bottom_final"] = {
            suffix: {
                "beta=1": data["cases"][f"beta+1_{suffix}"]["K_probe"][-1],
                "beta=-1": data["cases"][f"beta-1_{suffix}"]["K_probe"][-1],
            }
            for suffix in ("k0.1", "k1_128")
        }
        data["penetration_ordering"] = {
            suffix: penetration_ordering(data["cases"], suffix) for suffix in ("k0.1", "k1_128")
        }
        data["node_states"] = node_states(data["cases"], results, plan)
        data["claims"] = assess(data)

        log("figures ...")
        t0 = clock()
        data["figures"] = figures.draw_all(data, frames, out / "figures")
        log(f"  {timer.part('figures (PNG and PDF)', t0)}")

    t0 = clock()
    data["wall_time_s"], data["cpu_time_s"] = timer.totals()
    report.write(data, out)
    timer.part("report", t0)
    data["wall_time_s"], data["cpu_time_s"] = timer.totals()
    report.write(data, out)  # again, with its own time and the totals
    (out / "reproduce.json").write_text(json.dumps(json_safe(data), indent=1) + "\n", encoding="utf-8")
    log(
        f"reproduce ({plan.mode}): {data['wall_time_s']['total']:.1f} s (CPU {data['cpu_time_s']['total']:.1f} s) "
        f"-> {out / 'report.html'}"
    )
    return data


def recorded_case(base: Path, spec: CaseSpec, out: Path) -> dict:
    """``case_record`` of ``solve_case``: what a worker returns of a run."""
    return case_record(spec, solve_case(base, spec, out))


def solve_case(base: Path, spec: CaseSpec, out: Path):
    """Solve one case and write its standard outputs; raises ReproduceError if a step fails."""
    from .. import solve
    from ..writers import write_run

    result = solve(load_case(base, spec.overrides))
    write_run(result, out, overwrite=True)
    if result.status != "complete":
        raise ReproduceError(f"run '{spec.name}' failed: {result.message} (outputs in {out})")
    return result


SERIES = (
    "t",
    "K_probe",
    "penetration_probe",
    "normal_stress_probe",
    "max_penetration",
    "mean_penetration",
    "nodes_separated",
    "nodes_in_compliance",
    "nodes_at_limit",
    "newton_iterations",
)


def step_rows(result) -> np.ndarray:
    """Indices of the history rows at the step times t_n, n = 1, …, steps (a step cut into sub-steps
    has several rows; its last one is at t_n)."""
    t = np.asarray(result.series("t"), dtype=float)
    return np.array([np.flatnonzero(np.isclose(t, tn, rtol=1e-12, atol=1e-12))[-1] for tn in result.problem.times])


def case_record(spec: CaseSpec, result) -> dict:
    """What reproduce.json keeps of a run: its overrides, sizes, time and its series at the step times."""
    steps = len(result.problem.times)
    rows = step_rows(result)
    record = {
        "label": spec.label,
        "group": spec.group,
        "overrides": spec.overrides,
        "steps": steps,
        "k": T / steps,
        "dofs": result.dofs,
        "elements": result.elements,
        "contact_nodes": result.contact_nodes,
        "wall_time_s": result.wall_time_s,
        "solver_method": result.method,
    }
    for name in SERIES:
        values = result.series(name)[rows]
        record[name] = (
            [int(v) for v in values]
            if name.startswith("nodes") or name == "newton_iterations"
            else [float(v) for v in values]
        )
    return record


def mesh_record(result) -> dict:
    """The figure mesh: elements, DOFs, contact nodes and edges on Γ3."""
    surface = result.problem.surface
    return {
        "elements": int(result.elements),
        "dofs": int(result.dofs),
        "nodes": int(result.nodes),
        "contact_nodes": int(result.contact_nodes),
        "contact_edges": int(surface.facets.shape[1]),
    }


def calibrate(base: Path, plan: Plan) -> dict:
    """The load c for which β = 1 gives K = 323 at the bottom point at t = 1.1 with k ≈ 1/128 (Brent),
    and what β = −1 gives at that c (the README's calibration, repeated with the fine time step)."""
    from scipy.optimize import brentq

    from .. import solve

    evaluations = []

    def K_final(c: float, beta: float) -> float:
        case = load_case(
            base,
            {
                "mesh.h": plan.figure_h,
                "time.steps": plan.steps_fine,
                "output.field_steps": "none",
                "contact.stiffness.beta": beta,
                **_load(c),
            },
        )
        result = solve(case)
        if result.status != "complete":
            raise ReproduceError(f"calibration run c = {c:g}, β = {beta:g} failed: {result.message}")
        return float(result.series("K_probe")[-1])

    def mismatch(c: float) -> float:
        K = K_final(c, 1.0)
        evaluations.append([c, K])
        return K - PAPER["K_hardening"]

    c = brentq(mismatch, 0.8 * CALIBRATED_LOAD, 1.25 * CALIBRATED_LOAD, xtol=1e-5, rtol=1e-10)
    return {
        "steps": plan.steps_fine,
        "k": T / plan.steps_fine,
        "c": c,
        "K_beta=1": evaluations[-1][1],
        "K_beta=-1": K_final(c, -1.0),
        "evaluations": len(evaluations),
    }


def run_named_study(out: Path, name: str, text: str, executor) -> list[dict]:
    """Write DIR/studies/NAME.toml, run it into DIR/studies/NAME with ``executor``, return study.csv's rows."""
    from ..studies import load_study, run_study

    folder = out / "studies"
    folder.mkdir(exist_ok=True)
    path = folder / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    study = load_study(path, folder / name)
    report = run_study(study, folder / name, executor=executor)
    if report["failed"]:
        raise ReproduceError(
            f"study '{name}': runs {', '.join(report['failed'])} failed (see {folder / name / 'study.csv'})"
        )
    with open(folder / name / "study.csv", newline="") as handle:
        return list(csv.DictReader(handle))


def _number(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def fit_slope(x, y) -> float:
    """Least-squares slope of log y against log x."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def rho_record(rows: list[dict], plan: Plan) -> dict:
    """Fig. 8: ‖u_ρ − u_*‖_V + ‖σ_ρ − σ_*‖_Q at t = 1.1 per ρ, and the node states per ρ (Fig. 9)."""
    by_id = {row["id"]: row for row in rows}
    key = f"t{T:g}"
    rho = list(plan.rho)
    V = [_number(by_id[f"rho={r:g}"][f"norm_V_{key}"]) for r in rho]
    Q = [_number(by_id[f"rho={r:g}"][f"norm_Q_{key}"]) for r in rho]
    difference = [v + q for v, q in zip(V, Q)]
    small = [i for i, r in enumerate(rho) if r <= 0.1]
    signorini = by_id["signorini"]
    return {
        "rho": rho,
        "V": V,
        "Q": Q,
        "difference": difference,
        "decreasing": bool(all(b < a for a, b in zip(difference, difference[1:]))),
        "slope": fit_slope([rho[i] for i in small], [difference[i] for i in small]) if len(small) > 1 else math.nan,
        "nodes_at_limit": [int(_number(by_id[f"rho={r:g}"]["nodes_at_limit"])) for r in rho],
        "nodes_in_compliance": [int(_number(by_id[f"rho={r:g}"]["nodes_in_compliance"])) for r in rho],
        "nodes_separated": [int(_number(by_id[f"rho={r:g}"]["nodes_separated"])) for r in rho],
        "contact_nodes": int(_number(signorini["contact_nodes"])),
        "signorini": {
            "nodes_at_limit": int(_number(signorini["nodes_at_limit"])),
            "nodes_in_compliance": int(_number(signorini["nodes_in_compliance"])),
            "penetration_probe": _number(signorini["penetration_probe"]),
        },
        "wall_time_s": [_number(by_id[f"rho={r:g}"]["wall_time_s"]) for r in rho],
    }


def hk_record(rows: list[dict], plan: Plan, folder: Path) -> dict:
    """Fig. 10: ‖u − u^{hk}‖_V at t = 1.1 against h + k, and the fitted slope."""
    by_id = {row["id"]: row for row in rows}
    key = f"t{T:g}"
    levels = list(plan.levels)
    h = [1.0 / level for level in levels]
    k = [T / level_overrides(level)["time.steps"] for level in levels]
    error = [_number(by_id[_level_id(level, plan)][f"norm_V_{key}"]) for level in levels]
    x = [a + b for a, b in zip(h, k)]
    reference = by_id[_level_id(plan.reference_level, plan)]
    try:
        elements = json.loads((folder / "runs" / reference["id"] / "summary.json").read_text())["elements"]
    except (OSError, ValueError, KeyError):
        elements = None
    local = [float(np.log(error[i + 1] / error[i]) / np.log(x[i + 1] / x[i])) for i in range(len(levels) - 1)]
    return {
        "levels": levels,
        "h": h,
        "k": k,
        "h_plus_k": x,
        "error_V": error,
        "error_Q": [_number(by_id[_level_id(level, plan)][f"norm_Q_{key}"]) for level in levels],
        "slope": fit_slope(x, error),
        "slope_finest_three": fit_slope(x[-3:], error[-3:]),
        "local_slopes": local,
        "dofs": [int(_number(by_id[_level_id(level, plan)]["dofs"])) for level in levels],
        "steps": [int(_number(by_id[_level_id(level, plan)]["steps"])) for level in levels],
        "K_probe": [_number(by_id[_level_id(level, plan)]["K_probe"]) for level in levels],
        "wall_time_s": [_number(by_id[_level_id(level, plan)]["wall_time_s"]) for level in levels],
        "reference": {
            "level": plan.reference_level,
            "dofs": int(_number(reference["dofs"])),
            "elements": elements,
            "contact_nodes": int(_number(reference["contact_nodes"])),
            "steps": int(_number(reference["steps"])),
            "K_probe": _number(reference["K_probe"]),
            "wall_time_s": _number(reference["wall_time_s"]),
        },
    }


def rate_record(rows: list[dict], ids: list[str], x: list[float]) -> dict:
    """The errors ‖u − u_ref‖_V and ‖σ − σ_ref‖_Q at t = 1.1 of the runs ``ids`` (their step size
    or mesh size ``x``), the slopes fitted to all of them and to the finest three, per norm; for runs
    with the error estimate also ‖u − u_ref‖_E, η(1.1) and the effectivity index η / ‖u − u_ref‖_E."""
    by_id = {row["id"]: row for row in rows}
    key = f"t{T:g}"
    record = {"x": x, "dofs": [int(_number(by_id[i]["dofs"])) for i in ids],
              "steps": [int(_number(by_id[i]["steps"])) for i in ids]}
    for norm in ("V", "Q"):
        error = [_number(by_id[i][f"norm_{norm}_{key}"]) for i in ids]
        record[f"error_{norm}"] = error
        record[f"slope_{norm}"] = fit_slope(x, error)
        record[f"slope_{norm}_finest_three"] = fit_slope(x[-3:], error[-3:])
    if "error_estimate" in rows[0]:  # the runs estimated their error: η against ‖u − u_ref‖_E
        record["error_energy"] = [_number(by_id[i][f"norm_energy_{key}"]) for i in ids]
        record["estimate"] = [_number(by_id[i]["error_estimate"]) for i in ids]
        record["effectivity"] = [eta / error for eta, error in zip(record["estimate"], record["error_energy"])]
    return record


def adaptive_record(base: Path, plan: Plan, out: Path, uniform: dict) -> dict:
    """Adaptive meshes ([adapt], the residual estimator, Dörfler θ = 0.5, the maximum over the steps) from
    h = 1/adapt_level with the rate in h's time steps, each cycle's error ‖u − u_ref‖_E at t = 1.1 against
    that study's reference; and the DOFs the cycles need to reach the error of its finest uniform mesh
    (``uniform``: the rate in h's record; log–log interpolation between the two cycles around it; NaN if
    no cycle reaches it)."""
    from ..rundir import run as run_directory
    from ..studies import snapshots_at

    case = load_case(base, {"mesh.h": level_overrides(plan.adapt_level)["mesh.h"], "time.steps": plan.h_steps,
                            "output.field_steps": "final", "adapt.cycles": plan.adapt_cycles,
                            "adapt.max_dofs": plan.adapt_max_dofs})
    folder = out / "cases" / "adaptive"
    outcome = run_directory(case, folder)
    if outcome.status != "complete":
        raise ReproduceError(f"the adaptive run failed: {outcome.message} (outputs in {folder})")
    with open(folder / "adapt.csv", newline="") as handle:
        cycles = list(csv.DictReader(handle))
    runs = out / "studies" / "h_convergence" / "runs"
    reference = snapshots_at(runs / f"h=1_{plan.h_reference_level}" / "solution.npz", [T])[T]
    errors = [differences(snapshots_at(folder / "cycles" / row["cycle"] / "solution.npz", [T])[T], reference)
              for row in cycles]
    dofs = [int(row["dofs"]) for row in cycles]
    energy = [e["energy"] for e in errors]
    finest, uniform_error = uniform["dofs"][-1], uniform["error_energy"][-1]
    return {"dofs": dofs, "estimate": [float(row["estimate"]) for row in cycles], "error_energy": energy,
            "error_V": [e["V"] for e in errors], "message": outcome.message,
            "uniform_finest": {"level": plan.h_levels[-1], "dofs": finest, "error_energy": uniform_error},
            "dofs_at_uniform_error": dofs_reaching(dofs, energy, uniform_error)}


def dofs_reaching(dofs: list[int], errors: list[float], target: float) -> float:
    """The DOFs at which a sequence of meshes reaches the error ``target``: interpolated log–log between
    the last mesh above it and the first at or below it; NaN if none reaches it."""
    below = [i for i, error in enumerate(errors) if error <= target]
    if not below:
        return math.nan
    i = below[0]
    if i == 0:
        return float(dofs[0])
    x0, x1, y0, y1 = (math.log(v) for v in (dofs[i - 1], dofs[i], errors[i - 1], errors[i]))
    return float(math.exp(x0 + (math.log(target) - y0) * (x1 - x0) / (y1 - y0)))


# --- the pictures' data ----------------------------------------------------------------------------
def figure_frames(results: dict, plan: Plan) -> dict:
    """Deformed meshes and contact forces for Figs. 2, 3 (t = 0.2, 0.5, 0.8, 1.1) and 5 (t = 1.1)."""
    from .figures import Frame

    frames = {}
    for sign in ("+1", "-1"):
        result = results[f"beta{sign}_k0.1"]
        for t in FIGURE_TIMES:
            step = round(t / (T / plan.steps_coarse))
            frames[f"beta{sign}_t{t:g}"] = Frame.from_result(result, step, f"t = {t:g} s")
    for name in CONTACT_CONDITIONS:
        result = results[f"{name}_k0.1"]
        frames[f"final_{name}"] = Frame.from_result(result, len(result.problem.times), SHORT_LABELS[name])
    return frames


def rho_frames(folder: Path, plan: Plan) -> dict:
    """Fig. 9: the final deformed meshes and contact forces of the ρ study, from its run directories."""
    from .figures import Frame

    return {f"rho_{rho:g}": Frame.from_run(folder / "runs" / f"rho={rho:g}", f"ρ = {rho:g}") for rho in plan.fig9_rho}


# --- what the paper states, measured ---------------------------------------------------------------
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
            i = round(t / (T / plan.steps_coarse)) - 1
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
    d1 = hard.contact_history("penetration")[step_rows(hard)]
    d2 = soft.contact_history("penetration")[step_rows(soft)]
    touching = (d1 > 0.0) | (d2 > 0.0)
    violations = touching & ~(d1 < d2)
    xy = results["beta+1_k0.1"].problem.surface.coordinates
    t = hard.problem.times
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


# --- the machine -------------------------------------------------------------------------------------
def machine() -> dict:
    """Platform, processor, cores, memory and the versions that matter."""
    from ..writers import versions

    memory = None
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    except (ValueError, OSError, AttributeError):
        pass
    processor = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                processor = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        from ..solvers.factorization import installed_backends

        backend = installed_backends()[0]
    except Exception:  # noqa: BLE001 - informational only
        backend = "unknown"
    try:
        import matplotlib

        mpl = matplotlib.__version__
    except ImportError:
        mpl = "not installed"
    return {
        "platform": platform.platform(),
        "processor": processor,
        "cores": os.cpu_count(),
        "memory_gb": round(memory, 1) if memory else None,
        "python": platform.python_version(),
        "factorization": backend,
        "versions": {**versions(), "matplotlib": mpl},
    }


def settings(plan: Plan) -> dict:
    return {
        "mode": plan.mode,
        "figure_mesh_h": plan.figure_h,
        "steps_coarse": plan.steps_coarse,
        "k_coarse": T / plan.steps_coarse,
        "steps_fine": plan.steps_fine,
        "k_fine": T / plan.steps_fine,
        "rho": list(plan.rho),
        "fig9_rho": list(plan.fig9_rho),
        "hk_levels": list(plan.levels),
        "hk_reference_level": plan.reference_level,
        "h_levels": list(plan.h_levels),
        "h_reference_level": plan.h_reference_level,
        "h_steps": plan.h_steps,
        "k_steps": list(plan.k_steps),
        "k_reference_steps": plan.k_reference_steps,
        "k_level": plan.k_level,
        "adapt_level": plan.adapt_level,
        "adapt_cycles": plan.adapt_cycles,
        "adapt_max_dofs": plan.adapt_max_dofs,
        "printed_load": PRINTED_LOAD,
        "calibrated_load": CALIBRATED_LOAD,
        "figure_times": list(FIGURE_TIMES),
    }
