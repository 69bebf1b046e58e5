"""The tabular layer laws (contact.stiffness.law = "table", contact.p = "table"): K(ξ) and p(r) given as points,
piecewise linear between them. A table sampled from the paper's law c_v (1 + α ξ)^β reproduces its run to the
interpolation error and converges at second order as it is refined; a table of 2 points is the constant or the
linear law; the derivative is the slope of the segment (right-sided at a breakpoint), the central difference of
the values elsewhere; a bad table is refused by its key through the command line; a run's contact.csv holds
K = the table's interpolant at its ξ."""

import copy
import tomllib

import numpy as np
import pandas as pd
import pytest
import tomli_w

import vpcontact
from vpcontact.laws.compliance import COMPLIANCE
from vpcontact.laws.stiffness import STIFFNESS
from conftest import assert_refused, half_disc_case, rectangle_case, run_cli, snapshot_tree

C_V, ALPHA, BETA = 100.0, 20.0, 2.0


def _power(xi):
    return C_V * (1.0 + ALPHA * xi) ** BETA


def _solved(case):
    result = vpcontact.solve(vpcontact.load_case(case))
    assert result.status == "complete"
    return result


def _table(xi, extrapolation="linear"):
    return {"law": "table", "xi": list(xi), "K": list(_power(np.asarray(xi))), "extrapolation": extrapolation}


def test_a_table_of_the_power_law_reproduces_its_run_and_converges_at_second_order():
    """The half disc (its contact nodes reach many histories ξ) with K = c_v (1 + α ξ)^2 and with the tables of
    that K on n + 1 equally spaced points of [0, 1.05 max ξ]: the penetrations differ by no more than the
    relative interpolation error h² max|K''| / (8 min K) of the penetrations, and that difference falls as h²
    (the least-squares rate over n = 8 ... 128 within 0.15 of 2, each halving within 0.35). Newton, with the
    slopes of the table as derivative, takes the power law's iterations (2 more at most over the run)."""
    reference = _solved(half_disc_case(g="inf", stiffness={"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": BETA}))
    d, xi = reference.contact_history("penetration"), reference.contact_history("xi")
    top, curvature = 1.05 * xi.max(), 2.0 * C_V * ALPHA**2  # K'' = c_v α² β (β − 1) (1 + α ξ)^(β − 2), β = 2
    counts, errors = np.array([8, 16, 32, 64, 128]), []
    for n in counts:
        table = _solved(half_disc_case(g="inf", stiffness=_table(np.linspace(0.0, top, n + 1))))
        difference = table.contact_history("penetration") - d
        h = top / n
        assert np.abs(difference).max() <= h**2 * curvature / (8.0 * C_V) * np.abs(d).max(), n
        errors.append(np.sqrt(np.mean(difference**2)))
        assert table.series("newton_iterations").sum() <= reference.series("newton_iterations").sum() + 2, n
    rate = -np.polyfit(np.log(counts), np.log(errors), 1)[0]
    halvings = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert abs(rate - 2.0) < 0.15, (rate, errors)
    assert np.all(np.abs(halvings - 2.0) < 0.35), halvings


def test_a_table_of_two_points_is_the_constant_law_and_the_linear_law():
    """K = [v, v] is the constant law v, the same run to the last bit; K = [c_v, c_v (1 + α ξ_1)] extrapolated
    linearly (ξ_1 = 0.01, well below the histories the run reaches) is the power law with β = 1 to rounding."""
    constant = _solved(rectangle_case(g="inf", stiffness={"law": "constant", "value": 150.0}))
    table = _solved(rectangle_case(g="inf", stiffness={"law": "table", "xi": [0.0, 1.0], "K": [150.0, 150.0],
                                                       "extrapolation": "constant"}))
    for name in ("penetration", "xi", "K"):
        np.testing.assert_array_equal(table.contact_history(name), constant.contact_history(name), err_msg=name)
    linear = _solved(rectangle_case(g="inf", stiffness={"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": 1.0}))
    table = _solved(rectangle_case(g="inf", stiffness={"law": "table", "xi": [0.0, 0.01],
                                                       "K": [C_V, C_V * (1.0 + ALPHA * 0.01)],
                                                       "extrapolation": "linear"}))
    assert linear.contact_history("xi").max() > 0.05  # beyond the last point: the extrapolation is what runs
    for name in ("penetration", "xi", "K"):
        np.testing.assert_allclose(table.contact_history(name), linear.contact_history(name), rtol=1e-12,
                                   err_msg=name)


