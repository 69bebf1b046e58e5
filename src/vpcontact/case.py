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
from pathlib import Path
from typing import Annotated, Any, Literal, Optional, Union

import tomli_w
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .errors import CaseError, quoted, shown
from .expressions import parse_expression
from .inputs import MAX_TOML_BYTES, check_regular_file
from .solvers.factorization import BACKENDS, installed_backends
from .space import CELLS

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
    return shown(text)


PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]


def _expression_value(value):
    """An expression: a string (parsed later with its key in the message) or a number."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ValueError(f"expected an expression (a string such as \"-1000*t\") or a number, got {_brief(value)}")
    if isinstance(value, float) and not math.isfinite(value):
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


def _thickness(value):
    """contact.g: a number > 0, inf (no rigid base: classical normal compliance), or an expression in the
    coordinates (a thickness that varies along Γ3, checked > 0 at the contact nodes)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise ValueError(f"contact.g = {_brief(value)}: must be > 0 (a number, \"inf\" or an expression in the "
                         f"coordinates)")
    return value


#: Layer parameters that may vary along Γ3 (the paper's K(x, ξ), (2.18)).
NonNegativeLayerValue = _layer_value(0.0)
LayerValue = _layer_value(None)


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
                raise ValueError(f"mesh.h = {_brief(self.h)}: about {elements:.1e} {CELLS[dim][2]} for this "
                                 f"{self.shape}, more than {MAX_ELEMENTS:.0e}")
        return self

    def _elements(self, dim: int) -> float:
        """About how many elements the shape has at size h (no ** : 1e300**2 raises OverflowError)."""
        if self.shape == "quarter_ball":
            from .ball import estimated_tetrahedra

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


class MaterialSection(_Section):
    """Isotropic elasticity (4.1); in 2D plane strain (the paper's formula, the default) or plane
    stress, in 3D the full tensor (no hypothesis); optionally a viscoplastic law 𝒢 of (2.1) (none:
    𝒢 = 0, linear elasticity)."""

    E: PositiveFloat
    nu: float
    hypothesis: Optional[Literal["plane_strain", "plane_stress"]] = None  # 2D only; None: plane strain in 2D
    viscoplastic: Optional[Viscoplastic] = None

    @model_validator(mode="after")
    def _admissible_poisson_ratio(self):
        _check_poisson_ratio("material.nu", self.nu, self.hypothesis)
        if isinstance(self.viscoplastic, RelaxationSection):
            _check_poisson_ratio("material.viscoplastic.nu_inf", self.viscoplastic.nu_inf, self.hypothesis)
        return self


def _stress_tensor(value):
    """A symmetric d × d tensor (d = 2 or 3) of finite numbers, e.g. [[sxx, sxy], [sxy, syy]]."""
    if not (isinstance(value, list) and len(value) in (2, 3)
            and all(isinstance(row, list) and len(row) == len(value) for row in value)):
        raise ValueError(f"initial.stress = {_brief(value)}: expected a d x d table, [[sxx, sxy], [sxy, syy]] in 2D "
                         f"or [[sxx, sxy, sxz], [sxy, syy, syz], [sxz, syz, szz]] in 3D")
    for row in value:
        for entry in row:
            if isinstance(entry, bool) or not isinstance(entry, (int, float)) or not _finite(entry):
                raise ValueError(f"initial.stress = {_brief(value)}: expected finite numbers, got {_brief(entry)}")
    for i in range(len(value)):
        for j in range(i + 1, len(value)):
            if value[i][j] != value[j][i]:
                raise ValueError(f"initial.stress = {_brief(value)}: must be symmetric (stress[{i}][{j}] = "
                                 f"{_brief(value[i][j])}, stress[{j}][{i}] = {_brief(value[j][i])})")
    return [[float(entry) for entry in row] for row in value]


class InitialSection(_Section):
    """Initial data (2.7): u_0 = 0 and a uniform initial stress σ_0 (default 0; d × d)."""

    stress: Optional[Annotated[Any, AfterValidator(_stress_tensor)]] = None


class DirichletSection(_Section):
    """u = 0 on a part, for the listed components (all when omitted)."""

    part: Part
    components: Optional[list[Literal["x", "y", "z"]]] = None


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


class ContactSection(_Section):
    """The contact condition (2.5) on a part: soft layer of thickness g on a rigid base."""

    part: Part
    g: Annotated[Any, AfterValidator(_thickness)]
    gap: Expression = 0.0
    p: Literal["positive_part", "power"] = "positive_part"
    exponent: Optional[Annotated[float, Field(ge=1)]] = None
    rho: NonNegativeFloat = 1.0
    probe: Optional[Annotated[list[float], Field(min_length=2, max_length=3)]] = None
    normal: Union[Literal["body"], Annotated[list[float], Field(min_length=2, max_length=3)]] = "body"
    stiffness: Stiffness

    @field_validator("normal")
    @classmethod
    def _direction(cls, value):
        if isinstance(value, list) and not math.hypot(*value) > 0:
            raise ValueError(f"contact.normal = {_brief(value)}: expected \"body\" or a nonzero vector (the "
                             f"foundation's outward direction seen from the body, e.g. [0, 0, -1])")
        return value

    @field_validator("g", mode="before")
    @classmethod
    def _infinite_layer(cls, value):
        if isinstance(value, str) and value.strip().lower() in ("inf", "infinity"):
            return math.inf
        if isinstance(value, float) and math.isnan(value):
            raise ValueError("contact.g = nan: expected a positive number or \"inf\"")
        return value

    @model_validator(mode="after")
    def _exponent_with_power(self):
        if self.p == "power" and self.exponent is None:
            raise ValueError("missing required value 'contact.exponent' (needed by contact.p = \"power\")")
        if self.p != "power" and self.exponent is not None:
            raise ValueError(f"contact.exponent is only used with contact.p = \"power\" (contact.p = \"{self.p}\")")
        return self


