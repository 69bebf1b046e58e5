"""Viscoplastic bodies: the 𝒢 laws of (2.1) and the explicit scheme of (2.28) (DESIGN §2),

    z_n = σ_0 − ℰε(u_0) + Σ_{j=0}^{n−1} k 𝒢(σ_j, ε(u_j)),   σ_n = ℰε(u_n) + z_n,

checked against a scalar recursion written here independently, against closed-form solutions of
the continuous problem, and against the elastic solution in the limits where they coincide."""

import json
import math
from pathlib import Path

import meshio
import numpy as np
import pytest
import tomli_w

import vpcontact
from vpcontact.cli import main
from vpcontact.laws.elasticity import deviator, tensor_norm
from vpcontact.laws.viscoplastic.perzyna import Perzyna, von_mises_projection
from conftest import half_disc_case

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "viscoplastic_ball.toml"

E, NU = 1000.0, 0.3
LAM, MU = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))  # plane strain (4.1)
M = LAM + 2 * MU  # the oedometric modulus: σ_yy = M ε_yy when ε_xx = 0
Q0 = 10.0  # the pressure on the top of the block
ETA, YIELD = 0.5, 2.0  # Perzyna
RATE, E_INF, NU_INF = 2.0, 500.0, 0.3  # relaxation
LAM_INF, MU_INF = E_INF * NU_INF / ((1 + NU_INF) * (1 - 2 * NU_INF)), E_INF / (2 * (1 + NU_INF))
M_INF = LAM_INF + 2 * MU_INF

LAWS = {
    "perzyna": {"law": "perzyna", "eta": ETA, "yield_stress": YIELD},
    "relaxation": {"law": "relaxation", "mu": RATE, "E_inf": E_INF, "nu_inf": NU_INF},
}
# initial stresses in equilibrium with the load (σ_yy = −Q0), so that u(0) = 0 = u_0: the data are
# consistent and the continuous solution is smooth. The Perzyna one is outside the yield set:
# ‖dev σ_0‖ = |σ_xx − σ_yy| / √2 = 7.07 > 2.
INITIAL = {"perzyna": [[0.0, 0.0], [0.0, -Q0]], "relaxation": [[-2.0, 0.0], [0.0, -Q0]]}


# --- the scalar model of a block in uniaxial strain, written independently of vpcontact ------------
def g_perzyna(sigma, strain):
    dev = sigma - 0.5 * np.trace(sigma) * np.eye(2)
    size = np.sqrt(np.sum(dev * dev))
    return -max(0.0, 1.0 - YIELD / size) * dev / ETA if size > 0 else np.zeros((2, 2))


def g_relaxation(sigma, strain):
    relaxed = LAM_INF * np.trace(strain) * np.eye(2) + 2 * MU_INF * strain
    return -RATE * (sigma - relaxed)


SCALAR_LAWS = {"perzyna": g_perzyna, "relaxation": g_relaxation}


def scalar_recursion(G, sigma0, k, steps):
    """ε = diag(0, e) (rollers on the sides and the bottom), σ_yy = −Q0 (the top): per step,
    e_n = (−Q0 − z_yy) / M, σ_n = ℰε_n + z_n, z_{n+1} = z_n + k 𝒢(σ_n, ε_n); z_1 = σ_0 + k 𝒢(σ_0, 0)."""
    z = np.array(sigma0, dtype=float) + k * G(np.array(sigma0, dtype=float), np.zeros((2, 2)))
    strains, stresses, histories = [], [], []
    for _ in range(steps):
        e = (-Q0 - z[1, 1]) / M
        strain = np.diag([0.0, e])
        sigma = LAM * np.trace(strain) * np.eye(2) + 2 * MU * strain + z
        strains.append(e), stresses.append(sigma), histories.append(z)
        z = z + k * G(sigma, strain)
    return np.array(strains), np.array(stresses), np.array(histories)


