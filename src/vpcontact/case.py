"""The case description: the one place that knows the keys of a case file.

A case is a TOML file (or a dict) validated against the schema below; ``--set key=value``
overrides are applied to the raw data before validation. Every problem is reported as a
:class:`~vpcontact.errors.CaseError` with a one-line message naming the bad key and value.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
import typing
from pathlib import Path
from typing import Annotated, Any, Literal, Optional, Union

import tomli_w
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .errors import CaseError
from .expressions import parse_expression
from .solvers.factorization import BACKENDS, installed_backends

# --- value types ---------------------------------------------------------------------------------
PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]


def _expression_value(value):
    """An expression: a string (parsed later with its key in the message) or a number."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ValueError(f"expected an expression (a string such as \"-1000*t\") or a number, got {value!r}")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"expected a finite number, got {value!r}")
    return value


Expression = Annotated[Any, AfterValidator(_expression_value)]
Part = Union[str, int]


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


# --- sections ------------------------------------------------------------------------------------
class MeshSection(_Section):
    """A built-in shape of element size h, or a mesh file."""

    shape: Optional[Literal["half_disc", "rectangle"]] = None
    file: Optional[str] = None
    h: Optional[PositiveFloat] = None
    radius: Optional[PositiveFloat] = None  # half_disc, default 1
    width: Optional[PositiveFloat] = None  # rectangle, default 1
    height: Optional[PositiveFloat] = None  # rectangle, default 1

    @model_validator(mode="after")
    def _one_source(self):
        if (self.shape is None) == (self.file is None):
            raise ValueError("mesh: give exactly one of mesh.shape and mesh.file")
        if self.shape is not None and self.h is None:
            raise ValueError(f"missing required value 'mesh.h' (the element size of mesh.shape = \"{self.shape}\")")
        sizes = {"half_disc": ("radius",), "rectangle": ("width", "height"), None: ()}[self.shape]
        for key in ("h", "radius", "width", "height"):
            if key in sizes and getattr(self, key) is None:
                setattr(self, key, 1.0)
            elif key != "h" and key not in sizes and getattr(self, key) is not None:
                where = f"mesh.shape = \"{self.shape}\"" if self.shape else "mesh.file"
                raise ValueError(f"mesh.{key} is not used with {where}")
        if self.file is not None and self.h is not None:
            raise ValueError("mesh.h is not used with mesh.file (the file fixes the elements)")
        return self


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


def _check_poisson_ratio(key: str, nu: float, hypothesis: str) -> None:
    upper_ok = nu < 0.5 if hypothesis == "plane_strain" else nu <= 0.5
    if not (-1.0 < nu and upper_ok):
        bound = "< 0.5" if hypothesis == "plane_strain" else "<= 0.5"
        name = key.rpartition(".")[2]
        raise ValueError(f"{key} = {nu!r}: must satisfy -1 < {name} {bound} for {hypothesis}")


class MaterialSection(_Section):
    """Isotropic elasticity (4.1); plane strain (the paper's formula) or plane stress; optionally a
    viscoplastic law 𝒢 of (2.1) (none: 𝒢 = 0, linear elasticity)."""

    E: PositiveFloat
    nu: float
    hypothesis: Literal["plane_strain", "plane_stress"] = "plane_strain"
    viscoplastic: Optional[Viscoplastic] = None

    @model_validator(mode="after")
    def _admissible_poisson_ratio(self):
        _check_poisson_ratio("material.nu", self.nu, self.hypothesis)
        if isinstance(self.viscoplastic, RelaxationSection):
            _check_poisson_ratio("material.viscoplastic.nu_inf", self.viscoplastic.nu_inf, self.hypothesis)
        return self


def _stress_tensor(value):
    """A symmetric 2 × 2 tensor [[sxx, sxy], [sxy, syy]] of finite numbers."""
    if not (isinstance(value, list) and len(value) == 2
            and all(isinstance(row, list) and len(row) == 2 for row in value)):
        raise ValueError(f"initial.stress = {value!r}: expected a 2 x 2 table [[sxx, sxy], [sxy, syy]]")
    for row in value:
        for entry in row:
            if isinstance(entry, bool) or not isinstance(entry, (int, float)) or not math.isfinite(entry):
                raise ValueError(f"initial.stress = {value!r}: expected finite numbers, got {entry!r}")
    if value[0][1] != value[1][0]:
        raise ValueError(f"initial.stress = {value!r}: must be symmetric (stress[0][1] = {value[0][1]!r}, "
                         f"stress[1][0] = {value[1][0]!r})")
    return [[float(entry) for entry in row] for row in value]


