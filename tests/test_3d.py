"""The 3D model on tetrahedra against references written here, independently of vpcontact's solvers:

- a block on the layer under a uniform pressure follows the scalar recursion of the layer law at every
  contact node (β = ±1, α = 0, g = ∞, and with nodes at the rigid limit);
- the quarter ball against generic SciPy solvers on the same P1 stiffness and loads (contact nodes,
  normals and weights rebuilt here): Signorini as a quadratic program, normal compliance with the
  rigid limit as a complementarity system, each checked on its own KKT conditions;
- the viscoplastic laws in S³ on a homogeneous block: the scalar recursion of the explicit scheme,
  the closed forms of the continuous problem, first order in k.

Hertz contact, the prism of the half disc against 2D, and the studies and norms between 3D meshes
are in test_3d_hertz.py, test_3d_prism.py and test_3d_studies.py; the condensed and full step
solvers on 3D cases with nodes in all three states in test_solvers_agree.py.
"""

import math

import numpy as np
import pytest
from scipy.optimize import root

import vpcontact
from conftest import solved
from test_half_disc_independent import signorini_by_its_dual
from test_uniform_block import C_V, Q_RATE, scalar_recursion

ALPHA = 20.0
SIDES = (("left", "x"), ("right", "x"), ("front", "y"), ("back", "y"))


def block_case(g=0.2, h=0.25, gap=0.0, stiffness=None) -> dict:
    """The block [0, 1]² × [0, 0.5] on rollers at its four sides, pushed down by the traction 100 t on
    its top onto the layer under its bottom (the uniform state: every contact node alike)."""
    return {
        "mesh": {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": h},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": part, "components": [c]} for part, c in SIDES],
                     "traction": [{"part": "top", "value": ["0", "0", f"-{Q_RATE}*t"]}]},
        "contact": {"part": "bottom", "g": g, "gap": gap,
                    "stiffness": stiffness or {"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": 1.0}},
        "time": {"T": 1.1, "steps": 11},
        "solver": {"tolerance": 1e-13},
        "output": {"field_steps": "none"},
    }


def ball_case(h=0.5, load=11.4443, g=0.2, stiffness=None, **contact) -> dict:
    """examples/quarter_ball.toml (rollers on the symmetry planes, the traction c·t on the top) at size h."""
    return {
        "mesh": {"shape": "quarter_ball", "h": h},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "sym_x", "components": ["x"]}, {"part": "sym_y", "components": ["y"]}],
                     "traction": [{"part": "top", "value": ["0", "0", f"-{load}*t"]}]},
        "contact": {"part": "bottom", "g": g, "probe": [0.0, 0.0, 0.0],
                    "stiffness": stiffness or {"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": 1.0}, **contact},
        "time": {"T": 1.1, "steps": 11},
        "solver": {"tolerance": 1e-12},
        "output": {"field_steps": "none"},
    }


def states(result) -> np.ndarray:
    """(rows, 3): the numbers of separated nodes, nodes in compliance and nodes at the limit."""
    return np.stack([result.series(f"nodes_{s}") for s in ("separated", "in_compliance", "at_limit")], axis=1)


# --- 1. the uniform block -------------------------------------------------------------------------
@pytest.mark.parametrize("beta, alpha, g", [(1.0, ALPHA, 0.2), (-1.0, ALPHA, 0.2), (1.0, 0.0, 0.2),
                                            (1.0, ALPHA, math.inf)])
