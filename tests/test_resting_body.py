"""A body that only the foundation holds, at a level where nothing presses it (the load passes through zero):
the step problem fixes its deformation but not its rigid position, and vpcontact places it where it changes
least from the last level (vpcontact.timeloop.resting). Checked against what such a level must be: zero contact force,
equilibrium of the body alone, every contact node off the layer, the least change (an independent QP solver),
the same answer from the three step methods and from a resumed run; and a load that pulls the body off the
foundation fails at once with one line."""

import numpy as np
import pytest
import scipy.optimize

import vpcontact
from conftest import block_3d_case, half_disc_case, rectangle_case, resumed_after, run_cli
from vpcontact.timeloop.resting import least_shift, unbalanced

METHODS = ["condensed", "full", "iterative"]
#: the block on rollers at its sides (its vertical motion free), pressed by a load that falls to zero at
#: t = 0.5 = step 5 of 10 and stays zero: 100 sin(2πt)⁺ (its rounding at t = 0.5 is 1e-15 of its peak)
CYCLE = "-100*max(0, sin(2*pi*t))"
#: pressed, unloaded to zero at t = 0.5 and pressed again: 100 |sin(2πt)|
RELOAD = "-100*abs(sin(2*pi*t))"


def block(load: str, method: str = "condensed", **time) -> dict:
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = load
    case["time"] = {"T": 1.0, "steps": 10, **time}
    case["solver"] = {**case["solver"], "method": method}
    case["output"] = {"field_steps": "all"}
    return case


def solved(case: dict):
    case = vpcontact.Case.model_validate(case)
    return vpcontact.solve(vpcontact.build_problem(case), output=case.output)


# --- the least-distance program and the balance test, against independent solvers --------------------------
@pytest.mark.parametrize("seed", range(20))
def test_the_least_shift_is_the_nearest_feasible_point_an_independent_qp_solver_finds(seed):
    """min ‖x‖ s.t. d + M x ≤ room, for random M (m × k, k = 1…6) and d with some nodes beyond their room: the
    Lawson–Hanson answer is feasible and no farther than SLSQP's from the origin (to 1e-7 of its size)."""
    rng = np.random.default_rng(seed)
    k = 1 + seed % 6
    m = 5 + seed
    M = rng.normal(size=(m, k))
    M[:, 0] = -np.abs(M[:, 0]) - 0.1  # the first coordinate lifts every node: a feasible point exists
    d, room = rng.normal(scale=0.3, size=m), np.where(rng.random(m) < 0.2, 0.05, 0.0)
    x = least_shift(M, d, room)
    assert x is not None and np.all(d + M @ x <= room + 1e-12)
    reference = scipy.optimize.minimize(lambda y: y @ y, np.full(k, 10.0) * (np.arange(k) == 0), jac=lambda y: 2 * y,
                                        constraints=[{"type": "ineq", "fun": lambda y: room - d - M @ y,
                                                      "jac": lambda y: -M}], method="SLSQP", tol=1e-14)
    assert reference.success
    assert np.linalg.norm(x) <= np.linalg.norm(reference.x) + 1e-7 * max(1.0, np.linalg.norm(reference.x))
    np.testing.assert_allclose(x, reference.x, atol=1e-6 * max(1.0, np.linalg.norm(reference.x)))


def test_no_shift_when_every_node_is_within_its_room_and_none_when_no_shift_helps():
    M = np.array([[-1.0], [-0.5], [0.0]])
    np.testing.assert_array_equal(least_shift(M, np.array([-0.3, -0.1, 0.0]), np.zeros(3)), [0.0])
    assert least_shift(M, np.array([0.3, 0.1, 1e-3]), np.zeros(3)) is None  # a node no motion moves, beyond
    np.testing.assert_allclose(least_shift(M, np.array([0.3, 0.1, 1e-3]), np.zeros(3), allowance=1e-2), [0.3])
    assert least_shift(np.array([[-1.0], [1.0]]), np.array([0.3, 0.1]), np.zeros(2)) is None  # pressed both ways


@pytest.mark.parametrize("seed", range(10))
def test_the_unbalanced_part_of_a_resultant_is_that_of_scipys_bounded_least_squares(seed):
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(8, 1 + seed % 3))
    r = rng.normal(size=M.shape[1])
    reference = scipy.optimize.lsq_linear(M.T, r, bounds=(0, np.inf), tol=1e-14)
    assert unbalanced(M, r) == pytest.approx(np.linalg.norm(M.T @ reference.x - r), abs=1e-9)
    assert unbalanced(M, M.T @ np.abs(rng.normal(size=8))) == pytest.approx(0.0, abs=1e-12)  # in the cone


