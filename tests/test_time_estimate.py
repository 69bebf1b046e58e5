"""The error estimate in time (vpcontact.timeloop.companion) and the steps it chooses (time.adaptive,
vpcontact.timeloop.time_control): the estimate against the error of runs with 8× and 16× as many steps, the companion's
second order, the time control's guarantee and its gain on a load that rises fast and is then held, a resumed run,
and a gmsh pad run by the command line in SI units."""

import json

import numpy as np
import pytest

import vpcontact
from conftest import assert_refused, run_cli, snapshot_tree
from test_adapt_during_run import pad_case, pad_mesh, vtu_displacement
from vpcontact import build_problem
from vpcontact.case.translate import output_options
from vpcontact.results.norms import energy_norm
from vpcontact.timeloop.companion import Companion
from vpcontact.timeloop.loop import TimeLoop


def ball(steps: int, *, h: float = 0.1, T: float = 1.1, load: str = "-17.977*t", viscoplastic: bool = False,
         beta: float = -1.0, alpha: float = 20.0, adaptive: dict | None = None) -> dict:
    """The paper's half disc (its calibrated load by default), its layer softening (β = −1), with the error
    estimates at every level; ``viscoplastic``: the body of examples/viscoplastic_ball.toml."""
    material = {"E": 1000.0, "nu": 0.3}
    if viscoplastic:
        material["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    return {"mesh": {"shape": "half_disc", "h": h}, "material": material,
            "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],
                         "traction": [{"part": "top_arc", "value": ["0", load]}]},
            "contact": {"part": "bottom_arc", "g": 0.2, "stiffness": {"law": "power", "c_v": 100.0, "alpha": alpha,
                                                                     "beta": beta}},
            "time": {"T": T, "steps": steps, **({"adaptive": True, **adaptive} if adaptive is not None else {})},
            "solver": {"tolerance": 1e-12}, "output": {"field_steps": "final", "error_estimate": True}}


def error_against(result, reference, problem) -> float:
    """‖u − u_ref‖_E at the last level of two runs on the mesh of ``problem``."""
    mesh = problem.mesh.mesh
    return energy_norm(mesh.p, mesh.t, result.final.displacement - reference.final.displacement,
                       problem.elasticity.lame)


def slope(x, y) -> float:
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def test_the_estimate_in_time_is_zero_where_the_scheme_has_no_error_in_time():
    """K constant (α = 0) and an elastic body: each level is the static problem of its loads, whatever the rules of
    the histories; the companion finds the run's solution again."""
    result = vpcontact.solve(ball(6, alpha=0.0))
    history = result.history
    assert result.status == "complete"
    assert history["time_estimate"].max() <= 1e-9 * history["error_estimate"].max()
    assert result.summary()["final"]["time_estimate"] == history["time_estimate"].iloc[-1]


@pytest.mark.parametrize("viscoplastic", [False, True], ids=["softening layer", "viscoplastic body"])
def test_the_estimate_in_time_is_the_error_of_the_time_steps(viscoplastic):
    """η_k(T) against ‖u_n − u(T)‖_E, u(T) a run with 16× the steps on the same mesh: the error and the estimate
    fall as k (first order) and the estimate is the error within 30 % (measured 0.9–1.15 on finer meshes,
    docs/adaptivity.md)."""
    steps = [5, 10, 20]
    problem = build_problem(ball(1, viscoplastic=viscoplastic))
    reference = vpcontact.solve(ball(320, viscoplastic=viscoplastic))
    errors, estimates = [], []
    for n in steps:
        result = vpcontact.solve(ball(n, viscoplastic=viscoplastic))
        errors.append(error_against(result, reference, problem))
        estimates.append(result.history["time_estimate"].iloc[-1])
    effectivity = np.array(estimates) / np.array(errors)
    assert np.all((effectivity > 0.75) & (effectivity < 1.3)), effectivity
    k = 1.1 / np.array(steps)
    assert 0.85 < slope(k, errors) < 1.2 and 0.85 < slope(k, estimates) < 1.2


def test_the_companion_is_second_order_in_time():
    """ũ = u + D, the companion's own solution (trapezoid rules for ξ and z, the rate at the level's end predicted):
    its error falls as k² against a companion with 16× the steps, on a viscoplastic body on a softening layer."""
    def companion(steps):
        problem = build_problem(ball(steps, viscoplastic=True))
        loop = TimeLoop(problem, output_options(vpcontact.load_case(ball(steps, viscoplastic=True)).output))
        result = loop.run()
        u = np.zeros(problem.basis.N)
        u[problem.basis.nodal_dofs] = result.final.displacement.T
        u[problem.free] += loop.companion.level.difference
        return problem, u[problem.basis.nodal_dofs].T

    problem, reference = companion(320)
    mesh = problem.mesh.mesh
    errors = [energy_norm(mesh.p, mesh.t, companion(n)[1] - reference, problem.elasticity.lame) for n in (5, 10, 20)]
    assert slope(1.1 / np.array([5, 10, 20]), errors) > 1.8, errors