def closed_form(law, t):
    """The continuous solution (e(t), σ_xx(t)) of σ' = ℰε' + 𝒢(σ, ε) with σ_yy = −Q0, ε_xx = 0."""
    s0 = INITIAL[law][0][0]
    if law == "perzyna":
        # D = σ_xx − σ_yy: D' = −c (D − √2 σ_y) while D > √2 σ_y, c = (λ + M) / (2ηM); e' = D' / (λ + M)
        c = (LAM + M) / (2 * ETA * M)
        D0 = s0 + Q0
        D = math.sqrt(2) * YIELD + (D0 - math.sqrt(2) * YIELD) * np.exp(-c * t)
        return (D - D0) / (LAM + M), D - Q0
    # M e' + μ (Q0 + M∞ e) = 0;  σ_xx' = λ e' − μ (σ_xx − λ∞ e)
    a = RATE * M_INF / M
    e_inf = -Q0 / M_INF
    e = e_inf * (1 - np.exp(-a * t))
    B = e_inf * (LAM * a - RATE * LAM_INF) / (RATE - a)
    C = s0 - LAM_INF * e_inf - B
    return e, LAM_INF * e_inf + B * np.exp(-a * t) + C * np.exp(-RATE * t)


def block(law, steps, T=1.0, method="auto", initial=None):
    """The block [0, 1] × [0, 0.5] on rollers (sides: u_x = 0, bottom: u_y = 0) under the pressure Q0 on
    its top: a homogeneous state, which P1 × P0 represents exactly."""
    case = {
        "mesh": {"shape": "rectangle", "width": 1.0, "height": 0.5, "h": 0.25},
        "material": {"E": E, "nu": NU},
        "boundary": {
            "dirichlet": [{"part": "left", "components": ["x"]}, {"part": "right", "components": ["x"]},
                          {"part": "bottom", "components": ["y"]}],
            "traction": [{"part": "top", "value": ["0", f"-{Q0}"]}],
        },
        "time": {"T": T, "steps": steps},
        "solver": {"method": method, "tolerance": 1e-13},
        "output": {"field_steps": "all"},
    }
    if law is not None:
        case["material"]["viscoplastic"] = LAWS[law]
    if initial is not None:
        case["initial"] = {"stress": initial}
    return case


def homogeneous(result, steps):
    """(e_n, σ_n, z_n) of every element at every step, checked homogeneous; u = (0, e y) at the nodes."""
    y = result.discretization.mesh.mesh.p[1]
    e, sigma, z = [], [], []
    for n in range(1, steps + 1):
        fields = result.fields[n]
        uy = fields.displacement[:, 1]
        slope = uy @ y / (y @ y)
        np.testing.assert_allclose(fields.displacement[:, 0], 0.0, rtol=0, atol=1e-14)
        np.testing.assert_allclose(uy, slope * y, rtol=0, atol=1e-15)
        e.append(slope), sigma.append(fields.stress), z.append(fields.z)
    return np.array(e), np.array(sigma), np.array(z)


# --- the laws themselves ---------------------------------------------------------------------------
def test_the_von_mises_projection():
    rng = np.random.default_rng(1)
    sigma = rng.normal(scale=5.0, size=(2, 2, 200))
    sigma = 0.5 * (sigma + sigma.transpose(1, 0, 2))
    P = von_mises_projection(sigma, 3.0)
    size = tensor_norm(deviator(sigma))
    outside = size > 3.0
    assert 20 < outside.sum() < 200
    np.testing.assert_allclose(tensor_norm(deviator(P))[outside], 3.0, rtol=1e-14)  # onto the sphere
    np.testing.assert_array_equal(P[:, :, ~outside], sigma[:, :, ~outside])  # inside: unchanged
    np.testing.assert_allclose(P[0, 0] + P[1, 1], sigma[0, 0] + sigma[1, 1], rtol=1e-14)  # trace kept
    np.testing.assert_allclose(von_mises_projection(P, 3.0), P, rtol=1e-14)  # a projection
    # orthogonal: (σ − Pσ) · (τ − Pσ) ≤ 0 for τ in the set (here τ = 0 and τ = its spherical part)
    residual = sigma - P
    assert np.all(np.einsum("ijn,ijn->n", residual, -P) <= 1e-10)
    # 𝒢 is 0 inside and −(1/η)(1 − σ_y/‖dev σ‖) dev σ outside
    G = Perzyna(0.25, 3.0)(sigma, np.zeros_like(sigma))
    np.testing.assert_array_equal(G[:, :, ~outside], 0.0)
    expected = -4.0 * (1.0 - 3.0 / size[outside]) * deviator(sigma)[:, :, outside]
    np.testing.assert_allclose(G[:, :, outside], expected, rtol=1e-12, atol=1e-12)


