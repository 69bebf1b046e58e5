"""A uniformly loaded block on the foundation: every contact node carries the same penetration,
which must follow the scalar recursion K(ξ_{n−1} + k d_n) p(d_n) = q(t_n) of the contact law
(with d_n = g and the rigid base taking the rest once the root exceeds g)."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import vpcontact
from conftest import rectangle_case

Q_RATE, C_V, ALPHA = 100.0, 100.0, 20.0


def scalar_recursion(beta, alpha, g, T=1.1, steps=11):
    """Penetration, ξ, K and the rigid pressure of one contact point under the pressure q = 100 t."""
    k = T / steps
    xi, out = 0.0, []
    for n in range(1, steps + 1):
        q = Q_RATE * n * k
        K = lambda d: C_V * (1.0 + alpha * (xi + k * d)) ** beta
        limit = min(g, 10.0)
        if K(limit) * limit <= q:  # the layer is crushed: the rigid base takes the rest
            d, rigid = g, q - K(g) * g
        else:
            d, rigid = brentq(lambda d: K(d) * d - q, 0.0, limit, xtol=1e-15, rtol=1e-15), 0.0
        xi += k * d
        out.append((d, xi, C_V * (1.0 + alpha * xi) ** beta, rigid))
    return np.array(out)


@pytest.mark.parametrize("beta, alpha, g", [(1.0, ALPHA, 0.2), (-1.0, ALPHA, 0.2), (1.0, 0.0, 0.2),
                                            (1.0, ALPHA, math.inf)])
def test_every_node_follows_the_scalar_recursion(beta, alpha, g):
    case = rectangle_case(g=g, stiffness={"law": "power", "c_v": C_V, "alpha": alpha, "beta": beta})
    result = vpcontact.solve(case)
    assert result.status == "complete"
    expected = scalar_recursion(beta, alpha, g)
    d = result.contact_history("penetration")
    np.testing.assert_allclose(d, np.repeat(expected[:, :1], d.shape[1], axis=1), rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("xi")[:, 0], expected[:, 1], rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("K")[:, 0], expected[:, 2], rtol=1e-10)
    np.testing.assert_allclose(result.contact_history("pressure_rigid")[:, 0], expected[:, 3], rtol=0, atol=1e-8)
    # equilibrium: the foundation carries the whole load q·width
    np.testing.assert_allclose(result.series("contact_force_y"), Q_RATE * result.series("t") * 1.0, rtol=1e-10)
    np.testing.assert_allclose(result.series("contact_force_x"), 0.0, atol=1e-9)


def test_the_recursion_reaches_the_rigid_base_only_where_expected():
    """β = −1 (softening) reaches g in this load range, β = +1 with g = 0.5 does not."""
    soft = vpcontact.solve(rectangle_case(stiffness={"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": -1.0}))
    hard = vpcontact.solve(rectangle_case(g=0.5))
    assert soft.series("nodes_at_limit")[-1] == soft.contact_nodes
    assert hard.series("nodes_at_limit").max() == 0
    assert np.all(np.diff(hard.contact_history("K"), axis=0) > 0)
    assert np.all(np.diff(soft.contact_history("K"), axis=0) < 0)


@pytest.mark.parametrize("method", ["condensed", "full", "iterative"])
def test_a_history_linear_in_time_is_predicted_exactly(method):
    """K constant, p(d) = d⁺, every node in contact from the first step on, load linear in t: the
    step problem is linear and u(t) = t u(1). From the third step on the first Newton iterate (the
    last level's solution extrapolated through the last two) is the solution: zero Newton iterations."""
    case = rectangle_case(g=math.inf, stiffness={"law": "constant", "value": C_V})
    case["solver"].update(method=method, tolerance=1e-10)
    result = vpcontact.solve(case)
    iterations = result.series("newton_iterations")
    assert np.all(iterations[:2] >= 1) and np.all(iterations[2:] == 0)
    d = result.contact_history("penetration")
    np.testing.assert_allclose(d, np.broadcast_to(Q_RATE * result.times[:, None] / C_V, d.shape), rtol=1e-9)
