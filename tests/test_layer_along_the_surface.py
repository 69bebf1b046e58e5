"""A layer that varies along Γ3 (the paper's K(x, ξ), (2.18), and a thickness g(x), beyond the paper):
the stiffness parameters and g as expressions in the coordinates, evaluated at the contact nodes, in
2D and 3D."""

import copy

import numpy as np
import pytest
import tomli_w

import vpcontact
from conftest import assert_refused, half_disc_case, run_cli, snapshot_tree, solved
from test_3d import ball_case, compliance_with_the_limit, full_vector, states

#: a strip of Γ3 (|x| < 0.3) four times as stiff, a hardening that grows away from the axis, and a
#: softening exponent that changes sign along Γ3: (c_v, α, β) as expressions, and as functions here
LAYER = ("100 + 300*heaviside(0.3 - abs(x))", "10 + 20*x*x", "1 - 2*heaviside(x - 0.5)")


def layer_values(x):
    return 100 + 300 * (np.abs(x) < 0.3), 10 + 20 * x * x, np.where(x > 0.5, -1.0, 1.0)


CASES = {
    "2D": half_disc_case(h=0.1, load=60.0),
    "3D": ball_case(h=0.4, load=40.0),
}


@pytest.mark.parametrize("dim", CASES)
def test_a_layer_varying_along_the_surface_matches_a_generic_root_finder(dim):
    """Nodes in compliance and at the limit with different (c_v, α, β) along Γ3, against MINPACK on
    the same P1 matrices with the parameters computed here at each node."""
    case = copy.deepcopy(CASES[dim])  # each test changes its own copy
    case["contact"]["stiffness"] = dict(zip(("c_v", "alpha", "beta"), LAYER), law="power")
    problem, result = solved(case)
    assert result.status == "complete", result.message
    surface = problem.surface
    c_v, alpha, beta = layer_values(surface.coordinates[0])
    assert len(set(c_v)) == 2 and len(set(beta)) == 2  # both stiffnesses and both exponents are on Γ3
    N = surface.operator[:, problem.free].toarray()
    g = case["contact"]["g"]
    d, lam, u, xi = compliance_with_the_limit(problem, N, surface.weights, c_v, alpha, beta, g)
    np.testing.assert_allclose(result.contact_history("penetration"), d, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("xi")[-1], xi, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.final.displacement, full_vector(problem, u), rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("pressure_rigid") * surface.weights, lam, rtol=0,
                               atol=1e-10 * c_v.max() * g * surface.weights.max())
    K = c_v * (1 + alpha * xi) ** beta
    np.testing.assert_allclose(result.contact_history("K")[-1], K, rtol=1e-10)
    _, compliance, limit = states(result)[-1]
    assert compliance > 0 and limit > 0, (compliance, limit)


#: a layer thinner away from the bottom point (the paper's g = 0.2 there)
THICKNESS = "0.2 - 0.15*x*x"


@pytest.mark.parametrize("dim", CASES)
def test_a_layer_of_varying_thickness_matches_a_generic_root_finder(dim):
    """g(x) along Γ3 with the paper's K = 100 (1 + 20 ξ)^−1: the nodes reach the rigid base at different
    penetrations; against MINPACK with g computed here at each node."""
    case = copy.deepcopy(CASES[dim])  # each test changes its own copy
    case["contact"]["g"] = THICKNESS
    case["contact"]["stiffness"] = {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}
    problem, result = solved(case)
    assert result.status == "complete", result.message
    surface = problem.surface
    g = 0.2 - 0.15 * surface.coordinates[0] ** 2
    N = surface.operator[:, problem.free].toarray()
    d, lam, u, xi = compliance_with_the_limit(problem, N, surface.weights, 100.0, 20.0, -1.0, g)
    np.testing.assert_allclose(result.contact_history("penetration"), d, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("xi")[-1], xi, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.final.displacement, full_vector(problem, u), rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("pressure_rigid") * surface.weights, lam, rtol=0,
                               atol=1e-10 * 100.0 * 0.2 * surface.weights.max())
    at_limit = result.contact_history("status")[-1] == 2
    np.testing.assert_allclose(d[-1][at_limit], g[at_limit], rtol=0, atol=1e-10)  # each on its own base
    assert at_limit.sum() > 1 and len(set(np.round(g[at_limit], 12))) > 1  # several thicknesses reached


@pytest.mark.parametrize("law, parameters", [("power", {"c_v": 100.0, "alpha": 20.0, "beta": -1.0}),
                                             ("exponential", {"c_v": 100.0, "alpha": -5.0}),
                                             ("constant", {"value": 150.0})])
def test_a_constant_written_as_an_expression_is_the_same_layer(law, parameters):
    """Bitwise: an expression with a constant value gives the same run as the number."""
    numbers, expressions = half_disc_case(h=0.2, load=25.0), half_disc_case(h=0.2, load=25.0)
    numbers["contact"]["stiffness"] = {"law": law, **parameters}
    expressions["contact"]["stiffness"] = {"law": law, **{k: f"{v!r} + 0*x" for k, v in parameters.items()}}
    a, b = vpcontact.solve(numbers), vpcontact.solve(expressions)
    np.testing.assert_array_equal(a.final.displacement, b.final.displacement)
    np.testing.assert_array_equal(a.contact_history("K"), b.contact_history("K"))


