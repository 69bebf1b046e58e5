"""The reactions of the Dirichlet parts, their mean displacements, the contact and limit areas (history.csv)
and the balance of the forces (summary.json), read as a user reads them: the run directory written by
``vpcontact.write_run``, history.csv and contact.csv by pandas, summary.json by json.

The closed forms: a body whose Dirichlet parts are the only supports of a direction carries the applied
resultant there, R = −Σ F in that direction; a frictionless flat foundation (normal −y) carries none in x.
"""

import json

import numpy as np
import pandas as pd
import pytest

import vpcontact
from conftest import rectangle_case

METHODS = ("full", "condensed", "iterative")


def written(case, tmp_path, name="run"):
    """(history.csv, contact.csv, summary.json, result) of ``case``'s run written into ``tmp_path / name``."""
    result = vpcontact.solve(case)
    out = vpcontact.write_run(result, tmp_path / name)
    summary = json.loads((out / "summary.json").read_text())
    return pd.read_csv(out / "history.csv"), pd.read_csv(out / "contact.csv"), summary, result


def on_rollers(method="full", **changes):
    """The block [0, 1] × [0, 0.5] held in x on its left side, pushed by a traction (7t, −100t) on its top onto
    the foundation under its bottom (g0 = 0: every bottom node in contact from the first step; the layer
    thickness g = 0.2 is reached at the last steps)."""
    case = rectangle_case()
    case["boundary"]["dirichlet"] = [{"part": "left", "components": ["x"]}]
    case["boundary"]["traction"] = [{"part": "top", "value": ["7*t", "-100*t"]}]
    case["solver"]["method"] = method
    case.update(changes)
    return case


def cantilever(method="full"):
    """The block held (u = 0) on its left side, bent by a traction −100t on its top towards the foundation,
    0.3 under its bottom (g0 = 0.3): no contact at the first steps, the free end on the layer later."""
    case = rectangle_case()
    case["boundary"]["dirichlet"] = [{"part": "left"}]
    case["contact"]["gap"] = "0.3"
    case["solver"]["method"] = method
    return case


def relative(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b))


def test_a_block_held_at_its_bottom_carries_the_load(tmp_path):
    """No contact: the bottom (u = 0) holds the traction (3t, −5t) on the top (width 1): R = −(3t, −5t); the mean
    displacement of the held part is 0, the areas 0, the balance holds to rounding."""
    case = rectangle_case()
    del case["contact"]
    case["boundary"]["dirichlet"] = [{"part": "bottom"}]
    case["boundary"]["traction"] = [{"part": "top", "value": ["3*t", "-5*t"]}]
    history, _, summary, _ = written(case, tmp_path)
    t = history["t"].to_numpy()
    assert relative(history["reaction_bottom_x"], -3 * t) < 1e-9
    assert relative(history["reaction_bottom_y"], 5 * t) < 1e-9
    assert relative(history["applied_force_x"], 3 * t) < 1e-12
    assert np.all(history[["displacement_bottom_x", "displacement_bottom_y", "contact_area", "limit_area"]] == 0)
    assert summary["final"]["balance_relative_residual"] < 1e-9
    assert summary["final"]["contact_area"] == 0


