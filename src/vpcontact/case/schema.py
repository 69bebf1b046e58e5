"""The case description: the one place that knows the keys of a case file.

A case is a TOML file (or a dict) validated against the schema below; ``--set key=value``
overrides are applied to the raw data before validation. Every problem is reported as a
:class:`~vpcontact.errors.CaseError` with a one-line message naming the bad key and value.
"""

from __future__ import annotations

import datetime
import difflib
import math
import os
import re
import tomllib
import typing
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Annotated, Any, Literal, Optional, Union

import numpy as np
import tomli_w
from pydantic import (AfterValidator, BaseModel, BeforeValidator, ConfigDict, Discriminator, Field, Tag, ValidationError,
                      ValidationInfo, field_validator, model_validator)

from ..errors import CaseError, one_line, quoted, shown
from .expressions import parse_expression
from .inputs import MAX_TOML_BYTES, check_regular_file
from ..solvers.factorization import BACKENDS, installed_backends
from ..mesh.cells import SIMPLICES

# --- value types ---------------------------------------------------------------------------------
#: Most time steps and (estimated) triangles of a built-in shape a case may ask for: beyond, the run
#: could not even allocate its arrays.
MAX_STEPS = 10**8
MAX_ELEMENTS = 10**9


def _finite(number) -> bool:
    """Is an int or float a finite float64 (an int beyond 1.8e308 is not)?"""
    try:
        return math.isfinite(float(number))
    except OverflowError:
        return False


def _brief(value) -> str:
    """repr(value), cut as :func:`~vpcontact.errors.shown` cuts (a huge number or list stays a short message)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 200:
        sign = "a negative" if value < 0 else "an"
        return f"{sign} integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - an object of the API may have any repr
        return f"a value of type {type(value).__name__}"
    if "\n" in text:  # an object shown over several lines (a scikit-fem mesh, a table): one line
        text = " ".join(text.split())
    return shown(text)


PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]


def _expression_value(value):
    """An expression: a string (parsed later with its key in the message) or a number."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ValueError(f"expected an expression (a string such as \"-1000*t\") or a number, got {_brief(value)}")
    if isinstance(value, (int, float)) and not _finite(value):  # an int too, beyond float64's range
        raise ValueError(f"expected a finite number, got {_brief(value)}")
    return value


Expression = Annotated[Any, AfterValidator(_expression_value)]
Part = Union[str, int]


def _layer_value(minimum: float | None):
    """A layer parameter: a number (at least ``minimum`` when given) or an expression in the coordinates,
    evaluated at the contact nodes (its values there are checked against ``minimum`` when the problem is
    built)."""

    def check(value):
        value = _expression_value(value)
        if isinstance(value, (int, float)) and minimum is not None and not value >= minimum:
            raise ValueError(f"expected a number >= {minimum:g} or an expression in the coordinates, got "
                             f"{_brief(value)}")
        return value

    return Annotated[Any, AfterValidator(check)]


def _infinite(value):
    """contact.g = "inf" (or "infinity"): the number inf; nan refused."""
    if isinstance(value, str) and value.strip().lower() in ("inf", "infinity"):
        return math.inf
    if isinstance(value, float) and math.isnan(value):
        raise ValueError("g = nan: expected a positive number or \"inf\"")
    return value


def _thickness(value):
    """contact.g: a number > 0, inf (no rigid base: classical normal compliance), or an expression in the
    coordinates (a thickness that varies along Γ3, checked > 0 at the contact nodes)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise ValueError(f"g = {_brief(value)}: must be > 0 (a number, \"inf\" or an expression in the "
                         f"coordinates)")
    if isinstance(value, int) and not _finite(value):
        raise ValueError(f"g = {_brief(value)}: beyond the range of float64; \"inf\" is a layer without rigid base")
    return value


Thickness = Annotated[Any, BeforeValidator(_infinite), AfterValidator(_thickness)]


#: Layer parameters that may vary along Γ3 (the paper's K(x, ξ), (2.18)).
NonNegativeLayerValue = _layer_value(0.0)
LayerValue = _layer_value(None)
#: The exponent m ≥ 1 of p = power, which may vary along Γ3 too (the paper's p(x, r), (2.19)).
Exponent = _layer_value(1.0)


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


# --- sections ------------------------------------------------------------------------------------
#: The size keys of each built-in shape (default 1 each) and its dimension.
SHAPES = {"half_disc": (("radius",), 2), "rectangle": (("width", "height"), 2),
          "quarter_ball": (("radius",), 3), "block": (("width", "depth", "height"), 3)}


class MeshSection(_Section):
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
            raise ValueError(f"mesh.coating = {_brief(self.coating)} must be less than mesh.radius = "
                             f"{_brief(self.radius)} (the coating is the outer shell of that thickness; the core has "
                             f"the radius radius - coating)")
        if self.file is not None and self.h is not None:
            raise ValueError("mesh.h is not used with mesh.file (the file fixes the elements)")
        if self.shape is not None:
            elements = self._elements(dim)
            if not elements <= MAX_ELEMENTS:
                raise ValueError(f"mesh.h = {_brief(self.h)}: about {elements:.1e} {SIMPLICES[dim].plural} for this "
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


class PerzynaSection(_Section):
    """𝒢(σ, ε) = −(1/η) (σ − P(σ)), P the projection onto {τ ∈ S² : ‖dev τ‖ ≤ yield_stress}."""

    law: Literal["perzyna"]
    eta: PositiveFloat  # viscosity η: the Lipschitz constant of 𝒢 is 1/η
    yield_stress: NonNegativeFloat  # σ_y; 0: the whole deviator relaxes


class RelaxationSection(_Section):
    """𝒢(σ, ε) = −μ (σ − 𝒞ε), 𝒞 isotropic (E_inf, nu_inf) with the material's hypothesis."""

    law: Literal["relaxation"]
    mu: PositiveFloat  # relaxation rate μ (1/time)
    E_inf: PositiveFloat
    nu_inf: float