# --- homogeneous states: the scheme is the scalar recursion ----------------------------------------
@pytest.mark.parametrize("method", ["full", "condensed"])
@pytest.mark.parametrize("law", ["perzyna", "relaxation"])
def test_the_homogeneous_block_follows_the_scalar_recursion(law, method):
    steps, T = 10, 1.0
    result = vpcontact.solve(block(law, steps, T, method, INITIAL[law]))
    assert result.status == "complete" and result.method == method
    e, sigma, z = homogeneous(result, steps)
    e_ref, sigma_ref, z_ref = scalar_recursion(SCALAR_LAWS[law], INITIAL[law], T / steps, steps)
    np.testing.assert_allclose(e, e_ref, rtol=1e-12, atol=0)
    np.testing.assert_allclose(sigma, np.repeat(sigma_ref[:, None], sigma.shape[1], axis=1), rtol=0, atol=1e-12 * Q0)
    np.testing.assert_allclose(z, np.repeat(z_ref[:, None], z.shape[1], axis=1), rtol=0, atol=1e-12 * Q0)
    assert abs(e[-1] - e[0]) > 0.1 * abs(e[0] if e[0] else e[-1])  # the strain did creep


@pytest.mark.parametrize("law", ["perzyna", "relaxation"])
def test_the_homogeneous_block_converges_at_first_order_in_k(law):
    T, errors = 1.0, []
    for steps in (10, 20, 40):
        result = vpcontact.solve(block(law, steps, T, initial=INITIAL[law]))
        e, sigma, _ = homogeneous(result, steps)
        e_exact, sxx_exact = closed_form(law, result.series("t"))
        errors.append((np.abs(e - e_exact).max() / np.abs(e_exact).max(),
                       np.abs(sigma[:, 0, 0, 0] - sxx_exact).max() / np.abs(sxx_exact).max()))
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all((0.9 < orders) & (orders < 1.1)), orders
    assert errors[-1].max() < 0.05


def test_perzyna_relaxes_onto_the_yield_set_at_the_closed_form_rate():
    """Outside the yield set, with σ_yy held by the load and ε_xx = 0 by the rollers, the distance
    ‖dev σ‖ − σ_y decays by exactly 1 − k c per step, c = (λ + M) / (2ηM) (the explicit scheme of
    D' = −c D), which converges to the continuous exp(−c t)."""
    steps, T = 60, 3.0
    k, c = T / steps, (LAM + M) / (2 * ETA * M)
    result = vpcontact.solve(block("perzyna", steps, T, initial=INITIAL["perzyna"]))
    _, sigma, _ = homogeneous(result, steps)
    distance = tensor_norm(deviator(np.moveaxis(sigma[:, 0], 0, -1))) - YIELD
    distance0 = tensor_norm(deviator(np.array(INITIAL["perzyna"]))) - YIELD
    np.testing.assert_allclose(distance, distance0 * (1 - k * c) ** np.arange(1, steps + 1), rtol=1e-11)
    assert distance[-1] > 0 and distance[-1] < 0.03 * distance0  # relaxed onto the set, from outside
    assert abs(distance[-1] / distance0 - math.exp(-c * T)) < 0.005


def test_the_first_term_of_the_history_sum_is_there():
    """𝒢 constant (a callable): z_n = σ_0 + Σ_{j=0}^{n−1} k 𝒢 = σ_0 + t_n 𝒢, exactly the continuous
    solution; without the j = 0 term it would lag by one step."""
    rate = np.array([[3.0, 0.0], [0.0, -1.0]])
    steps, T = 5, 1.0
    result = vpcontact.solve(block(None, steps, T), viscoplastic=lambda s, e: np.broadcast_to(rate[..., None], s.shape))
    e, sigma, z = homogeneous(result, steps)
    t = result.series("t")
    np.testing.assert_allclose(z[:, 0], t[:, None, None] * rate, rtol=1e-14)
    np.testing.assert_allclose(e, (-Q0 - t * rate[1, 1]) / M, rtol=1e-12)
    np.testing.assert_allclose(sigma[:, 0, 0, 0], LAM * e + t * rate[0, 0], rtol=1e-12)


