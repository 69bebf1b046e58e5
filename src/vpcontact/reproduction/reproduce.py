"""Every numerical result of Sect. 4 of the paper, regenerated: the runs, the measurements, the claims.

    vpcontact reproduce --out DIR [--quick]

The runs are a plain list, in the order of the paper:

- Figs. 2–7: the four contact conditions (β = 1; β = −1; α = 0, g = 0.2; α = 0, g = 2000) on the
  calibrated example, with k = 0.1 (the paper's data, N = 11) and with k ≈ 1/128 (what its Sect. 4.3
  says the figures used), solved in this process (`paper.CONTACT_CONDITIONS`, `plan.figure_cases`);
- the load: the printed load (1000 t N/m) for β = ±1 and ρ = 0.01, and the load recalibrated for
  k ≈ 1/128 (`plan.load_cases`, `calibration.calibrate`);
- Figs. 8, 9: the study ρ = 1, …, 1e−6 against K ≡ 0 (`study_files.rho_study_text`, run by
  `vpcontact.drivers.studies.run_study`);
- Fig. 10: the study h = k = 1/4, …, 1/256 against 1/512 (`study_files.hk_study_text`);
- beyond the paper: the rates in h alone and in k alone (`study_files.h_study_text`, `study_files.k_study_text`,
  `records.rate_record`), the residual error estimate's effectivity, and adaptive meshes against uniform
  ones (`records.adaptive_record`).

Each run writes the standard outputs under DIR/cases/ or DIR/studies/ (a study can be rerun with
``vpcontact study DIR/studies/NAME.toml --out DIR/studies/NAME``). `run` measures what the paper
states (:mod:`.claims`), draws the figures (:mod:`.figures`) and writes DIR/reproduce.json and the
report (:mod:`.report`).
"""

from __future__ import annotations

import json
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable

from .. import __version__
from ..io import directory
from ..io.files import remove_files
from ..io.run import OUTPUTS as RUN_FILES, TEMPORARIES
from ..progress import SILENT, Progress
from ..io.summary import json_safe
from . import figures, report
from .calibration import calibrate
from .claims import assess, node_states, penetration_ordering
from .frames import figure_frames, rho_frames
from .machine import machine
from .paper import CALIBRATED_LOAD, PAPER, PAPER_CASE, PRINTED_LOAD, T
from .plan import figure_cases, load_cases, make_plan, settings
from .records import adaptive_record, hk_record, rate_record, rho_record
from .runs import ReproduceError, case_record, mesh_record, recorded_case, run_named_study, solve_case
from .study_files import h_id, h_study_text, hk_study_text, k_id, k_study_text, rho_study_text
from .timing import Timer, clock

__all__ = ["OutputError", "ReproduceError", "run"]


class OutputError(ValueError):
    """--out cannot be used (nothing was run)."""


RUN_FOLDERS = ("cases/*", "studies/*/runs/*")
"""Where `run` keeps its runs (each a run directory: io.run.OUTPUTS)."""
OUTPUTS = (*[f"{folder}/{name}" for folder in (*RUN_FOLDERS, "studies/*")
             for name in (*RUN_FILES, *TEMPORARIES, directory.LOCK)],
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
        remove_files(out, OUTPUTS)
    out.mkdir(parents=True, exist_ok=True)


def run(
    out: str | os.PathLike,
    *,
    quick: bool = False,
    workers: int | None = None,
    overwrite: bool = False,
    log: Callable[[str], None] = print,
    progress: Progress = SILENT,
) -> dict:
    """The whole reproduction into ``out``; returns the content of reproduce.json. ``log`` hears of each part
    as it starts and ends; ``progress`` (:mod:`vpcontact.progress`) of each run as it starts and ends, and of
    the adaptive run's cycles."""
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
        results = {spec.name: solve_case(base, spec, out / "cases" / spec.name, progress) for spec in specs}
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
        rho_rows = run_named_study(out, "rho_sweep", rho_study_text(plan), executor, progress)
        data["rho_study"] = rho_record(rho_rows, plan)
        frames.update(rho_frames(out / "studies" / "rho_sweep", plan))
        log(f"  {timer.part(f'Figs. 8, 9: ρ study ({len(plan.rho) + 1} runs)', t0)}")

        log(f"Fig. 10: h–k study (1/{plan.levels[0]} … 1/{plan.levels[-1]}, reference 1/{plan.reference_level}) ...")
        t0 = clock()
        hk_rows = run_named_study(out, "hk_convergence", hk_study_text(plan), executor, progress)
        data["hk_study"] = hk_record(hk_rows, plan, out / "studies" / "hk_convergence")
        log(f"  {timer.part(f'Fig. 10: h–k study ({len(plan.levels) + 1} runs)', t0)}")

        log("beyond the paper: the rates in h and in k separately ...")
        t0 = clock()
        h_rows = run_named_study(out, "h_convergence", h_study_text(plan), executor, progress)
        k_rows = run_named_study(out, "k_convergence", k_study_text(plan), executor, progress)
        data["rates"] = {
            "h": rate_record(h_rows, [h_id(level) for level in plan.h_levels], [1.0 / level for level in plan.h_levels]),
            "k": rate_record(k_rows, [k_id(steps) for steps in plan.k_steps], [T / steps for steps in plan.k_steps]),
        }
        runs = len(plan.h_levels) + len(plan.k_steps) + 2
        log(f"  {timer.part(f'beyond the paper: rates in h and in k ({runs} runs)', t0)}")

        log("beyond the paper: adaptive meshes against uniform ones ...")
        t0 = clock()
        data["adaptive"] = adaptive_record(base, plan, out, data["rates"]["h"], progress)
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