# --- the time loop ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", METHODS)
def test_an_elastic_block_unloaded_to_zero_rests_undeformed_on_the_layer(method):
    """Pressed up to t = 0.4, unloaded from t = 0.5 on: at every unloaded level the contact force is zero, the
    block (elastic, so undeformed) is back at u = 0, its bottom touching the layer (d = 0 at every node), and
    the levels before balance the load."""
    result = solved(block(CYCLE, method))
    assert result.status == "complete", result.message
    t = result.series("t")
    np.testing.assert_allclose(t, np.linspace(0.1, 1.0, 10))
    force = result.series("contact_force_y")
    np.testing.assert_allclose(force, 100 * np.maximum(0.0, np.sin(2 * np.pi * t)), rtol=1e-9, atol=1e-9)
    d = result.contact_history("penetration")
    peak = np.abs(result.fields[2].displacement).max()
    assert np.all(d[:4] > 0) and np.all(np.abs(d[4:]) <= 1e-12 * peak)
    assert np.all(result.contact_history("pressure_compliance")[4:] == 0.0)
    assert np.all(result.series("nodes_in_compliance")[4:] == 0)
    for n in range(5, 11):
        assert np.abs(result.fields[n].displacement).max() <= 1e-12 * peak
        assert np.abs(result.fields[n].stress).max() <= 1e-10 * np.abs(result.fields[2].stress).max()


def test_the_three_methods_agree_through_an_unloading_and_a_reloading():
    """100 |sin 2πt|: the block rests at t = 0.5 and is pressed again; every level of the three methods agrees
    (penetrations to 1e-10 of the largest), and the reloaded levels balance the load."""
    results = {method: solved(block(RELOAD, method)) for method in METHODS}
    reference = results["full"]
    scale = np.abs(reference.contact_history("penetration")).max()
    for method, result in results.items():
        assert result.status == "complete", (method, result.message)
        np.testing.assert_allclose(result.contact_history("penetration"), reference.contact_history("penetration"),
                                   atol=1e-10 * scale, rtol=0)
        np.testing.assert_allclose(result.contact_history("xi"), reference.contact_history("xi"), atol=1e-10 * scale)
    t = reference.series("t")
    np.testing.assert_allclose(reference.series("contact_force_y"), 100 * np.abs(np.sin(2 * np.pi * t)),
                               rtol=1e-9, atol=1e-9)


def test_a_viscoplastic_block_keeps_its_permanent_strain_and_rests_on_the_layer():
    """A Perzyna block (yield stress below the peak load) unloaded to zero keeps a permanent deformation: the
    rest level is not u = 0, but its contact force is zero, its lowest nodes touch the layer (max d = 0), none
    penetrates, and the whole system balances without contact: ‖A u − b‖ is rounding."""
    case = block(CYCLE, "full")
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.05, "yield_stress": 20.0}
    case["time"]["steps"] = 20
    problem = vpcontact.build_problem(vpcontact.Case.model_validate(case))
    output = vpcontact.Case.model_validate(case).output
    result = vpcontact.solve(problem, output=output)
    assert result.status == "complete", result.message
    d = result.contact_history("penetration")
    rest = result.series("t") > 0.5 + 1e-9
    assert np.all(result.series("contact_force_y")[rest] == 0.0)
    assert np.all(np.abs(d[rest].max(axis=1)) <= 1e-12 * d.max())
    last = result.fields[20]
    permanent = np.abs(last.displacement[:, 1]).max()
    assert permanent > 1e-3 * np.abs(result.fields[5].displacement[:, 1]).max()  # not back at u = 0
    # equilibrium without contact: the internal forces of σ balance the (zero) load at every free dof
    from vpcontact.fem.assembly import stress_force

    residual = stress_force(problem.basis, np.moveaxis(last.stress, 0, -1))[problem.free]
    assert np.linalg.norm(residual) <= 1e-9 * np.linalg.norm(stress_force(problem.basis, np.moveaxis(
        result.fields[5].stress, 0, -1))[problem.free])


