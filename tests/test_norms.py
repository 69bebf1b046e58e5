"""Tests of vpcontact.results.norms: transfer between meshes, the L² norms and `differences`."""

import math
import time

import numpy as np
import pytest

from vpcontact.mesh import half_disc, rectangle
from vpcontact.results.norms import Snapshot, differences, strain_norm, stress_norm, transfer

GRADIENT = np.array([[0.7, -1.3], [2.1, 0.4]])  # ∂u_i/∂x_j of the linear test field
STRESS = np.array([[3.0, -1.5], [-1.5, 2.0]])


def linear(p):
    """u(x) = (0.25, −0.5) + GRADIENT x at points p (2, n), as (n, 2)."""
    return np.array([0.25, -0.5]) + (GRADIENT @ p).T


def constant_stress(t, value=STRESS):
    return np.broadcast_to(value, (t.shape[1], 2, 2)).copy()


def areas(p, t):
    a, b, c = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    return 0.5 * np.abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def barycentric(p, t, x):
    """Barycentric coordinates (n, m, 3) of points x (n, 2) in every triangle, by solving the 3×3 systems."""
    vertices = p[:, t].transpose(2, 1, 0)  # (m, 3, 2)
    systems = np.concatenate((vertices, np.ones((t.shape[1], 3, 1))), axis=2).transpose(0, 2, 1)  # (m, 3, 3)
    rhs = np.concatenate((x, np.ones((x.shape[0], 1))), axis=1)
    rhs = np.broadcast_to(rhs[:, None, :, None], (x.shape[0], t.shape[1], 3, 1))
    return np.linalg.solve(systems[None], rhs)[..., 0]


def triangle_distance(p, t, x):
    """Distance (n, m) from points x (n, 2) to every triangle (0 inside), brute force."""
    lam = barycentric(p, t, x)
    out = np.full(lam.shape[:2], np.inf)
    for k in range(3):
        a, b = p[:, t[k]].T, p[:, t[(k + 1) % 3]].T  # (m, 2)
        s = np.clip(((x[:, None] - a) * (b - a)).sum(-1) / ((b - a) ** 2).sum(-1), 0, 1)
        out = np.minimum(out, np.linalg.norm(x[:, None] - a - s[..., None] * (b - a), axis=-1))
    return np.where(lam.min(axis=2) >= -1e-12, 0.0, out)


@pytest.mark.parametrize("h_source, h_target", [(0.2, 0.1), (0.1, 0.2)])
def test_transfer_reproduces_linear_displacement_and_constant_stress(h_source, h_target):
    source, target = half_disc(h_source).mesh, half_disc(h_target).mesh
    snapshot = Snapshot(source.p, source.t, linear(source.p), constant_stress(source.t))
    moved = transfer(snapshot, target.p, target.t)
    assert moved.displacement.shape == (target.p.shape[1], 2)
    assert moved.stress.shape == (target.t.shape[1], 2, 2)
    np.testing.assert_allclose(moved.displacement, linear(target.p), rtol=0, atol=1e-12)
    np.testing.assert_allclose(moved.stress, constant_stress(target.t), rtol=0, atol=1e-12)

    outside = triangle_distance(source.p, source.t, target.p.T).min(axis=1) > 0
    if h_source > h_target:
        # the finer arc's nodes between the coarse arc's nodes lie outside the coarse polygon
        assert outside.sum() == 2 * math.ceil(0.5 * math.pi / h_source)
        np.testing.assert_allclose(moved.displacement[outside], linear(target.p[:, outside]), rtol=0, atol=1e-12)
    else:
        assert not outside.any()


def test_outside_points_extrapolate_the_nearest_element():
    """A non-linear P1 field at the fine arc's nodes outside the coarse polygon: the linear
    extrapolation of the coarse element nearest to the node (brute force)."""
    source, target = half_disc(0.2).mesh, half_disc(0.1).mesh
    values = np.stack((np.sin(3 * source.p[0]) + source.p[1] ** 2, np.exp(source.p[0] * source.p[1])), axis=1)
    moved = transfer(Snapshot(source.p, source.t, values, constant_stress(source.t)), target.p, target.t)
    x = target.p.T
    distance = triangle_distance(source.p, source.t, x)
    outside = np.flatnonzero(distance.min(axis=1) > 0)
    assert outside.size == 16
    nearest = distance[outside].argmin(axis=1)
    lam = barycentric(source.p, source.t, x[outside])[np.arange(outside.size), nearest]  # (k, 3)
    expected = np.einsum("kv,vkd->kd", lam, values[source.t[:, nearest]])
    assert lam.min() < -1e-3  # really an extrapolation
    np.testing.assert_allclose(moved.displacement[outside], expected, rtol=0, atol=1e-12)
    # inside: the interpolation in the containing element
    inside = np.setdiff1d(np.arange(x.shape[0]), outside)
    nearest_in = distance[inside].argmin(axis=1)
    lam_in = barycentric(source.p, source.t, x[inside])[np.arange(inside.size), nearest_in]
    np.testing.assert_allclose(moved.displacement[inside],
                               np.einsum("kv,vkd->kd", lam_in, values[source.t[:, nearest_in]]), rtol=0, atol=1e-12)