def test_an_initial_stress_alone_is_carried_elastically():
    """No 𝒢: σ = ℰε + σ_0 at every step (a prestressed elastic body)."""
    initial = [[4.0, 0.0], [0.0, -3.0]]
    result = vpcontact.solve(block(None, 3, initial=initial))
    e, sigma, z = homogeneous(result, 3)
    np.testing.assert_allclose(e, (-Q0 + 3.0) / M, rtol=1e-12)
    np.testing.assert_allclose(z, np.broadcast_to(initial, z.shape), rtol=0, atol=0)
    np.testing.assert_allclose(sigma[-1, 0], [[4.0 + LAM * e[-1], 0.0], [0.0, -Q0]], rtol=0, atol=1e-12 * Q0)


# --- the ball: limits where the elastic solution comes back, and convergence in time --------------
def ball(h=0.1, steps=11, T=1.1, **material):
    case = half_disc_case(h=h, load=17.977)
    case["boundary"]["traction"][0]["value"] = ["0", "-17.977*min(t, 0.5)"]
    case["time"] = {"T": T, "steps": steps}
    case["output"]["field_steps"] = "final"
    case["material"].update(material)
    return case


def test_perzyna_inside_the_yield_set_is_elastic():
    elastic = vpcontact.solve(ball())
    largest = tensor_norm(deviator(np.moveaxis(elastic.final.stress, 0, -1))).max()
    inside = vpcontact.solve(ball(viscoplastic={"law": "perzyna", "eta": 0.5, "yield_stress": 1.01 * largest}))
    np.testing.assert_array_equal(inside.final.z, 0.0)  # 𝒢 = 0 exactly
    np.testing.assert_array_equal(inside.final.displacement, elastic.final.displacement)
    np.testing.assert_array_equal(inside.contact_history("K"), elastic.contact_history("K"))
    yielding = vpcontact.solve(ball(viscoplastic={"law": "perzyna", "eta": 0.5, "yield_stress": 0.5 * largest}))
    assert np.abs(yielding.final.displacement - elastic.final.displacement).max() > 1e-3


def test_relaxation_towards_the_elasticity_tensor_is_elastic():
    elastic = vpcontact.solve(ball())
    same = vpcontact.solve(ball(viscoplastic={"law": "relaxation", "mu": 5.0, "E_inf": E, "nu_inf": NU}))
    np.testing.assert_allclose(same.final.displacement, elastic.final.displacement, rtol=0, atol=1e-14)
    np.testing.assert_allclose(same.final.stress, elastic.final.stress, rtol=0, atol=1e-12)
    assert np.abs(same.final.z).max() < 1e-12


def test_a_slow_relaxation_tends_to_the_elastic_solution_linearly_in_mu():
    elastic = vpcontact.solve(ball())
    scale = np.abs(elastic.final.displacement).max()
    gaps = []
    for mu in (1e-2, 1e-3, 1e-4):
        result = vpcontact.solve(ball(viscoplastic={"law": "relaxation", "mu": mu, "E_inf": E_INF, "nu_inf": NU_INF}))
        gaps.append(np.abs(result.final.displacement - elastic.final.displacement).max() / scale)
    assert gaps[-1] < 1e-4
    np.testing.assert_allclose(np.array(gaps[:-1]) / np.array(gaps[1:]), 10.0, rtol=0.02)


def test_the_ball_converges_at_first_order_in_time():
    """Perzyna body on the hardening layer, k = 0.05, 0.025, 0.0125, 0.00625: successive differences
    of u, σ and the penetrations halve with k."""
    law = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    runs = [vpcontact.solve(ball(steps=steps, T=1.0, viscoplastic=law)) for steps in (20, 40, 80, 160)]
    for name, value in [("displacement", lambda r: r.final.displacement), ("stress", lambda r: r.final.stress),
                        ("penetration", lambda r: r.contact_history("penetration")[-1])]:
        differences = [np.abs(value(a) - value(b)).max() for a, b in zip(runs, runs[1:])]
        ratios = np.array(differences[:-1]) / np.array(differences[1:])
        assert np.all((1.85 < ratios) & (ratios < 2.15)), (name, ratios)


