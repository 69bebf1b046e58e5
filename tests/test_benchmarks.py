"""The benchmark scripts run and their JSON holds what docs/performance.md reads from it."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import require_gmsh

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def test_the_3d_scaling_ladder_reports_each_method_on_its_quickest_level():
    done = subprocess.run([sys.executable, str(BENCHMARKS / "scaling.py"), "--dim", "3", "--quick"], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    records = json.loads(done.stdout)
    assert [r["method"] for r in records] == ["condensed", "iterative", "full"]
    for record in records:
        assert record["status"] == "complete", record
        # the quarter ball at h = 0.3: 12 n³ tetrahedra with n = ceil(1.5 / 0.3) = 5
        assert record["tetrahedra"] == 12 * 5**3 and record["dofs"] % 3 == 0
        assert 0 < record["contact_dofs"] <= 3 * record["contact_nodes"] < record["dofs"]
        assert 0 < record["rss_after_problem_mb"] <= record["rss_after_setup_mb"] <= record["peak_rss_mb"]
        assert record["condensed_memory_mb"] > 8 * record["contact_nodes"] ** 2 / 2**20  # holds S (m × m) at least
        assert 0 < record["time_loop_s"] < record["total_s"] < record["process_s"]
        assert record["linear_solves"] > 0
    condensed, iterative, full = records
    assert condensed["dofs"] == full["dofs"] == iterative["dofs"]
    assert condensed["contact_nodes"] == full["contact_nodes"] == iterative["contact_nodes"]
    for direct in (condensed, full):
        assert direct["factor"]["factor_nonzeros"] >= direct["factor"]["matrix_nonzeros"] / 2  # a triangle at least
        assert direct["krylov_iterations"] == 0
    assert full["setup_s"]["factorization"] == 0.0 < condensed["setup_s"]["factorization"]
    assert full["linear_solves"] == full["newton_iterations"] == iterative["linear_solves"]
    # the iterative method: one hierarchy, a few CG iterations per Newton iteration
    assert iterative["factor"]["setups"] == 1 and iterative["factor"]["levels"] >= 2
    assert iterative["linear_solves"] <= iterative["krylov_iterations"] <= 40 * iterative["linear_solves"]
    assert 1 <= iterative["factor"]["most_cg_iterations_per_solve"] <= 40


def test_the_assembly_benchmark_times_both_implementations_and_compares_them():
    done = subprocess.run([sys.executable, str(BENCHMARKS / "assembly.py"), "--quick", "--steps", "2"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    old, new = json.loads(done.stdout)
    assert (old["implementation"], new["implementation"]) == ("skfem", "numpy")
    stages = ("stiffness_s", "load_setup_s", "load_step_s", "strain_s", "stress_force_s")
    for record in (old, new):
        assert record["status"] == "complete", record
        assert record["tetrahedra"] == 12 * 3**3 and record["dofs"] % 3 == 0  # h = 0.5: n = 3
        assert all(0 < record[stage] < record["process_s"] for stage in stages)
        assert 0 < record["rss_before_mb"] <= record["peak_rss_mb"]
    # the same pattern but for entries that cancel: exactly 0 one way, of the order of rounding the other
    assert abs(new["nonzeros"] - old["nonzeros"]) < 0.01 * old["nonzeros"]
    assert set(new["speedup"]) == set(stages) and new["peak_rss_ratio"] > 0
    assert all(difference <= 1e-13 for difference in new["relative_difference"].values()), new


def test_the_setup_benchmark_times_the_phases_of_the_build_and_the_peaks():
    done = subprocess.run([sys.executable, str(BENCHMARKS / "setup_phases.py"), "--quick", "--steps", "1"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    [record] = json.loads(done.stdout)
    assert record["status"] == "complete" and record["cores"] == os.cpu_count() and record["processor"]
    assert (record["dofs"], record["tetrahedra"], record["steps"]) == (1188, 1500, 1)  # h = 0.3: n = 5
    phases = record["phases_s"]
    assert set(phases) == {"mesh_tetrahedra", "mesh_wrap", "space", "stiffness", "loads", "contact_surface"}
    assert all(seconds > 0 for seconds in phases.values())
    assert phases["mesh_tetrahedra"] + phases["mesh_wrap"] <= record["mesh_s"]
    assert record["mesh_s"] + record["assembly_s"] == pytest.approx(record["build_s"])
    assert record["rest_of_build_s"] > 0 and record["build_s"] < record["process_s"]
    assert 0 < record["build_peak_rss_mb"] <= record["run_peak_rss_mb"] and record["sampled_peak_rss_mb"] > 0
    assert record["method"] == "iterative" and record["krylov_iterations"] > 0


def test_the_targets_benchmark_measures_each_target_against_its_limit():
    """benchmarks/targets.py --quick: every target's measurement at a small size, compared with nothing (its
    limits are for the full sizes); the parts skipped are left out of the record."""
    done = subprocess.run([sys.executable, str(BENCHMARKS / "targets.py"), "--quick", "--skip", "startup"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    assert record["machine"]["cores"] >= 1 and record["machine"]["processor"]
    assert set(record["measurements"]) == {"finest", "viscoplastic", "peer", "reproduce"}
    names = [t["target"] for t in record["targets"]]
    assert names[:5] == ["1/32, β = 1, end to end (mesh to the last step)", "1/32, β = 1, time loop",
                         "1/32, β = -1, end to end (mesh to the last step)", "1/32, β = -1, time loop",
                         "assembly at 1/32 (1,856 triangles)"]
    assert names[5].startswith("1/32, viscoplastic") and names[6].startswith("GetFEM / vpcontact")
    finest = record["measurements"]["finest"]["records"]
    for target in record["targets"]:
        assert target["met"] is None and target["relation"] in ("<=", ">=")
        if target["unit"] == "s":
            assert 0 < target["measured"] < 60
    for beta, runs in finest.items():
        (run,) = runs
        assert run["status"] == "complete" and run["time_loop_s"] < run["total_s"]
    assert record["targets"][1]["measured"] == finest["beta=1"][0]["time_loop_s"]
    assert record["met"] == "0 of 0"


def test_the_displacement_control_benchmark_costs_no_factor_and_no_solve_more():
    """Pressed by its top's displacement or by the traction of the same force, the block is the same run: the same
    force at the first peak, the rigid limit reached and the layer left in both; the condensed method solves with
    its factor twice in the whole run either way (the right-hand sides b − A_fh u_D(t) stay in a span of two)."""
    done = subprocess.run([sys.executable, str(BENCHMARKS / "displacement_control.py"), "--quick"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    runs = {(r["control"], r["method"]): r for r in json.loads(done.stdout)["runs"]}
    assert set(runs) == {(c, m) for c in ("displacement", "traction") for m in ("condensed", "full")}
    for record in runs.values():
        assert record["status"] == "complete" and record["step_cuts"] == 0, record
        assert record["nodes_at_limit_max"] == record["nodes_separated_max"] == record["contact_nodes"] > 0, record
        assert abs(record["force_at_t1_N"] - runs["displacement", "full"]["force_at_t1_N"]) < 1e-9 * \
            record["force_at_t1_N"]
    assert runs["displacement", "condensed"]["linear_solves"] == runs["traction", "condensed"]["linear_solves"] == 2
    assert runs["displacement", "full"]["linear_solves"] == runs["displacement", "full"]["newton_iterations"]


def test_the_ladder_runs_each_method_and_auto_picks_the_one_its_cost_model_predicts_fastest():
    """benchmarks/ladder.py --quick: the gmsh punch (skipped without gmsh's library) at 7k dofs, condensed and
    iterative each in a fresh process, and auto run for real (``--auto-runs``); every run records its plan's
    prediction, and auto runs the method its own prediction puts first (3 steps: too few to weigh a switch)."""
    require_gmsh()
    done = subprocess.run([sys.executable, str(BENCHMARKS / "ladder.py"), "--quick", "--auto-runs"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    runs = report["runs"]
    assert [(r["rung"], r["asked"]) for r in runs] == [("punch-quick", method)
                                                       for method in ("condensed", "iterative", "auto")]
    for run in runs:
        assert run["status"] == "complete", run
        # a method asked for is predicted (with the others whose prediction costs nothing more); auto predicts all
        assert run["method"] in run["predicted"]
        assert set(run["predicted"]) == ({"iterative"} if run["asked"] == "iterative" else {"condensed", "iterative",
                                                                                            "full"})
        assert all(cost["total_s"] > 0 and cost["memory_bytes"] > 0 for cost in run["predicted"].values())
        assert run["predicted_peak_bytes"] > 0 and run["peak_rss_bytes"] > 0
    for auto in (r for r in runs if r["asked"] == "auto"):
        fitting = {name: cost["total_s"] for name, cost in auto["predicted"].items() if cost["fits"]}
        assert auto["method"] == min(fitting, key=fitting.get)
        assert auto["reason"].startswith(f'solver.method = "auto": the {auto["method"]} method is predicted fastest')
    punch = next(r for r in runs if r["rung"] == "punch-quick")
    assert punch["contact_nodes"] < punch["dofs"] / 3  # the flat face of the gmsh punch, meshed finer
    assert [s["rung"] for s in report["summaries"]] == ["punch-quick"]
    assert all(s["auto_over_fastest"] > 0 and s["auto_ran"] and s["auto_switch"] is None for s in report["summaries"])


def test_the_long_history_benchmark_compares_one_adaptive_pass_with_one_run_on_its_last_mesh():
    done = subprocess.run([sys.executable, str(BENCHMARKS / "adaptivity_long_history.py"), "--steps", "11", "22",
                           "--tolerances", "0.3", "--repeat", "1"], capture_output=True, text=True, timeout=300,
                          cwd=BENCHMARKS)
    assert done.returncode == 0, done.stderr
    runs = json.loads(done.stdout)["runs"]
    assert [(r["steps"], r["tolerance"]) for r in runs] == [(11, 0.3), (22, 0.3)]
    for run in runs:
        assert run["refined_at_steps"] and run["refined_at_steps"][0] == 1
        assert run["dofs"] > 162  # past h = 1/8 (81 nodes)
        assert 2 <= run["levels_estimated"] < run["steps"]  # the first and the last, not every one
        assert run["time_ratio"] == run["wall_time_s"] / run["one_run_on_last_mesh_s"] > 0
