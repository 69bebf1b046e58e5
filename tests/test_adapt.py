"""The adaptive loop ([adapt], vpcontact.adaptivity.cycles): Dörfler marking, the time functional of the indicators,
the cycles and their run directory."""

import csv
import json
import typing

import numpy as np
import pytest

import vpcontact
from conftest import assert_refused, half_disc_case, run_cli, snapshot_tree, solved
from vpcontact import adapt
from vpcontact.adaptivity.cycles import dorfler, solve_and_estimate
from vpcontact.estimate.estimators import ESTIMATORS
from vpcontact.case.run import AdaptSection
from vpcontact.case.translate import adapt_options, output_options
from vpcontact.estimate.indicators import Level
from vpcontact.mesh import read_mesh
from vpcontact.results.norms import differences
from vpcontact import build_problem
from vpcontact.estimate.recovery import estimate as recovery_estimate
from vpcontact.estimate.residual import estimate as residual_estimate


def test_dorfler_marks_the_fewest_largest_entries_holding_theta_of_the_sum():
    values = np.array([1.0, 5.0, 3.0, 1.0])
    np.testing.assert_array_equal(dorfler(values, 0.5), [1])
    np.testing.assert_array_equal(dorfler(values, 0.6), [1, 2])
    np.testing.assert_array_equal(dorfler(values, 1.0), [0, 1, 2, 3])
    assert dorfler(np.zeros(3), 0.5).size == 0


def test_the_estimators_are_those_the_case_accepts():
    accepted = typing.get_args(AdaptSection.model_fields["estimator"].annotation)
    assert set(accepted) == set(ESTIMATORS)


def paper_case(**settings):
    case = half_disc_case(h=0.25)
    case["adapt"] = {"cycles": 1, **settings}
    case["output"] = {"field_steps": [3, 11]}
    return vpcontact.load_case(case)


@pytest.mark.parametrize("functional", ["max", "l2"])
@pytest.mark.parametrize("estimator", ["residual", "recovery"])
def test_the_time_functional_folds_every_steps_indicators(functional, estimator):
    case = paper_case(functional=functional, estimator=estimator)
    result, folded = solve_and_estimate(build_problem(case), adapt_options(case.adapt), output_options(case.output))
    assert sorted(result.fields) == [3, 11]  # the other steps' fields were dropped once folded
    problem, every = solved(case.model_copy(update={"output": case.output.model_copy(update={"field_steps": "all"})}))
    estimate = {"residual": residual_estimate, "recovery": recovery_estimate}[estimator]
    squared = np.array([estimate(Level.of(every, n, problem)).squared for n in range(1, 12)])
    expected = squared.max(axis=0) if functional == "max" else problem.k * squared.sum(axis=0)
    np.testing.assert_allclose(folded, expected, rtol=1e-10)
    assert folded.max() > 0.0


def test_the_cycles_refine_where_the_indicators_are_large_and_the_estimate_falls():
    case = paper_case(cycles=4, theta=0.4)
    seen = []
    adaptation = adapt(build_problem(case), case.adapt, case.output, after_cycle=seen.append)
    assert adaptation.status == "complete" and len(adaptation.rows) == 4
    dofs = np.array([row["dofs"] for row in adaptation.rows])
    estimates = np.array([row["estimate"] for row in adaptation.rows])
    assert np.all(np.diff(dofs) > 0) and np.all(np.diff(estimates) < 0)
    # the estimate falls at least like the uniform rate N^(-1/2) (measured: about N^(-0.45) from 4 cycles)
    rate = -np.polyfit(np.log(dofs), np.log(estimates), 1)[0]
    assert rate > 0.35
    first, last = seen[0].result.discretization.mesh, seen[-1].result.discretization.mesh
    assert last.regions == {} and last.part_names == first.part_names
    assert np.abs(np.hypot(*(last.mesh.p[:, last.nodes("bottom_arc")] - [[0.0], [1.0]])) - 1.0).max() < 1e-15
    assert seen[-1].result.contact_nodes > seen[0].result.contact_nodes