def test_strain_norm_of_linear_field_and_stress_norm_of_constant():
    for mesh, area in ((rectangle(2.0, 1.0, 0.25).mesh, 2.0), (half_disc(0.1).mesh, None)):
        p, t = mesh.p, mesh.t
        area = areas(p, t).sum() if area is None else area
        sym = 0.5 * (GRADIENT + GRADIENT.T)
        assert strain_norm(p, t, linear(p)) == pytest.approx(math.sqrt(area) * np.linalg.norm(sym), rel=1e-13)
        assert stress_norm(p, t, constant_stress(t)) == pytest.approx(math.sqrt(area) * np.linalg.norm(STRESS),
                                                                      rel=1e-13)
        # a rigid motion has no strain; the triangles' orientation does not matter
        rigid = np.array([1.0, 2.0]) + (np.array([[0.0, -0.3], [0.3, 0.0]]) @ p).T
        assert strain_norm(p, t, rigid) < 1e-14
        flipped = t.copy()
        flipped[[1, 2], ::2] = flipped[[2, 1], ::2]
        assert strain_norm(p, flipped, linear(p)) == pytest.approx(strain_norm(p, t, linear(p)), rel=1e-14)


def test_differences():
    mesh = rectangle(2.0, 1.0, 0.25).mesh
    p, t = mesh.p, mesh.t
    rng = np.random.default_rng(1)
    reference = Snapshot(p, t, rng.standard_normal((p.shape[1], 2)), rng.standard_normal((t.shape[1], 2, 2)))
    same = differences(reference, reference)
    assert same["V"] == 0.0 and same["Q"] == 0.0
    assert same["V_reference"] == strain_norm(p, t, reference.displacement) > 0
    assert same["Q_reference"] == stress_norm(p, t, reference.stress) > 0

    # a difference of a known linear field and a known constant stress; area 2
    offset = np.array([[1.0, 4.0], [-2.0, 0.5]])  # w = offset x: sym ∇w = [[1, 1], [1, 0.5]]
    solution = Snapshot(p.copy(), t.copy(), reference.displacement + (offset @ p).T,
                        reference.stress + constant_stress(t, STRESS))
    result = differences(solution, reference)
    assert result["V"] == pytest.approx(math.sqrt(2.0) * math.sqrt(1 + 1 + 1 + 0.25), rel=1e-12, abs=0)
    assert result["Q"] == pytest.approx(math.sqrt(2.0) * math.sqrt(9 + 2 * 2.25 + 4), rel=1e-12, abs=0)

    plain = Snapshot(p, t, linear(p), constant_stress(t))
    result = differences(solution, plain)
    sym = 0.5 * (GRADIENT + GRADIENT.T)
    assert result["V_reference"] == pytest.approx(math.sqrt(2.0) * np.linalg.norm(sym), rel=1e-13)
    assert result["Q_reference"] == pytest.approx(math.sqrt(2.0) * np.linalg.norm(STRESS), rel=1e-13)


def test_differences_across_meshes_of_a_linear_solution_vanish():
    coarse, fine = half_disc(0.2).mesh, half_disc(0.05).mesh
    solution = Snapshot(coarse.p, coarse.t, linear(coarse.p), constant_stress(coarse.t))
    reference = Snapshot(fine.p, fine.t, linear(fine.p), constant_stress(fine.t))
    result = differences(solution, reference)
    assert result["V"] < 1e-12 * result["V_reference"] and result["Q"] < 1e-12 * result["Q_reference"]
    tilted = Snapshot(fine.p, fine.t, linear(fine.p) + 0.1 * fine.p[::-1].T, constant_stress(fine.t))
    area = areas(fine.p, fine.t).sum()  # sym ∇ of 0.1 (y, x) is 0.1 [[0, 1], [1, 0]]
    assert differences(solution, tilted)["V"] == pytest.approx(math.sqrt(area) * 0.1 * math.sqrt(2), rel=1e-12)


def test_interpolation_error_converges_at_first_order():
    def smooth(p):
        return np.stack((np.sin(p[0]) * np.cos(p[1]), p[0] ** 2 * p[1]), axis=1)

    fine = half_disc(0.0125).mesh
    reference = Snapshot(fine.p, fine.t, smooth(fine.p), np.zeros((fine.t.shape[1], 2, 2)))
    hs = [0.1, 0.05, 0.025]
    errors = []
    for h in hs:
        mesh = half_disc(h).mesh
        errors.append(differences(Snapshot(mesh.p, mesh.t, smooth(mesh.p), np.zeros((mesh.t.shape[1], 2, 2))),
                                  reference)["V"])
    rates = [math.log(errors[i] / errors[i + 1]) / math.log(hs[i] / hs[i + 1]) for i in range(2)]
    print(f"\n‖ε(I_h u − I_ref u)‖ for h = {hs}: {errors}; observed rates {rates}")
    assert all(0.8 <= r <= 1.3 for r in rates), rates


