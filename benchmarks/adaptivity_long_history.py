"""What a run that adapts during the run costs against one run on its last mesh as its history grows longer: prints
JSON (docs/adaptivity.md, "Adapting during the run, measured").

The 2D flat punch of benchmarks/effectivity.py (the unit square pressed onto a flat rigid punch under half its
bottom, the pressure growing like r^(−1/2) at the punch's edge), from h = 1/8, T = 1.1 in each of --steps, adapted
during the run (adapt.mode = "run", residual estimator, θ = 0.5) to each of --tolerances. For each: the last mesh's
dofs, the steps refined at, the levels estimated, the pass's wall time and that of one run on its last mesh (build
and solve, the same outputs, in the same process: no import is timed), the best of --repeat each, and their ratio.

    python benchmarks/adaptivity_long_history.py                            # 11, 44, 110 steps; tolerance 0.05
    python benchmarks/adaptivity_long_history.py --steps 11 --tolerances 0.2 --repeat 1   # seconds
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import vpcontact
from vpcontact import adapt, build_problem

from effectivity import punch_case


def case_with(steps: int) -> vpcontact.Case:
    """The punch from h = 1/8 on ``steps`` steps to T = 1.1, its fields at the last step."""
    data = punch_case(8, None, [11]).model_dump(exclude_none=True)
    data["time"] = {"T": 1.1, "steps": steps}
    data["output"]["field_steps"] = [steps]
    return vpcontact.Case.model_validate(data)


def measure(steps: int, tolerance: float, repeat: int) -> dict:
    """The pass and one run on its last mesh, the best wall time of ``repeat`` each."""
    case = case_with(steps)
    settings = {"mode": "run", "tolerance": tolerance, "theta": 0.5, "estimator": "residual"}
    passes, plains = [], []
    for _ in range(repeat):
        started = time.perf_counter()
        adaptation = adapt(build_problem(case), settings, case.output)
        passes.append(time.perf_counter() - started)
        if adaptation.status != "complete":
            raise SystemExit(f"the pass failed: {adaptation.message}")
        started = time.perf_counter()
        plain = vpcontact.solve(build_problem(case, mesh=adaptation.mesh), output=case.output)
        plains.append(time.perf_counter() - started)
        if plain.status != "complete":
            raise SystemExit(f"the run on the last mesh failed: {plain.message}")
    row = {"steps": steps, "tolerance": tolerance, "dofs": int(adaptation.result.dofs),
           "refined_at_steps": sorted({r["step"] for r in adaptation.rows if r["refined"]}),
           "levels_estimated": sum(not r["refined"] for r in adaptation.rows),
           "wall_time_s": min(passes), "one_run_on_last_mesh_s": min(plains), "time_ratio": min(passes) / min(plains)}
    print(f"{steps} steps, tolerance {tolerance:g}: {row['dofs']:,} dofs, {row['levels_estimated']} levels estimated, "
          f"{row['wall_time_s']:.2f} s against {row['one_run_on_last_mesh_s']:.2f} s: {row['time_ratio']:.2f}",
          file=sys.stderr, flush=True)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, nargs="+", default=[11, 44, 110])
    parser.add_argument("--tolerances", type=float, nargs="+", default=[0.05])
    parser.add_argument("--repeat", type=int, default=3, help="the best of this many of each (default 3)")
    args = parser.parse_args()
    measure(11, 0.5, 1)  # warm: imports, the first PARDISO call
    rows = [measure(steps, tolerance, args.repeat) for tolerance in args.tolerances for steps in args.steps]
    json.dump({"case": "punch (benchmarks/effectivity.py), from h = 1/8, T = 1.1", "runs": rows}, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