class InitialSection(_Section):
    """Initial data (2.7): u_0 = 0 and a uniform initial stress σ_0 (default 0)."""

    stress: Annotated[Any, AfterValidator(_stress_tensor)] = [[0.0, 0.0], [0.0, 0.0]]


class DirichletSection(_Section):
    """u = 0 on a part, for the listed components (all when omitted)."""

    part: Part
    components: Optional[list[Literal["x", "y"]]] = None


class TractionSection(_Section):
    """σν = f2 on a part: one expression in x, y, t per component."""

    part: Part
    value: Annotated[list[Expression], Field(min_length=2, max_length=2)]


class BodyForceSection(_Section):
    """f0 in Ω: one expression in x, y, t per component."""

    value: Annotated[list[Expression], Field(min_length=2, max_length=2)]


class BoundarySection(_Section):
    dirichlet: list[DirichletSection] = []
    traction: list[TractionSection] = []
    body_force: list[BodyForceSection] = []


class PowerStiffnessSection(_Section):
    """K(ξ) = c_v (1 + α ξ)^β (the paper's law)."""

    law: Literal["power"]
    c_v: NonNegativeFloat
    alpha: NonNegativeFloat
    beta: float


class ConstantStiffnessSection(_Section):
    """K(ξ) = value; 0 gives the Signorini condition with gap g."""

    law: Literal["constant"]
    value: NonNegativeFloat


class ExponentialStiffnessSection(_Section):
    """K(ξ) = c_v exp(α ξ)."""

    law: Literal["exponential"]
    c_v: NonNegativeFloat
    alpha: float


Stiffness = Annotated[
    Union[PowerStiffnessSection, ConstantStiffnessSection, ExponentialStiffnessSection], Field(discriminator="law")
]


class ContactSection(_Section):
    """The contact condition (2.5) on a part: soft layer of thickness g on a rigid base."""

    part: Part
    g: Annotated[float, Field(gt=0, allow_inf_nan=True)]
    gap: Expression = 0.0
    p: Literal["positive_part", "power"] = "positive_part"
    exponent: Optional[Annotated[float, Field(ge=1)]] = None
    rho: NonNegativeFloat = 1.0
    probe: Optional[Annotated[list[float], Field(min_length=2, max_length=2)]] = None
    stiffness: Stiffness

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
    steps: Annotated[int, Field(ge=1)]


class SolverSection(_Section):
    """The step solver: "full" (Newton on the whole system), "condensed" (factor once, Newton on the
    contact nodes) or "auto" (condensed when its dense contact operator fits in memory)."""

    method: Literal["auto", "condensed", "full"] = "auto"
    factorization: str = "auto"  # sparse direct backend of "condensed"
    tolerance: Annotated[float, Field(gt=0, lt=1)] = 1e-10
    max_iterations: Annotated[int, Field(ge=1)] = 50
    augmentation: Optional[PositiveFloat] = None  # Alart–Curnier r; "auto": the median normal stiffness

    @field_validator("factorization")
    @classmethod
    def _installed_backend(cls, value):
        if value != "auto" and value not in installed_backends():
            known = "not installed here" if value in BACKENDS else "unknown"
            raise ValueError(f"solver.factorization = \"{value}\": {known}; expected \"auto\" or one of "
                             f"{', '.join(repr(b) for b in installed_backends())}")
        return value

    @field_validator("augmentation", mode="before")
    @classmethod
    def _automatic(cls, value):
        return None if value == "auto" else value


