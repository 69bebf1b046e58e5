"""Long runs that survive: step cuts when Newton fails, checkpoints and --resume after SIGKILL,
SIGINT/SIGTERM, atomic outputs with summary.json last, and bitwise-reproducible runs."""

import csv
import json
import os
import random
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import tomli_w

import vpcontact
import vpcontact.timeloop.loop
from vpcontact.io import directory
from vpcontact.drivers import rundir
from vpcontact.cli import main
from vpcontact.results.columns import INTEGER_COLUMNS
from vpcontact.solvers import StepSolution
from conftest import half_disc_case

#: times, what a resume changes (a resumed run factors its matrices again), and the costs predicted at the
#: machine's speed in each session (predicted_costs, and solver_reason for a resumed run)
NOT_NUMBERS = {"wall_time_s", "timings_s", "linear_solves", "krylov_iterations", "newton_factorizations",
               "resumed_at_steps", "solver_reason", "predicted_costs", "peak_memory_bytes"}
SOLVER_REPORTS = {"residual", "complementarity"}  # below the tolerance, not results


def creeping_case(steps=200, h=0.05, method="auto", **output):
    """The paper's half disc, Perzyna body, softening layer (nodes reach the rigid base): a load ramped
    up to t = 0.5, then held while the body creeps."""
    case = half_disc_case(h=h, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["boundary"]["traction"][0]["value"] = ["0", "-20*min(t, 0.5)"]
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    case["time"] = {"T": 2.0, "steps": steps}
    case["solver"] = {"method": method, "tolerance": 1e-10}
    case["output"] = {"field_steps": [steps // 4, steps // 2, steps], "checkpoint_every_steps": 1, **output}
    return case


def write(tmp_path, case, name="case.toml"):
    path = tmp_path / name
    path.write_text(tomli_w.dumps(case))
    return path


def read_csv(path):
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], rows[1:]


def assert_same_run(out, reference, *, bitwise, rtol=1e-12):
    """history.csv, contact.csv, solution.npz and summary.json of two run directories agree: bitwise, or
    every number to rtol relative to the largest of its column (the solver's residual reports only
    below its tolerance)."""
    for name in ("history.csv", "contact.csv"):
        header, rows = read_csv(out / name)
        header_ref, rows_ref = read_csv(reference / name)
        assert header == header_ref and len(rows) == len(rows_ref), name
        for j, column in enumerate(header):
            mine, theirs = [r[j] for r in rows], [r[j] for r in rows_ref]
            if bitwise or column in (*INTEGER_COLUMNS, "t", "k", "node", "status"):
                assert mine == theirs, (name, column)
            elif column in SOLVER_REPORTS:
                assert max(map(float, mine + theirs)) <= 1e-10, (name, column)
            else:
                a, b = np.array(mine, dtype=float), np.array(theirs, dtype=float)
                assert np.abs(a - b).max() <= rtol * np.abs(b).max(), (name, column, np.abs(a - b).max())
    with np.load(out / "solution.npz") as mine, np.load(reference / "solution.npz") as theirs:
        assert mine.files == theirs.files
        for key in theirs.files:
            if bitwise:
                np.testing.assert_array_equal(mine[key], theirs[key], err_msg=key)
            else:
                np.testing.assert_allclose(mine[key], theirs[key], rtol=0, atol=rtol * np.abs(theirs[key]).max(), err_msg=key)
    summary, expected = (json.loads((d / "summary.json").read_text()) for d in (out, reference))
    assert summary["status"] == expected["status"] == "complete"
    for key in set(expected) - NOT_NUMBERS:
        if bitwise or key != "final":
            assert summary[key] == expected[key], key
        else:
            for name, value in expected["final"].items():
                np.testing.assert_allclose(summary["final"][name], value, rtol=rtol, atol=rtol * 100, err_msg=name)


def start(path, out, *args):
    return subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "run", str(path), "--out", str(out), "--quiet",
                             *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)


def wait_for_checkpoint(process, out, timeout=60.0):
    state = out / "checkpoint" / "state.npz"
    deadline = time.time() + timeout
    while not state.exists():
        assert process.poll() is None, f"the run ended before its first checkpoint: {process.stderr.read()}"
        assert time.time() < deadline, "no checkpoint"
        time.sleep(0.005)


def checkpoint_step(out):
    with np.load(out / "checkpoint" / "state.npz") as state:
        return int(state["step"])


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted run of the creeping case (no checkpoints)."""
    folder = tmp_path_factory.mktemp("reference")
    path = write(folder, creeping_case(checkpoint_every_steps=0, checkpoint_every_seconds=0))
    assert main(["run", str(path), "--out", str(folder / "run"), "--quiet"]) == 0
    return folder / "run"


# --- checkpoints and --resume ------------------------------------------------------------------------
def test_a_run_killed_at_a_random_moment_resumes_to_the_same_numbers(tmp_path, reference, capsys):
    seed = int.from_bytes(os.urandom(4), "little")
    delay = random.Random(seed).uniform(0.0, 0.6)
    path = write(tmp_path, creeping_case())
    out = tmp_path / "run"
    process = start(path, out)
    wait_for_checkpoint(process, out)
    time.sleep(delay)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    assert process.returncode == -signal.SIGKILL, f"seed {seed}: the run was not killed"
    assert not (out / "summary.json").exists()  # never looks complete
    step = checkpoint_step(out)
    assert 1 <= step < 200, f"seed {seed}"
    before = (out / "checkpoint" / "state.npz").stat().st_mtime_ns

    # another case is refused (one line, exit 2) and the directory is left alone
    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume", "--set", "contact.g=0.25"]) == 2
    error = capsys.readouterr().err
    assert "different case (contact.g = 0.2 in the run, 0.25 now)" in error and error.count("\n") == 1
    assert (out / "checkpoint" / "state.npz").stat().st_mtime_ns == before
    # without --resume or --overwrite a used directory is refused
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 2 and "--resume" in capsys.readouterr().err

    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 0, f"seed {seed}"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["resumed_at_steps"] == [step] and summary["steps"] == 200
    assert not (out / "checkpoint").exists() and not list(out.rglob(".*tmp-*"))
    assert_same_run(out, reference, bitwise=False)
    # resuming a complete run does nothing
    mtime = (out / "summary.json").stat().st_mtime_ns
    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 0
    assert "already complete" in capsys.readouterr().out and (out / "summary.json").stat().st_mtime_ns == mtime


def test_with_the_full_solver_a_resumed_run_is_bitwise_the_uninterrupted_one(tmp_path):
    case = creeping_case(steps=120, h=0.1, method="full", checkpoint_every_steps=3)
    path = write(tmp_path, case)
    assert main(["run", str(path), "--out", str(tmp_path / "whole"), "--quiet"]) == 0
    out = tmp_path / "run"
    process = start(path, out)
    wait_for_checkpoint(process, out)
    time.sleep(random.uniform(0.0, 0.2))
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    step = checkpoint_step(out)
    assert 3 <= step < 120 and step % 3 == 0
    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 0
    assert json.loads((out / "summary.json").read_text())["resumed_at_steps"] == [step]
    assert_same_run(out, tmp_path / "whole", bitwise=True)


@pytest.mark.parametrize("number, code, cadence", [
    (signal.SIGTERM, 143, {"checkpoint_every_steps": 1}),
    (signal.SIGINT, 130, {"checkpoint_every_steps": 0, "checkpoint_every_seconds": 0.1}),
])
def test_a_signal_stops_the_run_at_the_end_of_a_step(tmp_path, reference, number, code, cadence, capsys):
    path = write(tmp_path, creeping_case(**cadence))
    out = tmp_path / "run"
    process = start(path, out)
    wait_for_checkpoint(process, out)
    if number == signal.SIGTERM:  # a second run into the same directory is refused while this one writes
        assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 2
        assert "another vpcontact run is writing to it" in capsys.readouterr().err
        assert process.poll() is None
    process.send_signal(number)
    _, error = process.communicate(timeout=60)
    assert process.returncode == code, error
    summary = json.loads((out / "summary.json").read_text())
    name = signal.Signals(number).name
    assert summary["status"] == "interrupted" and f"stopped by {name} after step {summary['steps']}" in summary["message"]
    assert error.strip() == f"vpcontact: {summary['message']}"
    _, rows = read_csv(out / "history.csv")
    assert 1 <= len(rows) == summary["steps"] == checkpoint_step(out) < 200  # what exists is written and saved
    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 0
    assert_same_run(out, reference, bitwise=False)


def test_outputs_are_atomic_and_summary_json_comes_last(tmp_path, monkeypatch):
    case = creeping_case(steps=20, h=0.1)
    out = tmp_path / "run"
    real = vpcontact.io.solution.write

    def disk_full(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(vpcontact.io.solution, "write", disk_full)
    with pytest.raises(OSError):
        rundir.run(vpcontact.load_case(case), out)
    assert not (out / "summary.json").exists() and not list(out.rglob(".*tmp-*"))
    assert len(read_csv(out / "history.csv")[1]) == 20 and checkpoint_step(out) == 20
    monkeypatch.setattr(vpcontact.io.solution, "write", real)
    outcome = rundir.run(vpcontact.load_case(case), out, resume=True)  # the loop has nothing left to do
    assert outcome.status == "complete" and outcome.result.resumed_at == [20]
    assert json.loads((out / "summary.json").read_text())["status"] == "complete"

    # --overwrite removes the old summary.json before anything else: a run that dies does not look complete
    def crash(self, **hooks):
        raise RuntimeError("killed")

    monkeypatch.setattr(vpcontact.drivers.rundir.TimeLoop, "run", crash)
    with pytest.raises(RuntimeError):
        rundir.run(vpcontact.load_case(case), out, overwrite=True)
    assert not (out / "summary.json").exists() and not (out / "solution.npz").exists()


def test_resume_without_a_checkpoint(tmp_path):
    """Killed before its first checkpoint: --resume starts again (same case only); a directory that
    holds no run is refused."""
    case = vpcontact.load_case(creeping_case(steps=10, h=0.2))
    out = tmp_path / "run"
    out.mkdir()
    vpcontact.io.run.write_resolved_case(case.to_toml(), out)
    (out / ".history.tmp-99999.csv").write_text("half a file")  # a writer killed midway
    with pytest.raises(vpcontact.CaseError, match=r"different case \(material.E = 1000.0 in the run, 900.0 now\)"):
        rundir.run(vpcontact.load_case(creeping_case(steps=10, h=0.2), {"material.E": 900.0}), out, resume=True)
    outcome = rundir.run(case, out, resume=True)
    assert outcome.status == "complete" and outcome.result.resumed_at == [] and outcome.result.steps == 10
    assert not list(out.rglob(".*tmp-*")) and not (out / directory.LOCK).exists()
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(vpcontact.CaseError, match="holds no run of vpcontact"):
        rundir.run(case, other, resume=True)
    assert sorted(p.name for p in other.iterdir()) == ["notes.txt"]


# --- step cuts ---------------------------------------------------------------------------------------
class RefusesWholeSteps:
    """A step solver that reports a failed Newton iteration for any step longer than k/2 (the real
    solver does the rest): every step is cut exactly once."""

    def __init__(self, inner, k):
        self.inner, self.k, self.refused = inner, k, 0

    def solve(self, step, previous):
        if step.k > 0.75 * self.k:
            self.refused += 1
            m = step.xi_prev.size
            return StepSolution(None, np.zeros(m), np.zeros(m), np.zeros(m, dtype=bool), 3, 1.0, 0.0, False, "refused")
        return self.inner.solve(step, previous)

    def __getattr__(self, name):
        return getattr(self.inner, name)


def test_a_cut_step_is_the_same_scheme_on_a_finer_grid(monkeypatch):
    """Every step cut in two halves = the uniform run with twice the steps: ξ gains k/2·d⁺ and z gains
    k/2·𝒢 per sub-step, the loads are taken at the sub-step times."""
    coarse, fine = creeping_case(steps=20, h=0.1), creeping_case(steps=40, h=0.1)
    for case in (coarse, fine):
        case["output"] = {"field_steps": "final"}
    uniform = vpcontact.solve(fine)
    make_solver = vpcontact.timeloop.method.make_solver
    monkeypatch.setattr(vpcontact.timeloop.method, "make_solver",
                        lambda *args, **kw: RefusesWholeSteps(make_solver(*args, **kw), 2.0 / 20))
    cut = vpcontact.solve(coarse)
    assert cut.status == "complete" and cut.steps == 20 and cut.step_cuts == 20 and len(cut.rows) == 40
    assert cut.series("step").tolist() == np.repeat(np.arange(1, 21), 2).tolist()
    assert cut.series("substep").tolist() == [1, 2] * 20 and np.all(cut.series("k") == 0.05)
    assert cut.ends_step().tolist() == [False, True] * 20
    np.testing.assert_allclose(cut.series("t"), uniform.series("t"), rtol=1e-15)
    np.testing.assert_array_equal(cut.series("t", substeps=False), cut.discretization.times)
    assert cut.series("newton_iterations").tolist() == uniform.series("newton_iterations").tolist()
    for name in ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid"):
        np.testing.assert_allclose(cut.contact_history(name), uniform.contact_history(name), rtol=1e-10, atol=1e-12,
                                   err_msg=name)
    assert cut.series("nodes_at_limit")[-1] > 0  # the rigid base is reached: the active set is exercised
    np.testing.assert_allclose(cut.final.z, uniform.final.z, rtol=0, atol=1e-10 * np.abs(uniform.final.z).max())
    np.testing.assert_allclose(cut.final.displacement, uniform.final.displacement, rtol=0, atol=1e-13)
    # ξ is the sum of k_sub d⁺ over the sub-steps, in order
    xi = np.zeros(cut.contact_nodes)
    for k, d in zip(cut.series("k"), cut.contact_history("penetration")):
        xi = xi + k * np.maximum(d, 0.0)
    np.testing.assert_array_equal(xi, cut.contact_history("xi")[-1])


def hard_case(max_iterations, **solver):
    case = half_disc_case(h=0.1, load=20.0, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["solver"].update(max_iterations=max_iterations, **solver)
    return case


def test_a_step_newton_cannot_do_whole_is_cut_and_the_run_completes():
    result = vpcontact.solve(hard_case(4))
    whole = vpcontact.solve(hard_case(50))
    assert whole.step_cuts == 0 and len(whole.rows) == 11 and whole.series("newton_iterations")[3] == 5
    assert result.status == "complete" and result.steps == 11 and result.step_cuts == 3 and len(result.rows) == 14
    cut = result.series("substep") > 1
    assert set(result.series("step")[cut]) == {4}  # step 4 was cut ...
    four = result.series("step") == 4
    assert result.series("k")[four].sum() == pytest.approx(0.1, abs=1e-15)  # ... into sub-steps that add up to k
    assert result.series("k")[four].min() == 0.1 / 8  # down to the 3rd halving
    np.testing.assert_array_equal(result.series("t", substeps=False), result.discretization.times)
    assert np.all(np.diff(result.series("t")) > 0)
    assert result.series("newton_iterations").max() <= 4
    # the same solution where no step was cut; close to it after the cut step
    np.testing.assert_array_equal(result.contact_history("xi")[:3], whole.contact_history("xi")[:3])
    np.testing.assert_allclose(result.series("K_probe", substeps=False), whole.series("K_probe"), rtol=2e-3)


def test_a_step_that_fails_after_every_cut_stops_the_run_cleanly(tmp_path, capsys):
    path = write(tmp_path, hard_case(3))
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 3
    error = capsys.readouterr().err.strip()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and error == f"vpcontact: {summary['message']}" and "\n" not in error
    assert error.startswith("vpcontact: step 4 (t = 0.4) failed after 4 step cuts (sub-step of length 0.00625 ending "
                            "at t = 0.33125): no convergence in 3 Newton iterations; residual ")
    assert "complementarity" in error and "contact nodes separated/in compliance/at limit = " in error
    assert summary["steps"] == 3 and summary["step_cuts"] == 7 and summary["history_rows"] == 7
    header, rows = read_csv(out / "history.csv")
    assert header[-2:] == ["substep", "k"]
    # steps 1 and 3 needed cuts too (3 iterations are few; step 2 starts from step 1's trend); the
    # converged sub-steps of step 4 are kept
    assert [(r[0], r[-2], r[-1]) for r in rows] == [("1", "1", "0.05"), ("1", "2", "0.05"), ("2", "1", "0.1"),
                                                    ("3", "1", "0.05"), ("3", "2", "0.05"), ("4", "1", "0.0125"),
                                                    ("4", "2", "0.0125")]
    assert [float(r[1]) for r in rows] == pytest.approx([0.05, 0.1, 0.2, 0.25, 0.3, 0.3125, 0.325], abs=1e-15)
    assert len(read_csv(out / "contact.csv")[1]) == 7 * summary["contact_nodes"]
    assert not (out / "checkpoint").exists()
    # without cuts it fails at the first step, at once, with the same kind of message
    result = vpcontact.solve(hard_case(3, max_step_cuts=0))
    assert result.status == "failed" and result.message.startswith(
        "step 1 (t = 0.1) failed: no convergence in 3 Newton iterations; residual ")
    assert result.message.endswith("contact nodes separated/in compliance/at limit = 0/17/0; try solver.max_iterations"
                                   " = 6, smaller time steps (time.steps), or solver.tolerance = 1e-11")
    assert len(result.rows) == 0 and result.step_cuts == 0 and result.summary()["final"] == {}


# --- reproducibility -----------------------------------------------------------------------------------
def test_two_runs_give_bitwise_the_same_numbers(tmp_path):
    """Default solver (condensed, MKL PARDISO where installed) on 37k dofs, a new right-hand side at
    every step and more than 50 solves (the plain factorization takes over): with PARDISO's solve on
    two threads, these runs differed from step 28 on."""
    case = creeping_case(steps=60, h=0.01, checkpoint_every_steps=0, checkpoint_every_seconds=0)
    case["output"]["field_steps"] = "final"
    path = write(tmp_path, case)
    for name in ("first", "second"):
        assert main(["run", str(path), "--out", str(tmp_path / name), "--quiet"]) == 0
    assert (tmp_path / "first" / "history.csv").read_bytes() == (tmp_path / "second" / "history.csv").read_bytes()
    assert (tmp_path / "first" / "contact.csv").read_bytes() == (tmp_path / "second" / "contact.csv").read_bytes()
    first, second = (json.loads((tmp_path / name / "summary.json").read_text()) for name in ("first", "second"))
    for summary in (first, second):
        del summary["wall_time_s"], summary["timings_s"], summary["predicted_costs"], summary["peak_memory_bytes"]
    assert first == second and first["linear_solves"] > 50
    assert_same_run(tmp_path / "first", tmp_path / "second", bitwise=True)


def test_pardiso_solves_are_reproducible():
    pardiso = pytest.importorskip("vpcontact.solvers.pardiso")
    try:
        pardiso.library()
    except OSError:
        pytest.skip("MKL PARDISO is not installed")
    problem = vpcontact.build_problem(vpcontact.load_case(creeping_case(h=0.01)))
    free = problem.free
    A = problem.A[free][:, free] + problem.surface.operator[:, free].T @ problem.surface.operator[:, free] * 100.0
    solver = pardiso.Pardiso(A.tocsr())
    b = np.random.default_rng(1).standard_normal(A.shape[0])
    first = solver.solve(b)
    for _ in range(20):
        np.testing.assert_array_equal(solver.solve(b), first)
    assert np.linalg.norm(A @ first - b) <= 1e-10 * np.linalg.norm(b)