RAMP_AND_HOLD = "-17.977*min(t/0.1, 1)"  # the calibrated load reached at t = 0.1, then held while the body creeps


def test_adaptive_steps_keep_the_estimate_in_time_within_its_share_and_pay_where_the_load_rises_fast():
    """time.adaptive on a viscoplastic ball loaded in 0.1 s, then held to t = 4: at every level the estimate in time
    is within the sum of what its sub-steps added (the triangle inequality of D = ũ − u), and within time.balance
    times the largest space estimate so far wherever no sub-step was accepted above its share. The sub-steps are
    short while the load rises and the body starts to flow, long while it creeps; a uniform run with as many levels
    has a larger ratio η_k / η_h."""
    balance = 0.3
    result = vpcontact.solve(ball(8, T=4.0, load=RAMP_AND_HOLD, viscoplastic=True, beta=1.0,
                                  adaptive={"balance": balance}))
    assert result.status == "complete"
    history = result.history
    eta_k, theta, eta_h = history["time_estimate"], history["time_estimate_step"], history["error_estimate"]
    assert np.all(eta_k <= np.cumsum(theta) * (1 + 1e-12))
    summary = result.summary()
    assert summary["time_cuts"] > 0
    within = eta_k <= balance * np.maximum.accumulate(eta_h)
    assert within.all() if summary["time_over_share"] == 0 else within.mean() > 0.9
    k = history.groupby("step")["k"].min()
    assert k[1] <= 0.5 / 2**5 and k[8] >= 0.25  # the rise in sub-steps of ~10 ms, the creep in steps of 0.25 s or more
    assert summary["step_cuts"] == 0 and history["k"].min() == 0.5 / 2**6  # time.max_halvings (6) and no deeper
    steps = history["step"].to_numpy()
    assert np.all(history["t"].to_numpy()[np.r_[steps[1:] != steps[:-1], True]] == 0.5 * np.arange(1, 9))
    uniform = vpcontact.solve(ball(len(history), T=4.0, load=RAMP_AND_HOLD, viscoplastic=True, beta=1.0)).history
    assert (eta_k / eta_h).max() < (uniform["time_estimate"] / uniform["error_estimate"]).max()


def failing_once(monkeypatch, call: int) -> list:
    """The companion's Newton iteration fails at its ``call``-th solve (one time); returns the (t, h) of the attempt
    of each of its solves."""
    calls = []
    solve = Companion._solve

    def maybe_failing(self, solver, attempt, *args):
        calls.append((attempt.t, attempt.h))
        return None if len(calls) == call else solve(self, solver, attempt, *args)

    monkeypatch.setattr(Companion, "_solve", maybe_failing)
    return calls


def test_a_companion_whose_newton_iteration_fails_restarts_from_the_run_and_leaves_the_run_as_it_is(monkeypatch):
    """Where the companion's step fails, that level has no estimate in time (NaN) and the companion restarts from
    the run's level: the estimates after it measure what the steps after it add; the run is the same bit for bit
    (the companion never feeds back into a run of fixed steps)."""
    case = ball(8, viscoplastic=True)
    plain = vpcontact.solve(case)
    calls = failing_once(monkeypatch, 4)
    failed = vpcontact.solve(case)
    assert failed.status == "complete" and len(calls) == 8
    mine, theirs = failed.history, plain.history
    assert np.isnan(mine["time_estimate"].iloc[3]) and np.isnan(mine["time_estimate_step"].iloc[3])
    assert np.isfinite(mine["time_estimate"].drop(index=3)).all()
    np.testing.assert_array_equal(mine["time_estimate"].iloc[:3], theirs["time_estimate"].iloc[:3])
    # restarted at the run's level 4: level 5's estimate is what step 5 adds, no more than the undisturbed one
    assert 0.0 < mine["time_estimate"].iloc[4] == mine["time_estimate_step"].iloc[4]
    assert mine["time_estimate"].iloc[4] < theirs["time_estimate"].iloc[4]
    others = [c for c in theirs.columns if not c.startswith("time_estimate") and c not in ("wall_s", "elapsed_s")]
    for column in others:
        np.testing.assert_array_equal(mine[column].to_numpy(), theirs[column].to_numpy(), err_msg=column)


