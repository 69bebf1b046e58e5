"""vpcontact: quasistatic contact of viscoplastic bodies with a foundation whose soft layer
hardens or softens with the history of penetration (Barboteu, Han, Sofonea).

    >>> import vpcontact
    >>> case = vpcontact.load_case("examples/paper_ball.toml", {"contact.stiffness.beta": -1})
    >>> result = vpcontact.solve(case)
    >>> result.series("K_probe")[-1]
"""

from importlib import metadata

try:
    __version__ = metadata.version("vpcontact")
except metadata.PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

from .case import Case, load_case  # noqa: E402
from .errors import CaseError  # noqa: E402
from .problem import Problem, build_problem  # noqa: E402
from .results import Result  # noqa: E402
from .stepping import solve_problem  # noqa: E402


def solve(case, *, progress: bool = False, **laws) -> Result:
    """Solve a case (a :class:`Case`, or a path or dict for :func:`load_case`).

    ``laws`` replace parts of the case by Python objects: ``p``, ``stiffness_law`` (callables with
    a ``derivative`` method, see :mod:`vpcontact.contact`), ``tractions`` ({part: f(x, y, t)}),
    ``body_force`` (f(x, y, t)) and ``viscoplastic`` (𝒢(σ, ε)).
    """
    if not isinstance(case, Case):
        case = load_case(case)
    return solve_problem(build_problem(case, **laws), progress=progress)


__all__ = ["Case", "CaseError", "Problem", "Result", "build_problem", "load_case", "solve", "solve_problem"]