class OutputSection(_Section):
    field_steps: Any = "final"  # "all", "final", "none" or a list of step numbers
    progress: bool = True

    @field_validator("field_steps")
    @classmethod
    def _steps(cls, value):
        if value in ("all", "final", "none"):
            return value
        if isinstance(value, list) and all(isinstance(s, int) and not isinstance(s, bool) and s >= 1 for s in value):
            return sorted(set(value))
        raise ValueError(
            f"output.field_steps = {value!r}: expected \"all\", \"final\", \"none\" or a list of step numbers >= 1"
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
            raise ValueError(f"output.field_steps: step {steps[-1]} is after the last step ({self.time.steps})")
        return self

    @property
    def mesh_path(self) -> Path | None:
        return None if self.mesh.file is None else Path(self.base_dir) / self.mesh.file

    def resolved(self) -> dict:
        """Every value used, defaults included (the content of case.resolved.toml)."""
        return self.model_dump(mode="python", exclude_none=True)

    def to_toml(self) -> str:
        return tomli_w.dumps(self.resolved())


# --- loading -------------------------------------------------------------------------------------
def load_case(source: str | Path | dict, overrides: dict | list[str] | None = None) -> Case:
    """Read and validate a case from a TOML file or a dict, after applying dotted-key overrides.

    ``overrides``: {"contact.stiffness.beta": -1} or ["contact.stiffness.beta=-1", ...] (values are
    TOML: ``-1``, ``"inf"``, ``[1, 2]``; a value that is not TOML is taken as a string).
    """
    base_dir = "."
    if isinstance(source, dict):
        data = _deep_copy(source)
    else:
        path = Path(source)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise CaseError(f"case file '{path}' not found") from None
        except (OSError, UnicodeDecodeError) as error:
            raise CaseError(f"case file '{path}' cannot be read: {error}") from None
        except tomllib.TOMLDecodeError as error:
            raise CaseError(f"case file '{path}' is not valid TOML: {error}") from None
        base_dir = str(path.parent)
    for key, value in _parse_overrides(overrides).items():
        _set_dotted(data, key, value)
    if "base_dir" in data:
        raise CaseError("unknown key 'base_dir'")
    try:
        case = Case.model_validate({**data, "base_dir": base_dir})
    except ValidationError as error:
        raise CaseError(_describe(error.errors()[0])) from None
    _check_expressions(case)
    return case


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
        return dict(overrides)
    parsed = {}
    for item in overrides:
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise CaseError(f"--set {item!r}: expected key=value, e.g. contact.stiffness.beta=-1")
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
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
            raise CaseError(f"override key {dotted!r} is not a dotted key such as contact.stiffness.beta")
        steps.append(match.group(1))
        steps += [int(i) for i in re.findall(r"\[(\d+)\]", match.group(2))]
    node = data
    for position, step in enumerate(steps[:-1]):
        if isinstance(step, int):
            if not isinstance(node, list) or step >= len(node):
                raise CaseError(f"override key {dotted!r}: no entry [{step}] there")
            node = node[step]
        else:
            if not isinstance(node, dict):
                raise CaseError(f"override key {dotted!r}: '{step}' is not inside a table")
            if step not in node and isinstance(steps[position + 1], int):
                raise CaseError(f"override key {dotted!r}: no list '{step}' to index")
            node = node.setdefault(step, {})
    last = steps[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise CaseError(f"override key {dotted!r}: no entry [{last}] there")
    elif not isinstance(node, dict):
        raise CaseError(f"override key {dotted!r}: '{last}' is not inside a table")
    node[last] = value


def _check_expressions(case: Case) -> None:
    """Parse every expression once, so that a bad one is reported with its key before any work."""
    for i, traction in enumerate(case.boundary.traction):
        for c, value in enumerate(traction.value):
            parse_expression(value, ("x", "y", "t"), where=f"boundary.traction[{i}].value[{c}]")
    for i, force in enumerate(case.boundary.body_force):
        for c, value in enumerate(force.value):
            parse_expression(value, ("x", "y", "t"), where=f"boundary.body_force[{i}].value[{c}]")
    if case.contact is not None:
        parse_expression(case.contact.gap, ("x", "y"), where="contact.gap")


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
        if cleaned and item in _LAW_TAGS.get(cleaned[-1], ()):
            continue
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
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, dict):
        return "{...}"
    return repr(value)


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
    return f"unknown key '{_dotted(loc)}' ({hint})"


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
