"""The 3D example's convergence in h, measured against a finer run: prints JSON.

examples/quarter_ball.toml (T = 1.1, the same time steps on every mesh, fields at t = 1.1 only, no
figures) is run as a vpcontact study on a ladder of mesh sizes and a finer reference, and compared
at t = 1.1 by the study's own difference norms (`vpcontact.results.norms.differences`: the coarser solution
interpolated at the reference's nodes): ‖ε(u − u_ref)‖ (the strain, equivalent to the energy norm),
‖u − u_ref‖ and ‖σ − σ_ref‖ in L², and the contact values at the probe (the bottom point): K, the
penetration and the normal stress. The observed rates are log(e_i / e_{i+1}) / log(h_i / h_{i+1})
between neighbouring levels and the least-squares slope of log e against log h, with h = R · 1.5 / n
for a mesh of n cells per radius (the size the built-in quarter ball really uses: n = ceil(1.5 R /
mesh.h)). The reference's own error enters every difference: the rates are also fitted with
d_i = (e(h_i)² + e(h_ref)²)^½, e(h) = C h^p, and the probe values of all levels and the reference by
v(h) = v* + C h^p.

    python benchmarks/convergence_3d.py              # h = 0.3, 0.2, 0.15, 0.1 against 0.07 (1.7 GB, 1–2 min)
    python benchmarks/convergence_3d.py --quick      # h = 0.5, 0.35 against 0.25, 3 steps (seconds)
    python benchmarks/convergence_3d.py --out results/convergence_3d   # keep the study's runs
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import tomli_w
from scipy.optimize import curve_fit

from vpcontact.mesh.ball import CELLS_PER_RADIUS
from vpcontact.io.csv_format import read_table
from vpcontact.drivers.studies import load_study, norm_column, run_study

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"
SETTINGS = {
    "full": {"levels": (0.3, 0.2, 0.15, 0.1), "reference": 0.07, "steps": 11},
    "quick": {"levels": (0.5, 0.35), "reference": 0.25, "steps": 3},
}
T = 1.1
#: The errors reported, by the difference norm of study.csv they come from (`vpcontact.drivers.studies.norm_column`).
ERRORS = {"error_strain": "V", "error_L2": "U", "error_stress": "Q"}
PROBE = ("K_probe", "penetration_probe", "normal_stress_probe")


def mesh_size(h: float) -> float:
    """The size the built-in quarter ball of radius 1 uses for mesh.h = h: 1.5 / n, n cells per radius."""
    return CELLS_PER_RADIUS / math.ceil(CELLS_PER_RADIUS / h)


def write_study(folder: Path, levels, reference: float, steps: int) -> Path:
    study = {"base": str(EXAMPLE),
             "set": {"time.steps": steps, "output.field_steps": "final", "output.figures": False},
             "vary": [{"mesh.h": list(levels)}],
             "runs": [{"id": "reference", "mesh.h": reference}],
             "compare": {"reference": "reference", "times": [T]}}
    path = folder / "convergence_3d.toml"
    path.write_text(tomli_w.dumps(study))
    return path


def rates(h: list[float], errors: list[float]) -> list[float]:
    """log(e_i / e_{i+1}) / log(h_i / h_{i+1}) for neighbouring levels."""
    return [math.log(errors[i] / errors[i + 1]) / math.log(h[i] / h[i + 1]) for i in range(len(h) - 1)]


def slope(h: list[float], errors: list[float]) -> float:
    """The least-squares slope of log e against log h."""
    return float(np.polyfit(np.log(h), np.log(errors), 1)[0]) if len(h) > 1 else math.nan


def fit_power(h: list[float], values: list[float]) -> dict:
    """v(h) = v* + C h^p fitted by least squares to all levels ({"limit": v*, "C": C, "p": p}; NaN where
    fewer than four levels or no fit)."""
    if len(h) < 4:
        return {"limit": math.nan, "C": math.nan, "p": math.nan}
    h, values = np.array(h), np.array(values)
    guess = (values[-1], (values[0] - values[-1]) / h[0], 1.0)
    try:
        (limit, C, p), _ = curve_fit(lambda x, v, c, q: v + c * x**q, h, values, p0=guess, maxfev=10_000)
    except RuntimeError:
        return {"limit": math.nan, "C": math.nan, "p": math.nan}
    return {"limit": float(limit), "C": float(C), "p": float(p)}


def fit_with_reference_error(h: list[float], h_reference: float, errors: list[float]) -> dict:
    """The rate p of e(h) = C h^p fitted to the measured differences d_i = ‖u_i − u_ref‖ modelled as
    (e(h_i)² + e(h_ref)²)^½ — the reference's own error, uncorrelated with the level's (different,
    non-nested meshes), adds to every d_i — by least squares in log d ({"C", "p"}; NaN where fewer than
    three levels or no fit)."""
    if len(h) < 3:
        return {"C": math.nan, "p": math.nan}
    h = np.array(h)

    def model(x, log_c, q):
        return log_c + 0.5 * np.log(x ** (2 * q) + h_reference ** (2 * q))

    try:
        (log_c, p), _ = curve_fit(model, h, np.log(errors), p0=(0.0, 1.0), maxfev=10_000)
    except RuntimeError:
        return {"C": math.nan, "p": math.nan}
    return {"C": float(math.exp(log_c)), "p": float(p)}


def measure(out: Path, setting: dict, workers: int | None) -> dict:
    """Run the study into ``out`` and gather the errors, probe values and rates."""
    path = write_study(out, setting["levels"], setting["reference"], setting["steps"])
    started = time.perf_counter()
    report = run_study(load_study(path, out / "study"), out / "study", workers=workers)
    wall = time.perf_counter() - started
    rows = {row["id"]: row for row in read_table(out / "study" / "study.csv")}
    if report["failed"] or report["interrupted"] or any(row["status"] != "complete" for row in rows.values()):
        raise SystemExit(f"convergence_3d: runs did not complete: {json.dumps(report)}")
    reference = rows.pop("reference")
    ordered = sorted(rows.values(), key=lambda row: -float(row["mesh.h"]))

    def record(row: dict) -> dict:
        h = float(row["mesh.h"])
        return {"mesh_h": h, "h": mesh_size(h), "cells_per_radius": round(CELLS_PER_RADIUS / mesh_size(h)),
                "dofs": int(row["dofs"]), "contact_nodes": int(row["contact_nodes"]),
                "wall_time_s": float(row["wall_time_s"]), **{key: float(row[key]) for key in PROBE}}

    levels = []
    for row in ordered:
        level = record(row)
        level.update({name: float(row[norm_column(norm, T)]) for name, norm in ERRORS.items()})
        level.update({f"{key}_difference": level[key] - float(reference[key]) for key in PROBE})
        levels.append(level)
    h = [level["h"] for level in levels]
    probe_errors = {key: [abs(level[f"{key}_difference"]) for level in levels] for key in PROBE}
    return {
        "example": EXAMPLE.name, "t": T, "steps": setting["steps"], "reference": record(reference),
        "levels": levels,
        "rates": {name: rates(h, [level[name] for level in levels]) for name in ERRORS},
        "slopes": {name: slope(h, [level[name] for level in levels]) for name in ERRORS},
        "slopes_without_finest": {name: slope(h[:-1], [level[name] for level in levels[:-1]]) for name in ERRORS},
        "fits_with_reference_error": {name: fit_with_reference_error(h, mesh_size(setting["reference"]),
                                                                     [level[name] for level in levels])
                                      for name in ERRORS},
        "probe_rates": {key: rates(h, errors) for key, errors in probe_errors.items()},
        "probe_fits": {key: fit_power(h + [mesh_size(setting["reference"])],
                                      [level[key] for level in levels] + [float(reference[key])]) for key in PROBE},
        "study_wall_time_s": wall,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the coarse ladder h = 0.5, 0.35 against 0.25, 3 steps")
    parser.add_argument("--out", type=Path, help="keep the study here (default: a temporary directory)")
    parser.add_argument("--workers", type=int, default=None, help="processes of the study (default: one per core)")
    args = parser.parse_args()
    setting = SETTINGS["quick" if args.quick else "full"]
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        result = measure(args.out, setting, args.workers)
    else:
        with tempfile.TemporaryDirectory() as folder:
            result = measure(Path(folder), setting, args.workers)
    json.dump(result, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
