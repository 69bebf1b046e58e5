"""Calibrate the load of the paper's example (README, "The paper's load"), in 2D or 3D.

Finds the magnitude c of the vertical traction (0, −c t) on Γ2 ((0, 0, −c t) in 3D) for which β = 1
gives K = 323 at the bottom point at t = 1.1 (k = 0.1), the value the paper reports, by Brent's
method on c; then reports, without further tuning, what β = −1 gives at that c (the paper reports 21)
and how many contact nodes reach the limit g.

    python examples/calibrate_paper_load.py [--target 323] [--set mesh.h=0.025]
    python examples/calibrate_paper_load.py --case examples/quarter_ball.toml
"""

import argparse
import json
from pathlib import Path

from scipy.optimize import brentq

import vpcontact

EXAMPLE = Path(__file__).with_name("paper_ball.toml")


def final_state(example: Path, c: float, beta: float, overrides: list[str]) -> tuple[float, int]:
    """K at the probe at the last step and the number of contact nodes at the limit, for load c."""
    dimension = len(vpcontact.load_case(example).boundary.traction[0].value)
    value = ", ".join(['"0"'] * (dimension - 1) + [f'"-{c!r}*t"'])
    case = vpcontact.load_case(example, overrides + [f"boundary.traction[0].value=[{value}]",
                                                     f"contact.stiffness.beta={beta}", 'output.field_steps="none"',
                                                     "output.figures=false"])
    result = vpcontact.solve(case)
    if result.status != "complete":
        raise RuntimeError(result.message)
    return float(result.series("K_probe")[-1]), int(result.series("nodes_at_limit")[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", type=Path, default=EXAMPLE, help="the example (default: the 2D paper_ball.toml)")
    parser.add_argument("--target", type=float, default=323.0)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--bracket", type=float, nargs=2, default=(5.0, 100.0))
    args = parser.parse_args()
    evaluations = []

    def mismatch(c):
        K, at_limit = final_state(args.case, c, 1.0, args.overrides)
        evaluations.append((c, K, at_limit))
        print(f"c = {c:.8g}: K at the bottom point at t = 1.1 = {K:.8g}", flush=True)
        return K - args.target

    c = brentq(mismatch, *args.bracket, xtol=1e-6, rtol=1e-10)
    K_softening, at_limit_softening = final_state(args.case, c, -1.0, args.overrides)
    print(json.dumps({"case": str(args.case), "c": c, "K_beta_plus_1": evaluations[-1][1],
                      "nodes_at_limit_beta_plus_1": evaluations[-1][2], "K_beta_minus_1": K_softening,
                      "nodes_at_limit_beta_minus_1": at_limit_softening, "evaluations": len(evaluations)}, indent=2))


if __name__ == "__main__":
    main()
