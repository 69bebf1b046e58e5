"""The reproduction is a subpackage nothing else imports, without import cycles; the rule for which
history rows are the steps t_n is one, and a run directory read back gives the run's own numbers."""

import ast
import graphlib
from pathlib import Path

import numpy as np
import pytest

import vpcontact
from conftest import half_disc_case
from vpcontact.results.columns import CONTACT_ARRAYS
from vpcontact.results.steps import step_ends
from vpcontact.io.contact_csv import read_contact
from vpcontact.io.solution import snapshots_at
from vpcontact.io.summary import read_summary

PACKAGE = Path(vpcontact.__file__).parent
SUBPACKAGE = "vpcontact.reproduction"


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path) -> list[tuple[str, bool]]:
    """The vpcontact modules ``path`` imports (relative imports resolved; ``from X import Y`` gives X.Y
    as well as X, since Y may be a module), each with whether the import is inside a function."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = module_name(path).split(".") if path.name == "__init__.py" else module_name(path).split(".")[:-1]
    inside = {id(node) for function in ast.walk(tree) if isinstance(function, (ast.FunctionDef, ast.AsyncFunctionDef))
              for node in ast.walk(function)}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(package[:len(package) - node.level + 1] + ([node.module] if node.module else [])) \
                if node.level else node.module
            names = [base, *(f"{base}.{alias.name}" for alias in node.names)]
        else:
            continue
        found += [(name, id(node) in inside) for name in names if name.split(".")[0] == "vpcontact"]
    return found


def is_reproduction(name: str) -> bool:
    return name == SUBPACKAGE or name.startswith(SUBPACKAGE + ".")


def test_nothing_in_the_package_imports_the_reproduction_but_the_reproduce_command():
    importers = {}
    for path in PACKAGE.rglob("*.py"):
        if not is_reproduction(module_name(path)):
            for name, lazy in imports(path):
                if is_reproduction(name):
                    importers.setdefault(module_name(path), set()).add(lazy)
    assert importers == {"vpcontact.cli": {True}}  # only the command line, inside the reproduce command


def test_the_reproduction_modules_import_each_other_without_a_cycle():
    modules = {module_name(path): path for path in (PACKAGE / "reproduction").glob("*.py")}
    assert {"vpcontact.reproduction.reproduce", "vpcontact.reproduction.figures", "vpcontact.reproduction.report",
            "vpcontact.reproduction.plan", "vpcontact.reproduction.paper"} <= set(modules)
    graph = {name: {imported for imported, _ in imports(path) if imported in modules and imported != SUBPACKAGE}
             for name, path in modules.items()}
    order = list(graphlib.TopologicalSorter(graph).static_order())  # CycleError on a cycle
    assert order.index("vpcontact.reproduction.paper") < order.index("vpcontact.reproduction.figures") \
        < order.index("vpcontact.reproduction.report") < order.index("vpcontact.reproduction.reproduce")
    assert not any((PACKAGE / name).exists() for name in ("reproduce.py", "figures.py", "report.py"))


def test_the_step_rule_takes_the_last_row_of_each_step_reached():
    steps = np.array([1, 1, 2, 3, 3, 3, 4, 4])  # steps 1 and 3 cut; step 4 cut and never reached
    assert step_ends(steps, 3).tolist() == [False, True, True, False, False, True, False, False]
    assert step_ends(steps, 4).tolist() == [False, True, True, False, False, True, False, True]
    assert step_ends(np.zeros(0), 0).tolist() == []


@pytest.fixture(scope="module")
def failed_run(tmp_path_factory):
    """A run whose steps Newton cannot do whole in 3 iterations: cut, and step 4 fails after its cuts,
    its converged sub-steps kept (tests/test_robustness.py has the same case)."""
    case = half_disc_case(h=0.1, load=20.0, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["solver"].update(max_iterations=3)
    case["output"] = {"field_steps": [1, 2, 3]}
    result = vpcontact.solve(case)
    out = tmp_path_factory.mktemp("failed") / "run"
    vpcontact.write_run(result, out)
    return result, out


def test_the_step_rows_are_those_at_the_step_times(failed_run):
    """The rule (the last row of each step reached) and the times t_n pick the same rows."""
    result, _ = failed_run
    assert result.status == "failed" and result.steps == 3 and result.step_cuts > 0
    ends = result.ends_step()
    np.testing.assert_array_equal(result.times[ends], result.discretization.times[:3])
    assert np.all(result.times[~ends] != result.discretization.times.at(result.series("step")[~ends]))
    assert list(result.end_of_step_rows()) == [1, 2, 3]


def test_a_run_directory_reads_back_as_the_run(failed_run):
    result, out = failed_run
    assert read_summary(out)["steps"] == 3
    for step in (1, 2, 3):
        contact = read_contact(out, step)
        assert contact["t"].tolist() == [result.discretization.times[step - 1]] * result.contact_nodes
        np.testing.assert_array_equal(contact["node"], result.discretization.surface.nodes)
        np.testing.assert_array_equal(contact["normals"], result.discretization.surface.normals)
        for name in CONTACT_ARRAYS:
            np.testing.assert_array_equal(contact[name], result.contact_history(name, substeps=False)[step - 1])
    np.testing.assert_array_equal(read_contact(out)["xi"], read_contact(out, 3)["xi"])  # default: the last step
    with pytest.raises(KeyError, match="step 4 was not reached"):
        read_contact(out, 4)
    snapshot = snapshots_at(out, [result.discretization.times[1]])[result.discretization.times[1]]
    np.testing.assert_array_equal(snapshot.displacement, result.fields[2].displacement)
    np.testing.assert_array_equal(snapshot.stress, result.fields[2].stress)


def test_a_damaged_run_directory_reads_as_nothing(tmp_path):
    (tmp_path / "summary.json").write_text("[1, 2")
    (tmp_path / "solution.npz").write_bytes(b"PK\x03\x04 not a zip")
    assert read_summary(tmp_path) is None and snapshots_at(tmp_path, [1.0]) == {}
    (tmp_path / "summary.json").write_text("[1, 2]")  # JSON, but not a summary
    assert read_summary(tmp_path) is None
