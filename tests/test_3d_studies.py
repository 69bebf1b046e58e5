"""Studies and their difference norms between two 3D meshes:

- a study of the quarter ball through the command line: the reference against itself is 0, a second
  run on the reference mesh differs by rounding only, the coarser runs' norms shrink with h, and each
  norm in study.csv equals one computed here independently (the coarse P1 displacement located on the
  fine mesh by scikit-fem's element finder, or by a brute-force nearest tetrahedron outside the coarse
  polyhedron, and integrated with a quadrature rule written here);
- the same norms through the Python API (`vpcontact.solve`, `Result.snapshot`, `norms.differences`);
- a solution against itself with its nodes and tetrahedra renumbered (so it is transferred) is 0;
- a linear displacement and a constant stress are transferred exactly between two quarter-ball
  meshes, their outside nodes included, and two solves of a linear problem (the block on a layer of
  constant stiffness) on different meshes differ by 0;
- a quadratic field: the norms match closed-form integrals over the block to the accuracy of P1
  interpolation (second order), and the difference of its interpolants on coarser meshes shrinks at
  first order (strain) and second order (displacement);
- the L² norm of a P1 field (new, `norm_U` in study.csv) exact for linear fields in 2D and 3D;
- benchmarks/convergence_3d.py, its quickest setting: positive, finite errors decreasing with h.
"""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from scipy.optimize import nnls
from skfem import CellBasis, ElementTetP1, ElementVector, Functional, MeshTet
from skfem.helpers import ddot, dot, sym_grad

import vpcontact
from vpcontact.mesh import block, quarter_ball, rectangle
from vpcontact.results.norms import Snapshot, differences, displacement_norm, strain_norm, stress_norm, transfer
from conftest import run_cli
from test_3d import block_case

ROOT = Path(__file__).resolve().parents[1]
COARSE, MIDDLE, FINE = 0.5, 0.35, 0.25
NORMS = ("V", "Q", "U")

#: A degree-2 rule on the reference tetrahedron (volume 1/6): four points, exact for quadratics.
_A, _B = (5.0 + 3.0 * math.sqrt(5.0)) / 20.0, (5.0 - math.sqrt(5.0)) / 20.0
QUADRATURE = (np.array([[_B, _A, _B, _B], [_B, _B, _A, _B], [_B, _B, _B, _A]]), np.full(4, 1.0 / 24.0))


# --- an independent computation of vpcontact's difference norms ------------------------------------
def barycentric_in_all(p, t, x):
    """Barycentric coordinates (q, m, 4) of points x (q, 3) in every tetrahedron, brute force."""
    systems = np.concatenate((p[:, t].transpose(2, 0, 1), np.ones((t.shape[1], 1, 4))), axis=1)  # (m, 4, 4)
    inverse = np.linalg.inv(systems)
    return np.einsum("mij,qj->qmi", inverse, np.concatenate((x, np.ones((x.shape[0], 1))), axis=1))


def distances_to_nearby_tetrahedra(p, t, point):
    """(candidates, distances) from one point outside the mesh to every tetrahedron with a vertex within
    (distance to the nearest node + longest edge) — the nearest point of the mesh lies in one of them —
    each distance by non-negative least squares over the barycentric coordinates (their sum 1
    enforced by a heavy row)."""
    edges = np.concatenate([p[:, t[i]] - p[:, t[j]] for i in range(4) for j in range(i)], axis=1)
    to_nodes = np.linalg.norm(p.T - point, axis=1)
    near = np.flatnonzero(to_nodes <= to_nodes.min() + np.linalg.norm(edges, axis=0).max())
    candidates = np.flatnonzero(np.isin(t, near).any(axis=0))
    heavy = 1e6
    distances = np.array([nnls(np.vstack((p[:, t[:, e]], np.full((1, 4), heavy))), np.append(point, heavy))[1]
                          for e in candidates])
    return candidates, distances


