"""The house (docs/architecture.md): every import of vpcontact's own modules points down the list of layers,
no module is over 400 lines, and at most a dozen modules stand directly in src/vpcontact.

The imports are read from the source (every ``import`` and ``from ... import``, inside functions too), so a
deferred import that runs back up is refused as well as one at the top of a module.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

import vpcontact

SOURCE = pathlib.Path(vpcontact.__file__).resolve().parent
#: The units of the package from the top down: a package or a module directly in src/vpcontact. A unit imports
#: only units of the layers below its own (two units of one layer do not import each other).
LAYERS = (
    ("__main__",),
    ("cli",),
    ("reproduction",),
    ("drivers",),
    ("api",),
    ("case",),
    ("adaptivity",),
    ("io",),
    ("timeloop",),
    ("estimate",),
    ("results",),
    ("problem",),
    ("solvers",),
    ("parallel",),
    ("fem",),
    ("laws",),
    ("mesh",),
    ("expressions", "progress"),
    ("inputs", "registry", "memory"),
    ("errors",),
    ("__init__",),
)
LAYER = {unit: depth for depth, units in enumerate(LAYERS) for unit in units}
MAX_LINES = 400
MAX_TOP_LEVEL_MODULES = 12


def unit_of(module: str) -> str:
    """The unit (see LAYERS) of a module named ``vpcontact.a.b...``: its first name below vpcontact, or __init__
    for the package's own namespace (``from vpcontact import submodule``)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def module_name(path: pathlib.Path) -> str:
    """The dotted name of the module at ``path`` below SOURCE."""
    parts = path.relative_to(SOURCE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_units(source: str, name: str, is_package: bool = False) -> dict[str, int]:
    """The units of vpcontact that the module ``name`` (a package's __init__ when ``is_package``) of the source
    text ``source`` imports, each with a line where it does."""
    package = name if is_package else name.rpartition(".")[0]
    units: dict[str, int] = {}
    for node in ast.walk(ast.parse(source, name)):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")[: len(package.split(".")) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            # `from vpcontact import x` names the unit x when x is one (a submodule), else the API's module of x
            targets = [module] if module != "vpcontact" else [
                f"vpcontact.{alias.name}" if alias.name in LAYER else
                f"vpcontact.{vpcontact.API[alias.name]}" if alias.name in vpcontact.API else "vpcontact"
                for alias in node.names]
        else:
            continue
        for target in targets:
            if target == "vpcontact" or target.startswith("vpcontact."):
                units.setdefault(unit_of(target), node.lineno)
    return units


MODULES = sorted(SOURCE.rglob("*.py"))


def test_the_layers_name_every_unit_once():
    units = {path.relative_to(SOURCE).parts[0].removesuffix(".py") for path in MODULES}
    assert units == set(LAYER), "a unit of src/vpcontact is missing from LAYERS, or LAYERS names one that is gone"
    assert sum(len(layer) for layer in LAYERS) == len(LAYER)


@pytest.mark.parametrize("path", MODULES, ids=lambda path: str(path.relative_to(SOURCE)))
def test_every_import_points_down(path):
    own = unit_of(module_name(path))
    imported = imported_units(path.read_text(), module_name(path), path.name == "__init__.py")
    upward = [f"{unit} (line {line})" for unit, line in imported.items() if unit != own and LAYER[unit] <= LAYER[own]]
    assert not upward, (f"{path.relative_to(SOURCE)} ({own}) imports {', '.join(upward)}, which is not below it in "
                        f"LAYERS (docs/architecture.md)")


def test_the_checker_sees_imports_that_run_back_up():
    """The check above can fail: a law with a deferred import of the time loop, and a mesh module importing the
    API's solve through the package, are found importing units above their own."""
    law = (SOURCE / "laws" / "contact.py").read_text() + "\n\ndef _late():\n    from ..timeloop.loop import TimeLoop\n"
    assert "timeloop" in imported_units(law, "vpcontact.laws.contact") and LAYER["timeloop"] < LAYER["laws"]
    shape = "from .. import solve, submodule\nfrom . import cells\n"
    assert imported_units(shape, "vpcontact.mesh.shapes") == {"api": 1, "__init__": 1, "mesh": 2}


def test_no_module_is_over_400_lines():
    lines = {str(path.relative_to(SOURCE)): len(path.read_text().splitlines()) for path in MODULES}
    long = {module: n for module, n in lines.items() if n > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_at_most_a_dozen_modules_directly_in_the_package():
    top = sorted(path.name for path in SOURCE.glob("*.py"))
    assert len(top) <= MAX_TOP_LEVEL_MODULES, top
