"""Materials that vary in space (ℰ(x) of (2.16), 𝒢(x, σ, ε) of (2.17)): E and ν as expressions in the
coordinates, materials by region, their checks and their outputs, in 2D and 3D.

The exact reference: two materials in series under a uniform traction, ν = 0. The stress is uniaxial
and the same in both (σ_xx = f), the strain f/E_i in material i, so u_x is piecewise linear in x with a
kink at the interface and u_y (u_z) = 0: P1 represents it exactly when the interface is a mesh line.
"""

from pathlib import Path

import meshio
import numpy as np
import pytest

from conftest import assert_refused, run_cli

from vpcontact import build_problem, load_case, solve
from vpcontact.errors import CaseError
from vpcontact.laws.viscoplastic.perzyna import Perzyna
from vpcontact.laws.materials import RegionalViscoplastic
from vpcontact.timeloop.loop import TimeLoop

E1, E2, F, A = 1000.0, 250.0, 10.0, 0.5  # moduli left and right of x = A, traction on the right


def bar_case(dim: int, material) -> dict:
    """The bar [0, 1] × [0, 0.5] (× [0, 0.5]) on rollers at x = 0 and on the lateral faces y = 0 (and z = 0),
    pulled by F·t along x on its right face."""
    if dim == 2:
        mesh = {"shape": "rectangle", "width": 1.0, "height": 0.5, "h": 0.125}
        dirichlet = [{"part": "left", "components": ["x"]}, {"part": "bottom", "components": ["y"]}]
    else:
        mesh = {"shape": "block", "width": 1.0, "depth": 0.5, "height": 0.5, "h": 0.25}
        dirichlet = [{"part": "left", "components": ["x"]}, {"part": "front", "components": ["y"]},
                     {"part": "bottom", "components": ["z"]}]
    traction = [f"{F}*t"] + ["0"] * (dim - 1)
    return {"mesh": mesh, "material": material,
            "boundary": {"dirichlet": dirichlet, "traction": [{"part": "right", "value": traction}]},
            "time": {"T": 1.0, "steps": 2}, "output": {"field_steps": "all", "progress": False}}


def exact_displacement(x: np.ndarray, t: float) -> np.ndarray:
    """u_x of two materials in series: σ_xx = F t in both, ε_xx = σ_xx / E_i."""
    stress = F * t
    return np.where(x <= A, stress * x / E1, stress * A / E1 + stress * (x - A) / E2)


SERIES_MODULUS = f"{E1} + ({E2} - {E1})*heaviside(x - {A})"  # E1 left of x = A, E2 right (centroids never on it)


@pytest.mark.parametrize("dim", [2, 3])
def test_two_materials_in_series_are_exact(dim):
    """E as an expression with a jump at the mesh line x = A: the P1 solution is the exact piecewise-linear
    displacement, the stress uniaxial and equal in both materials."""
    problem = build_problem(load_case(bar_case(dim, {"E": SERIES_MODULUS, "nu": 0.0})))
    result = solve(problem)
    assert result.status == "complete"
    p = problem.mesh.mesh.p
    for step, fields in result.fields.items():
        t = problem.times[step - 1]
        expected = exact_displacement(p[0], t)
        scale = np.abs(expected).max()
        assert np.abs(fields.displacement[:, 0] - expected).max() < 1e-12 * scale
        assert np.abs(fields.displacement[:, 1:]).max() < 1e-12 * scale
        assert np.allclose(fields.stress[:, 0, 0], F * t, rtol=1e-12, atol=0)
        assert np.abs(fields.stress[:, 1:, 1:]).max() < 1e-11 * F * t
    E = problem.materials.E
    centroids = p[:, problem.mesh.mesh.t].mean(axis=1)
    assert np.array_equal(E, np.where(centroids[0] < A, E1, E2))