def test_max_dofs_stops_before_a_mesh_too_large():
    case = paper_case(cycles=10, max_dofs=700)
    adaptation = adapt(build_problem(case), case.adapt, case.output)
    assert all(row["dofs"] <= 700 for row in adaptation.rows)
    assert "more than adapt.max_dofs = 700" in adaptation.message


def write_case(tmp_path, case: dict, name="case.toml"):
    import tomli_w

    path = tmp_path / name
    path.write_text(tomli_w.dumps(case))
    return path


def adaptive_case(h=0.25, cycles=3, **settings):
    case = half_disc_case(h=h)
    case["adapt"] = {"cycles": cycles, "theta": 0.5, **settings}
    case["output"] = {"field_steps": [5, 11], "progress": False}
    return case


def test_an_adaptive_run_writes_its_cycles_and_a_mesh_that_runs_again(tmp_path):
    """End to end: adapt.csv, cycles/<n>/, final_mesh.msh; the final mesh read back as mesh.file gives the same
    run; the error against a fine uniform reference falls from cycle to cycle."""
    out = tmp_path / "run"
    status, _, stderr = run_cli("run", str(write_case(tmp_path, adaptive_case())), "--out", str(out))
    assert status == 0, stderr
    with open(out / "adapt.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["cycle"] for row in rows] == ["1", "2", "3"]
    assert list(rows[0]) == ["cycle", "dofs", "contact_nodes", "estimate", "wall_time_s"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "complete" and len(summary["cycles"]) == 3
    for n in (1, 2, 3):
        cycle = json.loads((out / "cycles" / str(n) / "summary.json").read_text())
        assert cycle["status"] == "complete" and cycle["dofs"] == int(rows[n - 1]["dofs"])
        assert (out / "cycles" / str(n) / "fields" / "body.pvd").is_file()

    mesh = read_mesh(out / "final_mesh.msh")
    assert 2 * mesh.mesh.p.shape[1] == int(rows[-1]["dofs"])
    assert {"axis", "bottom_arc", "top_arc"} <= set(mesh.part_names)  # with their group numbers
    again = half_disc_case()
    again["mesh"] = {"file": str(out / "final_mesh.msh")}
    again["output"] = {"field_steps": [11]}
    rerun = vpcontact.solve(again)
    final = np.load(out / "cycles" / "3" / "solution.npz")
    assert rerun.dofs == int(rows[-1]["dofs"]) and rerun.contact_nodes == int(rows[-1]["contact_nodes"])
    # the file's normals are averaged from the facets, the built-in shape's exact: close, not equal
    np.testing.assert_allclose(rerun.fields[11].displacement, final["displacement"][-1], atol=2e-3 * np.abs(
        final["displacement"][-1]).max())

    reference = vpcontact.solve(half_disc_case(h=1 / 64) | {"output": {"field_steps": [11]}}).snapshot(11)
    errors = []
    for n in (1, 2, 3):
        saved = np.load(out / "cycles" / str(n) / "solution.npz")
        elements = saved["triangles"]
        snapshot = vpcontact.results.norms.Snapshot(saved["points"], elements, saved["displacement"][-1], saved["stress"][-1])
        errors.append(differences(snapshot, reference)["V"])
    assert errors[2] < errors[1] < errors[0]


def test_a_quarter_ball_adapts_in_3d(tmp_path):
    case = {
        "mesh": {"shape": "quarter_ball", "h": 0.5},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "sym_x", "components": ["x"]}, {"part": "sym_y", "components": ["y"]}],
                     "traction": [{"part": "top", "value": ["0", "0", "-20*t"]}]},
        "contact": {"part": "bottom", "g": 0.2, "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0,
                                                               "beta": 1.0}},
        "time": {"T": 1.1, "steps": 4},
        "adapt": {"cycles": 3, "theta": 0.5},
    }
    loaded = vpcontact.load_case(case)
    adaptation = adapt(build_problem(loaded), loaded.adapt, loaded.output)
    assert adaptation.status == "complete"
    first, _, last = adaptation.rows
    assert last["dofs"] > first["dofs"] and last["contact_nodes"] > first["contact_nodes"]
    assert last["estimate"] < 0.8 * first["estimate"]  # measured 0.202 -> 0.148
    mesh = adaptation.mesh
    radius = np.linalg.norm(mesh.mesh.p[:, mesh.nodes("bottom")] - [[0.0], [0.0], [1.0]], axis=0)
    np.testing.assert_allclose(radius, 1.0, rtol=0, atol=1e-14)


