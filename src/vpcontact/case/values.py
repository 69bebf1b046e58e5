"""The values of a case file and their checks: numbers, expressions, part names, the layer's parameters.

Each is a pydantic annotated type used by the sections (:mod:`vpcontact.case.material`, ...); a bad value is a
ValueError whose message :mod:`vpcontact.case.messages` turns into one line naming its key.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Union

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field

from ..errors import brief, quoted


#: Most time steps and (estimated) triangles of a built-in shape a case may ask for: beyond, the run
#: could not even allocate its arrays.
MAX_STEPS = 10**8
MAX_ELEMENTS = 10**9


def finite(number) -> bool:
    """Is an int or float a finite float64 (an int beyond 1.8e308 is not)?"""
    try:
        return math.isfinite(float(number))
    except OverflowError:
        return False


PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]


def _expression_value(value):
    """An expression: a string (parsed later with its key in the message) or a number."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ValueError(f"expected an expression (a string such as \"-1000*t\") or a number, got {brief(value)}")
    if isinstance(value, (int, float)) and not finite(value):  # an int too, beyond float64's range
        raise ValueError(f"expected a finite number, got {brief(value)}")
    return value


Expression = Annotated[Any, AfterValidator(_expression_value)]
Part = Union[str, int]


def layer_value(minimum: float | None = None, strict: bool = False):
    """A parameter of the layer's laws (K(x, ξ) of (2.18), p(x, r) of (2.19): they may vary along Γ3): a number (at
    least ``minimum`` when given, more than it when ``strict``) or an expression in the coordinates, evaluated at
    the contact nodes (its values there are checked against ``minimum`` when the problem is built)."""

    def check(value):
        value = _expression_value(value)
        if isinstance(value, (int, float)) and minimum is not None and not (value > minimum if strict else
                                                                             value >= minimum):
            raise ValueError(f"expected a number {'>' if strict else '>='} {minimum:g} or an expression in the "
                             f"coordinates, got {brief(value)}")
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
        raise ValueError(f"g = {brief(value)}: must be > 0 (a number, \"inf\" or an expression in the "
                         f"coordinates)")
    if isinstance(value, int) and not finite(value):
        raise ValueError(f"g = {brief(value)}: beyond the range of float64; \"inf\" is a layer without rigid base")
    return value


Thickness = Annotated[Any, BeforeValidator(_infinite), AfterValidator(_thickness)]


class Section(BaseModel):
    """A table of a case file: unknown keys refused, values of the stated types only (no conversion), finite numbers."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


def show(value) -> str:
    """A value as a message shows it: strings in double quotes, control characters escaped, a long one
    cut (see :func:`~vpcontact.errors.quoted`)."""
    if isinstance(value, str):
        return quoted(value)
    if isinstance(value, dict):
        return "{...}"
    return brief(value)