@pytest.mark.parametrize("extrapolation", ["constant", "linear"])
def test_the_derivative_is_the_slope_of_the_segment_right_sided_at_the_breakpoints(extrapolation):
    """Away from the breakpoints the derivative of K and of p is the central difference of their values (inside,
    beyond the last point, and for p below 0); at a breakpoint it is the slope of the segment after it, at the
    last point the extrapolation's (0 or the last segment's), and p'(0) is the first segment's slope."""
    xi, K = np.array([0.0, 0.1, 0.25, 0.4]), np.array([100.0, 140.0, 130.0, 180.0])
    r, p = np.array([0.0, 0.05, 0.2]), np.array([0.0, 0.01, 0.2])
    stiffness = STIFFNESS["table"].make(xi=xi, K=K, extrapolation=extrapolation)
    compliance = COMPLIANCE["table"].make(r=r, p_of_r=p, p_extrapolation=extrapolation)
    delta = 1e-7
    for law, points, at in ((stiffness, xi, np.linspace(0.003, 0.6, 211)), (compliance, r, np.linspace(-0.1, 0.4, 211))):
        at = at[np.abs(at[:, None] - points[None, :]).min(axis=1) > 10 * delta]
        np.testing.assert_allclose(law.derivative(at), (law(at + delta) - law(at - delta)) / (2 * delta), rtol=1e-6,
                                   atol=1e-6)
    slopes = np.diff(K) / np.diff(xi)
    last = slopes[-1] if extrapolation == "linear" else 0.0
    np.testing.assert_array_equal(stiffness.derivative(xi), [*slopes, last])
    np.testing.assert_array_equal(compliance.derivative(np.array([-1e-300, 0.0, 0.05])), [0.0, *np.diff(p) / np.diff(r)])
    np.testing.assert_array_equal(compliance(np.array([-1.0, 0.0, 0.05])), [0.0, 0.0, 0.01])
    beyond = 180.0 + (50.0 / 0.15) * 0.2 if extrapolation == "linear" else 180.0
    assert stiffness(np.array([0.6]))[0] == pytest.approx(beyond, rel=1e-14)


TOML_TABLE = {"law": "table", "xi": [0.0, 0.02, 0.04, 0.05], "K": [100.0, 90.0, 130.0, 200.0], "extrapolation": "linear"}
TOML_P = {"p": "table", "r": [0.0, 0.02, 0.06], "p_of_r": [0.0, 0.01, 0.1], "p_extrapolation": "linear"}


@pytest.mark.parametrize("where, key, value, named", [
    ("stiffness", "xi", [0.0, 0.05, 0.02, 0.2], "contact.stiffness.xi = [0.0, 0.05, 0.02, 0.2]: expected strictly "
                                                "increasing values"),
    ("stiffness", "K", [100.0, 90.0, 130.0], "contact.stiffness.K = [100.0, 90.0, 130.0]: expected 4 values"),
    ("stiffness", "K", [100.0, -1.0, 130.0, 200.0], "contact.stiffness.K[1] = -1.0: must be >= 0"),
    ("stiffness", "K", [100.0, float("nan"), 130.0, 200.0], "contact.stiffness.K[1] = nan: expected a finite number"),
    ("stiffness", "xi", [0.01, 0.02, 0.05, 0.2], "contact.stiffness.xi = [0.01, 0.02, 0.05, 0.2]: the table must "
                                                 "start at ξ = 0"),
    ("stiffness", "extrapolation", "quadratic", 'contact.stiffness.extrapolation = "quadratic": expected one of'),
    ("contact", "r", [0.0, 0.1, 0.02], "contact.r = [0.0, 0.1, 0.02]: expected strictly increasing values"),
    ("contact", "p_of_r", [0.0, 0.02, 0.01], "contact.p_of_r = [0.0, 0.02, 0.01]: expected non-decreasing values"),
    ("contact", "p_of_r", [0.0, 0.01], "contact.p_of_r = [0.0, 0.01]: expected 3 values"),
])
def test_a_bad_table_is_refused_by_its_key_through_the_command_line(tmp_path, where, key, value, named):
    case = rectangle_case(g="inf", stiffness=copy.deepcopy(TOML_TABLE), **TOML_P)
    (case["contact"]["stiffness"] if where == "stiffness" else case["contact"])[key] = value
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", "case.toml", "--out", "run", "--quiet", cwd=tmp_path)
    assert_refused(status, stderr, named, untouched=[(tmp_path, before)])
    assert not (tmp_path / "run").exists()