Viscoplastic = Annotated[Union[PerzynaSection, RelaxationSection], Field(discriminator="law")]


def _check_poisson_ratio(key: str, nu: float, hypothesis: str | None) -> None:
    upper_ok = nu <= 0.5 if hypothesis == "plane_stress" else nu < 0.5
    if not (-1.0 < nu and upper_ok):
        bound = "<= 0.5" if hypothesis == "plane_stress" else "< 0.5"
        name = key.rpartition(".")[2]
        model = hypothesis or "plane_strain and 3D"
        raise ValueError(f"{key} = {_brief(nu)}: must satisfy -1 < {name} {bound} for {model}")


def _modulus(value):
    """material.E: a number > 0 or an expression in the coordinates (checked > 0 at the element centroids)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not _finite(value) or not value > 0:
        raise ValueError(f"= {_brief(value)}: expected a finite number > 0 or an expression in the coordinates")
    return value


Modulus = Annotated[Any, AfterValidator(_modulus)]


def _region_names(value):
    """material.region: a region name (a string, or a physical group's number) or a non-empty list of them."""
    names = value if isinstance(value, list) else [value]
    if not names or any(isinstance(name, bool) or not isinstance(name, (str, int)) for name in names):
        raise ValueError(f"expected a region name (a string or a physical group number) or a non-empty list of them, "
                         f"got {_brief(value)}")
    return value


class MaterialSection(_Section):
    """Isotropic elasticity (4.1); in 2D plane strain (the paper's formula, the default) or plane
    stress, in 3D the full tensor (no hypothesis); optionally a viscoplastic law 𝒢 of (2.1) (none:
    𝒢 = 0, linear elasticity). E and ν are numbers or expressions in the coordinates (ℰ(x) of (2.16),
    evaluated at the element centroids). ``region``: the mesh regions (``Mesh.regions``) the entry is
    the material of; None: the whole body (then it is the only entry)."""

    E: Modulus
    nu: Expression
    hypothesis: Optional[Literal["plane_strain", "plane_stress"]] = None  # 2D only; None: plane strain in 2D
    viscoplastic: Optional[Viscoplastic] = None
    region: Optional[Annotated[Any, AfterValidator(_region_names)]] = None

    def check_poisson_ratios(self, key: str) -> None:
        """ValueError unless ν (a number) and the relaxed ν_inf are admissible for the hypothesis; ``key``
        names the entry in the message ("material" or "material[i]")."""
        if not isinstance(self.nu, str):
            _check_poisson_ratio(f"{key}.nu", self.nu, self.hypothesis)
        if isinstance(self.viscoplastic, RelaxationSection):
            _check_poisson_ratio(f"{key}.viscoplastic.nu_inf", self.viscoplastic.nu_inf, self.hypothesis)

    @property
    def regions(self) -> list[str]:
        """The names of the regions of the entry (empty: the whole body)."""
        if self.region is None:
            return []
        return [str(name) for name in (self.region if isinstance(self.region, list) else [self.region])]


def _material_kind(value) -> str:
    return "list" if isinstance(value, list) else "table"


#: ``[material]`` (one material, the whole body) or ``[[material]]`` (a list of entries by region).
Materials = Annotated[Union[Annotated[MaterialSection, Tag("table")],
                            Annotated[list[MaterialSection], Field(min_length=1), Tag("list")]],
                      Discriminator(_material_kind)]


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
        raise ValueError(f"initial.stress = {_brief(value)}: expected a d x d table, [[sxx, sxy], [sxy, syy]] in 2D "
                         f"or [[sxx, sxy, sxz], [sxy, syy, syz], [sxz, syz, szz]] in 3D")
    for row in value:
        for entry in row:
            if isinstance(entry, bool) or not isinstance(entry, (int, float, str)) or (
                    not isinstance(entry, str) and not _finite(entry)):
                raise ValueError(f"initial.stress = {_brief(value)}: expected finite numbers or expressions in the "
                                 f"coordinates, got {_brief(entry)}")
    for i in range(len(value)):
        for j in range(i + 1, len(value)):
            if _source(value[i][j]) != _source(value[j][i]):
                raise ValueError(f"initial.stress = {_brief(value)}: must be symmetric (stress[{i}][{j}] = "
                                 f"{_brief(value[i][j])}, stress[{j}][{i}] = {_brief(value[j][i])})")
    return [[entry if isinstance(entry, str) else float(entry) for entry in row] for row in value]


class InitialSection(_Section):
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


class DirichletSection(_Section):
    """u = 0 on a part, for the listed components (all when omitted)."""

    part: Part
    components: Optional[list[Literal["x", "y", "z"]]] = None  # None: all

    @field_validator("components")
    @classmethod
    def _some(cls, value):
        if value == []:  # not "all": an empty list would hold nothing, and read as None it would hold everything
            raise ValueError("= []: no component; list the components held at 0, or leave out components to hold "
                             "all of them")
        return value


class TractionSection(_Section):
    """σν = f2 on a part: one expression in x, y, (z,) t per component (one per dimension)."""

    part: Part
    value: Annotated[list[Expression], Field(min_length=2, max_length=3)]


class BodyForceSection(_Section):
    """f0 in Ω: one expression in x, y, (z,) t per component (one per dimension)."""

    value: Annotated[list[Expression], Field(min_length=2, max_length=3)]


class BoundarySection(_Section):
    dirichlet: list[DirichletSection] = []
    traction: list[TractionSection] = []
    body_force: list[BodyForceSection] = []


class PowerStiffnessSection(_Section):
    """K(ξ) = c_v (1 + α ξ)^β (the paper's law)."""

    law: Literal["power"]
    c_v: NonNegativeLayerValue
    alpha: NonNegativeLayerValue
    beta: LayerValue


class ConstantStiffnessSection(_Section):
    """K(ξ) = value; 0 gives the Signorini condition with gap g."""

    law: Literal["constant"]
    value: NonNegativeLayerValue


class ExponentialStiffnessSection(_Section):
    """K(ξ) = c_v exp(α ξ)."""

    law: Literal["exponential"]
    c_v: NonNegativeLayerValue
    alpha: LayerValue


Stiffness = Annotated[
    Union[PowerStiffnessSection, ConstantStiffnessSection, ExponentialStiffnessSection], Field(discriminator="law")
]


#: The lengths a vector contact.normal may have: only its direction counts (it is divided by its length), and
#: squares of its entries must neither underflow nor overflow in float64 (so [0, 0, -1e-200] is refused).
NORMAL_LENGTHS = (1e-100, 1e100)


def _normal(value):
    """contact.normal: "body", or a nonzero vector of 2 or 3 finite numbers (made floats) whose length is in
    NORMAL_LENGTHS."""
    if value == "body":
        return value
    if not (isinstance(value, list) and 2 <= len(value) <= 3 and
            all(isinstance(c, (int, float)) and not isinstance(c, bool) and _finite(c) for c in value)):
        raise ValueError(f"contact.normal = {_show(value)}: expected \"body\" or a vector of 2 or 3 finite numbers, "
                         f"the foundation's outward direction seen from the body (e.g. [0, 0, -1])")
    vector = [float(c) for c in value]
    length = math.hypot(*vector)
    if not length > 0:
        raise ValueError(f"contact.normal = {_brief(vector)}: expected \"body\" or a nonzero vector (the "
                         f"foundation's outward direction seen from the body, e.g. [0, 0, -1])")
    if not NORMAL_LENGTHS[0] <= length <= NORMAL_LENGTHS[1]:
        raise ValueError(f"contact.normal = {_brief(vector)}: its length {length:.3g} is outside "
                         f"[{NORMAL_LENGTHS[0]:g}, {NORMAL_LENGTHS[1]:g}], where it is made a unit vector without "
                         f"underflow or overflow; give the direction with entries of order 1, e.g. [0, 0, -1]")
    return vector


#: The keys of one layer: stated in [contact] for one contact part, in each entry of contact.parts for several.
LAYER_KEYS = ("part", "g", "gap", "p", "exponent", "stiffness")
#: The keys of the whole contact, one value for all its parts.
GLOBAL_CONTACT_KEYS = ("rho", "probe", "normal")


class ContactPartSection(_Section):
    """One part of Γ3 with its own layer (an entry of contact.parts)."""

    part: Part
    g: Thickness
    gap: Expression = 0.0
    p: Literal["positive_part", "power"] = "positive_part"
    exponent: Optional[Exponent] = None
    stiffness: Stiffness

    @model_validator(mode="before")
    @classmethod
    def _no_global_key(cls, data):
        if isinstance(data, dict):
            for key in GLOBAL_CONTACT_KEYS:
                if key in data:
                    raise ValueError(f"{key} is one value for the whole contact, not a part's: state it once in "
                                     f"[contact] (contact.{key})")
        return data


class ContactSection(_Section):
    """The contact condition (2.5) on Γ3: soft layer of thickness g on a rigid base. Γ3 is one part
    (``part`` and its layer's keys here) or several (``parts``: a list of parts, each with its layer); a
    node where two parts meet takes the layer of the one listed first. rho, probe and normal are the
    whole contact's."""

    part: Optional[Part] = None
    g: Thickness = None
    gap: Optional[Expression] = None  # default 0 with part
    p: Optional[Literal["positive_part", "power"]] = None  # default "positive_part" with part
    exponent: Optional[Exponent] = None
    rho: NonNegativeFloat = 1.0
    probe: Optional[Annotated[list[float], Field(min_length=2, max_length=3)]] = None
    normal: Annotated[Any, AfterValidator(_normal)] = "body"
    stiffness: Optional[Stiffness] = None
    parts: Optional[Annotated[list[ContactPartSection], Field(min_length=1)]] = None

    @model_validator(mode="after")
    def _one_form(self, info: ValidationInfo):
        """One part or several; ``info.context["python_laws"]``: the laws (``p``, ``stiffness``) given as Python
        objects instead (vpcontact.compose), which the one-part form then leaves out."""
        python_laws = (info.context or {}).get("python_laws", ())
        if self.parts is None:
            self._one_part(python_laws)
        else:
            self._several_parts()
        for key, layer in self.layers():
            if layer.p == "power" and layer.exponent is None:
                raise ValueError(f"missing required value '{key}.exponent' (needed by {key}.p = \"power\")")
            if layer.p != "power" and layer.exponent is not None:
                raise ValueError(f"{key}.exponent is only used with {key}.p = \"power\" ({key}.p = \"{layer.p}\")")
        return self

    def _one_part(self, python_laws: Collection[str]) -> None:
        for key in ("part", "g", "stiffness"):
            if getattr(self, key) is None and key not in python_laws:
                hint = " (or contact.parts, a list of parts each with its layer)" if key == "part" else ""
                raise ValueError(f"missing required value 'contact.{key}'{hint}")
        self.gap = 0.0 if self.gap is None else self.gap
        if "p" not in python_laws:
            self.p = "positive_part" if self.p is None else self.p

    def _several_parts(self) -> None:
        given = [key for key in LAYER_KEYS if getattr(self, key) is not None]
        if given:
            raise ValueError(f"contact.{given[0]} is given with contact.parts: each entry of contact.parts states "
                             f"its own layer ({', '.join(LAYER_KEYS)}); move contact.{given[0]} into the entries")
        names = [str(entry.part) for entry in self.parts]
        for j, name in enumerate(names):
            if name in names[:j]:
                raise ValueError(f"contact.parts[{j}].part = {_show(name)} is also contact.parts[{names.index(name)}]"
                                 f".part: each part has one layer")

    def layers(self) -> list[tuple[str, "ContactSection | ContactPartSection"]]:
        """(key, layer) of each contact part, in order: ("contact", self) for one part, else
        ("contact.parts[j]", entry); a layer has the attributes part, g, gap, p, exponent, stiffness."""
        if self.parts is None:
            return [("contact", self)]
        return [(f"contact.parts[{j}]", entry) for j, entry in enumerate(self.parts)]


def check_time_span(start: float, T: float, steps: int, where: str) -> None:
    """ValueError unless t_0 = ``start`` (named ``where``) is before T by steps of a positive float64 length."""
    if not T > start:
        raise ValueError(f"time.T = {_brief(T)} must be > {where} = {_brief(start)}")
    if not (math.isfinite(T - start) and (T - start) / steps > 0):
        raise ValueError(f"{where} = {_brief(start)}: the steps (T - {where}) / time.steps are not positive finite "
                         f"numbers in float64")


class TimeSection(_Section):
    """[t_0, T] in ``steps`` equal steps k = (T − t_0) / steps; t_0 = ``start`` (default 0, or the time of
    the step a restart starts from, initial.from_run)."""

    T: PositiveFloat
    steps: Annotated[int, Field(ge=1, le=MAX_STEPS)]
    start: Optional[float] = None

    @model_validator(mode="after")
    def _start_before_end(self):
        if self.start is not None:
            check_time_span(self.start, self.T, self.steps, "time.start")
        return self


class SolverSection(_Section):
    """The step solver: "full" (Newton on the whole system), "condensed" (factor once, Newton on the
    contact nodes) or "auto" (condensed when its dense contact operator fits in memory)."""

    method: Literal["auto", "condensed", "full", "iterative"] = "auto"
    factorization: str = "auto"  # sparse direct backend of "condensed"
    tolerance: Annotated[float, Field(gt=0, lt=1)] = 1e-10
    max_iterations: Annotated[int, Field(ge=1)] = 50
    max_step_cuts: Annotated[int, Field(ge=0, le=30)] = 4  # halvings of a step whose Newton iteration fails
    augmentation: Optional[PositiveFloat] = None  # Alart–Curnier r; "auto": the median normal stiffness

    @field_validator("factorization")
    @classmethod
    def _installed_backend(cls, value):
        if value != "auto" and value not in installed_backends():
            known = "not installed here" if value in BACKENDS else "unknown"
            raise ValueError(f"solver.factorization = {_show(value)}: {known}; expected \"auto\" or one of "
                             f"{', '.join(repr(b) for b in installed_backends())}")
        return value

    @field_validator("augmentation", mode="before")
    @classmethod
    def _automatic(cls, value):
        return None if value == "auto" else value

    @model_validator(mode="after")
    def _factorization_used(self):
        if self.method == "iterative" and self.factorization != "auto":
            raise ValueError(f"solver.factorization = {_show(self.factorization)} is not used by solver.method = "
                             f"\"iterative\" (it factors nothing): remove it, or choose the method \"condensed\" "
                             f"or \"full\"")
        return self


class OutputSection(_Section):
    field_steps: Any = "final"  # "all", "final", "none" or a list of step numbers
    progress: bool = True
    checkpoint_every_steps: Annotated[int, Field(ge=0)] = 0  # 0: not by step count
    checkpoint_every_seconds: NonNegativeFloat = 60.0  # 0: not by time
    figures: bool = False  # figures/*.png at the end of a complete or failed run (vpcontact.results.plots)
    error_estimate: bool = False  # the residual error estimate at every step (vpcontact.estimate.residual)
    xdmf: bool = False  # fields/body.xdmf + body.h5 (contact too) beside the VTU files (vpcontact.io.xdmf)

    @field_validator("field_steps")
    @classmethod
    def _steps(cls, value):
        if value in ("all", "final", "none"):
            return value
        if isinstance(value, list) and all(isinstance(s, int) and not isinstance(s, bool) and s >= 1 for s in value):
            return sorted(set(value))
        raise ValueError(
            f"output.field_steps = {_brief(value)}: expected \"all\", \"final\", \"none\" or a list of step numbers >= 1"
        )


class AdaptSection(_Section):
    """Adaptive meshes (:mod:`vpcontact.estimate.adapt`): up to ``cycles`` solves of the whole history, each on the
    mesh refined from the one before by Dörfler marking (the fewest elements holding ``theta`` of the sum of
    the time functional of the indicators), none with more than ``max_dofs`` dofs."""

    cycles: Annotated[int, Field(ge=1)]
    theta: Annotated[float, Field(gt=0, le=1)] = 0.5
    max_dofs: Annotated[int, Field(gt=0)] = 1_000_000
    functional: Literal["max", "l2"] = "max"  # max over the steps of η_K²(t_n), or Σ_n k_n η_K²(t_n)
    estimator: Literal["residual", "recovery"] = "residual"  # the keys of vpcontact.estimate.adapt.ESTIMATORS


class Model(_Section):
    """The problem as a mechanician states it, without its mesh and without the settings of a run: the
    material(s), the boundary conditions, the contact condition, the initial state, the time grid and the
    solver options. A :class:`Case` is a Model with a mesh, outputs and adaptive meshes; a problem keeps
    its Model (``Problem.model``), so that it can be built again on another mesh. ``base_dir`` resolves
    relative file names (the case file's folder)."""

    material: Materials
    boundary: BoundarySection = BoundarySection()
    contact: Optional[ContactSection] = None
    initial: InitialSection = InitialSection()
    time: TimeSection
    solver: SolverSection = SolverSection()
    base_dir: Annotated[str, Field(exclude=True)] = "."

    @model_validator(mode="after")
    def _materials_by_region(self):
        """Admissible Poisson ratios; a list of materials: each entry names its regions, and all give one
        2D hypothesis."""
        for key, entry in _material_keys(self):
            entry.check_poisson_ratios(key)
        if isinstance(self.material, list):
            for i, entry in enumerate(self.material):
                if entry.region is None and len(self.material) > 1:
                    raise ValueError(f"material[{i}] has no region and there are {len(self.material)} materials: give "
                                     f"each its material[{i}].region (a region of the mesh, or a list of them)")
            hypotheses = {entry.hypothesis or "plane_strain" for entry in self.material}
            if len(hypotheses) > 1:
                raise ValueError(f"material: the entries give different hypotheses ({', '.join(sorted(hypotheses))}); "
                                 f"plane strain or plane stress is one assumption for the whole 2D body")
        return self

    @property
    def materials(self) -> list[MaterialSection]:
        """The material entries: the single ``[material]`` as a list of one."""
        return self.material if isinstance(self.material, list) else [self.material]

    @property
    def from_run_path(self) -> Path | None:
        """initial.from_run, relative to the case file's folder."""
        return None if self.initial.from_run is None else Path(self.base_dir) / self.initial.from_run


#: The sections of a case file, in the order case.resolved.toml lists them.
SECTIONS = ("mesh", "material", "boundary", "contact", "initial", "time", "solver", "output", "adapt")


class Case(Model):
    """A whole case: the :class:`Model`, its mesh (``[mesh]``), the run's outputs and adaptive meshes."""

    mesh: MeshSection
    output: OutputSection = OutputSection()
    adapt: Optional[AdaptSection] = None

    @property
    def model(self) -> Model:
        """The case without its mesh, outputs and adaptive meshes (the same section objects)."""
        return Model.model_construct(**{name: getattr(self, name) for name in Model.model_fields})

    @model_validator(mode="after")
    def _adapt_from_the_case_mesh(self):
        if self.adapt is not None and self.initial.from_run is not None:
            raise ValueError("[adapt] with initial.from_run: the fields a restart starts from are on the mesh of that "
                             "run, and the adaptive cycles solve on other meshes; remove one of them")
        return self

    @model_validator(mode="after")
    def _field_steps_in_range(self):
        steps = self.output.field_steps
        if isinstance(steps, list) and steps and steps[-1] > self.time.steps:
            raise ValueError(f"output.field_steps: step {_brief(steps[-1])} is after the last step ({self.time.steps})")
        return self

    @property
    def mesh_path(self) -> Path | None:
        return None if self.mesh.file is None else Path(self.base_dir) / self.mesh.file

    def resolved(self) -> dict:
        """Every value used, defaults included (the content of case.resolved.toml); a mesh file by its
        absolute path, so that the resolved case runs again from any folder (its run directory too)."""
        dumped = self.model_dump(mode="python", exclude_none=True)
        data = {name: dumped[name] for name in SECTIONS if name in dumped}
        if self.mesh.file is not None:
            data["mesh"]["file"] = os.path.abspath(self.mesh_path)
        if self.initial.from_run is not None:
            data["initial"]["from_run"] = os.path.abspath(self.from_run_path)
        return data

    def to_toml(self) -> str:
        return tomli_w.dumps(self.resolved())


# --- loading -------------------------------------------------------------------------------------
def load_case(source: str | Path | dict, overrides: dict | list[str] | None = None) -> Case:
    """Read and validate a case from a TOML file or a dict, after applying dotted-key overrides.

    ``overrides``: {"contact.stiffness.beta": -1} or ["contact.stiffness.beta=-1", ...] (values are
    TOML: ``-1``, ``"inf"``, ``[1, 2]``; a value that is not TOML is taken as a string).
    Whatever the input, the result is a Case or a CaseError with a one-line message.
    """
    try:
        return _load_case(source, overrides)
    except CaseError as error:
        raise CaseError(one_line(str(error))) from None


def _load_case(source, overrides) -> Case:
    base_dir = "."
    if isinstance(source, dict):
        data = plain(source)
        _check_tree(data)
    elif isinstance(source, (str, os.PathLike)):
        try:
            path = Path(source)
        except TypeError:
            raise CaseError(f"case file {_brief(source)}: not a file name") from None
        check_regular_file(path, "case file", MAX_TOML_BYTES)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise CaseError(f"case file '{path}' not found") from None
        except (OSError, UnicodeDecodeError, ValueError) as error:  # ValueError: a NUL in the name
            raise CaseError(f"case file '{path}' cannot be read: {error}") from None
        try:
            data = tomllib.loads(text)
        except ValueError as error:  # TOMLDecodeError, or an integer of more than 4300 digits
            raise CaseError(f"case file '{path}' is not valid TOML: {error}") from None
        except RecursionError:
            raise CaseError(f"case file '{path}' is not valid TOML: nested too deeply") from None
        _check_tree(data)
        base_dir = str(path.parent)
    else:
        raise CaseError(f"a case is a TOML file name or a table (dict), not {type(source).__name__}")
    for key, value in _parse_overrides(overrides).items():
        _check_tree(value, (key,))
        _set_dotted(data, key, value)
    if "base_dir" in data:
        raise CaseError("unknown key 'base_dir'")
    try:
        case = Case.model_validate({**data, "base_dir": base_dir})
    except ValidationError as error:
        raise CaseError(_describe(error.errors()[0])) from None
    _check_expressions(case)
    return case


#: Deepest nesting of tables and lists accepted in a case (a case needs 5).
MAX_NESTING = 32
_VALUE_TYPES = (str, bool, int, float, list, dict, datetime.date, datetime.time)  # what TOML holds


def _check_tree(data, prefix: tuple = ()) -> None:
    """Refuse what no TOML file holds before it reaches the validation: tables nested deeper than
    MAX_NESTING, keys that are not strings, values of other types (sets, bytes, objects).
    ``prefix``: where ``data`` sits in the case (an override's key)."""
    stack = [(data, prefix, 0)]
    while stack:
        value, path, depth = stack.pop()
        if depth > MAX_NESTING:
            raise CaseError(f"{_dotted(path[:4])}...: nested more than {MAX_NESTING} levels deep")
        if not isinstance(value, _VALUE_TYPES):
            raise CaseError(f"{_dotted(path) or 'the case'} = {_type_name(value)}: not a value a case file can hold "
                            f"(a number, string, boolean, list or table)")
        if isinstance(value, int) and value.bit_length() > 13000:  # Python cannot even print it (4300 digits)
            raise CaseError(f"{_dotted(path) or 'the case'} = {_brief(value)}: too large for any value of a case")
        if isinstance(value, dict):
            for key, item in value.items():
                if not isinstance(key, str):
                    raise CaseError(f"key {_type_name(key)} in {_dotted(path) or 'the case'}: keys must be strings")
                stack.append((item, (*path, key), depth + 1))
        elif isinstance(value, list):
            stack.extend((item, (*path, i), depth + 1) for i, item in enumerate(value))


def _type_name(value) -> str:
    """A value for a message without calling its repr (any object may be given)."""
    if isinstance(value, (int, float, str, bytes, type(None))):
        return _brief(value)
    return f"a value of type {type(value).__name__}"


#: The Python value a NumPy number of each kind is in a case (a complex number, a date: none, refused by key).
_PLAIN = {"b": bool, "i": int, "u": int, "f": float, "U": str}


def plain(value, depth: int = 0):
    """A copy of ``value`` (a case's table, list or value given from Python) holding the plain values a case
    file holds instead of NumPy's, through its tables (any mapping, made a dict) and lists: a NumPy number
    (``np.float32(1000)``, ``np.int64(10)``) and a 0-d array of one become the Python float or int,
    ``np.bool_`` a bool, ``np.str_`` a str, an array of one or more dimensions and a tuple the (nested) list
    of their values (``np.array([0, -1])`` -> ``[0, -1]``). Anything else is left as it is, for the
    validation to accept or refuse by its key (a complex number, an object): NaN and inf stay NaN and inf,
    refused where a finite number is wanted, and a NumPy bool is a bool, refused where a number is wanted.
    Below MAX_NESTING levels nothing is changed (:func:`_check_tree` refuses such nesting)."""
    if depth > MAX_NESTING:
        return value
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, np.generic):
        convert = _PLAIN.get(value.dtype.kind)
        return value if convert is None else convert(value)
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, Mapping):
        return {key: plain(item, depth + 1) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(item, depth + 1) for item in value]
    return value