def test_every_node_of_the_block_follows_the_scalar_recursion(beta, alpha, g):
    result = vpcontact.solve(block_case(g=g, stiffness={"law": "power", "c_v": C_V, "alpha": alpha, "beta": beta}))
    assert result.status == "complete" and result.contact_nodes == 25
    expected = scalar_recursion(beta, alpha, g)
    d = result.contact_history("penetration")
    np.testing.assert_allclose(d, np.repeat(expected[:, :1], d.shape[1], axis=1), rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("xi"), np.repeat(expected[:, 1:2], d.shape[1], axis=1),
                               rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.contact_history("K"), np.repeat(expected[:, 2:3], d.shape[1], axis=1),
                               rtol=1e-10)
    np.testing.assert_allclose(result.contact_history("pressure_rigid"),
                               np.repeat(expected[:, 3:4], d.shape[1], axis=1), rtol=0, atol=1e-8)
    at_limit = expected[:, 3] > 0  # the steps at which the recursion is on the rigid base
    # a step that ends exactly on the base with no reaction from it (α = 0: d = g at step 2) is a tie: rounding in
    # the last digits of u decides, node by node, whether the base's multiplier is active there (11 of the 25 nodes
    # on 2026-11-28, numpy 2.4.6, scipy 1.17.1); its reaction is zero either way (asserted above)
    tie = (expected[:, 0] == g) & ~at_limit
    counted = result.series("nodes_at_limit")
    np.testing.assert_array_equal(counted[~tie], np.where(at_limit, 25, 0)[~tie])
    assert at_limit.any() == math.isfinite(g)  # g = 0.2 is reached: at steps 6 (β = 1), 2 (β = −1), 3 (α = 0)
    # equilibrium: the foundation carries the whole load q·area (area 1), straight up
    np.testing.assert_allclose(result.series("contact_force_z"), Q_RATE * result.series("t"), rtol=1e-10)
    np.testing.assert_allclose(result.series("contact_force_x"), 0.0, atol=1e-9)
    np.testing.assert_allclose(result.series("contact_force_y"), 0.0, atol=1e-9)


# --- 2. the quarter ball against generic solvers --------------------------------------------------
def independent_contact_data(problem, radius=1.0):
    """Nodes of the part "bottom", exact normals (x − c)/|x − c| (c the ball's center), lumped weights (a
    third of the area of each adjacent triangle) and N on the free dofs, all rebuilt from the mesh."""
    mesh = problem.mesh.mesh
    triangles = mesh.facets[:, problem.mesh.facets("bottom")]
    nodes, local = np.unique(triangles, return_inverse=True)
    a, b, c = (mesh.p[:, triangles[i]] for i in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a, axis=0), axis=0)
    weights = np.bincount(local.ravel(), weights=np.tile(area / 3.0, 3), minlength=nodes.size)
    normals = mesh.p[:, nodes] - np.array([[0.0], [0.0], [radius]])
    normals /= np.linalg.norm(normals, axis=0)
    N = np.zeros((nodes.size, problem.basis.N))
    for k in range(3):
        N[np.arange(nodes.size), problem.basis.nodal_dofs[k, nodes]] = normals[k]
    return nodes, weights, N[:, problem.free]


def full_vector(problem, free_values):
    full = np.zeros(problem.basis.N)
    full[problem.free] = free_values
    return full[problem.basis.nodal_dofs].T  # (nodes, d)


#: How far the SLSQP reference of the Signorini test is trusted (a length; the ball's size is 2).
REFERENCE_ACCURACY = 1e-7
#: How far a reference whose KKT conditions hold to rounding (residuals ≤ 1e-12 relative) is trusted.
CERTIFIED_ACCURACY = 1e-10