def admissible_elements(coarse: MeshTet, x):
    """For points x (q, 3): the coarse tetrahedra vpcontact may evaluate its fields in — those holding
    the point (barycentric coordinates ≥ −1e-12) or, for a point outside the mesh, those nearest to it
    (within 1e-7 of the least distance: a point beyond an edge of the coarse polyhedron is equally near
    to the tetrahedra around that edge) — and whether each point is inside. scikit-fem's element finder
    must find one of the holding ones."""
    holding = barycentric_in_all(coarse.p, coarse.t, x).min(axis=2) >= -1e-12  # (q, m)
    inside = holding.any(axis=1)
    found = coarse.element_finder()(*x[inside].T)
    assert holding[np.flatnonzero(inside), found].all()
    admissible = [np.flatnonzero(row) for row in holding]
    for i in np.flatnonzero(~inside):
        candidates, distances = distances_to_nearby_tetrahedra(coarse.p, coarse.t, x[i])
        admissible[i] = candidates[distances <= distances.min() + 1e-7]
    return admissible, inside


def assert_values_from_admissible_elements(values, admissible, value_in):
    """values (q, …) equal, at each point i, value_in(i, e) for one of its admissible elements e."""
    for i, elements in enumerate(admissible):
        gaps = [np.abs(values[i] - value_in(i, e)).max() for e in elements]
        assert min(gaps) <= 1e-12 * max(1.0, np.abs(values[i]).max()), (i, elements, gaps)


def independent_norms(solution: Snapshot, reference: Snapshot):
    """{"V", "Q", "U"} as vpcontact defines them: the coarse P1 displacement's values at the fine nodes
    and the coarse P0 stress at the fine centroids (`norms.transfer`, checked here point by point to
    come from an admissible coarse tetrahedron: one holding the point, or one nearest to it,
    extrapolated linearly), integrated on the fine mesh with scikit-fem and QUADRATURE. Also the
    number of fine nodes outside the coarse mesh."""
    coarse, fine = MeshTet(solution.points, solution.elements), MeshTet(reference.points, reference.elements)
    moved = transfer(solution, reference.points, reference.elements)
    nodes, inside = admissible_elements(coarse, fine.p.T)
    weights = barycentric_in_all(coarse.p, coarse.t, fine.p.T)  # (q, m, 4)
    assert_values_from_admissible_elements(
        moved.displacement, nodes, lambda i, e: weights[i, e] @ solution.displacement[coarse.t[:, e]])
    centroids, _ = admissible_elements(coarse, fine.p[:, fine.t].mean(axis=1).T)
    assert_values_from_admissible_elements(moved.stress, centroids, lambda i, e: solution.stress[e])

    basis = CellBasis(fine, ElementVector(ElementTetP1()), quadrature=QUADRATURE)
    difference = np.zeros(basis.N)
    difference[basis.nodal_dofs] = (moved.displacement - reference.displacement).T
    field = basis.interpolate(difference)
    V2 = Functional(lambda w: ddot(sym_grad(w["u"]), sym_grad(w["u"]))).assemble(basis, u=field)
    U2 = Functional(lambda w: dot(w["u"], w["u"])).assemble(basis, u=field)
    volumes = basis.dx.sum(axis=1)
    Q2 = np.sum(volumes * ((moved.stress - reference.stress) ** 2).sum(axis=(1, 2)))
    return {"V": math.sqrt(V2), "Q": math.sqrt(Q2), "U": math.sqrt(U2)}, int((~inside).sum())


# --- a study of the quarter ball through the command line ------------------------------------------
@pytest.fixture(scope="module")
def ball_study(tmp_path_factory):
    """examples/quarter_ball.toml in 3 steps at h = 0.5 and 0.35 against h = 0.25, and a second run at
    h = 0.25 ("again"), through `python -m vpcontact.cli study`: (output directory, study.csv rows)."""
    folder = tmp_path_factory.mktemp("ball_study")
    study = {"base": str(ROOT / "examples" / "quarter_ball.toml"),
             "set": {"time.steps": 3, "output.field_steps": "final", "output.figures": False},
             "vary": [{"mesh.h": [COARSE, MIDDLE]}],
             "runs": [{"id": "reference", "mesh.h": FINE}, {"id": "again", "mesh.h": FINE}],
             "compare": {"reference": "reference", "times": [1.1]}}
    (folder / "study.toml").write_text(tomli_w.dumps(study))
    status, _, stderr = run_cli("study", folder / "study.toml", "--out", folder / "out", "--workers", "2", "--quiet")
    assert status == 0, stderr
    with open(folder / "out" / "study.csv") as handle:
        rows = {row["id"]: row for row in csv.DictReader(handle)}
    return folder / "out", rows