def section(model: type[_Section], value, key: str):
    """The table ``value`` of the section [``key``] given from Python (an argument of the API) as its
    ``model`` (:class:`OutputSection`, :class:`AdaptSection`, ...): None its defaults, an instance of it as it
    is, a dict validated as the case file's table (NumPy values as numbers, see :func:`plain`); anything
    else, or a bad value in it, is a CaseError naming the key (``output.field_steps = ...``)."""
    if isinstance(value, model):
        return value
    if value is not None and not isinstance(value, Mapping):
        raise CaseError(f"{key} = {_brief(value)}: expected a table (dict) of the [{key}] keys (or a "
                        f"vpcontact.case.schema.{model.__name__})")
    data = plain(dict(value or {}))
    _check_tree(data, (key,))
    try:
        return model.model_validate(data)
    except ValidationError as error:
        first = error.errors()[0]
        raise CaseError(_describe({**first, "loc": (key, *first["loc"])})) from None


def _parse_overrides(overrides) -> dict:
    if overrides is None:
        return {}
    if isinstance(overrides, dict):
        for key in overrides:
            if not isinstance(key, str):
                raise CaseError(f"override key {_type_name(key)}: expected a dotted key such as contact.stiffness.beta")
        return {key: plain(value) for key, value in overrides.items()}
    if not isinstance(overrides, (list, tuple)):
        raise CaseError(f"overrides: expected a dict or a list of \"key=value\" strings, not {type(overrides).__name__}")
    parsed = {}
    for item in overrides:
        if not isinstance(item, str):
            raise CaseError(f"--set {_type_name(item)}: expected a \"key=value\" string")
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise CaseError(f"--set {_brief(item)}: expected key=value, e.g. contact.stiffness.beta=-1")
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except (ValueError, RecursionError):  # not TOML (or an integer of more than 4300 digits)
            value = text
        parsed[key.strip()] = value
    return parsed