def test_signorini_on_the_quarter_ball_matches_the_quadratic_program():
    """K ≡ 0: at each time the Signorini problem with gap g is the QP min ½uᵀAu − bᵀu, N u ≤ g. The
    rollers leave A singular (the vertical translation e); its dual
        max_{λ ≥ 0}  −½ (b − Nᵀλ)ᵀ A⁺ (b − Nᵀλ) − gᵀλ   subject to  eᵀ(b − Nᵀλ) = 0
    is solved by SLSQP. Its active set then gives the KKT system [A Nₐᵀ; Nₐ 0] (u, λₐ) = (b, g), solved
    exactly; λₐ ≥ 0 and N u ≤ g off the active set certify that solution (a convex QP)."""
    problem, result = solved(ball_case(load=11.4443, stiffness={"law": "constant", "value": 0.0}))
    nodes, w, N = independent_contact_data(problem)
    np.testing.assert_array_equal(nodes, problem.surface.nodes)
    A = problem.A[problem.free][:, problem.free].toarray()
    e = np.zeros(problem.basis.N)
    e[problem.basis.nodal_dofs[2]] = 1.0
    e = e[problem.free]
    assert np.abs(A @ e).max() < 1e-10 * np.abs(A).max()  # the free motion left by the rollers
    b = problem.loads(problem.times[-1])[problem.free]
    g = 0.2

    u, lam = signorini_by_its_dual(A, N, b, g, e)
    d = N @ u
    # the optimiser's own accuracy: feasibility d ≤ g and complementarity λ (g − d) = 0
    assert np.all(d <= g + REFERENCE_ACCURACY)
    assert np.max(lam * np.abs(g - d)) <= REFERENCE_ACCURACY * lam.max()
    np.testing.assert_allclose(result.contact_history("penetration")[-1], d, rtol=0, atol=REFERENCE_ACCURACY)
    np.testing.assert_allclose(result.contact_history("pressure_rigid")[-1] * w, lam, rtol=0, atol=1e-6 * lam.max())

    active = lam > 1e-6 * lam.max()
    m = active.sum()
    kkt = np.block([[A, N[active].T], [N[active], np.zeros((m, m))]])
    exact = np.linalg.solve(kkt, np.concatenate([b, np.full(m, g)]))
    u, lam_active = exact[:-m], exact[-m:]
    d = N @ u
    assert lam_active.min() > 0 and np.all(d[~active] < g)  # the KKT conditions: this is the solution
    assert np.abs(A @ u + N[active].T @ lam_active - b).max() < 1e-12 * np.abs(b).max()
    np.testing.assert_allclose(result.contact_history("penetration")[-1], d, rtol=0, atol=CERTIFIED_ACCURACY)
    np.testing.assert_allclose(result.final.displacement, full_vector(problem, u), rtol=0, atol=CERTIFIED_ACCURACY)
    rigid = result.contact_history("pressure_rigid")[-1] * w
    np.testing.assert_allclose(rigid[active], lam_active, rtol=CERTIFIED_ACCURACY)
    np.testing.assert_array_equal(rigid[~active], 0.0)
    np.testing.assert_array_equal(result.contact_history("status")[-1] == 2, active)
    assert 2 <= m < nodes.size - 2


def fischer_burmeister(a, b):
    """φ(a, b) = a + b − √(a² + b²): zero exactly when a ≥ 0, b ≥ 0, a b = 0."""
    return a + b - np.hypot(a, b)


def compliance_with_the_limit(problem, N, w, c_v, alpha, beta, g, exponent=1.0):
    """The steps of K = c_v (1 + α ξ)^β and p(d) = (d⁺)^m with the rigid limit g (each a number or one
    value per contact node), on the problem's P1 matrices and the contact data N, w given: each step is
        A u + Nᵀ (w K(ξ_{n−1} + k d⁺) (d⁺)^m + λ) = b,   φ(λ, c_v w (g − d)) = 0,   d = N u,
    with φ the Fischer–Burmeister function, solved by MINPACK's hybrid method (with its Jacobian) from
    the previous step, then Newton steps where it stalls, and checked on its residual and KKT
    conditions (to rounding). Returns the
    penetrations and the rigid forces λ of every step (steps, m), and the last u (free dofs) and ξ."""
    A = problem.A[problem.free][:, problem.free].toarray()
    n, m, k = A.shape[0], N.shape[0], problem.k
    scale = c_v * w  # a gap times this is a force
    force = np.max(scale * g)  # the largest force the layer gives a node
    xi, x, penetrations, rigid = np.zeros(m), np.zeros(n + m), [], []
    for t in problem.times:
        b = problem.loads(t)[problem.free]

        def residual(x, xi=xi, b=b):
            u, lam = x[:n], x[n:]
            d = N @ u
            K = c_v * (1.0 + alpha * (xi + k * np.maximum(d, 0.0))) ** beta
            return np.concatenate([A @ u + N.T @ (w * K * np.maximum(d, 0.0) ** exponent + lam) - b,
                                   fischer_burmeister(lam, scale * (g - d))])

        def jacobian(x, xi=xi):
            u, lam = x[:n], x[n:]
            d = N @ u
            positive, on = np.maximum(d, 0.0), (d > 0.0).astype(float)
            base = 1.0 + alpha * (xi + k * positive)
            K, dK = c_v * base**beta, c_v * alpha * beta * base ** (beta - 1.0)
            a, c = lam, scale * (g - d)
            r = np.where(np.hypot(a, c) > 0, np.hypot(a, c), 1.0)
            dp = exponent * positive ** (exponent - 1.0)  # times `on`: d⁺ has the derivative 1 at d = 0
            tangent = w * on * (K * dp + dK * k * positive**exponent)
            return np.block([[A + N.T @ (tangent[:, None] * N), N.T],
                             [-((1.0 - c / r) * scale)[:, None] * N, np.diag(1.0 - a / r)]])

        x = root(residual, x, jac=jacobian, method="hybr", tol=1e-15).x
        for _ in range(20):  # where MINPACK stalls at a kink of φ: Newton steps on the same system
            if np.abs(residual(x)).max() < 1e-14 * np.abs(b).max():  # equilibrium and φ, both forces
                break
            x = x - np.linalg.solve(jacobian(x), residual(x))
        u, lam = x[:n], x[n:]
        d = N @ u
        assert np.abs(residual(x)[:n]).max() < 1e-12 * np.abs(b).max(), t
        assert lam.min() > -1e-12 * force and np.all(d < g + 1e-12), t
        assert np.max(lam * (g - d)) < 1e-12 * force * np.max(g), t
        penetrations.append(d), rigid.append(lam)
        xi = xi + k * np.maximum(d, 0.0)
    return np.array(penetrations), np.array(rigid), u, xi