def test_both_step_solvers_give_the_same_viscoplastic_solution():
    law = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    full, condensed = (_with_method(ball(viscoplastic=law), method) for method in ("full", "condensed"))
    assert (full.method, condensed.method) == ("full", "condensed")
    scale = np.abs(full.final.displacement).max()
    assert np.abs(full.final.displacement - condensed.final.displacement).max() < 1e-9 * scale
    assert np.abs(full.final.z - condensed.final.z).max() < 1e-8 * np.abs(full.final.z).max()
    np.testing.assert_allclose(full.contact_history("K"), condensed.contact_history("K"), rtol=1e-9)


@pytest.mark.parametrize("field_steps", ["none", [2]])
def test_the_fields_kept_are_those_of_every_step(field_steps):
    """The loop computes σ at every level but builds the fields at the field steps only: those kept, and
    the last level's of a run interrupted after step 4 (``result.final``), are the ones a run keeping every
    step's has there."""
    from vpcontact.case.translate import output_options
    from vpcontact.timeloop.loop import TimeLoop

    case = ball(h=0.2, viscoplastic={"law": "perzyna", "eta": 0.5, "yield_stress": 1.0})
    case["output"]["field_steps"] = "all"
    every = vpcontact.solve(case)
    case["output"]["field_steps"] = field_steps
    loaded = vpcontact.load_case(case)
    loop = TimeLoop(vpcontact.build_problem(loaded), output_options(loaded.output))
    stopped = loop.run(stop=lambda: "stopped" if loop.state.step == 4 else None)
    kept = [] if field_steps == "none" else field_steps
    assert stopped.status == "interrupted" and stopped.steps == 4 and sorted(stopped.fields) == kept
    for fields, expected in [(stopped.final, every.fields[4])] + [(stopped.fields[n], every.fields[n]) for n in kept]:
        for name in ("displacement", "stress", "stress33", "von_mises", "z"):
            np.testing.assert_array_equal(getattr(fields, name), getattr(expected, name))
    assert np.abs(every.fields[4].z).max() > 0.1


def _with_method(case, method):
    case["solver"]["method"] = method
    return vpcontact.solve(case)


def test_a_callable_law_gives_the_built_in_law():
    law = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    built_in = vpcontact.solve(ball(viscoplastic=law))

    def perzyna(sigma, strain):  # vectorized over (2, 2, elements), written out
        mean = 0.5 * (sigma[0, 0] + sigma[1, 1])
        dev = sigma - mean * np.eye(2)[:, :, None]
        size = np.sqrt((dev**2).sum(axis=(0, 1)))
        return -np.maximum(0.0, 1.0 - 3.0 / np.maximum(size, 1e-300)) * dev / 0.5

    called = vpcontact.solve(ball(), viscoplastic=perzyna)
    np.testing.assert_allclose(called.final.displacement, built_in.final.displacement, rtol=0, atol=1e-13)
    np.testing.assert_allclose(called.final.z, built_in.final.z, rtol=0, atol=1e-11)


def test_a_callable_of_the_wrong_shape_is_refused():
    with pytest.raises(vpcontact.CaseError, match=r"viscoplastic: .* returned an array of shape \(3,\)"):
        vpcontact.solve(block(None, 2), viscoplastic=lambda s, e: np.zeros(3))


