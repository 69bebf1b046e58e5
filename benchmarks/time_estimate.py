"""The error estimate in time and the adaptive time steps, measured: prints JSON (docs/adaptivity.md, "The error in
time").

Part "rates": the paper's half disc on one mesh (h = 1/32 by default, as the rate in k of `vpcontact reproduce`), its
layer softening (β = −1) and hardening (β = 1), and the viscoplastic ball of examples/viscoplastic_ball.toml; each
run with --steps and against the reference with 8× the last of them (1,128 for 141): the energy
error E = ‖u_n − u_ref‖_E at T, the estimate in time η_k(T), their ratio (effectivity) and their rates in k; the
space estimate η_h(T) beside them (it does not change with k). Then, at 141 steps, the meshes h = 1/4 … 1/32: η_h
and η_k against h (the space estimate carries the rate in h, the time estimate stays), so that the paper's two
rates, in h and in k, are the two estimates' (the paper's Fig. 10 measures them together, h = k).

Part "adaptive": the viscoplastic ball under two loads, the calibrated load reached in 0.1 s and then held to t = 4
(8 steps), and a load that rises, and falls back (0.55 − 0.45 cos πt, to t = 1.9, 10 steps). For each, uniform runs
with 10·2^j steps and the adaptive runs (time.adaptive, time.balance --balances): levels (history rows), the
largest ratio max_t η_k(t) / η_h(t), sub-steps cut, levels accepted above their share, wall time; then the uniform
steps that reach each adaptive run's largest ratio (log–log interpolation, the ratio ∝ 1/steps) and the wall time
of that uniform run without the estimates (what a user without time.adaptive would run), from the median of
--repeats runs each.

    python benchmarks/time_estimate.py --out docs/figures          # about 4 minutes on a 2-core machine
    python benchmarks/time_estimate.py --level 8 --steps 4 9 18 --repeats 1     # seconds
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

import vpcontact
from vpcontact import build_problem
from vpcontact.results.norms import energy_norm

RAMP_AND_HOLD = ("-17.977*min(t/0.1, 1)", 4.0, 8)
RISE_AND_FALL = ("-17.977*(0.55 - 0.45*cos(pi*t))", 1.9, 10)


def ball(level: int, steps: int, *, beta: float = -1.0, viscoplastic: bool = False, load: str = "-17.977*t",
         T: float = 1.1, estimate: bool = True, balance: float | None = None) -> dict:
    """The paper's half disc meshed as the reproduction's level (element edge √2/level), its calibrated load."""
    material = {"E": 1000.0, "nu": 0.3}
    if viscoplastic:
        material["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    time_table = {"T": T, "steps": steps, **({} if balance is None else {"adaptive": True, "balance": balance})}
    return {"mesh": {"shape": "half_disc", "h": math.sqrt(2.0) / level}, "material": material,
            "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],
                         "traction": [{"part": "top_arc", "value": ["0", load]}]},
            "contact": {"part": "bottom_arc", "g": 0.2,
                        "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": beta}},
            "time": time_table, "solver": {"tolerance": 1e-12},
            "output": {"field_steps": "final", "error_estimate": estimate, "progress": False}}


def timed(case: dict):
    """(result, wall seconds of solve, build included)."""
    started = time.perf_counter()
    result = vpcontact.solve(case)
    return result, time.perf_counter() - started


def slope(x, y) -> float:
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def rates(level: int, steps: list[int], levels: list[int]) -> dict:
    """Part "rates" (the module docstring)."""
    cases = {"softening layer (beta = -1)": {"beta": -1.0}, "hardening layer (beta = 1)": {"beta": 1.0},
             "viscoplastic ball": {"beta": 1.0, "viscoplastic": True, "load": "-17.977*min(t, 0.5)", "T": 2.0}}
    report = {}
    for name, settings in cases.items():
        T = settings.get("T", 1.1)
        problem = build_problem(ball(level, 1, **settings))
        mesh, lame = problem.mesh.mesh, problem.elasticity.lame
        reference, seconds = timed(ball(level, 8 * steps[-1], **settings))
        log(f"{name}: reference {8 * steps[-1]} steps, {seconds:.1f} s")
        rows = []
        for n in steps:
            result, seconds = timed(ball(level, n, **settings))
            error = energy_norm(mesh.p, mesh.t, result.final.displacement - reference.final.displacement, lame)
            last = result.history.iloc[-1]
            rows.append({"steps": n, "k": T / n, "error_energy": error, "time_estimate": float(last["time_estimate"]),
                         "effectivity": float(last["time_estimate"]) / error,
                         "space_estimate": float(last["error_estimate"]), "seconds": seconds})
        k = [row["k"] for row in rows]
        report[name] = {"dofs": int(problem.basis.N), "reference_steps": 8 * steps[-1], "runs": rows,
                        "rate_error": slope(k, [row["error_energy"] for row in rows]),
                        "rate_time_estimate": slope(k, [row["time_estimate"] for row in rows])}
    in_h = []
    for h_level in levels:
        result, _ = timed(ball(h_level, 141))
        last = result.history.iloc[-1]
        in_h.append({"level": h_level, "h": 1.0 / h_level, "dofs": result.dofs,
                     "space_estimate": float(last["error_estimate"]), "time_estimate": float(last["time_estimate"])})
    h = [row["h"] for row in in_h]
    report["in h (softening layer, 141 steps)"] = {
        "runs": in_h, "rate_space_estimate": slope(h, [row["space_estimate"] for row in in_h]),
        "rate_time_estimate": slope(h, [row["time_estimate"] for row in in_h])}
    return report


def largest_ratio(history) -> float:
    """max_t η_k(t) / η_h(t) over the levels of a run."""
    return float((history["time_estimate"] / history["error_estimate"]).max())


def adaptive(level: int, balances: list[float], repeats: int) -> dict:
    """Part "adaptive" (the module docstring)."""
    report = {}
    for name, (load, T, steps) in {"ramp and hold": RAMP_AND_HOLD, "rise and fall": RISE_AND_FALL}.items():
        settings = {"beta": 1.0, "viscoplastic": True, "load": load, "T": T}
        uniform = []
        for j in range(6):
            result, seconds = timed(ball(level, 10 * 2**j, **settings))
            uniform.append({"steps": 10 * 2**j, "largest_ratio": largest_ratio(result.history), "seconds": seconds})
        runs = []
        for balance in balances:
            walls = []
            for _ in range(repeats):
                result, seconds = timed(ball(level, steps, balance=balance, **settings))
                walls.append(seconds)
            history, summary = result.history, result.summary()
            ratio = largest_ratio(history)
            needed = steps_reaching(uniform, ratio)
            plain = [timed(ball(level, needed, estimate=False, **settings))[1] for _ in range(repeats)]
            runs.append({"balance": balance, "levels": len(history), "time_cuts": summary["time_cuts"],
                         "levels_over_share": summary["time_over_share"], "largest_ratio": ratio,
                         "seconds": float(np.median(walls)), "uniform_steps_for_that_ratio": needed,
                         "uniform_seconds_without_estimates": float(np.median(plain)),
                         "smallest_step": float(history["k"].min()), "largest_step": float(history["k"].max())})
            log(f"{name}, balance {balance}: {len(history)} levels, ratio {ratio:.3f}; uniform needs {needed} steps")
        report[name] = {"load": load, "T": T, "steps": steps, "uniform": uniform, "adaptive": runs}
    return report


def steps_reaching(uniform: list[dict], ratio: float) -> int:
    """The uniform steps whose largest ratio is ``ratio``: log–log interpolation (extrapolation at the ends)."""
    steps = np.log([row["steps"] for row in uniform])
    ratios = np.log([row["largest_ratio"] for row in uniform])
    i = int(np.clip(np.searchsorted(-ratios, -math.log(ratio)), 1, len(steps) - 1))
    weight = (math.log(ratio) - ratios[i - 1]) / (ratios[i] - ratios[i - 1])
    return int(math.ceil(math.exp(steps[i - 1] + weight * (steps[i] - steps[i - 1]))))


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--level", type=int, default=32, help="the mesh of part rates: h = 1/level (default 32)")
    parser.add_argument("--steps", type=int, nargs="+", default=[4, 9, 18, 35, 70, 141])
    parser.add_argument("--levels", type=int, nargs="+", default=[4, 8, 16, 32], help="the meshes of the rate in h")
    parser.add_argument("--adaptive-level", type=int, default=16, help="the mesh of part adaptive (default 16)")
    parser.add_argument("--balances", type=float, nargs="+", default=[1.0, 0.3, 0.1])
    parser.add_argument("--repeats", type=int, default=3, help="runs timed for each median (default 3)")
    parser.add_argument("--out", type=Path, help="also write time_estimate.json into this folder")
    args = parser.parse_args()
    started = time.perf_counter()
    report = {"rates": rates(args.level, args.steps, args.levels),
              "adaptive": adaptive(args.adaptive_level, args.balances, args.repeats)}
    report["seconds"] = time.perf_counter() - started
    text = json.dumps(report, indent=1)
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "time_estimate.json").write_text(text + "\n")


if __name__ == "__main__":
    main()
