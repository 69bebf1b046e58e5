"""Python callables for the laws and loads, the initial gap, and mesh files, each checked against
the equivalent built-in setting."""

import os
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest
import tomli_w

import vpcontact
from vpcontact.laws.contact import CallableLaw
from vpcontact.mesh import rectangle
from conftest import half_disc_case, rectangle_case, run_cli, solved


def test_python_callables_give_the_built_in_laws():
    reference = vpcontact.solve(half_disc_case(h=0.2, load=40.0))
    case = half_disc_case(h=0.2, load=40.0)
    case["boundary"]["traction"] = []
    result = vpcontact.solve(
        case,
        p=CallableLaw(lambda r: np.maximum(r, 0.0), lambda r: (r >= 0).astype(float)),
        stiffness_law=CallableLaw(lambda xi: 100.0 * (1.0 + 20.0 * xi), lambda xi: 2000.0 + 0.0 * xi),
        tractions={"top_arc": lambda x, y, t: (0.0 * x, -40.0 * t + 0.0 * x)},
    )
    np.testing.assert_allclose(result.final.displacement, reference.final.displacement, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(result.contact_history("K"), reference.contact_history("K"), rtol=1e-12)


def test_a_law_without_derivative_converges_to_the_same_solution():
    reference = vpcontact.solve(half_disc_case(h=0.2, load=40.0))
    result = vpcontact.solve(half_disc_case(h=0.2, load=40.0),
                             stiffness_law=CallableLaw(lambda xi: 100.0 * (1.0 + 20.0 * xi)))
    np.testing.assert_allclose(result.contact_history("penetration"), reference.contact_history("penetration"),
                               rtol=0, atol=1e-10)


def test_an_initial_gap_delays_contact_by_a_rigid_translation():
    """A uniform gap g0 on the block: the same penetrations and pressures, the body moved by −g0."""
    reference = vpcontact.solve(rectangle_case())
    result = vpcontact.solve(rectangle_case(gap="0.01"))
    np.testing.assert_allclose(result.contact_history("penetration"), reference.contact_history("penetration"),
                               atol=1e-12)
    shift = result.final.displacement - reference.final.displacement
    np.testing.assert_allclose(shift, np.tile([0.0, -0.01], (shift.shape[0], 1)), atol=1e-12)


def test_a_body_force_is_carried_by_the_foundation():
    """Gravity ρ_m g on the block instead of the traction: the foundation carries the weight."""
    case = rectangle_case(g=float("inf"))
    case["boundary"]["traction"] = []
    case["boundary"]["body_force"] = [{"value": ["0", "-50*t"]}]
    result = vpcontact.solve(case)
    np.testing.assert_allclose(result.series("contact_force_y"), 50.0 * result.series("t") * 0.5, rtol=1e-10)


def write_block_mesh(path):
    """The built-in block (rectangle 1 × 0.5, h = 0.125) as a gmsh 2.2 file, parts by name and number."""
    built_in = rectangle(1.0, 0.5, 0.125)
    skmesh = built_in.mesh
    tags = {"left": 1, "right": 2, "bottom": 3, "top": 4}
    lines = np.hstack([skmesh.facets[:, built_in.facets(name)] for name in tags]).T
    physical = np.concatenate([np.full(built_in.facets(name).size, tag) for name, tag in tags.items()])
    mesh = meshio.Mesh(skmesh.p.T, [("triangle", skmesh.t.T), ("line", lines)],
                       cell_data={"gmsh:physical": [np.zeros(skmesh.t.shape[1], int), physical],
                                  "gmsh:geometrical": [np.zeros(skmesh.t.shape[1], int), physical]},
                       field_data={name: np.array([tag, 1]) for name, tag in tags.items()})
    meshio.write(path, mesh, file_format="gmsh22", binary=False)


def test_a_gmsh_file_gives_the_built_in_mesh_solution(tmp_path):
    write_block_mesh(tmp_path / "block.msh")
    case = rectangle_case()
    case["mesh"] = {"file": "block.msh"}
    case["contact"]["part"] = 3  # by physical number
    (tmp_path / "case.toml").write_text(tomli_w.dumps(case))
    from_file = vpcontact.solve(tmp_path / "case.toml")
    reference = vpcontact.solve(rectangle_case())
    np.testing.assert_allclose(from_file.contact_history("penetration"), reference.contact_history("penetration"),
                               atol=1e-12)
    np.testing.assert_allclose(from_file.series("contact_force_y"), reference.series("contact_force_y"), rtol=1e-12)


# --- the Python API does what the README says -------------------------------------------------------------
def uniform_push(load: float):
    """f(x, y, t) = (0, −load·t) as a Python function."""
    return lambda x, y, t: (0.0 * x, -load * t + 0.0 * x)


def test_a_traction_of_the_api_replaces_the_case_traction_on_its_part():
    """The block's case pushes its top with 100 t; tractions={"top": 50 t} replaces it: the foundation carries
    50 t (width 1), as with a case of 50 t, not 150 t as if they were added."""
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = "-50*t"
    reference = vpcontact.solve(case)
    result = vpcontact.solve(rectangle_case(), tractions={"top": uniform_push(50.0)})
    np.testing.assert_allclose(result.series("contact_force_y"), 50.0 * result.series("t"), rtol=1e-10)
    np.testing.assert_allclose(result.contact_history("penetration"), reference.contact_history("penetration"),
                               rtol=0, atol=1e-14)


def test_a_traction_of_the_api_on_another_part_leaves_the_case_traction():
    result = vpcontact.solve(rectangle_case(), tractions={"left": uniform_push(0.0)})
    np.testing.assert_allclose(result.series("contact_force_y"), 100.0 * result.series("t"), rtol=1e-10)


def test_a_body_force_of_the_api_replaces_the_case_body_forces():
    """The case's 50 t per unit area (area 0.5) replaced by 20 t: the foundation carries 10 t, not 35 t."""
    case = rectangle_case(g=float("inf"))
    case["boundary"]["traction"] = []
    case["boundary"]["body_force"] = [{"value": ["0", "-50*t"]}]
    result = vpcontact.solve(case, body_force=uniform_push(20.0))
    np.testing.assert_allclose(result.series("contact_force_y"), 10.0 * result.series("t"), rtol=1e-10)


def test_plain_functions_are_laws():
    """p and K as plain functions (no derivative): wrapped in CallableLaw, the same solution as the built-in
    laws to the accuracy of its central difference."""
    reference = vpcontact.solve(half_disc_case(h=0.2, load=40.0))
    problem, result = solved(half_disc_case(h=0.2, load=40.0), p=lambda r: np.maximum(r, 0.0),
                             stiffness_law=lambda xi: 100.0 * (1.0 + 20.0 * xi))
    assert isinstance(problem.law.stiffness, CallableLaw) and isinstance(problem.law.p, CallableLaw)
    np.testing.assert_allclose(result.contact_history("K"), reference.contact_history("K"), rtol=1e-9)


def test_a_law_with_a_derivative_is_used_as_it_is():
    class Linear:
        def __call__(self, xi):
            return 100.0 * (1.0 + 20.0 * xi)

        def derivative(self, xi):
            return np.full_like(xi, 2000.0)

    law = Linear()
    problem, result = solved(half_disc_case(h=0.2, load=40.0), stiffness_law=law)
    assert problem.law.stiffness is law and result.status == "complete"


@pytest.mark.parametrize("arguments, words", [
    ({"stiffness_law": 3}, ["stiffness_law = 3: expected a function"]),
    ({"p": "positive_part"}, ["p = 'positive_part': expected a function"]),
    ({"stiffness_law": lambda xi: np.zeros((2, 2))}, ["stiffness_law: stiffness_law(0.0, 0.001) returned an array of "
                                                      "shape (2, 2) for arguments of shape (2,)"]),
    ({"stiffness_law": lambda xi: "soft"}, ["stiffness_law", "returned a value of type str, not numbers"]),
    ({"stiffness_law": lambda xi: np.nan * xi}, ["stiffness_law", "is not finite (nan)"]),
    ({"p": lambda r: r / r}, ["p: p(0.0, 0.001) is not finite (nan)"]),
    ({"tractions": {"nope": uniform_push(1.0)}}, ["tractions: unknown part 'nope'", "bottom, left, right, top"]),
    ({"tractions": {("top",): uniform_push(1.0)}}, ["tractions: unknown part ('top',)"]),
    ({"tractions": [("top", uniform_push(1.0))]}, ["tractions = [('top', <function", "expected a dict"]),
    ({"tractions": {"top": 5.0}}, ["tractions['top'] = float: expected a function f(x, y, t) -> (fx, fy)"]),
    ({"tractions": {"top": lambda x, y, t: (x, y, t)}}, ["tractions['top']: f(x, y, t) must return (fx, fy)",
                                                        "a tuple of 3 values"]),
    ({"tractions": {"top": lambda x, y, t: (np.zeros(5), 0.0)}}, ["tractions['top']: f(x, y, t) must return",
                                                                   "of shapes [(5,), ()]"]),
    ({"body_force": "0"}, ["body_force = str: expected a function"]),
    ({"viscoplastic": 1}, ["viscoplastic = 1: expected a function G(sigma, strain)"]),
    ({"viscoplastic": lambda sigma, strain: np.nan * sigma},
     ["viscoplastic: G(initial.stress, 0) is not finite (nan)"]),
])
def test_bad_arguments_of_the_api_are_one_line_case_errors(arguments, words):
    with pytest.raises(vpcontact.CaseError) as error:
        vpcontact.solve(rectangle_case(), **arguments)
    message = str(error.value)
    assert "\n" not in message and len(message) < 300, message
    for word in words:
        assert word in message, (word, message)


def test_laws_for_a_case_without_contact_are_refused():
    case = rectangle_case()
    del case["contact"]
    case["boundary"]["dirichlet"].append({"part": "bottom"})
    with pytest.raises(vpcontact.CaseError, match=r"the case has no \[contact\]"):
        vpcontact.solve(case, stiffness_law=lambda xi: xi)


def test_the_documented_submodules_come_with_import_vpcontact():
    """After ``import vpcontact`` alone: ``vpcontact.results.norms.differences`` and the others, loaded on first use
    (``import vpcontact`` does not load norms, so the command line starts as fast as before)."""
    code = ("import sys, vpcontact; assert 'vpcontact.results.norms' not in sys.modules; "
            "print(vpcontact.results.norms.differences.__name__, vpcontact.laws.contact.CallableLaw.__name__, "
            "vpcontact.drivers.studies.run_study.__name__, vpcontact.io.run.write_run.__name__); vpcontact.nothing")
    process = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert process.stdout.split() == ["differences", "CallableLaw", "run_study", "write_run"], process.stderr
    assert "AttributeError: module 'vpcontact' has no attribute 'nothing'" in process.stderr


def test_a_result_is_shown_in_one_short_line():
    problem, result = solved(rectangle_case())
    text = repr(result)
    assert len(text) < 300 and "\n" not in text, text
    assert text == (f"Result(complete, 2D, 90 dofs, 9 contact nodes, 11/11 steps, method {result.method}, "
                    f"{result.wall_time_s:.3g} s)")
    assert repr(problem) == ("Problem(dofs=90, free_dofs=80, elements=64, nodes=45, contact_nodes=9, steps=11, "
                                    "k=0.1)")
    assert repr(result.final) == "Fields(displacement(45, 2), stress(64, 2, 2), stress33(64,), von_mises(64,))"


@pytest.mark.parametrize("call, words", [
    (lambda r: r.series("K"), ["unknown history column 'K'", "contact_history('K') has it", "K_probe"]),
    (lambda r: r.series("force"), ["unknown history column 'force'", "valid names: step, t,", "contact_force_y"]),
    (lambda r: r.contact_history("pressure"), ["unknown contact array 'pressure'", "did you mean 'pressure_rigid'"]),
    (lambda r: r.contact_history("K_probe"), ["series('K_probe') has it"]),
    (lambda r: r.snapshot(3), ["no fields kept at step 3", "steps kept: none (output.field_steps)"]),
])
def test_an_unknown_name_is_a_key_error_naming_the_valid_ones(call, words):
    result = vpcontact.solve(rectangle_case())
    with pytest.raises(KeyError) as error:
        call(result)
    assert isinstance(error.value, vpcontact.CaseError)
    for word in words:
        assert word in str(error.value), (word, str(error.value))


def test_times_are_an_array():
    result = vpcontact.solve(rectangle_case())
    assert isinstance(result.times, np.ndarray) and result.times.dtype == np.float64
    np.testing.assert_array_equal(result.times, result.series("t"))
    np.testing.assert_array_equal(result.times, result.discretization.times)


def test_a_result_writes_its_files(tmp_path):
    result = vpcontact.solve(rectangle_case())
    assert vpcontact.write_run(result, tmp_path / "run") == tmp_path / "run"
    assert {p.name for p in (tmp_path / "run").iterdir()} >= {"summary.json", "history.csv", "contact.csv",
                                                              "case.resolved.toml"}
    rows = (tmp_path / "run" / "history.csv").read_text().splitlines()
    assert len(rows) == 12 and rows[0].startswith("step,t,")
    with pytest.raises(FileExistsError):
        vpcontact.write_run(result, tmp_path / "run")
    vpcontact.write_run(result, tmp_path / "run", overwrite=True)
    assert (tmp_path / "run" / "summary.json").is_file()


def test_the_resolved_case_of_a_run_on_a_mesh_file_runs_again_from_its_run_directory(tmp_path):
    """The mesh path is written absolute: `vpcontact run DIR/case.resolved.toml` from another folder
    finds the mesh and gives the same numbers."""
    source = tmp_path / "project"
    source.mkdir()
    write_block_mesh(source / "block.msh")
    case = rectangle_case()
    case["mesh"] = {"file": "block.msh"}
    (source / "case.toml").write_text(tomli_w.dumps(case))
    same_package = {"PYTHONPATH": os.pathsep.join([str(Path(vpcontact.__file__).parents[1]),
                                                   os.environ.get("PYTHONPATH", "")])}  # from any cwd
    status, _, stderr = run_cli("run", "project/case.toml", "--out", "runs/first", "--quiet", cwd=tmp_path,
                                env=same_package)
    assert status == 0, stderr
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    status, _, stderr = run_cli("run", tmp_path / "runs/first/case.resolved.toml", "--out", "again", "--quiet",
                                cwd=elsewhere, env=same_package)
    assert status == 0, stderr
    first = (tmp_path / "runs/first/history.csv").read_text()
    assert first == (elsewhere / "again/history.csv").read_text()
    assert (tmp_path / "runs/first/contact.csv").read_text() == (elsewhere / "again/contact.csv").read_text()