class TimeSection(_Section):
    """[0, T] in ``steps`` equal steps k = T / steps."""

    T: PositiveFloat
    steps: Annotated[int, Field(ge=1, le=MAX_STEPS)]


class SolverSection(_Section):
    """The step solver: "full" (Newton on the whole system), "condensed" (factor once, Newton on the
    contact nodes) or "auto" (condensed when its dense contact operator fits in memory)."""

    method: Literal["auto", "condensed", "full"] = "auto"
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


class OutputSection(_Section):
    field_steps: Any = "final"  # "all", "final", "none" or a list of step numbers
    progress: bool = True
    checkpoint_every_steps: Annotated[int, Field(ge=0)] = 0  # 0: not by step count
    checkpoint_every_seconds: NonNegativeFloat = 60.0  # 0: not by time
    figures: bool = False  # figures/*.png at the end of a complete or failed run (vpcontact.plots)

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


class Case(_Section):
    """A whole case; ``base_dir`` resolves relative file names (the case file's folder)."""

    mesh: MeshSection
    material: MaterialSection
    boundary: BoundarySection = BoundarySection()
    contact: Optional[ContactSection] = None
    initial: InitialSection = InitialSection()
    time: TimeSection
    solver: SolverSection = SolverSection()
    output: OutputSection = OutputSection()
    base_dir: Annotated[str, Field(exclude=True)] = "."

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
        data = self.model_dump(mode="python", exclude_none=True)
        if self.mesh.file is not None:
            data["mesh"]["file"] = os.path.abspath(self.mesh_path)
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


#: Longest message of a refusal (the command line cuts longer ones): a user's values are shown
#: shortened (errors.shown), so this cuts only the explanations of the longest mesh diagnoses.
LONGEST_MESSAGE = 800


def one_line(message: str) -> str:
    """The message on one line: control and separator characters escaped, at most LONGEST_MESSAGE long."""
    text = "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in message)
    return text if len(text) <= LONGEST_MESSAGE else text[: LONGEST_MESSAGE - 3] + "..."


def _load_case(source, overrides) -> Case:
    base_dir = "."
    if isinstance(source, dict):
        _check_tree(source)
        data = _deep_copy(source)
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


def _deep_copy(data):
    if isinstance(data, dict):
        return {k: _deep_copy(v) for k, v in data.items()}
    if isinstance(data, list):
        return [_deep_copy(v) for v in data]
    return data


def _parse_overrides(overrides) -> dict:
    if overrides is None:
        return {}
    if isinstance(overrides, dict):
        for key in overrides:
            if not isinstance(key, str):
                raise CaseError(f"override key {_type_name(key)}: expected a dotted key such as contact.stiffness.beta")
        return dict(overrides)
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


def _check_expressions(case: Case) -> None:
    """Parse every expression once, so that a bad one is reported with its key before any work."""
    for i, traction in enumerate(case.boundary.traction):
        for c, value in enumerate(traction.value):
            parse_expression(value, ("x", "y", "z", "t"), where=f"boundary.traction[{i}].value[{c}]")
    for i, force in enumerate(case.boundary.body_force):
        for c, value in enumerate(force.value):
            parse_expression(value, ("x", "y", "z", "t"), where=f"boundary.body_force[{i}].value[{c}]")
    if case.contact is not None:
        parse_expression(case.contact.gap, ("x", "y", "z"), where="contact.gap")


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


def _dotted(loc) -> str:
    text = ""
    for item in loc:
        text += f"[{item}]" if isinstance(item, int) else (f".{item}" if text else str(item))
    return text


def _clean_loc(loc) -> tuple:
    """Drop the discriminator tags pydantic inserts (contact.stiffness.power.beta -> contact.stiffness.beta)."""
    cleaned = []
    for item in loc:
        if cleaned and (item in _LAW_TAGS.get(cleaned[-1], ()) or (cleaned[-1] == "part" and item in ("str", "int"))):
            continue  # a law's tag, or the member of the union str | int of a part name
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
        return message if key in ("", "mesh", "material", "contact", "output") or message.startswith(key) else f"{key}: {message}"
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
        return f"{key} = {_show(value)}: expected {ctx.get('min_length', ctx.get('max_length'))} values"
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
    """The law a tagged union was validated as (the tag pydantic inserts after "stiffness" etc.)."""
    for before, item in zip(raw_loc, raw_loc[1:]):
        if item in _LAW_TAGS.get(before, ()):
            return item
    return None


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
    keys = {k for model in models for k, f in model.model_fields.items() if not f.exclude}
    return sorted(keys)


def _models_in(annotation) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [model for arg in typing.get_args(annotation) for model in _models_in(arg)]