def snapshot_of(run: Path) -> Snapshot:
    with np.load(run / "solution.npz") as solution:
        return Snapshot(solution["points"], solution["tetrahedra"], solution["displacement"][-1],
                        solution["stress"][-1])


def table_norms(row) -> dict:
    return {name: float(row[f"norm_{name}_t1.1"]) for name in NORMS}


def test_a_3d_study_reports_norms_that_vanish_on_the_reference_and_shrink_with_h(ball_study):
    out, rows = ball_study
    assert sorted(rows) == ["again", "h=0.35", "h=0.5", "reference"]
    assert {row["status"] for row in rows.values()} == {"complete"}
    assert [int(rows[i]["dofs"]) for i in ("h=0.5", "h=0.35", "reference")] == [336, 1188, 1911]
    assert "contact_force_z" in rows["reference"]
    assert table_norms(rows["reference"]) == {"V": 0.0, "Q": 0.0, "U": 0.0}
    size = differences(snapshot_of(out / "runs" / "h=0.5"), snapshot_of(out / "runs" / "reference"))
    again = table_norms(rows["again"])
    for name in NORMS:  # the same case solved in another process: equal to rounding
        assert again[name] <= 1e-10 * size[f"{name}_reference"], (name, again)
    coarse, middle = table_norms(rows["h=0.5"]), table_norms(rows["h=0.35"])
    for name in NORMS:
        assert 0.0 < middle[name] < coarse[name] < size[f"{name}_reference"], (name, coarse, middle)


@pytest.mark.parametrize("run", ["h=0.5", "h=0.35"])
def test_the_study_norms_equal_an_independent_computation(ball_study, run):
    out, rows = ball_study
    solution, reference = snapshot_of(out / "runs" / run), snapshot_of(out / "runs" / "reference")
    expected, outside = independent_norms(solution, reference)
    assert outside > 20  # fine nodes on the sphere outside the coarse inscribed polyhedron: extrapolated
    for name in NORMS:
        assert float(rows[run][f"norm_{name}_t1.1"]) == pytest.approx(expected[name], rel=1e-10, abs=0), name


def test_the_python_api_gives_the_norms_of_the_study(ball_study):
    _, rows = ball_study
    results = {h: vpcontact.solve(vpcontact.load_case(ROOT / "examples" / "quarter_ball.toml", {
        "mesh.h": h, "time.steps": 3, "output.field_steps": "final", "output.figures": False}))
        for h in (MIDDLE, FINE)}
    norms = differences(results[MIDDLE].snapshot(), results[FINE].snapshot())
    for name in NORMS:
        assert norms[name] == pytest.approx(float(rows["h=0.35"][f"norm_{name}_t1.1"]), rel=1e-9, abs=0), name


def test_a_solution_against_itself_renumbered_differs_by_nothing(ball_study):
    out, _ = ball_study
    reference = snapshot_of(out / "runs" / "reference")
    rng = np.random.default_rng(3)
    nodes, elements = rng.permutation(reference.points.shape[1]), rng.permutation(reference.elements.shape[1])
    renumbered = np.argsort(nodes)[reference.elements[:, elements]]
    renumbered = renumbered[rng.permutation(4)]  # the vertices of every tetrahedron in another order
    shuffled = Snapshot(reference.points[:, nodes], renumbered, reference.displacement[nodes],
                        reference.stress[elements])
    norms = differences(shuffled, reference)
    for name in NORMS:
        assert norms[name] <= 1e-12 * norms[f"{name}_reference"], (name, norms)
    assert norms["V_reference"] > 0 and norms["Q_reference"] > 0 and norms["U_reference"] > 0


# --- fields known in closed form -------------------------------------------------------------------
GRADIENT = np.array([[0.7, -1.3, 0.2], [2.1, 0.4, -0.6], [-0.5, 0.9, 1.1]])
STRESS = np.array([[3.0, -1.5, 0.5], [-1.5, 2.0, 0.25], [0.5, 0.25, -1.0]])


def linear(p):
    """u(x) = (0.25, −0.5, 0.1) + GRADIENT x at points p (3, n), as (n, 3)."""
    return np.array([0.25, -0.5, 0.1]) + (GRADIENT @ p).T


def constant(t):
    return np.broadcast_to(STRESS, (t.shape[1], 3, 3)).copy()


