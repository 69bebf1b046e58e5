"""The numbers of the reproduction's studies, from their study.csv rows: Fig. 8 (ρ → 0), Fig. 10
(h = k, the fitted slope), the rates in h alone and in k alone with the error estimate's effectivity,
and adaptive meshes against uniform ones."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..case.load import load_case
from ..results.norms import differences, norm_column
from ..progress import SILENT, Progress
from ..io.csv_format import read_table
from ..io.solution import snapshots_at
from ..io.summary import read_summary
from .paper import T
from .plan import Plan, level_overrides, level_step
from .runs import ReproduceError
from .study_files import h_id, level_id, rho_id


def _number(value) -> float:
    """A cell of study.csv as a number (NaN when empty or not a number)."""
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
    rho = list(plan.rho)
    V = [_number(by_id[rho_id(r)][norm_column("V", T)]) for r in rho]
    Q = [_number(by_id[rho_id(r)][norm_column("Q", T)]) for r in rho]
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
        "nodes_at_limit": [int(_number(by_id[rho_id(r)]["nodes_at_limit"])) for r in rho],
        "nodes_in_compliance": [int(_number(by_id[rho_id(r)]["nodes_in_compliance"])) for r in rho],
        "nodes_separated": [int(_number(by_id[rho_id(r)]["nodes_separated"])) for r in rho],
        "contact_nodes": int(_number(signorini["contact_nodes"])),
        "signorini": {
            "nodes_at_limit": int(_number(signorini["nodes_at_limit"])),
            "nodes_in_compliance": int(_number(signorini["nodes_in_compliance"])),
            "penetration_probe": _number(signorini["penetration_probe"]),
        },
        "wall_time_s": [_number(by_id[rho_id(r)]["wall_time_s"]) for r in rho],
    }


def hk_record(rows: list[dict], plan: Plan, folder: Path) -> dict:
    """Fig. 10: ‖u − u^{hk}‖_V at t = 1.1 against h + k, and the fitted slope."""
    by_id = {row["id"]: row for row in rows}
    levels = list(plan.levels)
    h = [1.0 / level for level in levels]
    k = [level_step(level) for level in levels]
    error = [_number(by_id[level_id(level, plan)][norm_column("V", T)]) for level in levels]
    x = [a + b for a, b in zip(h, k)]
    reference = by_id[level_id(plan.reference_level, plan)]
    elements = (read_summary(folder / "runs" / reference["id"]) or {}).get("elements")
    local = [float(np.log(error[i + 1] / error[i]) / np.log(x[i + 1] / x[i])) for i in range(len(levels) - 1)]
    return {
        "levels": levels,
        "h": h,
        "k": k,
        "h_plus_k": x,
        "error_V": error,
        "error_Q": [_number(by_id[level_id(level, plan)][norm_column("Q", T)]) for level in levels],
        "slope": fit_slope(x, error),
        "slope_finest_three": fit_slope(x[-3:], error[-3:]),
        "local_slopes": local,
        "dofs": [int(_number(by_id[level_id(level, plan)]["dofs"])) for level in levels],
        "steps": [int(_number(by_id[level_id(level, plan)]["steps"])) for level in levels],
        "K_probe": [_number(by_id[level_id(level, plan)]["K_probe"]) for level in levels],
        "wall_time_s": [_number(by_id[level_id(level, plan)]["wall_time_s"]) for level in levels],
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
    record = {"x": x, "dofs": [int(_number(by_id[i]["dofs"])) for i in ids],
              "steps": [int(_number(by_id[i]["steps"])) for i in ids]}
    for norm in ("V", "Q"):
        error = [_number(by_id[i][norm_column(norm, T)]) for i in ids]
        record[f"error_{norm}"] = error
        record[f"slope_{norm}"] = fit_slope(x, error)
        record[f"slope_{norm}_finest_three"] = fit_slope(x[-3:], error[-3:])
    if "error_estimate" in rows[0]:  # the runs estimated their error: η against ‖u − u_ref‖_E
        record["error_energy"] = [_number(by_id[i][norm_column("energy", T)]) for i in ids]
        record["estimate"] = [_number(by_id[i]["error_estimate"]) for i in ids]
        record["effectivity"] = [eta / error for eta, error in zip(record["estimate"], record["error_energy"])]
    return record


def adaptive_record(base: Path, plan: Plan, out: Path, uniform: dict, progress: Progress = SILENT) -> dict:
    """Adaptive meshes ([adapt], the residual estimator, Dörfler θ = 0.5, the maximum over the steps) from
    h = 1/adapt_level with the rate in h's time steps, each cycle's error ‖u − u_ref‖_E at t = 1.1 against
    that study's reference; and the DOFs the cycles need to reach the error of its finest uniform mesh
    (``uniform``: the rate in h's record; log–log interpolation between the two cycles around it; NaN if
    no cycle reaches it); ``progress`` hears of the adaptive run (its cycles, their set-up and steps)."""
    from ..drivers.rundir import run as run_directory

    case = load_case(base, {"mesh.h": level_overrides(plan.adapt_level)["mesh.h"], "time.steps": plan.h_steps,
                            "output.field_steps": "final", "adapt.cycles": plan.adapt_cycles,
                            "adapt.max_dofs": plan.adapt_max_dofs})
    folder = out / "cases" / "adaptive"
    outcome = run_directory(case, folder, progress=progress)
    if outcome.status != "complete":
        raise ReproduceError(f"the adaptive run failed: {outcome.message} (outputs in {folder})")
    cycles = read_table(folder / "adapt.csv")
    runs = out / "studies" / "h_convergence" / "runs"
    reference = snapshots_at(runs / h_id(plan.h_reference_level), [T])[T]
    errors = [differences(snapshots_at(folder / "cycles" / row["cycle"], [T])[T], reference)
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