def test_an_adaptive_step_whose_companion_fails_is_halved_and_completes(monkeypatch):
    """time.adaptive: a step whose companion fails has no estimate to accept it by, so it is done again in halves."""
    calls = failing_once(monkeypatch, 3)
    result = vpcontact.solve(ball(8, adaptive={"max_halvings": 4}))
    history = result.history
    assert result.status == "complete" and history["step"].iloc[-1] == 8 and history["t"].iloc[-1] == 1.1
    assert np.isfinite(history["time_estimate"]).all()
    t, h = calls[2]
    ending_there = history[np.isclose(history["t"], t, rtol=0.0, atol=1e-12)]
    assert len(ending_there) == 1 and ending_there["k"].iloc[0] < h  # reached in halves, not in the attempt that failed


def test_an_adaptive_run_stopped_and_resumed_is_the_run_that_never_stopped():
    """A snapshot after step 3 (as a checkpoint keeps it) restored in a new loop: the same sub-steps, the same
    estimates, bit for bit."""
    case = vpcontact.load_case(ball(8, T=4.0, load=RAMP_AND_HOLD, viscoplastic=True, beta=1.0,
                                    adaptive={"balance": 0.3}))
    output = output_options(case.output)
    whole = TimeLoop(build_problem(case), output).run()
    first = TimeLoop(build_problem(case), output)
    first.run(stop=lambda: "enough" if first.state.step == 3 else None)
    second = TimeLoop(build_problem(case), output)
    second.restore(first.snapshot())
    resumed = second.run()
    columns = ["t", "k", "substep", "error_estimate", "time_estimate", "time_estimate_step", "K_probe"]
    assert resumed.history[columns].equals(whole.history[columns])
    assert resumed.summary()["time_cuts"] == whole.summary()["time_cuts"] > 0
    np.testing.assert_array_equal(resumed.final.displacement, whole.final.displacement)


@pytest.mark.parametrize("setting, words", [
    ("time.balance=0.5", ("time.balance", "time.adaptive")),
    ("time.max_halvings=3", ("time.max_halvings", "time.adaptive")),
    ("time.adaptive=maybe", ("time.adaptive",)),
])
def test_the_time_control_keys_are_checked_before_anything_runs(tmp_path, setting, words):
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", "examples/paper_ball.toml", "--set", setting, "--out", str(tmp_path / "run"))
    assert_refused(status, stderr, *words, untouched=[(tmp_path, before)])


@pytest.mark.parametrize("setting, words", [("time.balance=0", ("time.balance",)),
                                            ("time.max_halvings=-1", ("time.max_halvings",))])
def test_a_time_control_value_out_of_range_is_refused(tmp_path, setting, words):
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", "examples/paper_ball.toml", "--set", "time.adaptive=true", "--set", setting,
                                "--out", str(tmp_path / "run"))
    assert_refused(status, stderr, *words, untouched=[(tmp_path, before)])


def test_a_gmsh_pad_pressed_and_released_in_adaptive_steps_from_the_command_line(tmp_path):
    """SI units, a gmsh file, displacement control that presses the pad fast, holds and releases it, time.adaptive,
    run by the command line off a terminal: pandas reads the sub-steps and both estimates in history.csv, the
    reaction balances the contact force at every level, the step rows are at the step times, VTK reads the fields."""
    import pandas
    import tomli_w

    pad_mesh(tmp_path / "pad.msh")
    case = {"mesh": {"file": "pad.msh"},
            "material": {"E": 5e6, "nu": 0.45, "viscoplastic": {"law": "perzyna", "eta": 0.2, "yield_stress": 2e5}},
            "boundary": {"dirichlet": [{"part": "left", "components": ["x"]},
                                       {"part": "top", "components": ["y"],
                                        "value": ["-3e-5*min(t/0.05, 1)*min(1, (2 - t)/0.5)"]}]},
            "contact": {"part": "bottom", "g": 1e-4, "stiffness": {"law": "power", "c_v": 2e10, "alpha": 1e4,
                                                                  "beta": 1.0}},
            "time": {"T": 1.9, "steps": 8, "adaptive": True}, "output": {"field_steps": [2, 8]}}
    (tmp_path / "pad.toml").write_text(tomli_w.dumps(case))
    status, stdout, stderr = run_cli("run", "pad.toml", "--out", "run", cwd=tmp_path)
    assert status == 0, stderr
    out = tmp_path / "run"
    history = pandas.read_csv(out / "history.csv")
    assert {"error_estimate", "time_estimate", "time_estimate_step"} <= set(history.columns)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["time_cuts"] > 0 and len(history) > 8
    assert f"8 steps in {len(history)} levels" in stdout and "error estimates at t = 1.9: in space" in stdout
    assert summary["final"]["time_estimate"] == pytest.approx(history["time_estimate"].iloc[-1], rel=1e-12)
    ends = history.drop_duplicates("step", keep="last")
    np.testing.assert_allclose(ends["t"], 1.9 * np.arange(1, 9) / 8, rtol=1e-15)
    assert history.groupby("step")["k"].sum().round(12).eq(round(1.9 / 8, 12)).all()
    assert summary["step_cuts"] > 0 or history["k"].min() >= 1.9 / 8 / 2**6  # at most time.max_halvings halvings
    scale = history["reaction_top_y"].abs().max()
    np.testing.assert_allclose(history["reaction_top_y"] + history["contact_force_y"], 0.0, atol=1e-8 * scale)
    assert np.all(history["time_estimate"] <= history["time_estimate_step"].cumsum() * (1 + 1e-12))
    assert vtu_displacement(out / "fields" / "body_00002.vtu")[:, 1].min() < -2e-5