@pytest.mark.parametrize("h_source, h_target", [(COARSE, FINE), (FINE, COARSE)])
def test_a_linear_field_moves_exactly_between_two_quarter_balls(h_source, h_target):
    source, target = quarter_ball(h_source).mesh, quarter_ball(h_target).mesh
    outside = barycentric_in_all(source.p, source.t, target.p.T).min(axis=2).max(axis=1) < -1e-12
    assert outside.sum() > 0 if h_source > h_target else not outside.any()
    norms = differences(Snapshot(source.p, source.t, linear(source.p), constant(source.t)),
                        Snapshot(target.p, target.t, linear(target.p), constant(target.t)))
    for name in NORMS:
        assert norms[name] <= 1e-12 * norms[f"{name}_reference"], (name, norms)
    volume = CellBasis(MeshTet(target.p, target.t), ElementTetP1()).dx.sum()
    sym = 0.5 * (GRADIENT + GRADIENT.T)
    assert norms["V_reference"] == pytest.approx(math.sqrt(volume) * np.linalg.norm(sym), rel=1e-12)
    assert norms["Q_reference"] == pytest.approx(math.sqrt(volume) * np.linalg.norm(STRESS), rel=1e-12)


def test_two_solves_of_a_linear_problem_on_different_meshes_differ_by_nothing():
    """The block on rollers on a layer of constant stiffness (α = 0, g = ∞) under a uniform pressure:
    u is linear and σ constant, represented exactly on any mesh."""
    def solve(h):
        case = block_case(g=math.inf, h=h, stiffness={"law": "power", "c_v": 100.0, "alpha": 0.0, "beta": 1.0})
        case["output"]["field_steps"] = "final"
        return vpcontact.solve(case).snapshot()

    coarse, fine = solve(0.5), solve(0.2)
    assert fine.points.shape[1] > 5 * coarse.points.shape[1]
    norms = differences(coarse, fine)
    for name in NORMS:
        assert norms[f"{name}_reference"] > 0
        assert norms[name] <= 1e-9 * norms[f"{name}_reference"], (name, norms)


def quadratic(p):
    """q(x, y, z) = (x², y z, x z + y²) at points p (3, n), as (n, 3)."""
    x, y, z = p
    return np.stack((x**2, y * z, x * z + y**2), axis=1)


def box_integral(f):
    """∫ f over [0, 1] × [0, 1] × [0, 0.5] for a polynomial f(x, y, z) of degree ≤ 4 per variable:
    Gauss–Legendre with 3 points per direction (exact to degree 5)."""
    nodes, weights = np.polynomial.legendre.leggauss(3)
    x, y, z = np.meshgrid(0.5 + 0.5 * nodes, 0.5 + 0.5 * nodes, 0.25 + 0.25 * nodes, indexing="ij")
    w = np.einsum("i,j,k->ijk", 0.5 * weights, 0.5 * weights, 0.25 * weights)
    return float(np.sum(w * f(x, y, z)))


def test_a_quadratic_field_matches_closed_form_integrals_to_second_order():
    """‖I_h q‖ and ‖ε(I_h q)‖ on block meshes against (∫|q|²)^½ and (∫ε(q):ε(q))^½ over the box (the
    polynomials integrated exactly): the gaps shrink at second order in h in L² and at least at first
    order for the strain (P1 interpolation)."""
    U_exact = math.sqrt(box_integral(lambda x, y, z: x**4 + (y * z) ** 2 + (x * z + y**2) ** 2))
    # ε(q): ε_xx = 2x, ε_yy = z, ε_zz = x, ε_xy = 0, ε_xz = (0 + z)/2, ε_yz = (y + 2y)/2
    V_exact = math.sqrt(box_integral(lambda x, y, z: 4 * x**2 + z**2 + x**2 + 2 * (z / 2) ** 2 + 2 * (1.5 * y) ** 2))
    hs = (0.25, 0.125)
    gaps = {"U": [], "V": []}
    for h in hs:
        mesh = block(1.0, 1.0, 0.5, h).mesh
        field = quadratic(mesh.p)
        gaps["U"].append(abs(displacement_norm(mesh.p, mesh.t, field) - U_exact) / U_exact)
        gaps["V"].append(abs(strain_norm(mesh.p, mesh.t, field) - V_exact) / V_exact)
    print(f"\nrelative gaps to the closed forms for h = {hs}: {gaps}")
    assert gaps["U"][1] < gaps["U"][0] / 3.5 and gaps["U"][0] < 0.05
    assert gaps["V"][1] < gaps["V"][0] / 1.8 and gaps["V"][0] < 0.2