BAD_LAYERS = [
    ({"g": "0.2 - x"}, ["contact.g = \"0.2 - x\" is -", "expected a finite number > 0"]),
    ({"g": "1/x"}, ["contact.g = \"1/x\" is inf", "expected a finite number > 0"]),
    ({"c_v": "100 - 300*x"}, ["contact.stiffness.c_v = \"100 - 300*x\" is -", "at the contact node (x, y) = (",
                              "expected a finite number >= 0"]),
    ({"alpha": "-1 + x"}, ["contact.stiffness.alpha", "expected a finite number >= 0"]),
    ({"beta": "log(x)"}, ["contact.stiffness.beta = \"log(x)\" is -inf", "expected finite"]),
    ({"c_v": "100*t"}, ["contact.stiffness.c_v", "t"]),
    ({"c_v": "100*z"}, ["contact.stiffness.c_v", "z"]),
]


@pytest.mark.parametrize("stiffness, words", BAD_LAYERS, ids=[str(s) for s, _ in BAD_LAYERS])
def test_a_layer_parameter_that_is_wrong_somewhere_on_the_surface_is_refused(tmp_path, stiffness, words):
    case = half_disc_case(h=0.2)
    case["contact"].update({k: v for k, v in stiffness.items() if k == "g"})
    case["contact"]["stiffness"].update({k: v for k, v in stiffness.items() if k != "g"})
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    before = snapshot_tree(tmp_path)
    status, _, err = run_cli("run", path, "--out", tmp_path / "out")
    assert_refused(status, err, *words, untouched=[(tmp_path, before)])


#: a compliance exponent that grows away from the bottom point: p(x, r) = (r⁺)^m(x), m from 1 to 2.5
EXPONENT = "1 + 1.5*x*x"


@pytest.mark.parametrize("dim", CASES)
def test_a_compliance_exponent_varying_along_the_surface_matches_a_generic_root_finder(dim):
    """p = (r⁺)^m with m(x) per node and the paper's K = 100 (1 + 20 ξ), g = 0.2: against MINPACK with m
    computed here at each node; the nodes where m > 1 penetrate further, some to the rigid base."""
    case = copy.deepcopy(CASES[dim])  # each test changes its own copy
    case["contact"].update(p="power", exponent=EXPONENT)
    problem, result = solved(case)
    assert result.status == "complete", result.message
    surface = problem.surface
    m = 1 + 1.5 * surface.coordinates[0] ** 2
    assert m.min() == 1.0 and m.max() > 2.0
    N = surface.operator[:, problem.free].toarray()
    d, lam, u, xi = compliance_with_the_limit(problem, N, surface.weights, 100.0, 20.0, 1.0, 0.2, exponent=m)
    np.testing.assert_allclose(result.contact_history("penetration"), d, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("xi")[-1], xi, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.final.displacement, full_vector(problem, u), rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("pressure_rigid") * surface.weights, lam, rtol=0,
                               atol=1e-10 * 100.0 * 0.2 * surface.weights.max())
    compliance = result.contact_history("pressure_compliance")[-1]
    np.testing.assert_allclose(compliance, 100.0 * (1 + 20.0 * xi) * np.maximum(d[-1], 0.0) ** m, rtol=1e-10)
    _, in_compliance, at_limit = states(result)[-1]
    assert in_compliance > 0 and at_limit > 0, (in_compliance, at_limit)


def test_an_exponent_written_as_an_expression_is_the_same_law():
    """Bitwise: contact.exponent = "1.5 + 0*x" gives the same run as 1.5."""
    number, expression = half_disc_case(h=0.2, load=25.0), half_disc_case(h=0.2, load=25.0)
    number["contact"].update(p="power", exponent=1.5)
    expression["contact"].update(p="power", exponent="1.5 + 0*x")
    a, b = vpcontact.solve(number), vpcontact.solve(expression)
    np.testing.assert_array_equal(a.final.displacement, b.final.displacement)
    np.testing.assert_array_equal(a.contact_history("pressure_compliance"), b.contact_history("pressure_compliance"))


@pytest.mark.parametrize("exponent, words", [
    ("0.5 + x", ["contact.exponent = \"0.5 + x\" is 0.5 at the contact node (x, y) = (0, 0)",
                 "expected a finite number >= 1"]),
    ("1/(x - 1)", ["contact.exponent = \"1/(x - 1)\"", "expected a finite number >= 1"]),
    (0.5, ["contact.exponent", "expected a number >= 1 or an expression in the coordinates, got 0.5"]),
])
def test_an_exponent_below_one_somewhere_on_the_surface_is_refused(tmp_path, exponent, words):
    case = half_disc_case(h=0.2)
    case["contact"].update(p="power", exponent=exponent)
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    before = snapshot_tree(tmp_path)
    status, _, err = run_cli("run", path, "--out", tmp_path / "out")
    assert_refused(status, err, *words, untouched=[(tmp_path, before)])