def test_a_gmsh_pad_pressed_released_and_lifted_off_in_adaptive_steps_stays_within_its_halvings(tmp_path):
    """The same pad on a rigid step under its right half, its top moved by −30 µm·sin(πt) to t = 1.5 (pressed,
    released, lifted off: the load reverses), a body that yields: the sub-steps gather where the contact nodes
    separate, a step is never halved more than time.max_halvings times (the next step's halvings, predicted anew
    by each sub-step, do not change those of the step being done), the reaction balances the contact force at every
    level and the pad is off the layer at the end."""
    import pandas
    import tomli_w

    pad_mesh(tmp_path / "pad.msh")
    case = pad_case(yield_stress=1e3, time={"T": 1.5, "steps": 6, "adaptive": True, "balance": 0.1})
    (tmp_path / "pad.toml").write_text(tomli_w.dumps(case))
    status, stdout, stderr = run_cli("run", "pad.toml", "--out", "run", cwd=tmp_path)
    assert status == 0, stderr
    history = pandas.read_csv(tmp_path / "run" / "history.csv")
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["step_cuts"] == 0 and summary["time_cuts"] > 0 and summary["time_over_share"] > 0
    assert history["k"].min() == 0.25 / 2**6
    levels = history.groupby("step").size()
    assert levels[[3, 4]].sum() > levels[[1, 5, 6]].sum()  # the release, where the nodes separate
    scale = history["reaction_top_y"].abs().max()
    np.testing.assert_allclose(history["reaction_top_y"] + history["contact_force_y"], 0.0, atol=1e-8 * scale)
    assert history["nodes_separated"].iloc[-1] == summary["contact_nodes"]
    assert vtu_displacement(tmp_path / "run" / "fields" / "body_00006.vtu")[:, 1].max() > 0  # lifted above its start


@pytest.mark.parametrize("time_adaptive", [False, True], ids=["uniform steps", "time.adaptive"])
def test_a_run_that_adapts_its_mesh_carries_the_companion_to_each_new_mesh(time_adaptive):
    """adapt.mode = "run" with output.error_estimate (and time.adaptive): the companion's level (ξ̃, d̃ on Γ3, z̃, 𝒢̃
    per element, ũ − u) is carried with the run's level before the step solved again, through every refinement; the
    estimate in time stays a number at every level, and within the sum of what the levels added."""
    from test_adapt_during_run import punch_case

    case = punch_case()
    case = vpcontact.load_case({**case, "output": {"field_steps": [11], "error_estimate": True},
                                "time": {**case["time"], **({"adaptive": True} if time_adaptive else {})},
                                "adapt": {"mode": "run", "tolerance": 0.3}})
    adaptation = vpcontact.adapt(build_problem(case), case.adapt, case.output)
    history = adaptation.result.history
    assert adaptation.refinements >= 1 and history["step"].iloc[-1] == 11
    assert (len(history) > 11) == time_adaptive
    assert np.all(np.isfinite(history["time_estimate"])) and history["time_estimate"].iloc[-1] > 0
    assert np.all(history["time_estimate"] <= history["time_estimate_step"].cumsum() * (1 + 1e-12))


def test_the_benchmark_prints_the_rates_and_the_adaptive_runs(tmp_path):
    """benchmarks/time_estimate.py on coarse settings: its JSON has both parts, and the rates in k are first order."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).parents[1] / "benchmarks" / "time_estimate.py"
    done = subprocess.run([sys.executable, str(script), "--level", "4", "--steps", "4", "9", "18", "--levels", "4", "8",
                           "--adaptive-level", "4", "--balances", "1", "--repeats", "1", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert json.loads((tmp_path / "time_estimate.json").read_text()) == report
    for name in ("softening layer (beta = -1)", "hardening layer (beta = 1)", "viscoplastic ball"):
        assert 0.7 < report["rates"][name]["rate_time_estimate"] < 1.3, report["rates"][name]
    assert set(report["adaptive"]) == {"ramp and hold", "rise and fall"}
    for part in report["adaptive"].values():
        run = part["adaptive"][0]
        assert run["levels"] >= part["steps"] and run["uniform_steps_for_that_ratio"] >= 1