@pytest.mark.parametrize("dim", [2, 3])
def test_a_constant_expression_is_the_number(dim):
    """E and ν written as expressions of constant value give bitwise the run of the numbers (the
    per-element assembly equals the homogeneous one)."""
    number = solve(build_problem(load_case(bar_case(dim, {"E": 700.0, "nu": 0.3}))))
    expression = solve(build_problem(load_case(bar_case(dim, {"E": "700 + 0*x", "nu": "0.3"}))))
    for step in number.fields:
        assert np.array_equal(number.fields[step].displacement, expression.fields[step].displacement)
        assert np.array_equal(number.fields[step].stress, expression.fields[step].stress)


def test_regional_viscoplastic_law_acts_on_its_elements_only():
    """𝒢 of materials by region: each law on its elements, 0 on the elements of a material without one."""
    rng = np.random.default_rng(1)
    sigma, strain = rng.normal(size=(2, 2, 2, 10)) * 5.0
    law = Perzyna(0.5, 1.0)
    mine = np.array([0, 3, 4, 9])
    rate = RegionalViscoplastic(((mine, law),))(sigma, strain)
    assert np.array_equal(rate[..., mine], law(sigma[..., mine], strain[..., mine]))
    assert not np.any(np.delete(rate, mine, axis=-1))


