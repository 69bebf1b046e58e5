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
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .results.result import Result

try:
    __version__ = metadata.version("vpcontact")
except metadata.PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

#: The names of the API, by the module that defines them.
API = {"Case": "case.schema", "Model": "case.schema", "load_case": "case.schema", "CaseError": "errors",
       "compose": "case.compose", "Problem": "problem.build", "build_problem": "problem.build",
       "Result": "results.result", "solve_problem": "timeloop.loop", "write_run": "io.run"}

#: The packages a user may reach as ``vpcontact.<name>`` after ``import vpcontact`` (and their modules as
#: ``vpcontact.<name>.<module>``), and the modules of the package itself.
SUBMODULES = ("case", "drivers", "errors", "estimate", "fem", "io", "laws", "mesh", "problem", "progress", "reproduction",
              "results", "solvers", "timeloop")


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


def solve(case, *, progress=False, **laws) -> Result:
    """Solve a case (a :class:`Case`, or a path or dict for :func:`load_case`).

    ``laws`` replace parts of the case by Python objects (see :func:`build_problem`): ``p`` and
    ``stiffness_law`` (functions of a NumPy array; with a ``derivative`` method, or a central difference is
    used; f(r, x) of the contact nodes' coordinates x too), ``tractions`` ({part: f(x, y, t) -> (fx, fy)}:
    replaces the case's traction on that part), ``body_force`` (f(x, y, t) -> (fx, fy): replaces the case's
    body forces), ``viscoplastic`` (𝒢(σ, ε)) and the initial state's arrays ``initial_displacement``
    (nodes, d), ``initial_stress`` (elements, d, d) or (d, d), ``initial_xi`` (contact nodes,).
    Bad objects are a :class:`CaseError` before the first step. Nothing is printed, unless ``progress`` is
    True (the set-up phases and the steps reported on stderr, as the command line does) or a reporter
    (:mod:`vpcontact.progress`).
    """
    from .case.schema import Case, load_case
    from .errors import flag
    from .problem.build import build_problem
    from .progress import reporting
    from .timeloop.loop import solve_problem

    progress = flag("progress", progress)
    if not isinstance(case, Case):
        case = load_case(case)
    with reporting(progress) as reporter:
        return solve_problem(build_problem(case, progress=reporter, **laws), output=case.output, progress=reporter)


__all__ = ["Case", "CaseError", "Model", "Problem", "Result", "build_problem", "compose", "load_case", "solve",
           "solve_problem", "write_run"]
