"""examples/coated_ball.toml (a soft coating over a stiff core, a layer harder on a strip of Γ3) and its
figure script, examples/coated_ball_figure.py, on a coarse mesh.

What must hold whatever the heterogeneity: the vertical contact force balances the load (the traction
c·t on every facet of the upper arc), the same in the four cases; each heterogeneity is there (the
materials on their regions, c_v on the strip in contact.csv)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import vpcontact
from conftest import solved
from vpcontact.results.plots import along_contact

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
sys.path.insert(0, str(EXAMPLES))
import coated_ball_figure  # noqa: E402

COARSE = ["mesh.h=0.05"]
LOAD = 17.977  # the example's c


def applied_force(problem) -> float:
    """c·t·(length of the upper arc's facets): the vertical load at t = T."""
    mesh = problem.mesh.mesh
    ends = mesh.p[:, mesh.facets[:, problem.mesh.facets("top_arc")]]
    return LOAD * problem.times[-1] * float(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=0).sum())


def test_the_four_cases_balance_the_same_load():
    cases = coated_ball_figure.variants(COARSE)
    solved_cases = {label: solved(case) for label, case in cases.items()}
    results = {label: result for label, (_, result) in solved_cases.items()}
    for label, (problem, result) in solved_cases.items():
        assert result.status == "complete", (label, result.message)
        force = result.series("contact_force_y")[-1]
        assert abs(force - applied_force(problem)) < 1e-9 * force, label
    coated, _ = solved_cases["coated ball, hard strip"]
    assert set(np.unique(coated.materials.E[coated.mesh.regions["core"]])) == {1000.0}
    assert set(np.unique(coated.materials.E[coated.mesh.regions["coating"]])) == {100.0}
    figure = along_contact(results, ("pressure", "K"))
    assert [len(ax.get_lines()) for ax in figure.axes] == [4, 4]


def test_the_figure_script_writes_its_figure_and_numbers(tmp_path):
    out = tmp_path / "coated.png"
    process = subprocess.run([sys.executable, str(EXAMPLES / "coated_ball_figure.py"), "--out", str(out),
                              *(f"--set={o}" for o in COARSE)], capture_output=True, text=True, timeout=300)
    assert process.returncode == 0, process.stderr
    numbers = json.loads(process.stdout)
    assert out.stat().st_size > 10_000
    strip = numbers["coated ball, hard strip"]
    uniform = numbers["coated ball, uniform layer"]
    # the strip is three times stiffer: there it carries more than beside it, and more than without the strip
    assert strip["mean_pressure_strip"] > 1.5 * strip["mean_pressure_beside"]
    assert strip["mean_pressure_strip"] > 1.5 * uniform["mean_pressure_strip"]


def test_the_example_runs_and_writes_the_layer_per_node(tmp_path):
    """The example as shipped, on the coarse mesh, through the CLI: c_v in contact.csv is 300 on the strip
    and 100 elsewhere; the body VTU names each element's material."""
    import csv

    import meshio

    from vpcontact.cli import main

    out = tmp_path / "run"
    assert main(["run", str(EXAMPLES / "coated_ball.toml"), "--out", str(out), "--quiet",
                 *(f"--set={o}" for o in COARSE)]) == 0
    with open(out / "contact.csv", newline="") as handle:
        rows = [row for row in csv.DictReader(handle) if row["step"] == "1"]
    x, c_v = (np.array([float(row[key]) for row in rows]) for key in ("x", "c_v"))
    assert np.array_equal(c_v, np.where((x > 0.1) & (x < 0.2), 300.0, 100.0))
    body = meshio.read(out / "fields" / "body_00011.vtu")
    assert set(np.unique(body.cell_data["material"][0])) == {0, 1}


def test_the_paper_figures_refuse_a_thickness_that_varies():
    """The paper's figures draw one foundation thickness: a run whose g varies is refused in one line (the
    run's own figures, vpcontact.results.plots, draw it)."""
    import pytest

    from vpcontact.errors import CaseError
    from vpcontact.reproduction.frames import Frame

    case = vpcontact.load_case(EXAMPLES / "coated_ball.toml", [*COARSE, 'contact.g="0.2 - 0.1*x"', "time.steps=1",
                                                                'output.field_steps="final"',
                                                                "time.T=0.1"])
    with pytest.raises(CaseError, match="one thickness g; this run's g varies along Γ3"):
        Frame.from_result(vpcontact.solve(case), 1, "varying g")
