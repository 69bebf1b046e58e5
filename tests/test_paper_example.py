"""The paper's example (Sect. 4.1) with the calibrated load, as shipped in examples/paper_ball.toml."""

from pathlib import Path

import numpy as np
import pytest

import vpcontact
from vpcontact.laws.contact import AT_LIMIT

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
VARIANTS = {"beta=1": {}, "alpha=0": {"contact.stiffness.alpha": 0.0}, "beta=-1": {"contact.stiffness.beta": -1.0}}


def solve_example(name="paper_ball.toml", **overrides):
    return vpcontact.solve(vpcontact.load_case(EXAMPLES / name, {"output.field_steps": "none", **overrides}))


@pytest.fixture(scope="module")
def runs():
    return {label: solve_example(**overrides) for label, overrides in VARIANTS.items()}


def test_calibrated_load_reproduces_the_paper_stiffness_for_both_betas(runs):
    """Calibrated on β = 1 (K: 100 → 323); β = −1 is a prediction: the paper reports 100 → 21."""
    assert runs["beta=1"].series("K_probe")[-1] == pytest.approx(323.0, abs=0.05)
    assert 20.5 <= runs["beta=-1"].series("K_probe")[-1] < 21.5
    assert runs["beta=1"].contact_nodes == 127  # 126 edges on Γ3, as the paper's 128


def test_penetration_is_ordered_by_the_hardening_of_the_layer(runs):
    mean = {label: r.series("mean_penetration")[-1] for label, r in runs.items()}
    assert mean["beta=1"] < mean["alpha=0"] < mean["beta=-1"]
    bottom = {label: r.series("penetration_probe")[-1] for label, r in runs.items()}
    assert bottom["beta=1"] < bottom["alpha=0"] <= bottom["beta=-1"] <= 0.2 + 1e-12


def test_the_hardening_layer_is_never_crushed_and_the_softening_one_largely_is(runs):
    assert runs["beta=1"].series("nodes_at_limit").max() == 0
    assert runs["beta=1"].series("nodes_in_compliance")[-1] == runs["beta=1"].contact_nodes
    soft = runs["beta=-1"]
    assert soft.series("nodes_at_limit")[-1] >= 0.25 * soft.contact_nodes
    assert np.all(soft.contact_history("penetration")[soft.contact_history("status") == AT_LIMIT] == pytest.approx(0.2))


def test_K_is_monotone_in_time_at_every_node(runs):
    assert np.all(np.diff(runs["beta=1"].contact_history("K"), axis=0) >= 0)
    assert np.all(np.diff(runs["beta=-1"].contact_history("K"), axis=0) <= 0)
    assert np.all(runs["alpha=0"].contact_history("K") == 100.0)


def test_every_step_converged_with_small_residuals(runs):
    for result in runs.values():
        assert result.status == "complete"
        assert result.series("residual").max() <= 1e-10
        assert result.series("complementarity").max() <= 1e-10 * 2.0


def test_the_printed_load_crushes_the_layer_whatever_beta():
    """With f2 = 1000 t nearly every contact node ends on the rigid base, for β = 1 as for β = −1."""
    for beta in (1.0, -1.0):
        result = solve_example("paper_ball_printed_load.toml", **{"contact.stiffness.beta": beta})
        assert result.series("nodes_at_limit")[-1] >= 0.95 * result.contact_nodes


def test_bottom_point_quantities_converge_under_mesh_refinement(runs):
    coarse, medium = (solve_example(**{"mesh.h": h}) for h in (0.05, 0.025))
    fine = runs["beta=1"]
    for column in ("normal_stress_probe", "max_penetration"):
        values = [r.series(column)[-1] for r in (coarse, medium, fine)]
        assert abs(values[2] - values[1]) < abs(values[1] - values[0]), (column, values)
        assert abs(values[2] - values[1]) < 1e-4 * abs(values[2]), (column, values)
