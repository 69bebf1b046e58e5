"""A problem composed in Python (vpcontact.compose) is the problem of the same case file; the problem
keeps its options and Python objects (Problem.on rebuilds it on a refined mesh); the case is translated once,
and nothing below it (the problem, the time loop, the solvers, the results, the files, the estimators) imports
it."""

import ast
import pathlib

import numpy as np
import pytest

import vpcontact
from vpcontact import mesh as meshes
from vpcontact.case.translate import output_options
from vpcontact.estimate.indicators import Level
from vpcontact.mesh.refinement import refine

from conftest import half_disc_case

REPO = pathlib.Path(__file__).resolve().parents[1]
SOURCE = REPO / "src" / "vpcontact"
#: The modules after the problem in the flow case -> problem -> time loop -> result -> writers.
DOWNSTREAM = ("timeloop/loop", "results/result", "io/run", "io/outputs", "io/checkpoint", "adaptivity/cycles",
              "estimate/indicators", "estimate/residual", "estimate/recovery", "results/plots/contact",
              "results/plots/body", "results/plots/history", "results/norms")
#: The packages below the case: they take plain options (vpcontact.case.translate), never the case itself.
BELOW_THE_CASE = ("problem", "timeloop", "solvers", "results", "io", "estimate", "adaptivity")