@pytest.mark.parametrize("beta, load", [(-1.0, 11.4443), (1.0, 40.0)])
def test_compliance_with_the_rigid_limit_matches_a_generic_root_finder(beta, load):
    """K = 100 (1 + 20 ξ)^β, g = 0.2, nodes in compliance and at the limit, against
    `compliance_with_the_limit` with contact nodes, normals and weights rebuilt here."""
    stiffness = {"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": beta}
    problem, result = solved(ball_case(load=load, stiffness=stiffness))
    _, w, N = independent_contact_data(problem)
    g = 0.2
    d, lam, u, xi = compliance_with_the_limit(problem, N, w, C_V, ALPHA, beta, g)
    np.testing.assert_allclose(result.contact_history("penetration"), d, rtol=0, atol=CERTIFIED_ACCURACY)
    np.testing.assert_allclose(result.contact_history("pressure_rigid") * w, lam, rtol=0,
                               atol=CERTIFIED_ACCURACY * C_V * g * w.max())
    np.testing.assert_allclose(result.final.displacement, full_vector(problem, u), rtol=0, atol=CERTIFIED_ACCURACY)
    np.testing.assert_allclose(result.contact_history("xi")[-1], xi, rtol=0, atol=CERTIFIED_ACCURACY)
    _, compliance, limit = states(result)[-1]
    assert compliance >= 10 and limit >= 4, (compliance, limit)


# --- 3. viscoplastic laws in S³ on a homogeneous block --------------------------------------------
E, NU = 1000.0, 0.3
LAM, MU = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))  # the isotropic tensor (4.1)
M = LAM + 2 * MU  # the oedometric modulus: σ_zz = M ε_zz when ε_xx = ε_yy = 0
Q0 = 10.0  # the pressure on the top of the block
ETA, YIELD = 0.5, 2.0  # Perzyna
RATE, E_INF, NU_INF = 2.0, 500.0, 0.3  # relaxation
LAM_INF, MU_INF = E_INF * NU_INF / ((1 + NU_INF) * (1 - 2 * NU_INF)), E_INF / (2 * (1 + NU_INF))
M_INF = LAM_INF + 2 * MU_INF
LAWS = {
    "perzyna": {"law": "perzyna", "eta": ETA, "yield_stress": YIELD},
    "relaxation": {"law": "relaxation", "mu": RATE, "E_inf": E_INF, "nu_inf": NU_INF},
}
# initial stresses in equilibrium with the load (σ_zz = −Q0; shear stresses would load the rollers), so
# that u(0) = 0 = u_0. AXIAL: σ_xx = σ_yy, for the closed forms; GENERAL: three different principal
# stresses, for the recursion. The Perzyna ones are outside the yield set (‖dev σ_0‖ = 8.2 and 8.6 > 2).
AXIAL = {"perzyna": np.diag([0.0, 0.0, -Q0]), "relaxation": np.diag([-2.0, -2.0, -Q0])}
GENERAL = {"perzyna": np.diag([0.0, 3.0, -Q0]), "relaxation": np.diag([-2.0, 1.0, -Q0])}