def test_a_block_already_off_the_layer_stays_where_it_is():
    """Unloaded for several levels in a row: the first rest level places the body, the next ones do not move
    it (the least change is none)."""
    result = solved(block(CYCLE, "condensed"))
    u = np.array([result.fields[n].displacement for n in range(5, 11)])
    peak = np.abs(result.fields[2].displacement).max()
    np.testing.assert_allclose(u, np.broadcast_to(u[0], u.shape), atol=1e-12 * peak, rtol=0)


@pytest.mark.parametrize("method", METHODS)
def test_the_paper_half_disc_under_log_t_rests_at_t_1_and_fails_once_the_load_pulls(method):
    """A traction (0, 20 log t) from t = 0.2: it presses the half disc down until t = 1, where it vanishes (the
    grid's t_8 = 1 + 2e-16: a rounding-level pull, treated as zero), then pulls it up: the run keeps every level
    to t = 1 (the body back at u = 0 there, elastic) and fails at t = 1.1 with one line saying the loads pull
    the body off the foundation."""
    case = half_disc_case()
    case["boundary"]["traction"][0]["value"] = ["0", "20*log(t)"]
    case["time"] = {"start": 0.2, "T": 1.1, "steps": 9}
    case["solver"]["method"] = method
    case["output"] = {"field_steps": "all"}
    result = solved(case)
    assert result.status == "failed"
    assert result.message.startswith("step 9 (t = 1.1) failed: at t = 1.1 the loads pull the body off the foundation")
    assert "\n" not in result.message
    t = result.series("t")
    assert t[-1] == 1.0000000000000002 and len(t) == 8
    assert result.series("contact_force_y")[-1] == 0.0
    assert np.abs(result.fields[8].displacement).max() <= 1e-12 * np.abs(result.fields[7].displacement).max()


def test_a_3d_block_unloaded_to_zero_rests_on_its_curved_gap():
    """The 3D block on a flat foundation with a curved initial gap x² + y², its vertical motion free: unloaded to
    zero it rests with the corner node (gap 0) touching and every other node off the layer."""
    case = block_3d_case()
    case["boundary"]["traction"][0]["value"][2] = "-30*max(0, sin(pi*t/1.1*1.25))"  # zero from t = 0.88 on
    case["output"] = {"field_steps": "all"}
    for method in ("condensed", "full"):
        case["solver"] = {"method": method}
        result = solved(case)
        assert result.status == "complete", result.message
        d = result.contact_history("penetration")
        scale = np.abs(d).max()
        assert np.all(result.series("contact_force_z")[-2:] == 0.0)
        assert np.all(d[-2:] <= 0.0) and np.all(np.abs(d[-2:].max(axis=1)) <= 1e-10 * scale)
        corner = np.argmin(np.sum(result.discretization.surface.coordinates[:2] ** 2, axis=0))
        assert np.argmax(d[-1]) == corner


@pytest.mark.parametrize("method", ["condensed", "full"])
def test_a_run_resumed_before_the_load_vanishes_rests_where_the_uninterrupted_run_does(tmp_path, method):
    """The body's position on its free motion comes back with the checkpoint: resumed after step 4, the rest
    levels are those of the uninterrupted run, bit for bit."""
    case = vpcontact.Case.model_validate(block(CYCLE, method))
    whole = solved(block(CYCLE, method))
    resumed = resumed_after(case, 4, tmp_path).run()
    assert resumed.status == "complete", resumed.message
    for n in range(5, 11):
        np.testing.assert_array_equal(resumed.fields[n].displacement, whole.fields[n].displacement)


def test_the_command_line_exits_3_with_one_line_when_the_load_pulls_the_body_off(tmp_path):
    import tomli_w

    case = block("100*t")
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    status, _, stderr = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert status == 3, stderr
    assert stderr.count("\n") == 1 and "pull the body off the foundation" in stderr
    assert "Traceback" not in stderr


def test_a_clamped_body_may_lift_off_the_foundation():
    """With its bottom's sides held in both directions the block has no free rigid motion: pulled up it
    separates from the foundation and the run completes."""
    case = block("100*t")
    case["boundary"]["dirichlet"] = [{"part": "left", "components": ["x", "y"]},
                                     {"part": "right", "components": ["x", "y"]}]
    result = solved(case)
    assert result.status == "complete", result.message
    d = result.contact_history("penetration")
    assert np.all(d[:, 1:-1] < 0) and np.all(d[:, [0, -1]] == 0)  # held at the corners, lifted between