_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


def _set_dotted(data: dict, dotted: str, value) -> None:
    """Set data[a][b][i][c] = value for the key "a.b[i].c", creating tables as needed."""
    steps: list[str | int] = []
    for piece in dotted.split("."):
        match = _KEY.match(piece)
        if match is None:
            raise CaseError(f"override key {_brief(dotted)} is not a dotted key such as contact.stiffness.beta")
        steps.append(match.group(1))
        steps += [int(i) if len(i) <= 18 else 10**18 for i in re.findall(r"\[(\d+)\]", match.group(2))]
    node = data
    for position, step in enumerate(steps[:-1]):
        if isinstance(step, int):
            if not isinstance(node, list) or step >= len(node):
                raise CaseError(f"override key {_brief(dotted)}: no entry [{step}] there")
            node = node[step]
        else:
            if not isinstance(node, dict):
                raise CaseError(f"override key {_brief(dotted)}: '{step}' is not inside a table")
            if step not in node and isinstance(steps[position + 1], int):
                raise CaseError(f"override key {_brief(dotted)}: no list '{step}' to index")
            node = node.setdefault(step, {})
    last = steps[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise CaseError(f"override key {_brief(dotted)}: no entry [{last}] there")
    elif not isinstance(node, dict):
        raise CaseError(f"override key {_brief(dotted)}: '{last}' is not inside a table")
    node[last] = value


def _check_expressions(case: Model) -> None:
    """Parse every expression once, so that a bad one is reported with its key before any work."""
    for i, traction in enumerate(case.boundary.traction):
        for c, value in enumerate(traction.value):
            parse_expression(value, ("x", "y", "z", "t"), where=f"boundary.traction[{i}].value[{c}]")
    for i, force in enumerate(case.boundary.body_force):
        for c, value in enumerate(force.value):
            parse_expression(value, ("x", "y", "z", "t"), where=f"boundary.body_force[{i}].value[{c}]")
    if case.contact is not None:
        for key, layer in case.contact.layers():
            parse_expression(layer.gap, ("x", "y", "z"), where=f"{key}.gap")
    for key, material in _material_keys(case):
        parse_expression(material.E, ("x", "y", "z"), where=f"{key}.E")
        parse_expression(material.nu, ("x", "y", "z"), where=f"{key}.nu")
    initial = case.initial
    for i, row in enumerate(initial.stress or ()):
        for j, value in enumerate(row):
            parse_expression(value, ("x", "y", "z"), where=f"initial.stress[{i}][{j}]")
    for i, value in enumerate(initial.displacement or ()):
        parse_expression(value, ("x", "y", "z"), where=f"initial.displacement[{i}]")
    if initial.xi is not None:
        parse_expression(initial.xi, ("x", "y", "z"), where="initial.xi")


def _material_keys(case: Model) -> list[tuple[str, MaterialSection]]:
    """(key, entry) of each material: "material" for the single table, "material[i]" in a list."""
    if isinstance(case.material, list):
        return [(f"material[{i}]", entry) for i, entry in enumerate(case.material)]
    return [("material", case.material)]


# --- error messages ------------------------------------------------------------------------------
_TYPE_WORDS = {
    "float_type": "expected a number",
    "int_type": "expected an integer",
    "string_type": "expected a string",
    "bool_type": "expected true or false",
    "list_type": "expected a list",
    "model_type": "expected a table",
    "dict_type": "expected a table",
    "model_attributes_type": "expected a table",
    "finite_number": "expected a finite number",
}
_STIFFNESS_TAGS = ("power", "constant", "exponential")
_VISCOPLASTIC_TAGS = ("perzyna", "relaxation")
_LAW_TAGS = {"stiffness": _STIFFNESS_TAGS, "viscoplastic": _VISCOPLASTIC_TAGS}  # tagged unions by section name
_FORM_TAGS = {"material": ("table", "list")}  # a section given as one table or a list of them


def _dotted(loc) -> str:
    text = ""
    for item in loc:
        text += f"[{item}]" if isinstance(item, int) else (f".{item}" if text else str(item))
    return text


def _clean_loc(loc) -> tuple:
    """Drop the discriminator tags pydantic inserts (contact.stiffness.power.beta -> contact.stiffness.beta,
    material.list.0.E -> material[0].E)."""
    cleaned = []
    for item in loc:
        tags = (*_LAW_TAGS.get(cleaned[-1], ()), *_FORM_TAGS.get(cleaned[-1], ())) if cleaned else ()
        if item in tags or (cleaned and cleaned[-1] in ("part", "region") and item in ("str", "int")):
            continue  # a law's or a form's tag, or the member of the union str | int of a part or region name
        cleaned.append(item)
    return tuple(cleaned)


def _describe(error: dict) -> str:
    loc = _clean_loc(error["loc"])
    key, kind, value = _dotted(loc), error["type"], error.get("input")
    ctx = error.get("ctx", {})
    if kind == "extra_forbidden":
        return _unknown_key(loc, _law_tag(error["loc"]))
    if kind == "missing":
        return f"missing required value '{key}'"
    if kind == "value_error":
        message = str(ctx.get("error", error["msg"]))
        if message.startswith("= "):  # "= <value>: ..." of a validator that does not know its key
            return f"{key} {message}"
        if key in ("", "mesh", "material", "contact", "output") or message.startswith(key):
            return message
        name = loc[-1] if loc else ""
        if isinstance(name, str) and message.startswith(f"{name} "):  # "g = 0: ..." of the key contact.parts[1].g
            return key + message[len(name):]
        return f"{key}: {message}"
    if kind in ("union_tag_invalid", "union_tag_not_found"):
        laws = ", ".join(f'"{t}"' for t in _LAW_TAGS.get(loc[-1] if loc else "", _STIFFNESS_TAGS))
        given = ctx.get("tag")
        if kind == "union_tag_not_found":
            return f"missing required value '{key}.law' (one of {laws})"
        return f"{key}.law = \"{given}\": unknown law; expected one of {laws}"
    if kind == "literal_error":
        return f"{key} = {_show(value)}: expected one of {ctx.get('expected')}"
    limits = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}
    if kind in limits:
        bound = next(iter(ctx.values()))
        return f"{key} = {_show(value)}: must be {limits[kind]} {bound}"
    if kind in ("too_short", "too_long"):
        bound = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        return (f"{key} = {_show(value)}: expected {'at least' if kind == 'too_short' else 'at most'} {bound} "
                f"value{'s' * (bound != 1)}")
    return f"{key} = {_show(value)}: {_TYPE_WORDS.get(kind, error['msg'])}"


