"""The body's sections: ``[mesh]`` (a built-in shape or a mesh file), ``[boundary]`` (Dirichlet conditions,
tractions, body forces) and ``[initial]`` (the initial state, or a restart from another run)."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, Optional

from pydantic import AfterValidator, Field, field_validator, model_validator

from ..errors import brief
from ..mesh.cells import SIMPLICES
from .values import MAX_ELEMENTS, Expression, Part, PositiveFloat, Section, finite


#: The size keys of each built-in shape (default 1 each) and its dimension.
SHAPES = {"half_disc": (("radius",), 2), "rectangle": (("width", "height"), 2),
          "quarter_ball": (("radius",), 3), "block": (("width", "depth", "height"), 3)}


class MeshSection(Section):
    """A built-in shape of element size h, or a mesh file."""

    shape: Optional[Literal["half_disc", "rectangle", "quarter_ball", "block"]] = None
    file: Optional[str] = None
    h: Optional[PositiveFloat] = None
    h_bottom: Optional[PositiveFloat] = None  # quarter_ball: the element size at the bottom point (graded)
    radius: Optional[PositiveFloat] = None  # half_disc, quarter_ball: default 1
    width: Optional[PositiveFloat] = None  # rectangle, block: default 1
    depth: Optional[PositiveFloat] = None  # block: default 1
    height: Optional[PositiveFloat] = None  # rectangle, block: default 1
    coating: Optional[PositiveFloat] = None  # half_disc, quarter_ball: regions "core" and "coating" (this thick)

    @model_validator(mode="after")
    def _one_source(self):
        if (self.shape is None) == (self.file is None):
            raise ValueError("mesh: give exactly one of mesh.shape and mesh.file")
        if self.shape is not None and self.h is None:
            raise ValueError(f"missing required value 'mesh.h' (the element size of mesh.shape = \"{self.shape}\")")
        sizes, dim = SHAPES.get(self.shape, ((), None))
        for key in ("radius", "width", "depth", "height"):
            if key in sizes and getattr(self, key) is None:
                setattr(self, key, 1.0)
            elif key not in sizes and getattr(self, key) is not None:
                where = f"mesh.shape = \"{self.shape}\"" if self.shape else "mesh.file"
                raise ValueError(f"mesh.{key} is not used with {where}")
        if self.h_bottom is not None and self.shape != "quarter_ball":
            where = f"mesh.shape = \"{self.shape}\"" if self.shape else "mesh.file"
            raise ValueError(f"mesh.h_bottom is only used with mesh.shape = \"quarter_ball\" (not with {where})")
        if self.coating is not None and self.shape not in ("half_disc", "quarter_ball"):
            where = f"mesh.shape = \"{self.shape}\"" if self.shape else "mesh.file (whose regions are its physical groups)"
            raise ValueError(f"mesh.coating is only used with mesh.shape = \"half_disc\" or \"quarter_ball\" (not with "
                             f"{where})")
        if self.coating is not None and not self.coating < self.radius:
            raise ValueError(f"mesh.coating = {brief(self.coating)} must be less than mesh.radius = "
                             f"{brief(self.radius)} (the coating is the outer shell of that thickness; the core has "
                             f"the radius radius - coating)")
        if self.file is not None and self.h is not None:
            raise ValueError("mesh.h is not used with mesh.file (the file fixes the elements)")
        if self.shape is not None:
            elements = self._elements(dim)
            if not elements <= MAX_ELEMENTS:
                raise ValueError(f"mesh.h = {brief(self.h)}: about {elements:.1e} {SIMPLICES[dim].plural} for this "
                                 f"{self.shape}, more than {MAX_ELEMENTS:.0e}")
        return self

    def _elements(self, dim: int) -> float:
        """About how many elements the shape has at size h (no ** : 1e300**2 raises OverflowError)."""
        if self.shape == "quarter_ball":
            from ..mesh.ball import estimated_tetrahedra

            return estimated_tetrahedra(self.h / self.radius,
                                        None if self.h_bottom is None else self.h_bottom / self.radius)
        r, w, d, h = self.radius, self.width, self.depth, self.height
        size = {"half_disc": lambda: math.pi * r * r / 2, "rectangle": lambda: w * h, "block": lambda: w * d * h}
        count = size[self.shape]()
        for _ in range(dim):
            count /= self.h
        return (2.0 if dim == 2 else 6.0) * count  # triangles per square, tetrahedra per cube of side h


def _source(entry):
    """An entry of initial.stress as it was written, for the symmetry check: a number by its value (a
    string that is a number too), an expression by its text without spaces."""
    if isinstance(entry, str):
        text = "".join(entry.split())
        try:
            return float(text)
        except ValueError:
            return text
    return float(entry)


def _stress_tensor(value):
    """A d × d table (d = 2 or 3), e.g. [[sxx, sxy], [sxy, syy]], whose entries are finite numbers or
    expressions in the coordinates (σ_0 per element, evaluated at the centroids), symmetric as written."""
    if not (isinstance(value, list) and len(value) in (2, 3)
            and all(isinstance(row, list) and len(row) == len(value) for row in value)):
        raise ValueError(f"initial.stress = {brief(value)}: expected a d x d table, [[sxx, sxy], [sxy, syy]] in 2D "
                         f"or [[sxx, sxy, sxz], [sxy, syy, syz], [sxz, syz, szz]] in 3D")
    for row in value:
        for entry in row:
            if isinstance(entry, bool) or not isinstance(entry, (int, float, str)) or (
                    not isinstance(entry, str) and not finite(entry)):
                raise ValueError(f"initial.stress = {brief(value)}: expected finite numbers or expressions in the "
                                 f"coordinates, got {brief(entry)}")
    for i in range(len(value)):
        for j in range(i + 1, len(value)):
            if _source(value[i][j]) != _source(value[j][i]):
                raise ValueError(f"initial.stress = {brief(value)}: must be symmetric (stress[{i}][{j}] = "
                                 f"{brief(value[i][j])}, stress[{j}][{i}] = {brief(value[j][i])})")
    return [[entry if isinstance(entry, str) else float(entry) for entry in row] for row in value]


class InitialSection(Section):
    """Initial data (2.7), (2.21): the displacement u_0 (d expressions in the coordinates, at the nodes),
    the stress σ_0 (a d × d table of expressions, per element) and the history ξ_0 of the layer (an
    expression, at the contact nodes), each 0 by default; or, instead of u_0 and σ_0, the state of
    another run at one of its field steps (``from_run``, ``step``: a restart)."""

    stress: Optional[Annotated[Any, AfterValidator(_stress_tensor)]] = None
    displacement: Optional[Annotated[list[Expression], Field(min_length=2, max_length=3)]] = None
    xi: Optional[Expression] = None
    from_run: Optional[str] = None  # a run directory written by ``vpcontact run`` (its solution.npz)
    step: Optional[Annotated[int, Field(ge=1)]] = None  # the field step of from_run to start from

    @model_validator(mode="after")
    def _one_source(self):
        if (self.from_run is None) != (self.step is None):
            given, missing = ("from_run", "step") if self.step is None else ("step", "from_run")
            raise ValueError(f"initial.{given} needs initial.{missing} (a restart from the field step initial.step "
                             f"of the run directory initial.from_run)")
        if self.from_run is not None:
            for key in ("displacement", "stress"):
                if getattr(self, key) is not None:
                    raise ValueError(f"initial.{key} and initial.from_run exclude each other (the restart takes "
                                     f"u_0 and sigma_0 from the run): remove one")
        return self


#: The name of a held set of nodes in the columns of its reaction and mean displacement (reaction_<name>_<c>).
HeldName = Annotated[str, Field(pattern=r"^[_.A-Za-z0-9-]+$", max_length=64)]


class HeldComponents(Section):
    """The components held (all when omitted) and their prescribed displacement: u_D = 0, or the expressions of
    ``value`` in x, y, (z,) t, one per listed component (e.g. ``value = ["-0.4*t"]``); ``name``: the name of the
    columns of the reaction and mean displacement of the nodes held."""

    components: Optional[list[Literal["x", "y", "z"]]] = None  # None: all
    value: Optional[Annotated[list[Expression], Field(min_length=1, max_length=3)]] = None  # None: 0
    name: Optional[HeldName] = None

    @field_validator("components")
    @classmethod
    def _some(cls, value):
        if value == []:  # not "all": an empty list would hold nothing, and read as None it would hold everything
            raise ValueError("= []: no component; list the components held, or leave out components to hold "
                             "all of them")
        return value

    @model_validator(mode="after")
    def _one_value_per_component(self):
        if self.value is not None and self.components is not None and len(self.value) != len(self.components):
            raise ValueError(f"value has {len(self.value)} expressions and components lists "
                             f"{len(self.components)} ({', '.join(self.components)}): give one expression in x, y, "
                             f"(z,) t per listed component")
        return self


class DirichletSection(HeldComponents):
    """u = u_D at the nodes of a part, or at the nodes where the condition ``where`` on the coordinates holds
    (``where = "abs(z - 0.02) < 1e-9"``), or at the nodes of the part where it holds (both given)."""

    part: Optional[Part] = None
    where: Optional[str] = None

    @model_validator(mode="after")
    def _nodes(self):
        if self.part is None and self.where is None:
            raise ValueError("give the nodes held: part (a part of the mesh), where (a condition on the coordinates, "
                             "e.g. \"abs(z - 0.02) < 1e-9\") or both")
        return self


class PointSection(HeldComponents):
    """u = u_D at the node nearest to the point ``at`` (a point constraint: a full model held against its rigid
    motions)."""

    at: Annotated[list[float], Field(min_length=2, max_length=3)]


class TractionSection(Section):
    """σν = f2 on a part: one expression in x, y, (z,) t per component (one per dimension)."""

    part: Part
    value: Annotated[list[Expression], Field(min_length=2, max_length=3)]


class BodyForceSection(Section):
    """f0 in Ω: one expression in x, y, (z,) t per component (one per dimension)."""

    value: Annotated[list[Expression], Field(min_length=2, max_length=3)]


class BoundarySection(Section):
    dirichlet: list[DirichletSection] = []
    point: list[PointSection] = []
    traction: list[TractionSection] = []
    body_force: list[BodyForceSection] = []