def g_perzyna(sigma, strain):
    dev = sigma - np.trace(sigma) / 3.0 * np.eye(3)
    size = np.sqrt(np.sum(dev * dev))
    return -max(0.0, 1.0 - YIELD / size) * dev / ETA if size > 0 else np.zeros((3, 3))


def g_relaxation(sigma, strain):
    return -RATE * (sigma - LAM_INF * np.trace(strain) * np.eye(3) - 2 * MU_INF * strain)


SCALAR_LAWS = {"perzyna": g_perzyna, "relaxation": g_relaxation}


def homogeneous_recursion(G, sigma0, k, steps):
    """ε = diag(0, 0, e) (rollers), σ_zz = −Q0 (the top): per step e_n = (−Q0 − z_zz) / M,
    σ_n = ℰε_n + z_n, z_{n+1} = z_n + k 𝒢(σ_n, ε_n); z_1 = σ_0 + k 𝒢(σ_0, 0)."""
    z = sigma0 + k * G(sigma0, np.zeros((3, 3)))
    strains, stresses, histories = [], [], []
    for _ in range(steps):
        e = (-Q0 - z[2, 2]) / M
        strain = np.diag([0.0, 0.0, e])
        sigma = LAM * e * np.eye(3) + 2 * MU * strain + z
        strains.append(e), stresses.append(sigma), histories.append(z)
        z = z + k * G(sigma, strain)
    return np.array(strains), np.array(stresses), np.array(histories)


def closed_form(law, t):
    """The continuous solution (e(t), σ_xx(t)) of σ' = ℰε' + 𝒢(σ, ε) with σ_zz = −Q0, ε_xx = ε_yy = 0,
    from σ_0 = AXIAL[law] (σ_xx = σ_yy throughout)."""
    s0 = AXIAL[law][0, 0]
    if law == "perzyna":
        # D = σ_xx − σ_zz, ‖dev σ‖ = √(2/3) D: D' = −c (D − √(3/2) σ_y), c = (2λ + M) / (3ηM); e' = 2D' / (2λ + M)
        c = (2 * LAM + M) / (3 * ETA * M)
        D0, D_yield = s0 + Q0, math.sqrt(1.5) * YIELD
        D = D_yield + (D0 - D_yield) * np.exp(-c * t)
        return 2 * (D - D0) / (2 * LAM + M), D - Q0
    # M e' + μ (Q0 + M∞ e) = 0;  σ_xx' = λ e' − μ (σ_xx − λ∞ e)
    a = RATE * M_INF / M
    e_inf = -Q0 / M_INF
    e = e_inf * (1 - np.exp(-a * t))
    B = e_inf * (LAM * a - RATE * LAM_INF) / (RATE - a)
    C = s0 - LAM_INF * e_inf - B
    return e, LAM_INF * e_inf + B * np.exp(-a * t) + C * np.exp(-RATE * t)