def test_outputs_carry_the_material_of_each_element(tmp_path):
    """The body VTU has each element's material index, E and ν: E the expression at the centroid."""
    from vpcontact.cli import main

    case = bar_case(2, {"E": "500 + 100*x*y", "nu": 0.25})
    case["output"]["field_steps"] = "final"
    import tomli_w

    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    assert main(["run", str(tmp_path / "case.toml"), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    body = meshio.read(tmp_path / "run" / "fields" / "body_00002.vtu")
    centroids = body.points[body.cells[0].data].mean(axis=1)
    assert np.allclose(body.cell_data["E"][0], 500 + 100 * centroids[:, 0] * centroids[:, 1], rtol=1e-14)
    assert np.all(body.cell_data["nu"][0] == 0.25) and np.all(body.cell_data["material"][0] == 0)


@pytest.mark.parametrize("material, words", [
    ({"E": "1000*(x - 0.5)", "nu": 0.3}, ["material.E = \"1000*(x - 0.5)\"", "at the element centroid", "> 0"]),
    ({"E": 1000.0, "nu": "0.3 + x"}, ["material.nu = \"0.3 + x\"", "at the element centroid", "< 0.5"]),
    ({"E": "1000/(x - x)", "nu": 0.3}, ["material.E", "is inf at the element centroid"]),
    ({"E": "1000*t", "nu": 0.3}, ["material.E = \"1000*t\"", "unknown name 't'"]),
    ({"E": "1000*z", "nu": 0.3}, ["material.E = \"1000*z\"", "uses z and the mesh is 2D"]),
    ([{"E": 1000.0, "nu": 0.3, "region": "core"}], ["material[0].region = 'core'", "the mesh has no regions"]),
    ([{"E": 1000.0, "nu": 0.3}, {"E": 10.0, "nu": 0.3, "region": "a"}], ["material[0] has no region"]),
    ([{"E": 1000.0, "nu": 0.3, "region": "a", "hypothesis": "plane_stress"}, {"E": 10.0, "nu": 0.3, "region": "b"}],
     ["different hypotheses"]),
])
def test_bad_materials_are_refused_naming_them(material, words):
    with pytest.raises(CaseError) as refused:
        build_problem(load_case(bar_case(2, material)))
    for word in words:
        assert word in str(refused.value), (word, str(refused.value))


def test_a_plane_hypothesis_in_a_3d_list_is_refused():
    case = bar_case(3, [{"E": 1000.0, "nu": 0.3, "hypothesis": "plane_strain"}])
    with pytest.raises(CaseError, match=r"material\[0\]\.hypothesis = \"plane_strain\" is a 2D reduction"):
        build_problem(load_case(case))


def test_the_time_loop_uses_the_stress_of_each_element():
    """σ = ℰ(x)ε(u) + z element by element: the stress of the series bar is the traction in both
    materials although the strains differ by E1/E2."""
    problem = build_problem(load_case(bar_case(2, {"E": SERIES_MODULUS, "nu": 0.0})))
    result = TimeLoop(problem).run()
    strain_xx = result.fields[2].stress[:, 0, 0] / problem.materials.E
    assert np.isclose(strain_xx.max() / strain_xx.min(), E1 / E2, rtol=1e-12)


# --- materials by region -------------------------------------------------------------------------
MESHES = Path(__file__).parent / "meshes"


def regions_case(dim: int, materials) -> dict:
    """The gmsh meshes of two regions side by side, 'core' (x < 1) and 'shell' (x > 1), each element also in
    'body': 2D [0, 2] × [0, 1] pulled by F·t along x on its right side, on rollers at x = 0 and y = 0;
    3D [0, 2] × [0, 1]², clamped on its bottom, under a body force."""
    if dim == 2:
        boundary = {"dirichlet": [{"part": "left", "components": ["x"]}, {"part": "bottom", "components": ["y"]}],
                    "traction": [{"part": "right", "value": [f"{F}*t", "0"]}]}
    else:
        boundary = {"dirichlet": [{"part": "bottom"}], "body_force": [{"value": ["10*t", "0", "-20*t*x"]}]}
    return {"mesh": {"file": str(MESHES / ("3d" if dim == 3 else "") / "regions.msh")}, "material": materials,
            "boundary": boundary, "time": {"T": 1.0, "steps": 2}, "output": {"field_steps": "all"}}


def test_two_regions_in_series_are_exact():
    """The same bar as above, stated as two regions of a gmsh file (its interface x = 1 a mesh line of an
    unstructured mesh): the P1 solution is the exact piecewise-linear displacement."""
    materials = [{"region": "core", "E": E1, "nu": 0.0}, {"region": "shell", "E": E2, "nu": 0.0}]
    problem = build_problem(load_case(regions_case(2, materials)))
    result = solve(problem)
    x = problem.mesh.mesh.p[0]
    for step, fields in result.fields.items():
        stress = F * problem.times[step - 1]
        expected = np.where(x <= 1.0, stress * x / E1, stress / E1 + stress * (x - 1.0) / E2)
        assert np.abs(fields.displacement[:, 0] - expected).max() < 1e-12 * expected.max()
        assert np.abs(fields.displacement[:, 1]).max() < 1e-12 * expected.max()
    assert set(np.unique(problem.materials.E[problem.mesh.regions["core"]])) == {E1}
    assert set(np.unique(problem.materials.E[problem.mesh.regions["shell"]])) == {E2}


@pytest.mark.parametrize("dim", [2, 3])
def test_one_material_in_every_region_is_the_single_material(dim):
    """Two entries with the same data on 'core' and 'shell' (a viscoplastic law in both) give the run of one
    [material] table, to rounding; naming a region by its number is naming it by its name."""
    law = {"law": "perzyna", "eta": 0.5, "yield_stress": 1.0}
    single = solve(build_problem(load_case(regions_case(dim, {"E": 800.0, "nu": 0.3, "viscoplastic": law}))))
    tags = {2: "6", 3: "4"}
    regional = solve(build_problem(load_case(regions_case(dim, [
        {"region": "core", "E": 800.0, "nu": 0.3, "viscoplastic": law},
        {"region": int(tags[dim]), "E": 800.0, "nu": 0.3, "viscoplastic": law}]))))
    for step in single.fields:
        scale = np.abs(single.fields[step].stress).max()
        assert np.abs(regional.fields[step].stress - single.fields[step].stress).max() < 1e-12 * scale
        assert np.abs(regional.fields[step].z - single.fields[step].z).max() < 1e-12 * scale
    assert np.abs(single.fields[2].z).max() > 1e-2 * np.abs(single.fields[2].stress).max()  # the law acts


@pytest.mark.parametrize("dim", [2, 3])
def test_a_region_without_a_law_stays_elastic(dim):
    """Perzyna in the core only: the history z stays exactly 0 in the shell (𝒢 = 0 there, σ_0 = 0), not in
    the core."""
    law = {"law": "perzyna", "eta": 0.5, "yield_stress": 0.0}
    problem = build_problem(load_case(regions_case(dim, [{"region": "core", "E": 800.0, "nu": 0.3, "viscoplastic": law},
                                                         {"region": "shell", "E": 300.0, "nu": 0.2}])))
    result = solve(problem)
    z = result.fields[2].z
    assert not np.any(z[problem.mesh.regions["shell"]])
    assert np.all(np.abs(z[problem.mesh.regions["core"]]).max(axis=(1, 2)) > 0)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("materials, words", [
    ([{"region": "core", "E": 1.0, "nu": 0.3}], ["elements have no material (in the mesh's regions 'shell', 'body'; one is at"]),
    ([{"region": "core", "E": 1.0, "nu": 0.3}, {"region": "body", "E": 2.0, "nu": 0.3}],
     ["material[1].region 'body' overlaps material[0].region (core)", "two materials"]),
    ([{"region": ["core", "shell"], "E": 1.0, "nu": 0.3}, {"region": "skin", "E": 2.0, "nu": 0.3}],
     ["material[1].region = 'skin': unknown region", "core", "shell"]),
])
def test_gaps_overlaps_and_unknown_regions_are_refused(dim, materials, words):
    with pytest.raises(CaseError) as refused:
        build_problem(load_case(regions_case(dim, materials)))
    for word in words:
        assert word in str(refused.value), (word, str(refused.value))


def test_a_mesh_region_in_no_material_is_named_through_the_cli(tmp_path):
    """The exit-code contract: exit 2, one line naming the region left without a material, nothing written."""
    import tomli_w

    case = regions_case(2, [{"region": "core", "E": 1.0, "nu": 0.3}, {"region": "5", "E": 2.0, "nu": 0.3}])
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    status, _, stderr = run_cli("run", tmp_path / "case.toml", "--out", tmp_path / "run", "--quiet")
    assert_refused(status, stderr, "material[1].region '5' overlaps material[0].region (core)")
    assert not (tmp_path / "run").exists()


def test_a_python_viscoplastic_law_of_the_centroids_is_the_regional_law():
    """𝒢(σ, ε, x) of the API (x the element centroids): Perzyna where x < 1, 0 elsewhere, equals the case's
    Perzyna on the region 'core' (x < 1) and an elastic 'shell', to rounding."""
    perzyna = Perzyna(0.5, 0.0)

    def G(sigma, strain, x):
        return np.where(x[0] < 1.0, perzyna(sigma, strain), 0.0)

    materials = [{"region": "core", "E": 800.0, "nu": 0.3}, {"region": "shell", "E": 300.0, "nu": 0.2}]
    by_python = solve(build_problem(load_case(regions_case(2, materials)), viscoplastic=G))
    materials[0]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 0.0}
    by_case = solve(build_problem(load_case(regions_case(2, materials))))
    scale = np.abs(by_case.fields[2].stress).max()
    assert np.abs(by_python.fields[2].stress - by_case.fields[2].stress).max() < 1e-12 * scale
    assert np.abs(by_case.fields[2].z).max() > 1e-2 * scale


def test_a_python_viscoplastic_law_of_four_arguments_is_refused():
    with pytest.raises(CaseError, match=r"viscoplastic takes 4 arguments \(a, b, c, d\)"):
        build_problem(load_case(regions_case(2, {"E": 1.0, "nu": 0.3})), viscoplastic=lambda a, b, c, d: a)
