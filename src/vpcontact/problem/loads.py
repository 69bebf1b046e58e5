"""The loads of a problem: the case's tractions and body forces as densities of their expressions (in the
coordinates and t), and the Python functions of the API that replace them, checked by their signature."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import CaseError, brief
from ..expressions.parse import parse_expression
from ..fem.assembly import Density, ExpressionDensity
from ..mesh.cells import coordinates
from ..laws.python_laws import accepts, parameters_in_words
from ..mesh.mesh import Mesh
from .options import ProblemOptions


def expression_density(values, where: str) -> ExpressionDensity:
    """The density of the d expressions ``values`` (one per component) of the case key ``where``."""
    names = coordinates(len(values))
    return ExpressionDensity(*(parse_expression(v, (*names, "t"), where=f"{where}[{i}]")
                               for i, v in enumerate(values)))


def traction_terms(options: ProblemOptions, mesh: Mesh,
                   tractions: Mapping | None) -> list[tuple[str, object, Density]]:
    """(name, part, density) of the case's tractions, those of ``tractions`` replacing the case's on their part."""
    terms = [(f"boundary.traction[{i}].value", t.part, expression_density(t.value, f"boundary.traction[{i}].value"))
             for i, t in enumerate(options.boundary.traction)]
    if tractions is None:
        return terms
    if not isinstance(tractions, Mapping):
        raise CaseError(f"tractions = {brief(tractions)}: expected a dict {{part: f(x, y, (z,) t) -> (fx, fy, (fz))}}")
    for part, density in tractions.items():
        if not (isinstance(part, (str, int)) and str(part) in mesh.parts):
            raise CaseError(f"tractions: unknown part {brief(part)}; the mesh has parts: {', '.join(mesh.part_names)}")
        check_density_arguments(f"tractions[{brief(part)}]", density, mesh.dim)
        facets = mesh.facets(part)
        terms = [term for term in terms if not np.array_equal(mesh.facets(term[1]), facets)]
        terms.append((f"tractions[{brief(part)}]", part, density))
    return terms


def check_density_arguments(name: str, density, dim: int) -> None:
    """CaseError unless a load density of the API takes the coordinates and the time, f(x, y, t) (f(x, y, z, t) in
    3D), as far as its signature tells (a NumPy ufunc or a builtin does not; a value that is not a function is
    refused where the load is made)."""
    if callable(density) and not accepts(density, dim + 1):
        names = coordinates(dim)
        raise CaseError(f"{name} = {brief(density)} takes {parameters_in_words(density)}: expected "
                        f"f({', '.join(names)}, t) -> ({', '.join('f' + c for c in names)})")