def viscoplastic_block(law, initial, steps, T=1.0, method="auto"):
    """The block [0, 1]² × [0, 0.5] on rollers (sides, bottom) under the pressure Q0 on its top."""
    dirichlet = [{"part": part, "components": [c]} for part, c in (*SIDES, ("bottom", "z"))]
    return {
        "mesh": {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": 0.5},
        "material": {"E": E, "nu": NU, "viscoplastic": LAWS[law]},
        "boundary": {"dirichlet": dirichlet, "traction": [{"part": "top", "value": ["0", "0", f"-{Q0}"]}]},
        "initial": {"stress": initial.tolist()},
        "time": {"T": T, "steps": steps},
        "solver": {"method": method, "tolerance": 1e-13},
        "output": {"field_steps": "all"},
    }


def homogeneous(result, steps):
    """(e_n, σ_n, z_n) of every element at every step, checked homogeneous: u = (0, 0, e z) at the nodes."""
    z = result.discretization.mesh.mesh.p[2]
    e, sigma, history = [], [], []
    for n in range(1, steps + 1):
        fields = result.fields[n]
        uz = fields.displacement[:, 2]
        slope = uz @ z / (z @ z)
        np.testing.assert_allclose(fields.displacement[:, :2], 0.0, rtol=0, atol=1e-14)
        np.testing.assert_allclose(uz, slope * z, rtol=0, atol=1e-15)
        e.append(slope), sigma.append(fields.stress), history.append(fields.z)
    return np.array(e), np.array(sigma), np.array(history)


@pytest.mark.parametrize("method", ["full", "condensed"])
@pytest.mark.parametrize("law", ["perzyna", "relaxation"])
def test_the_homogeneous_3d_block_follows_the_scalar_recursion(law, method):
    steps, T = 10, 1.0
    result = vpcontact.solve(viscoplastic_block(law, GENERAL[law], steps, T, method))
    assert result.status == "complete" and result.method == method
    e, sigma, z = homogeneous(result, steps)
    assert sigma.shape[2:] == (3, 3)
    e_ref, sigma_ref, z_ref = homogeneous_recursion(SCALAR_LAWS[law], GENERAL[law], T / steps, steps)
    np.testing.assert_allclose(e, e_ref, rtol=1e-12, atol=0)
    np.testing.assert_allclose(sigma, np.repeat(sigma_ref[:, None], sigma.shape[1], axis=1), rtol=0, atol=1e-12 * Q0)
    np.testing.assert_allclose(z, np.repeat(z_ref[:, None], z.shape[1], axis=1), rtol=0, atol=1e-12 * Q0)
    assert abs(e[-1] - e[0]) > 0.1 * abs(e[0] if e[0] else e[-1])  # the strain did creep
    assert abs(sigma[-1, 0, 0, 0] - sigma[-1, 0, 1, 1]) > 0.1  # three distinct principal stresses throughout


@pytest.mark.parametrize("law", ["perzyna", "relaxation"])
def test_the_homogeneous_3d_block_converges_to_the_closed_form_at_first_order_in_k(law):
    T, errors = 1.0, []
    for steps in (10, 20, 40):
        result = vpcontact.solve(viscoplastic_block(law, AXIAL[law], steps, T))
        e, sigma, _ = homogeneous(result, steps)
        e_exact, sxx_exact = closed_form(law, result.series("t"))
        np.testing.assert_allclose(sigma[:, :, 0, 0], sigma[:, :, 1, 1], rtol=1e-13)  # σ_xx = σ_yy
        errors.append((np.abs(e - e_exact).max() / np.abs(e_exact).max(),
                       np.abs(sigma[:, 0, 0, 0] - sxx_exact).max() / np.abs(sxx_exact).max()))
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all((0.9 < orders) & (orders < 1.1)), orders
    assert errors[-1].max() < 0.05


def test_perzyna_in_3d_relaxes_onto_the_yield_set_at_the_closed_form_rate():
    """‖dev σ‖ − σ_y = √(2/3) (D − √(3/2) σ_y) decays by exactly 1 − k c per step, c = (2λ + M)/(3ηM)
    (the explicit scheme of D' = −c (D − √(3/2) σ_y)), which tends to the continuous exp(−c t)."""
    steps, T = 60, 3.0
    k, c = T / steps, (2 * LAM + M) / (3 * ETA * M)
    result = vpcontact.solve(viscoplastic_block("perzyna", AXIAL["perzyna"], steps, T))
    _, sigma, _ = homogeneous(result, steps)
    dev = sigma[:, 0] - np.trace(sigma[:, 0], axis1=1, axis2=2)[:, None, None] / 3.0 * np.eye(3)
    distance = np.sqrt((dev**2).sum(axis=(1, 2))) - YIELD
    dev0 = AXIAL["perzyna"] - np.trace(AXIAL["perzyna"]) / 3.0 * np.eye(3)
    distance0 = np.sqrt((dev0**2).sum()) - YIELD
    np.testing.assert_allclose(distance, distance0 * (1 - k * c) ** np.arange(1, steps + 1), rtol=1e-11)
    assert distance[-1] > 0 and distance[-1] < 0.03 * distance0  # relaxed onto the set, from outside
    assert abs(distance[-1] / distance0 - math.exp(-c * T)) < 0.005
