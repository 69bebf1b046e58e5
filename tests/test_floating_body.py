"""A body that only the foundation holds: when no contact node carries a force and the Dirichlet conditions
leave a rigid motion free, the step problem does not determine the body's position. The run fails there with
one line saying so, in every step method, instead of reporting a position its Newton start made up."""

import numpy as np
import pytest

import vpcontact
from conftest import rectangle_case, resumed_after, run_cli

#: the block on rollers at its sides (its vertical motion free), pressed by a load that falls to zero at
#: t = 0.5 = step 5 of 10 and stays zero: 10 sin(2πt)⁺ (its rounding at t = 0.5 is 1e-15 of its peak)
CYCLE = "-100*max(0, sin(2*pi*t))"


def cycle_case(preload: float = 0.0, method: str = "condensed") -> dict:
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = f"{CYCLE} - {preload}"
    case["time"] = {"T": 1.0, "steps": 10}
    case["solver"] = {**case["solver"], "method": method}
    return case


@pytest.mark.parametrize("method", ["condensed", "full", "iterative"])
def test_a_body_nothing_holds_fails_the_run_where_its_load_vanishes(method):
    result = vpcontact.solve(cycle_case(method=method))
    assert result.status == "failed"
    assert result.message.startswith("step 5 (t = 0.5) failed: at t = 0.5 no contact node carries a force")
    assert "rigid motion of the body free" in result.message
    assert np.allclose(result.series("t"), [0.1, 0.2, 0.3, 0.4])  # the levels before are kept


def test_the_steps_before_are_kept_and_the_penetration_there_is_that_of_the_load():
    """Up to step 4 the block is pressed: every contact node carries the same pressure, and the resultant of
    the compliance pressures balances the traction on the top (width 1, density 100 sin(2πt))."""
    result = vpcontact.solve(cycle_case())
    t = result.series("t")
    assert np.allclose(t, [0.1, 0.2, 0.3, 0.4])
    force = result.series("contact_force_y")  # on the body, upwards
    np.testing.assert_allclose(force, 100 * np.sin(2 * np.pi * t), rtol=1e-9)


def test_a_small_preload_keeps_the_body_held_through_the_whole_cycle():
    """1 % of the peak load pressing the block keeps every step determined; at the unloaded steps the contact
    force is that preload."""
    result = vpcontact.solve(cycle_case(preload=1.0))
    assert result.status == "complete", result.message
    t = result.series("t")
    force = result.series("contact_force_y")  # on the body, upwards
    np.testing.assert_allclose(force, 100 * np.maximum(0.0, np.sin(2 * np.pi * t)) + 1.0, rtol=1e-9, atol=1e-9)


def test_a_clamped_body_may_lift_off_the_foundation():
    """With its bottom's sides held in both directions the block has no free rigid motion: pulled up it
    separates from the foundation and the run completes."""
    case = cycle_case()
    case["boundary"]["traction"][0]["value"][1] = "100*t"
    case["boundary"]["dirichlet"] = [{"part": "left", "components": ["x", "y"]},
                                     {"part": "right", "components": ["x", "y"]}]
    result = vpcontact.solve(case)
    assert result.status == "complete", result.message
    d = result.contact_history("penetration")
    assert np.all(d[:, 1:-1] < 0) and np.all(d[:, [0, -1]] == 0)  # held at the corners, lifted between


def test_a_run_resumed_before_the_load_vanishes_fails_there_too(tmp_path):
    """The largest pressure so far comes back with the levels of a checkpoint: resumed after step 4, the run
    still fails at step 5, its first level (its rounding-level pressure is measured against steps 1–4, not
    against itself alone)."""
    resumed = resumed_after(vpcontact.Case.model_validate(cycle_case()), 4, tmp_path).run()
    assert resumed.status == "failed" and resumed.message.startswith("step 5 (t = 0.5) failed: at t = 0.5 no contact")


def test_the_command_line_exits_3_with_the_message_on_one_line(tmp_path):
    import tomli_w

    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(cycle_case()))
    status, _, stderr = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert status == 3, stderr
    assert stderr.count("\n") == 1 and "no contact node carries a force" in stderr
    assert "Traceback" not in stderr