def composed(h=0.1, **changes):
    """The half disc of conftest.half_disc_case, composed in Python (``changes`` replace arguments)."""
    arguments = dict(
        material={"E": 1000.0, "nu": 0.3},
        dirichlet={"axis": "x"},
        traction={"top_arc": ["0", "-20.0*t"]},
        contact={"part": "bottom_arc", "g": 0.2, "probe": [0.0, 0.0],
                 "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
        time={"T": 1.1, "steps": 11},
        solver={"tolerance": 1e-12},
    )
    arguments.update(changes)
    return vpcontact.compose(meshes.half_disc(h), **arguments)


@pytest.fixture(scope="module")
def from_file():
    return vpcontact.solve(vpcontact.load_case(half_disc_case()))


def test_a_composed_problem_is_the_problem_of_the_case(from_file):
    """The same tables through compose and through a case: the same operators and the same run, bit for bit."""
    problem = composed()
    case_problem = vpcontact.build_problem(vpcontact.load_case(half_disc_case()))
    assert (problem.A != case_problem.A).nnz == 0
    np.testing.assert_array_equal(problem.free, case_problem.free)
    result = vpcontact.solve(problem)
    assert result.status == "complete"
    np.testing.assert_array_equal(result.final.displacement, from_file.final.displacement)
    np.testing.assert_array_equal(result.series("K_probe"), from_file.series("K_probe"))
    assert problem.source is None and case_problem.source is not None  # no case file: no case.resolved.toml


def test_python_objects_replace_the_tables(from_file):
    """A traction f(x, y, t), a stiffness law K(ξ) with its derivative and a mesh file's name give the run of
    the tables (the load integrated by the same quadrature; the law is the power law (2.18) itself)."""
    class Power:
        def __call__(self, xi):
            return 100.0 * (1.0 + 20.0 * xi)

        def derivative(self, xi):
            return np.full_like(xi, 2000.0)

    contact = {"part": "bottom_arc", "g": 0.2, "probe": [0.0, 0.0], "stiffness": Power()}
    result = vpcontact.solve(composed(traction={"top_arc": lambda x, y, t: (0 * x, -20.0 * t + 0 * y)}, contact=contact))
    assert result.status == "complete"
    scale = np.abs(from_file.final.displacement).max()
    np.testing.assert_allclose(result.final.displacement, from_file.final.displacement, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(result.series("K_probe"), from_file.series("K_probe"), rtol=1e-9)


def test_a_3d_problem_from_a_mesh_table():
    """The block pressed on its bottom, composed with a [mesh] table: the uniform state, in which every contact
    node carries the applied pressure c t (K p(d) = c t, d = c t / K for K constant)."""
    c, K, T = 50.0, 1000.0, 1.0
    problem = vpcontact.compose(
        {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": 0.25},
        material={"E": 1000.0, "nu": 0.0},
        dirichlet={"left": "x", "right": "x", "front": "y", "back": "y"},
        traction={"top": ["0", "0", f"-{c}*t"]},
        contact={"part": "bottom", "g": 1.0, "stiffness": {"law": "constant", "value": K}},
        time={"T": T, "steps": 2},
    )
    assert problem.mesh.dim == 3
    result = vpcontact.solve(problem)
    d = result.contact_row()["penetration"]
    np.testing.assert_allclose(d, c * T / K, rtol=1e-8)


def test_a_problem_is_built_again_on_a_refined_mesh():
    """Problem.on(mesh) is the problem composed on that mesh directly, with its Python objects."""
    law = lambda xi: 100.0 * (1.0 + 20.0 * xi)  # noqa: E731
    contact = {"part": "bottom_arc", "g": 0.2, "probe": [0.0, 0.0], "stiffness": law}
    coarse = composed(h=0.2, contact=contact)
    marked = np.arange(0, coarse.mesh.mesh.t.shape[1], 3)
    fine_mesh = refine(coarse.mesh, marked)
    rebuilt = coarse.on(fine_mesh)
    direct = vpcontact.compose(fine_mesh, **{name: value for name, value in dict(
        material={"E": 1000.0, "nu": 0.3}, dirichlet={"axis": "x"}, traction={"top_arc": ["0", "-20.0*t"]},
        contact=contact, time={"T": 1.1, "steps": 11}, solver={"tolerance": 1e-12}).items()})
    assert rebuilt.basis.N > coarse.basis.N
    assert (rebuilt.A != direct.A).nnz == 0
    np.testing.assert_array_equal(vpcontact.solve(rebuilt).final.displacement, vpcontact.solve(direct).final.displacement)


def test_initial_arrays_belong_to_their_mesh():
    """ξ_0 given as an array of the contact nodes: used, and refused on another mesh."""
    probe = composed(h=0.2)
    problem = composed(h=0.2, initial={"xi": np.full(probe.surface.size, 0.01)})
    np.testing.assert_array_equal(problem.initial.xi, 0.01)
    with pytest.raises(vpcontact.CaseError, match="initial_xi is an array on the mesh"):
        problem.on(refine(problem.mesh, np.arange(4)))


@pytest.mark.parametrize("changes, words", [
    ({"material": {"E": 1000.0}}, "material.nu"),
    ({"material": {"E": -1.0, "nu": 0.3}}, "material.E"),
    ({"dirichlet": {"nowhere": "x"}}, "unknown part 'nowhere'"),
    ({"dirichlet": 3}, "dirichlet = 3"),
    ({"traction": ["0", "-t"]}, "traction = "),
    ({"traction": {"top_arc": ["0", "-t*"]}}, "boundary.traction[0].value[1]"),
    ({"contact": {"part": "bottom_arc", "g": 0.2}}, "contact.stiffness"),
    ({"contact": "bottom_arc"}, "expected a table"),
    ({"time": {"T": 1.0}}, "time.steps"),
    ({"solver": {"method": "magic"}}, "solver.method"),
])
def test_bad_arguments_are_one_line_errors_naming_them(changes, words):
    with pytest.raises(vpcontact.CaseError) as error:
        composed(h=0.2, **changes)
    message = str(error.value)
    assert words in message and "\n" not in message


def test_a_mesh_that_is_not_a_mesh_is_refused():
    with pytest.raises(vpcontact.CaseError, match="expected a vpcontact.mesh.Mesh"):
        vpcontact.compose(42, material={"E": 1.0, "nu": 0.3}, time={"T": 1.0, "steps": 1})
    with pytest.raises(vpcontact.CaseError, match="mesh.h"):
        vpcontact.compose({"shape": "half_disc"}, material={"E": 1.0, "nu": 0.3}, time={"T": 1.0, "steps": 1})
    model = vpcontact.load_case(half_disc_case()).model
    with pytest.raises(vpcontact.CaseError, match="needs a mesh"):
        vpcontact.build_problem(model)


def test_nothing_downstream_of_the_problem_reads_a_case():
    """DESIGN §8: the modules after the problem take what they need as arguments (outputs, adapt settings)
    and read neither ``.case`` of an object nor the case module's Case."""
    for name in DOWNSTREAM:
        tree = ast.parse((SOURCE / f"{name}.py").read_text(encoding="utf-8"))
        reads = [node.lineno for node in ast.walk(tree) if isinstance(node, ast.Attribute) and node.attr == "case"]
        imports = [node.lineno for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                   and node.module == "case" and any(alias.name in ("Case", "load_case") for alias in node.names)]
        assert not reads and not imports, (name, reads, imports)
    assert not hasattr(composed(h=0.2), "case")


def imported_modules(path: pathlib.Path) -> set[str]:
    """The absolute names of the modules the source file ``path`` of vpcontact imports, at any depth of its code
    (``from ..case.model import Case`` in problem/build.py: vpcontact.case.model and vpcontact.case.model.Case;
    ``from .. import case``: vpcontact and vpcontact.case)."""
    package = ".".join(("vpcontact", *path.relative_to(SOURCE).parent.parts))
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1])
                base = f"{parent}.{base}" if base else parent
            names |= {base, *(f"{base}.{alias.name}" for alias in node.names)}
    return names


@pytest.mark.parametrize("package", BELOW_THE_CASE)
def test_no_module_below_the_case_imports_it(package):
    """Every module of the packages below the case imports nothing of vpcontact.case: the case is translated once
    into options (vpcontact.case.translate), by the command line, the API and compose."""
    assert "vpcontact.problem.options" in imported_modules(SOURCE / "case" / "translate.py")  # the helper sees them
    modules = sorted((SOURCE / package).rglob("*.py"))
    assert len(modules) >= 3
    for path in modules:
        names = imported_modules(path)
        case = sorted(name for name in names if name == "vpcontact.case" or name.startswith("vpcontact.case."))
        assert not case, (path.relative_to(SOURCE).as_posix(), case)


def test_the_problem_does_not_import_the_time_loop():
    """The arrow runs from the time loop to the problem only: a problem is solved by vpcontact.solve."""
    for path in sorted((SOURCE / "problem").rglob("*.py")):
        loop = sorted(name for name in imported_modules(path) if name.startswith("vpcontact.timeloop"))
        assert not loop, (path.relative_to(SOURCE).as_posix(), loop)


def test_the_default_outputs_are_the_case_files():
    """The options of an [output] table left out are the case file's defaults, with and without a table."""
    assert output_options(None) == output_options({}) == vpcontact.results.output_options.OutputOptions()


def test_the_readme_example_balances_its_load():
    """README's composed quarter ball runs, and the foundation's force balances the traction on the top:
    F_z = 15 T |top| with |top| the area of the top's facets (the load is integrated exactly on them)."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    block = readme.split("A problem in Python")[1].split("```python\n")[1].split("```")[0]
    namespace = {}
    exec(block, namespace)  # noqa: S102 -- the README's own example
    result, problem, finer = namespace["result"], namespace["problem"], namespace["finer"]
    assert result.status == "complete"
    p, facets = problem.mesh.mesh.p, problem.mesh.mesh.facets[:, problem.mesh.facets("top")]
    area = 0.5 * np.linalg.norm(np.cross(p[:, facets[1]] - p[:, facets[0]], p[:, facets[2]] - p[:, facets[0]],
                                         axis=0), axis=0).sum()
    assert result.series("contact_force_z")[-1] == pytest.approx(15.0 * 1.0 * area, rel=1e-8)
    assert finer.basis.N > problem.basis.N


def test_a_result_is_sent_between_processes(from_file, tmp_path):
    """A result pickles as the data it is, without a problem (the operators, loads and laws stay with the
    problem): the copy holds none of the stiffness matrix's values, which the problem's pickle holds, and the
    discretization's exact normals (objects, not closures), writes the same run directory, and is estimated with the problem beside it."""
    import pickle

    problem = vpcontact.build_problem(vpcontact.load_case(half_disc_case()))
    sent = pickle.dumps(from_file)
    copy = pickle.loads(sent)
    assert not hasattr(copy, "problem") and not hasattr(from_file, "problem")
    stiffness = problem.A.data.tobytes()
    assert stiffness in pickle.dumps(problem) and stiffness not in sent
    np.testing.assert_array_equal(copy.final.displacement, from_file.final.displacement)
    view = copy.discretization
    np.testing.assert_array_equal(view.mesh.exact_normals["bottom_arc"](view.surface.coordinates),
                                  from_file.discretization.surface.normals)
    vpcontact.write_run(from_file, tmp_path / "solved")
    vpcontact.write_run(copy, tmp_path / "copy")
    for name in ("history.csv", "contact.csv", "case.resolved.toml"):
        assert (tmp_path / "copy" / name).read_bytes() == (tmp_path / "solved" / name).read_bytes(), name
    np.testing.assert_array_equal(copy.contact_table()["K"], from_file.contact_table()["K"])
    np.testing.assert_array_equal(Level.of(copy, 11, problem).fields.stress, from_file.final.stress)