def test_interpolants_of_a_quadratic_field_on_quarter_balls_converge_at_first_and_second_order():
    fine = quarter_ball(0.125).mesh
    reference = Snapshot(fine.p, fine.t, quadratic(fine.p), np.zeros((fine.t.shape[1], 3, 3)))
    hs = (0.5, 0.25)  # 3 and 6 cells per radius; the reference has 12
    errors = {"V": [], "U": []}
    for h in hs:
        mesh = quarter_ball(h).mesh
        norms = differences(Snapshot(mesh.p, mesh.t, quadratic(mesh.p), np.zeros((mesh.t.shape[1], 3, 3))),
                            reference)
        for name in errors:
            errors[name].append(norms[name])
    rates = {name: math.log(e[0] / e[1]) / math.log(hs[0] / hs[1]) for name, e in errors.items()}
    print(f"\n‖I_h q − I_ref q‖ for h = {hs}: {errors}; observed rates {rates}")
    assert 0.8 <= rates["V"] <= 1.6 and 1.6 <= rates["U"] <= 2.6, rates


def test_stress_norm_of_a_centroid_sampled_linear_stress_is_the_midpoint_rule():
    """‖Π σ‖ for σ(x) = STRESS · (1 + x + 2z) sampled at the centroids: the midpoint rule of ∫|σ|²,
    second-order accurate against the closed form."""
    exact = math.sqrt(np.sum(STRESS**2) * box_integral(lambda x, y, z: (1 + x + 2 * z) ** 2))
    gaps = []
    for h in (0.25, 0.125):
        mesh = block(1.0, 1.0, 0.5, h).mesh
        c = mesh.p[:, mesh.t].mean(axis=1)
        sampled = STRESS[None] * (1 + c[0] + 2 * c[2])[:, None, None]
        gaps.append(abs(stress_norm(mesh.p, mesh.t, sampled) - exact) / exact)
    assert 0 < gaps[1] < gaps[0] / 3.5 and gaps[0] < 0.01, gaps


# --- benchmarks/convergence_3d.py ------------------------------------------------------------------
def test_the_3d_convergence_benchmark_reports_errors_that_shrink_with_h(tmp_path):
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "convergence_3d.py"), "--quick",
                           "--out", str(tmp_path / "study")], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout)
    levels = report["levels"]
    assert len(levels) >= 2 and report["reference"]["h"] < levels[-1]["h"]
    assert [level["h"] for level in levels] == sorted((level["h"] for level in levels), reverse=True)
    for name in ("error_strain", "error_L2", "error_stress"):
        errors = [level[name] for level in levels]
        assert all(math.isfinite(e) and e > 0 for e in errors), (name, errors)
        assert all(a > b for a, b in zip(errors, errors[1:])), (name, errors)
    assert all(math.isfinite(r) for r in report["rates"]["error_strain"])


def test_the_l2_norm_of_a_linear_field_is_exact_in_2d_and_3d():
    """‖u‖_{L²} of u = a + B x (represented exactly by P1) against ∫|u|² by Gauss–Legendre on the box."""
    nodes, weights = np.polynomial.legendre.leggauss(3)
    for mesh, sides in ((rectangle(2.0, 1.0, 0.25).mesh, (2.0, 1.0)), (block(1.0, 1.0, 0.5, 0.25).mesh, (1.0, 1.0, 0.5))):
        d = len(sides)
        a, B = np.array([0.25, -0.5, 0.1])[:d], GRADIENT[:d, :d]
        points = np.meshgrid(*[0.5 * L * (1 + nodes) for L in sides], indexing="ij")
        w = np.ones_like(points[0])
        for axis, L in enumerate(sides):
            w = w * (0.5 * L * weights).reshape([-1 if i == axis else 1 for i in range(d)])
        values = a + np.einsum("ij,j...->...i", B, np.stack(points))
        exact = math.sqrt(np.sum(w * (values**2).sum(axis=-1)))
        assert displacement_norm(mesh.p, mesh.t, a + (B @ mesh.p).T) == pytest.approx(exact, rel=1e-13)