@pytest.mark.parametrize("method", METHODS)
def test_rollers_carry_the_tangential_load_and_the_layer_the_normal_one(tmp_path, method):
    """Held in x on the left, on a frictionless layer: the left side carries −7t (the whole x resultant) and
    nothing in y, the foundation 100t; every bottom node is in contact: the contact area is the bottom's length
    1 (and the sum of contact.csv's weights where d > 0); the limit area is that of the nodes at the limit; the
    mean displacement of the left side is that of the last level's displacement field at its nodes."""
    history, contact, summary, result = written(on_rollers(method), tmp_path)
    t = history["t"].to_numpy()
    left = result.discretization.mesh.nodes("left")  # the mean displacement, against the last level's field
    assert history["displacement_left_y"].iloc[-1] == pytest.approx(result.final.displacement[left, 1].mean(), rel=1e-10)
    assert relative(history["reaction_left_x"], -7 * t) < 1e-9
    assert np.all(np.abs(history["reaction_left_y"]) == 0)  # y is not held: no dof contributes
    assert relative(history["contact_force_y"], 100 * t) < 1e-9
    assert np.all(history["displacement_left_x"] == 0)
    assert np.all(history["displacement_left_y"] < 0)
    assert np.allclose(history["contact_area"], 1.0, rtol=1e-12)
    rows = contact.groupby("step")
    in_contact = rows.apply(lambda r: r["weight"][r["penetration"] > 0].sum(), include_groups=False)
    at_limit = rows.apply(lambda r: r["weight"][r["status"] == "at_limit"].sum(), include_groups=False)
    assert np.allclose(history.set_index("step")["contact_area"], in_contact, rtol=1e-12, atol=0)
    assert np.allclose(history.set_index("step")["limit_area"], at_limit, rtol=1e-12, atol=0)
    assert history["limit_area"].iloc[0] == 0 and history["limit_area"].iloc[-1] == pytest.approx(1.0, rel=1e-12)
    final = summary["final"]
    assert final["balance_relative_residual"] < 1e-9
    assert final["reaction"][0] == pytest.approx(-7 * 1.1, rel=1e-9)
    assert final["applied_force"] == pytest.approx([7 * 1.1, -100 * 1.1], rel=1e-12)


def test_no_contact_area_before_contact_and_the_reaction_of_a_cantilever(tmp_path):
    """The cantilever: while every node is off the layer the contact area is 0 and the held side carries the
    whole traction, R = (0, 100t); once the free end is on the layer it carries the rest: R + F + contact = 0."""
    history, contact, summary, _ = written(cantilever(), tmp_path)
    t = history["t"].to_numpy()
    separated = history["nodes_separated"] == history["nodes_separated"].max()
    assert 1 <= separated.sum() < len(history)
    before = history[separated]
    assert np.all(before["contact_area"] == 0)
    assert relative(before["reaction_left_y"], 100 * before["t"]) < 1e-9
    assert np.all(np.abs(before["reaction_left_x"]) < 1e-9 * 100 * before["t"])
    after = history[~separated]
    assert np.all(after["contact_area"] > 0) and np.all(after["contact_area"] < 1)
    assert relative(after["reaction_left_y"] + after["contact_force_y"], 100 * after["t"]) < 1e-9
    last = contact[contact["step"] == contact["step"].max()]
    assert history["contact_area"].iloc[-1] == pytest.approx(last["weight"][last["penetration"] > 0].sum(), rel=1e-12)
    assert summary["final"]["balance_relative_residual"] < 1e-9
    assert relative(history["applied_force_y"], -100 * t) < 1e-12


@pytest.mark.parametrize("case", [on_rollers, cantilever])
def test_the_three_methods_agree(case):
    """full, condensed (the reactions without recovering u) and iterative give the same columns to 1e-8 (relative
    to the largest value of the same kind: a component that is 0 is compared with the part's reaction)."""
    histories = {method: vpcontact.solve(case(method)).history for method in METHODS}
    for kind in ("reaction_", "displacement_", "contact_area", "limit_area"):
        columns = [c for c in histories["full"].columns if c.startswith(kind)]
        reference = histories["full"][columns].to_numpy()
        for method in ("condensed", "iterative"):
            difference = np.abs(histories[method][columns].to_numpy() - reference).max()
            assert difference <= 1e-8 * np.abs(reference).max(), (method, kind, difference)


