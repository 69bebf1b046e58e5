"""Calibrate the load of the paper's example (README, "The paper's load").

Finds the magnitude c of the traction (0, −c t) on Γ2 for which β = 1 gives K = 323 at the bottom
point (0, 0) at t = 1.1 (k = 0.1), the value the paper reports, by Brent's method on c; then
reports, without further tuning, what β = −1 gives at that c (the paper reports 21).

    python examples/calibrate_paper_load.py [--target 323] [--set mesh.h=0.025]
"""

import argparse
import json
from pathlib import Path

from scipy.optimize import brentq

import vpcontact

EXAMPLE = Path(__file__).with_name("paper_ball.toml")


def final_K_probe(c: float, beta: float, overrides: list[str]) -> float:
    case = vpcontact.load_case(EXAMPLE, overrides + [f'boundary.traction[0].value=["0", "-{c!r}*t"]',
                                                     f"contact.stiffness.beta={beta}", 'output.field_steps="none"'])
    result = vpcontact.solve(case)
    if result.status != "complete":
        raise RuntimeError(result.message)
    return float(result.series("K_probe")[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--target", type=float, default=323.0)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--bracket", type=float, nargs=2, default=(5.0, 100.0))
    args = parser.parse_args()
    evaluations = []

    def mismatch(c):
        K = final_K_probe(c, 1.0, args.overrides)
        evaluations.append((c, K))
        print(f"c = {c:.8g}: K(0, 0; t = 1.1) = {K:.8g}", flush=True)
        return K - args.target

    c = brentq(mismatch, *args.bracket, xtol=1e-6, rtol=1e-10)
    K_softening = final_K_probe(c, -1.0, args.overrides)
    print(json.dumps({"c": c, "K_beta_plus_1": evaluations[-1][1], "K_beta_minus_1": K_softening,
                      "evaluations": len(evaluations)}, indent=2))


if __name__ == "__main__":
    main()