def test_a_run_with_tables_from_a_case_file_reports_the_tables_values_in_contact_csv(tmp_path):
    """contact.csv of a run with K and p as TOML tables: K = the interpolant of the table at ξ (np.interp inside,
    the last segment's line beyond), the compliance pressure = K p(d) with p the interpolant at the penetration,
    and the run goes through every breakpoint of both tables and beyond their last points."""
    case = rectangle_case(g="inf", stiffness=TOML_TABLE, **TOML_P)
    case["boundary"]["traction"][0]["value"] = ["0", "-20*t"]
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    status, _, stderr = run_cli("run", "case.toml", "--out", "run", "--quiet", cwd=tmp_path)
    assert status == 0, stderr
    contact = pd.read_csv(tmp_path / "run" / "contact.csv")
    xi, d = contact["xi"].to_numpy(), contact["penetration"].to_numpy()
    assert xi.max() > TOML_TABLE["xi"][-1] and d.max() > TOML_P["r"][-1], (xi.max(), d.max())
    table_xi, table_K = np.array(TOML_TABLE["xi"]), np.array(TOML_TABLE["K"])
    beyond = table_K[-1] + (table_K[-1] - table_K[-2]) / (table_xi[-1] - table_xi[-2]) * (xi - table_xi[-1])
    expected_K = np.where(xi > table_xi[-1], beyond, np.interp(xi, table_xi, table_K))
    np.testing.assert_allclose(contact["K"], expected_K, rtol=1e-12)
    r, p = np.array(TOML_P["r"]), np.array(TOML_P["p_of_r"])
    p_of_d = np.where(d > r[-1], p[-1] + (p[-1] - p[-2]) / (r[-1] - r[-2]) * (d - r[-1]), np.interp(d, r, p))
    np.testing.assert_allclose(contact["pressure_compliance"], expected_K * np.where(d > 0, p_of_d, 0.0), rtol=1e-12)
    resolved = tomllib.loads((tmp_path / "run" / "case.resolved.toml").read_text())["contact"]
    assert resolved["stiffness"] == TOML_TABLE and {key: resolved[key] for key in TOML_P} == TOML_P


def test_tables_given_from_python_on_two_contact_parts_are_the_laws_they_tabulate(tmp_path):
    """vpcontact.compose with the tables as NumPy arrays, a different table on each part of a split Γ3 (K linear
    in ξ on both, p = r⁺ below and p = 2 r⁺ above, each a table of 2 points extrapolated linearly): the same
    penetrations, histories and pressures, to rounding, as the case with p = r⁺ and K power (β = 1, c_v times
    the slope of p) on those parts; the parts' tables are kept apart (a PiecewiseLaw), not merged per node."""
    from test_contact_parts import split_case

    case, part, _ = split_case(tmp_path, 2)
    case["contact"].pop("stiffness")
    layers = [(f"{part}_below", 100.0, 20.0, 1.0), (f"{part}_above", 300.0, 5.0, 2.0)]
    powers = {"probe": [0.0, 0.0], "parts": [
        {"part": name, "g": 0.2, "p": "power", "exponent": 1.0,
         "stiffness": {"law": "power", "c_v": c_v * slope, "alpha": alpha, "beta": 1.0}}
        for name, c_v, alpha, slope in layers]}
    tables = {"probe": np.zeros(2), "parts": [
        {"part": name, "g": 0.2, "p": "table", "r": np.array([0.0, 1.0]), "p_of_r": np.array([0.0, slope]),
         "p_extrapolation": "linear",
         "stiffness": {"law": "table", "xi": np.array([0.0, 0.01]), "K": np.array([c_v, c_v * (1 + alpha * 0.01)]),
                       "extrapolation": "linear"}}
        for name, c_v, alpha, slope in layers]}
    reference = _solved({**case, "contact": powers})
    problem = vpcontact.compose(case["mesh"]["file"], case["material"], dirichlet=case["boundary"]["dirichlet"],
                                traction={item["part"]: item["value"] for item in case["boundary"]["traction"]},
                                contact=tables, time=case["time"], solver=case["solver"])
    assert type(problem.law.stiffness).__name__ == type(problem.law.p).__name__ == "PiecewiseLaw"
    tabled = vpcontact.solve(problem)
    assert tabled.status == "complete"
    for name in ("penetration", "xi", "pressure_compliance"):
        expected = reference.contact_history(name)
        np.testing.assert_allclose(tabled.contact_history(name), expected, rtol=0,
                                   atol=1e-11 * np.abs(expected).max(), err_msg=name)
    assert reference.contact_history("K")[-1].max() > 0 and reference.contact_history("xi").max() > 0.01
