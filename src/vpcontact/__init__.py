"""vpcontact: quasistatic contact of viscoplastic bodies with a foundation whose soft layer
hardens or softens with the history of penetration (Barboteu, Han, Sofonea).

    >>> import vpcontact
    >>> case = vpcontact.load_case("examples/paper_ball.toml", {"contact.stiffness.beta": -1})
    >>> result = vpcontact.solve(case)
    >>> result.series("K_probe")[-1]
    >>> vpcontact.write_run(result, "results/beta-1")   # the files of a run directory, as `vpcontact run` writes

The names of the API (``vpcontact.solve``, ``vpcontact.Case``, ...) and the submodules
(``vpcontact.results.norms``, ``vpcontact.laws.contact``, ...) are loaded on first use: ``import vpcontact`` (and
``vpcontact --help``) imports no numerics.
"""

from __future__ import annotations

import importlib
from importlib import metadata

try:
    __version__ = metadata.version("vpcontact")
except metadata.PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

#: The names of the API, by the module that defines them.
API = {"Case": "case.model", "Model": "case.model", "load_case": "case.load", "CaseError": "errors",
       "compose": "case.compose", "Problem": "problem.build", "build_problem": "api", "solve": "api", "adapt": "api",
       "Result": "results.result", "write_run": "io.run"}

#: The packages a user may reach as ``vpcontact.<name>`` after ``import vpcontact`` (and their modules as
#: ``vpcontact.<name>.<module>``), and the modules of the package itself.
SUBMODULES = ("adaptivity", "api", "case", "cli", "drivers", "errors", "estimate", "expressions", "fem", "inputs", "io",
              "laws", "memory", "mesh", "problem", "progress", "registry", "reproduction", "results", "solvers", "timeloop")


def submodule(package: str, name: str):
    """The module ``name`` of ``package``, imported on first use: what a package's ``__getattr__`` returns, so
    that ``vpcontact.results.norms`` needs no import of its own; AttributeError for a name that is none."""
    try:
        return importlib.import_module(f"{package}.{name}")
    except ModuleNotFoundError as error:
        if error.name != f"{package}.{name}":
            raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}") from None


def __getattr__(name: str):
    """The names of the API and the SUBMODULES, imported when first used."""
    if name in API:
        value = getattr(importlib.import_module(f".{API[name]}", __name__), name)
        globals()[name] = value  # once
        return value
    if name in SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(API) | set(SUBMODULES))


__all__ = ["Case", "CaseError", "Model", "Problem", "Result", "adapt", "build_problem", "compose", "load_case", "solve",
           "write_run"]