def test_a_callable_whose_shape_changes_during_the_run_fails_the_step_in_one_line():
    """A law of the right shape at t_0 (the check before the run: σ_0 = 0 there) that returns another shape
    once the body is loaded: the step fails with one line naming both shapes, no exception escapes."""
    def changing(sigma, strain):
        return np.zeros_like(sigma) if not np.any(sigma) else np.zeros(3)

    result = vpcontact.solve(block(None, 4), viscoplastic=changing)
    assert result.status == "failed" and result.steps == 0 and "\n" not in result.message
    assert result.message == ("step 1 (t = 0.25) failed: at t = 0.25 the viscoplastic law returned an array of shape "
                              "(3,); expected (2, 2, 16) (d, d, elements), like its arguments")


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
def test_an_unstable_explicit_step_fails_cleanly():
    """k ≫ η: the explicit history blows up; the run stops with status "failed" and says why."""
    case = block(None, 400, T=400.0, initial=INITIAL["perzyna"])
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 1e-3, "yield_stress": YIELD}
    case["output"]["field_steps"] = "none"
    result = vpcontact.solve(case)
    assert result.status == "failed" and "not finite" in result.message and result.steps < 400


# --- the example and the outputs ---------------------------------------------------------------------
def test_the_example_creeps_under_the_held_load():
    """examples/viscoplastic_ball.toml on a coarser mesh: while the load is held (t ≥ 0.5) the Perzyna
    body keeps shortening where the elastic one does not, the penetration at the rim of the contact
    part (the probe) keeps growing, and the layer hardens (K grows at every node)."""
    coarse = {"mesh.h": 0.05, "output.field_steps": "all", "output.progress": False}
    viscous = vpcontact.solve(vpcontact.load_case(EXAMPLE, coarse))
    case = vpcontact.load_case(EXAMPLE, coarse)
    case.material.viscoplastic = None
    elastic = vpcontact.solve(case)
    p = viscous.discretization.mesh.mesh.p
    top, bottom = np.argmax(p[1]), np.argmin(np.abs(p[0]) + p[1])  # (0, 2) and (0, 0)
    held = np.flatnonzero(viscous.series("t") >= 0.5 - 1e-12) + 1  # the steps of the hold

    def shortening(result):
        return np.array([result.fields[n].displacement[bottom, 1] - result.fields[n].displacement[top, 1] for n in held])

    viscous_shortening, elastic_shortening = shortening(viscous), shortening(elastic)
    assert np.ptp(elastic_shortening) < 0.02 * elastic_shortening[0]  # 1.4 %: the pressure redistributes
    assert np.all(np.diff(viscous_shortening) > 0) and viscous_shortening[-1] > 1.5 * viscous_shortening[0]
    rim = viscous.series("penetration_probe")[held - 1]
    assert np.all(np.diff(rim) > 0) and rim[-1] > 2 * rim[0]
    assert np.all(np.diff(viscous.contact_history("K")[held - 1], axis=0) > 0)  # the layer hardens
    assert viscous.series("mean_penetration")[-1] > 1.05 * elastic.series("mean_penetration")[-1]


def test_the_history_is_written(tmp_path):
    case = ball(h=0.2, viscoplastic={"law": "perzyna", "eta": 0.5, "yield_stress": 3.0})
    case["output"]["field_steps"] = [5, 11]
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    result = vpcontact.solve(path)
    saved = np.load(tmp_path / "run" / "solution.npz")
    assert saved["z"].shape == saved["stress"].shape == (2, result.elements, 2, 2)
    np.testing.assert_array_equal(saved["z"][-1], result.final.z)
    assert np.abs(saved["z"][-1]).max() > 0
    body = meshio.read(tmp_path / "run" / "fields" / "body_00011.vtu")
    np.testing.assert_array_equal(body.cell_data["z"][0].reshape(-1, 3, 3)[:, :2, :2], result.final.z)
    resolved = vpcontact.load_case(tmp_path / "run" / "case.resolved.toml")
    assert resolved.material.viscoplastic.law == "perzyna" and resolved.material.viscoplastic.eta == 0.5
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["status"] == "complete"

    elastic = tmp_path / "elastic.toml"
    del case["material"]["viscoplastic"]
    elastic.write_text(tomli_w.dumps(case))
    assert main(["run", str(elastic), "--out", str(tmp_path / "elastic"), "--quiet"]) == 0
    assert "z" not in np.load(tmp_path / "elastic" / "solution.npz")
    assert "z" not in meshio.read(tmp_path / "elastic" / "fields" / "body_00011.vtu").cell_data