@pytest.mark.parametrize("setting, words", [
    ("adapt.cycles=0", ["adapt.cycles", ">= 1"]),
    ("adapt.cycles=1.5", ["adapt.cycles", "integer"]),
    ("adapt.theta=0", ["adapt.theta", "> 0"]),
    ("adapt.theta=1.01", ["adapt.theta", "<= 1"]),
    ("adapt.max_dofs=-3", ["adapt.max_dofs", "> 0"]),
    ("adapt.max_dofs=50", ["adapt.max_dofs = 50", "dofs of the first mesh"]),
    ("adapt.functional=\"sum\"", ["adapt.functional", "'max' or 'l2'"]),
    ("adapt.estimator=\"kelly\"", ["adapt.estimator", "'residual'"]),
    ("adapt.cycle=2", ["unknown key 'adapt.cycle'", "adapt.cycles"]),
    ("initial={from_run=\"elsewhere\", step=1}", ["[adapt] with initial.from_run"]),
    ("adapt.mode=\"run\"", ["missing required value 'adapt.tolerance'", "energy norm"]),
    ("adapt={mode=\"run\", tolerance=0.1, cycles=3}", ["adapt.cycles = 3 with mode = \"run\"", "remove adapt.cycles"]),
    ("adapt.tolerance=0.1", ["adapt.tolerance = 0.1 with mode = \"cycles\""]),
    ("adapt.mode=\"steps\"", ["adapt.mode", "'cycles' or 'run'"]),
])
def test_bad_adapt_settings_are_refused_in_one_line(tmp_path, setting, words):
    path = write_case(tmp_path, adaptive_case())
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    before = snapshot_tree(out)
    status, _, stderr = run_cli("run", str(path), "--set", setting, "--overwrite", "--out", str(out))
    assert_refused(status, stderr, *words, untouched=[(out, before)])


def test_resume_of_an_adaptive_run_is_refused_and_overwrite_replaces_only_its_outputs(tmp_path):
    path = write_case(tmp_path, adaptive_case(cycles=2))
    out = tmp_path / "out"
    assert run_cli("run", str(path), "--out", str(out))[0] == 0
    (out / "notes.txt").write_text("mine")
    (out / "cycles" / "mine.txt").write_text("mine too")
    before = snapshot_tree(out)
    status, _, stderr = run_cli("run", str(path), "--resume", "--out", str(out))
    assert_refused(status, stderr, "--resume of an adaptive run", "--overwrite", untouched=[(out, before)])
    status, _, stderr = run_cli("run", str(path), "--set", "adapt.cycles=1", "--overwrite", "--out", str(out))
    assert status == 0, stderr
    assert (out / "notes.txt").read_text() == "mine" and (out / "cycles" / "mine.txt").read_text() == "mine too"
    assert sorted(p.name for p in (out / "cycles").iterdir()) == ["1", "mine.txt"]
    assert len((out / "adapt.csv").read_text().splitlines()) == 2


def test_a_study_of_an_adaptive_case_is_refused(tmp_path):
    write_case(tmp_path, adaptive_case(), "base.toml")
    (tmp_path / "study.toml").write_text('base = "base.toml"\n[[vary]]\n"contact.rho" = [1.0, 0.5]\n')
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("study", str(tmp_path / "study.toml"), "--out", str(tmp_path / "study"), "--quiet")
    assert_refused(status, stderr, "[adapt]", "vpcontact run", untouched=[(tmp_path, before)])


def test_a_stopped_cycle_stops_the_adaptation_with_its_status():
    case = paper_case(cycles=3)
    asked = []

    def stop():
        asked.append(1)
        return "stopped by a test" if len(asked) > 14 else None  # in the second cycle (11 steps each)

    adaptation = adapt(build_problem(case), case.adapt, case.output, stop=stop)
    assert adaptation.status == "interrupted" and len(adaptation.rows) == 2
    assert adaptation.message.startswith("cycle 2: stopped by a test after step 3")