@pytest.mark.parametrize("method", METHODS)
def test_a_viscoplastic_body_balances(tmp_path, method):
    """Perzyna's law: the reactions include Bᵀz; the forces balance and the rollers still carry −7t."""
    case = on_rollers(method)
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 10.0, "yield_stress": 30.0}
    history, _, summary, result = written(case, tmp_path)
    assert result.final.z is not None and np.abs(result.final.z).max() > 1.0  # the history is not negligible
    assert relative(history["reaction_left_x"], -7 * history["t"]) < 1e-9
    assert summary["final"]["balance_relative_residual"] < 1e-9


def test_the_force_displacement_and_contact_area_figures_draw_the_history():
    """result.plot.force_displacement draws the part's reaction against its mean displacement, contact_area the
    two areas against t, the numbers of result.history; a part that is not held is one line naming the held ones."""
    result = vpcontact.solve(cantilever())
    history = result.history
    figure = result.plot.force_displacement("left", force="y", displacement="x")
    (line,) = figure.axes[0].get_lines()
    np.testing.assert_array_equal(line.get_xdata(), history["displacement_left_x"])
    np.testing.assert_array_equal(line.get_ydata(), history["reaction_left_y"])
    figure = result.plot.contact_area()
    for ax, column in zip(figure.axes, ("contact_area", "limit_area")):
        np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), history[column])
    with pytest.raises(vpcontact.CaseError, match="'top' is not a Dirichlet part of the run; its Dirichlet parts: left"):
        result.plot.force_displacement("top")
    with pytest.raises(vpcontact.CaseError, match="force = 'w': expected one of x, y"):
        result.plot.force_displacement("left", force="w")


def test_a_3d_block_on_rollers_balances(tmp_path):
    """The 3D block held in x at x = 0 and in y at y = 0, pushed down onto a flat layer (normal −z): no force in x
    or y reaches the rollers (R_x = R_y = 0 to 1e-9 of the load), the layer carries the load, the forces balance;
    the contact area is the sum of contact.csv's weights where d > 0 and grows with the load."""
    from conftest import block_3d_case

    history, contact, summary, _ = written(block_3d_case(), tmp_path)
    load = np.abs(history["applied_force_z"]).to_numpy()
    assert relative(load, 30 * history["t"]) < 1e-12  # −30t on the unit square top
    for column in ("reaction_left_x", "reaction_front_y"):
        assert np.all(np.abs(history[column]) <= 1e-9 * load), column
    assert np.all(history[["reaction_left_y", "reaction_left_z", "reaction_front_x", "reaction_front_z"]] == 0)
    assert relative(history["contact_force_z"], load) < 1e-9
    last = contact[contact["step"] == contact["step"].max()]
    assert history["contact_area"].iloc[-1] == pytest.approx(last["weight"][last["penetration"] > 0].sum(), rel=1e-12)
    assert 0 < history["contact_area"].iloc[0] < history["contact_area"].iloc[-1] < 1
    assert summary["final"]["balance_relative_residual"] < 1e-9


def test_a_dof_held_by_two_parts_is_shared_and_the_parts_add_up(tmp_path):
    """The bottom held (u = 0) and the left side held in x: their corner's x dof is shared equally, and the two
    parts' x reactions add up to the whole, −3t; the bottom alone carries 5t in y."""
    case = rectangle_case()
    del case["contact"]
    case["boundary"]["dirichlet"] = [{"part": "bottom"}, {"part": "left", "components": ["x"]}]
    case["boundary"]["traction"] = [{"part": "top", "value": ["3*t", "-5*t"]}]
    history, _, summary, _ = written(case, tmp_path)
    t = history["t"]
    assert np.all(history["reaction_left_x"].abs() > 1e-3 * t)  # the left side takes a share
    assert relative(history["reaction_left_x"] + history["reaction_bottom_x"], -3 * t) < 1e-9
    assert relative(history["reaction_bottom_y"], 5 * t) < 1e-9
    assert np.all(history["reaction_left_y"] == 0)
    assert summary["final"]["balance_relative_residual"] < 1e-9