# --- bad input -------------------------------------------------------------------------------------
BAD = [
    ({"material.viscoplastic": {"law": "bingham", "eta": 1.0}},
     'material.viscoplastic.law = "bingham": unknown law; expected one of "perzyna", "relaxation"'),
    ({"material.viscoplastic": {"eta": 1.0}},
     "missing required value 'material.viscoplastic.law' (one of \"perzyna\", \"relaxation\")"),
    ({"material.viscoplastic": {"law": "perzyna", "eta": 0.0, "yield_stress": 1.0}},
     "material.viscoplastic.eta = 0.0: must be > 0.0"),
    ({"material.viscoplastic": {"law": "perzyna", "eta": 1.0, "yield_stress": -1.0}},
     "material.viscoplastic.yield_stress = -1.0: must be >= 0.0"),
    ({"material.viscoplastic": {"law": "perzyna", "eta": 1.0}},
     "missing required value 'material.viscoplastic.yield_stress'"),
    ({"material.viscoplastic": {"law": "perzyna", "eta": 1.0, "yield_stress": 1.0, "mu": 2.0}},
     "unknown key 'material.viscoplastic.mu' (valid keys: eta, law, yield_stress)"),
    ({"material.viscoplastic": {"law": "perzyna", "eta": "fast", "yield_stress": 1.0}},
     'material.viscoplastic.eta = "fast": expected a number'),
    ({"material.viscoplastic": {"law": "perzyna", "eta": math.inf, "yield_stress": 1.0}},
     "material.viscoplastic.eta = inf: expected a finite number"),
    ({"material.viscoplastic": {"law": "relaxation", "mu": 0.0, "E_inf": 100.0, "nu_inf": 0.3}},
     "material.viscoplastic.mu = 0.0: must be > 0.0"),
    ({"material.viscoplastic": {"law": "relaxation", "mu": 1.0, "E_inf": -100.0, "nu_inf": 0.3}},
     "material.viscoplastic.E_inf = -100.0: must be > 0.0"),
    ({"material.viscoplastic": {"law": "relaxation", "mu": 1.0, "E_inf": 100.0, "nu_inf": 0.5}},
     "material.viscoplastic.nu_inf = 0.5: must satisfy -1 < nu_inf < 0.5 for plane_strain and 3D"),
    ({"material.viscoplastic": {"law": "relaxation", "mu": 1.0, "E_inf": 100.0}},
     "missing required value 'material.viscoplastic.nu_inf'"),
    ({"material.viscoplastic": "perzyna"}, 'material.viscoplastic = "perzyna": expected a table'),
    ({"initial.stress": [[1.0, 2.0], [3.0, 4.0]]},
     "initial.stress = [[1.0, 2.0], [3.0, 4.0]]: must be symmetric (stress[0][1] = 2.0, stress[1][0] = 3.0)"),
    ({"initial.stress": [[1.0, 2.0], [2.0]]},
     "initial.stress = [[1.0, 2.0], [2.0]]: expected a d x d table, [[sxx, sxy], [sxy, syy]] in 2D or "
     "[[sxx, sxy, sxz], [sxy, syy, syz], [sxz, syz, szz]] in 3D"),
    ({"initial.stress": [[1.0, 0.0], [0.0, math.nan]]},
     "initial.stress = [[1.0, 0.0], [0.0, nan]]: expected finite numbers or expressions in the coordinates, got nan"),
    ({"initial.strain": 1.0}, "unknown key 'initial.strain' (valid keys: displacement, from_run, step, stress, xi)"),
]


@pytest.mark.parametrize("override, message", BAD, ids=[m.split(" ")[0] + str(i) for i, (_, m) in enumerate(BAD)])
def test_bad_viscoplastic_input(override, message):
    with pytest.raises(vpcontact.CaseError) as caught:
        vpcontact.load_case(block(None, 1), override)
    assert str(caught.value) == message
    assert "\n" not in str(caught.value)


def test_bad_input_from_the_command_line(tmp_path, capsys):
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(block(None, 1)))
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet",
                 "--set", "material.viscoplastic.law=\"maxwell\""])
    assert code == 2 and not (tmp_path / "out").exists()
    assert 'material.viscoplastic.law = "maxwell": unknown law; expected one of "perzyna", "relaxation"' in capsys.readouterr().err