def _show(value) -> str:
    """A value as a message shows it: strings in double quotes, control characters escaped, a long one
    cut (see :func:`~vpcontact.errors.quoted`)."""
    if isinstance(value, str):
        return quoted(value)
    if isinstance(value, dict):
        return "{...}"
    return _brief(value)


def _law_tag(raw_loc) -> str | None:
    """The law a tagged union was validated as (the last tag pydantic inserts after "stiffness" etc.)."""
    tags = [item for before, item in zip(raw_loc, raw_loc[1:]) if item in _LAW_TAGS.get(before, ())]
    return tags[-1] if tags else None


def _unknown_key(loc, law: str | None = None) -> str:
    valid = _valid_keys(loc[:-1], law)
    name = str(loc[-1])
    close = difflib.get_close_matches(name, valid, n=1)
    hint = f"did you mean '{_dotted((*loc[:-1], close[0]))}'?" if close else f"valid keys: {', '.join(valid)}"
    return f"unknown key '{shown(_dotted(loc))}' ({hint})"


def _valid_keys(loc, law: str | None = None) -> list[str]:
    """The keys allowed at ``loc`` (a path of section names and list indices); ``law`` picks the
    member of a tagged union of laws."""
    models = [Case]
    for item in loc:
        if isinstance(item, int):
            continue
        models = [inner for model in models if item in model.model_fields
                  for inner in _models_in(model.model_fields[item].annotation)]
    if law is not None and len(models) > 1:
        models = [model for model in models if law in typing.get_args(model.model_fields.get("law").annotation)] or models
    models = list(dict.fromkeys(models))  # a section given as a table or a list of them: one model
    keys = {k for model in models for k, f in model.model_fields.items() if not f.exclude}
    return sorted(keys)


def _models_in(annotation) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [model for arg in typing.get_args(annotation) for model in _models_in(arg)]