def test_snapshot_checks_shapes():
    mesh = rectangle(1.0, 1.0, 0.5).mesh
    with pytest.raises(ValueError, match="stress"):
        Snapshot(mesh.p, mesh.t, np.zeros((mesh.p.shape[1], 2)), np.zeros((mesh.t.shape[1], 3)))


def test_transfer_timing_note():
    """Not an assertion: prints the time of a transfer half_disc(0.02) → half_disc(0.005)."""
    source, target = half_disc(0.02).mesh, half_disc(0.005).mesh
    snapshot = Snapshot(source.p, source.t, linear(source.p), constant_stress(source.t))
    started = time.perf_counter()
    moved = transfer(snapshot, target.p, target.t)
    elapsed = time.perf_counter() - started
    print(f"\ntransfer {source.t.shape[1]} → {target.t.shape[1]} triangles ({target.p.shape[1]} nodes): "
          f"{elapsed:.3f} s")
    assert moved.displacement.shape == (target.p.shape[1], 2)


def test_difference_norms_through_the_api_between_two_solves():
    """Two solves of one case differ by 0. The block with g = ∞ and constant K is a linear problem:
    doubling the traction doubles u and σ, so ‖u₁ − u₂‖_V = ½‖u₂‖_V and likewise in Q."""
    import vpcontact
    from conftest import rectangle_case

    case = rectangle_case(g=float("inf"), stiffness={"law": "power", "c_v": 100.0, "alpha": 0.0, "beta": 1.0})
    one = vpcontact.solve(case)
    assert differences(one.snapshot(), vpcontact.solve(case).snapshot())["V"] == 0.0
    case["boundary"]["traction"][0]["value"] = ["0", "-200*t"]
    two = vpcontact.solve(case).snapshot()
    norms = differences(one.snapshot(), two)
    assert norms["V"] == pytest.approx(0.5 * norms["V_reference"], rel=1e-10)
    assert norms["Q"] == pytest.approx(0.5 * norms["Q_reference"], rel=1e-10)


def test_the_energy_norm_of_a_difference_uses_the_references_lame_parameters():
    """w = offset x on the rectangle of area 2: ε(w) = [[1, 1], [1, 0.5]], tr ε = 1.5, ε:ε = 3.25, so
    ‖w‖_E² = 2 (λ 1.5² + 2μ 3.25) with the reference's (λ, μ); elements of another (λ, μ) weigh theirs."""
    mesh = rectangle(2.0, 1.0, 0.25).mesh
    p, t = mesh.p, mesh.t
    lam, mu = 577.0, 385.0
    lame = np.array([np.full(t.shape[1], lam), np.full(t.shape[1], mu)])
    reference = Snapshot(p, t, np.zeros((p.shape[1], 2)), np.zeros((t.shape[1], 2, 2)), lame)
    offset = np.array([[1.0, 4.0], [-2.0, 0.5]])
    solution = Snapshot(p, t, (offset @ p).T, np.zeros((t.shape[1], 2, 2)))
    result = differences(solution, reference)
    assert result["energy"] == pytest.approx(math.sqrt(2.0 * (lam * 1.5**2 + 2 * mu * 3.25)), rel=1e-12)
    assert result["energy_reference"] == 0.0
    stiffer = lame.copy()
    stiffer[:, p[0, t].mean(axis=0) < 1.0] *= 4.0  # the left half (area 1) four times as stiff
    result = differences(solution, Snapshot(p, t, reference.displacement, reference.stress, stiffer))
    assert result["energy"] == pytest.approx(math.sqrt(5.0 * (lam * 1.5**2 + 2 * mu * 3.25)), rel=1e-12)
    assert "energy" not in differences(reference, solution)  # a reference without (λ, μ): no energy norm


def test_points_outside_a_graded_mesh_take_the_nearest_element():
    """A quarter ball graded from h = 0.6 to 0.1 at its bottom (elements of four sizes): the nodes of a
    finer mesh outside its inscribed polyhedron take the element nearest to them, as a search over every
    element finds it (the candidates are bounded per element size, not by the largest element)."""
    from vpcontact.mesh import quarter_ball
    from vpcontact.mesh.locate import Locator

    coarse, fine = quarter_ball(0.6, h_bottom=0.1).mesh, quarter_ball(0.3).mesh
    locator = Locator(coarse.p, coarse.t)
    assert len(locator.groups) > 1
    element, coordinates = locator.locate(fine.p.T.copy())
    outside = np.flatnonzero(coordinates.min(axis=1) < -1e-10)
    assert outside.size > 20
    outside = outside[:: max(1, outside.size // 40)]  # 40 of them against every element
    every = np.broadcast_to(np.arange(coarse.t.shape[1]), (outside.size, coarse.t.shape[1]))
    nearest = locator.distance(fine.p.T[outside], every).min(axis=1)
    np.testing.assert_allclose(locator.distance(fine.p.T[outside], element[outside][:, None])[:, 0], nearest,
                               rtol=0, atol=1e-14)
