"""The run directory: every file the contract names, consistent with each other and with the API."""

import csv
import json
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import tomli_w

import vpcontact
from vpcontact.cli import main
from conftest import half_disc_case, solved

SUMMARY_FINAL = {"t", "max_penetration", "mean_penetration", "K_min", "K_max", "K_probe", "penetration_probe",
                 "normal_stress_probe", "nodes_separated", "nodes_in_compliance", "nodes_at_limit", "contact_force"}


def test_run_directory_contract(tmp_path, capsys):
    case = half_disc_case(h=0.2, load=60.0)
    case["output"]["field_steps"] = [3, 11]
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--set", "contact.stiffness.beta=-1", "--quiet"]) == 0

    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["steps"] == 11
    assert summary["solver_method"] == "condensed"
    assert summary["solver_reason"].startswith("solver.method = \"auto\": the condensed method is predicted fastest")
    predicted = summary["predicted_costs"]
    assert set(predicted) == {"condensed", "full", "iterative"} and all(cost["fits"] for cost in predicted.values())
    assert min(predicted, key=lambda name: predicted[name]["total_s"]) == "condensed"
    assert all(cost["total_s"] == cost["setup_s"] + cost["loop_s"] > 0 for cost in predicted.values())
    assert SUMMARY_FINAL <= set(summary["final"])
    assert {"vpcontact", "numpy", "scipy", "scikit-fem", "meshio"} <= set(summary["versions"])

    with (out / "history.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 11 and float(rows[-1]["t"]) == summary["final"]["t"] == 1.1
    for key in SUMMARY_FINAL - {"contact_force"}:
        assert float(rows[-1][key]) == summary["final"][key], key
    assert [float(rows[-1]["contact_force_x"]), float(rows[-1]["contact_force_y"])] == summary["final"]["contact_force"]
    counts = [int(rows[-1][k]) for k in ("nodes_separated", "nodes_in_compliance", "nodes_at_limit")]
    assert sum(counts) == summary["contact_nodes"]

    with (out / "contact.csv").open() as handle:
        contact = list(csv.DictReader(handle))
    assert len(contact) == 11 * summary["contact_nodes"]
    last = [r for r in contact if r["step"] == "11"]
    assert {r["status"] for r in contact} <= {"separated", "in_compliance", "at_limit"}
    assert sum(r["status"] == "at_limit" for r in last) == summary["final"]["nodes_at_limit"]
    probe = min(last, key=lambda r: float(r["x"]) ** 2 + float(r["y"]) ** 2)
    assert float(probe["K"]) == summary["final"]["K_probe"]
    assert -(float(probe["pressure_compliance"]) + float(probe["pressure_rigid"])) == summary["final"]["normal_stress_probe"]
    # the contact force is the weighted sum of the nodal pressures along −ν
    force = -sum(float(r["weight"]) * (float(r["pressure_compliance"]) + float(r["pressure_rigid"]))
                 * np.array([float(r["normal_x"]), float(r["normal_y"])]) for r in last)
    np.testing.assert_allclose(force, summary["final"]["contact_force"], rtol=1e-12)

    collection = ET.parse(out / "fields" / "body.pvd").getroot()
    files = [(float(d.get("timestep")), d.get("file")) for d in collection.iter("DataSet")]
    assert [round(t, 12) for t, _ in files] == [0.3, 1.1]
    body = meshio.read(out / "fields" / files[-1][1])
    assert body.point_data["displacement"].shape == (body.points.shape[0], 3)
    assert body.cell_data["stress"][0].shape[1] == 9 and "von_mises" in body.cell_data
    surface = meshio.read(out / "fields" / "contact_00011.vtu")
    for name in ("penetration", "xi", "K", "pressure", "pressure_compliance", "pressure_rigid", "status"):
        assert name in surface.point_data, name
    np.testing.assert_allclose(np.sort(surface.point_data["penetration"]),
                               np.sort([float(r["penetration"]) for r in last]), rtol=1e-15)

    # the resolved case reproduces the run bit for bit
    resolved = vpcontact.load_case(out / "case.resolved.toml")
    assert resolved.contact.stiffness.beta == -1.0 and resolved.solver.augmentation is None
    problem, again = solved(resolved)
    assert [float(r["K_probe"]) for r in rows] == again.series("K_probe").tolist()
    np.testing.assert_array_equal(body.point_data["displacement"][:, :2], again.final.displacement)
    # equilibrium in y (the roller on the axis carries no vertical force): contact force = −applied load
    applied = problem.loads(1.1)[problem.basis.nodal_dofs[1]].sum()
    np.testing.assert_allclose(summary["final"]["contact_force"][1], -applied, rtol=1e-9)

    # an existing result is not overwritten without --overwrite
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert main(["run", str(path), "--out", str(out), "--quiet", "--overwrite"]) == 0
    assert json.loads((out / "summary.json").read_text())["final"]["K_probe"] > summary["final"]["K_probe"]


def test_auto_says_why_it_does_not_run_the_condensed_method(monkeypatch):
    """With less memory than the condensed method's dense algebra needs twice over, "auto" runs the fastest
    method predicted among the others (the full one, on this small 2D body) and says why; an explicit method is named as the case's choice."""
    import vpcontact
    from vpcontact.solvers import condensed

    case = vpcontact.load_case(half_disc_case(h=0.2))
    monkeypatch.setattr(condensed, "available_memory", lambda: 1000)
    result = vpcontact.solve(case)
    assert result.method == "full" and result.status == "complete"
    assert result.predicted["full"]["total_s"] < result.predicted["iterative"]["total_s"]
    assert result.method_reason.endswith("; condensed would not fit in the memory available"), result.method_reason
    monkeypatch.undo()
    explicit = vpcontact.solve(vpcontact.load_case(half_disc_case(h=0.2), {"solver.method": "condensed"}))
    assert explicit.method_reason == "solver.method = \"condensed\""
