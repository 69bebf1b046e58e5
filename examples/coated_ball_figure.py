"""What the heterogeneity of examples/coated_ball.toml does: the contact pressure and K(ξ) along Γ3.

Runs the example and the three cases that remove one heterogeneity or both (the same mesh size, load
and times): the paper's ball (one material, c_v = 100 everywhere), the paper's ball on the layer with
the hard strip, the coated ball on the uniform layer, the coated ball on the hard strip (the example);
draws the pressure and K along the contact arc at the last step, the strip shaded
(`vpcontact.results.plots.along_contact`), and prints per run the vertical contact force, the largest
pressure, the mean pressure and K on the strip and beside it, as JSON.

    python examples/coated_ball_figure.py --out coated_ball.png [--set mesh.h=0.025]
"""

import argparse
import json
import tomllib
from pathlib import Path

import numpy as np

import vpcontact
from vpcontact.results.plots import DPI, along_contact, arc_length

EXAMPLE = Path(__file__).with_name("coated_ball.toml")
STRIP = (0.1, 0.2)  # the x range of the hard strip in examples/coated_ball.toml
UNIFORM_LAYER = 100.0  # c_v off the strip
ONE_MATERIAL = {"E": 1000.0, "nu": 0.3, "hypothesis": "plane_strain"}  # the core's: the paper's ball


def variants(overrides: list[str]) -> dict:
    """The four cases {label: Case}: with and without the coating, with and without the hard strip."""
    example = tomllib.loads(EXAMPLE.read_text())
    cases = {}
    for coated in (False, True):
        for strip in (False, True):
            data = json.loads(json.dumps(example))  # a deep copy
            if not coated:
                data["material"] = dict(ONE_MATERIAL)
                del data["mesh"]["coating"]
            if not strip:
                data["contact"]["stiffness"]["c_v"] = UNIFORM_LAYER
            label = f"{'coated' if coated else 'homogeneous'} ball, {'hard strip' if strip else 'uniform layer'}"
            cases[label] = vpcontact.load_case(data, [*overrides, 'output.field_steps="none"', "output.progress=false"])
    return cases


def summary(result) -> dict:
    """The numbers of one run at its last step."""
    x = result.discretization.surface.coordinates[0]
    on_strip = (x > STRIP[0]) & (x < STRIP[1])
    beside = (x > STRIP[1]) & (x < STRIP[1] + (STRIP[1] - STRIP[0]))
    pressure = result.contact_history("pressure_compliance")[-1] + result.contact_history("pressure_rigid")[-1]
    K = result.contact_history("K")[-1]
    return {"status": result.status, "contact_force_y": float(result.series("contact_force_y")[-1]),
            "max_pressure": float(pressure.max()), "x_of_max_pressure": float(x[np.argmax(pressure)]),
            "mean_pressure_strip": float(pressure[on_strip].mean()), "mean_pressure_beside": float(pressure[beside].mean()),
            "mean_K_strip": float(K[on_strip].mean()), "mean_K_beside": float(K[beside].mean()),
            "nodes_at_limit": int(result.series("nodes_at_limit")[-1])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("coated_ball.png"), help="the figure (PNG)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], help="key=value for every case")
    args = parser.parse_args()
    results = {label: vpcontact.solve(case) for label, case in variants(args.overrides).items()}
    figure = along_contact(results, ("pressure", "K", "xi"))
    surface = next(iter(results.values())).discretization.surface
    order, s, _ = arc_length(surface.coordinates, surface.facets)  # x grows along the bottom arc
    x = surface.coordinates[0, order]
    strip = np.interp(STRIP, x, s)  # the strip's x range as arc lengths along Γ3
    for ax in figure.axes:
        for line in ax.get_lines():
            if line.get_label().startswith("homogeneous"):
                line.set_linestyle("--")  # the coated ball's curves on the uniform layer lie almost on them
        ax.axvspan(*strip, color="0.85", zorder=0, label="hard strip")
        ax.set_xlim(0.0, float(np.interp(0.6, x, s)))
    figure.axes[0].legend(fontsize=8, frameon=False)
    figure.savefig(args.out, dpi=DPI)
    print(json.dumps({label: summary(result) for label, result in results.items()}, indent=2))


if __name__ == "__main__":
    main()
