"""Expressions of a case file, parsed once and evaluated vectorized with NumPy.

:func:`parse_expression` turns a case file's value, a number or a string such as ``"-1000*t"``, into an
:class:`Expression`: a callable that computes the value in float64 for arrays of coordinates and times
(what the text may contain, and how it is checked: :mod:`vpcontact.expressions.language`).
Floating-point warnings are not silenced here: a result may be ``inf`` or ``nan`` (``1/x`` at
``x = 0``, ``sqrt(-1)``) and the caller evaluates under ``np.errstate`` and checks finiteness where it
matters (the loads, the initial gap), reporting the expression and where it is not finite.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

import numpy as np

from ..errors import CaseError, shown
from .language import Compiler, Evaluator, check_variables

class Expression:
    """A parsed arithmetic expression in a fixed set of variables, evaluated with NumPy.

    Create one with :func:`parse_expression`. Calling it with the variables as keyword
    arguments (arrays or scalars) computes the expression elementwise in float64 and
    returns a new array of the broadcast shape of all the values passed, also when the
    expression uses only some of them or none (``"0"`` gives ``np.zeros(shape)``). When
    every value passed is a scalar (or nothing is passed), the result is a Python float.

    Equal expressions have the same source and variables. Pickling stores only
    ``source``, ``variables`` and ``where`` and parses the text again when loaded.
    """

    __slots__ = ("source", "variables", "where", "_evaluate", "_depends_on")
    #: The type of a value: Python floats for scalars, float64 arrays (a Condition's: bool).
    _scalar = float

    source: str
    variables: tuple[str, ...]
    where: str

    def __init__(
        self,
        source: str,
        variables: tuple[str, ...],
        where: str,
        evaluate: Evaluator,
        depends_on: frozenset[str],
    ) -> None:
        """Wrap an already checked and compiled expression (use :func:`parse_expression`)."""
        self.source = source
        self.variables = variables
        self.where = where
        self._evaluate = evaluate
        self._depends_on = depends_on

    @property
    def depends_on(self) -> frozenset[str]:
        """The variables that occur in the expression, e.g. ``{"t"}`` for ``"-1000*t"``."""
        return self._depends_on

    def __call__(self, **values: object) -> np.ndarray | float:
        """Compute the expression for the given variable values, broadcast together.

        Values for variables the expression does not use may be omitted; those that are
        given still take part in the broadcast shape. Passing a name that is not one of
        ``variables``, or omitting one the expression uses, is a TypeError.
        """
        arrays, shape = variable_values(self, values)
        result = self._evaluate(arrays)
        if shape == ():
            return self._scalar(result)
        out = np.empty(shape, dtype=self._scalar)
        out[...] = result
        return out

    def __reduce__(self) -> tuple[Callable[..., Expression], tuple[str, tuple[str, ...], str]]:
        """Pickle as the call ``parse_expression(source, variables, where)``."""
        return parse_expression, (self.source, self.variables, self.where)

    def __eq__(self, other: object) -> bool:
        """Expressions (conditions) are equal when their source text and variables are equal."""
        if type(other) is not type(self):
            return NotImplemented
        return (self.source, self.variables) == (other.source, other.variables)

    def __hash__(self) -> int:
        """Hash of the source text and variables (consistent with ``==``)."""
        return hash((self.source, self.variables))

    def __repr__(self) -> str:
        """``Expression('-1000*t', variables=('x', 'y', 't'))``."""
        return f"{type(self).__name__}({self.source!r}, variables={self.variables!r})"

    def __str__(self) -> str:
        """The source text."""
        return self.source


def variable_values(
    parsed: Expression, values: dict[str, object]
) -> tuple[dict[str, np.ndarray], tuple[int, ...]]:
    """The values passed to ``parsed`` (an Expression or a Condition) as float64 arrays and their broadcast shape.

    A name that is not one of its variables, or a missing value of one it uses, is a TypeError.
    """
    unknown = sorted(set(values) - set(parsed.variables))
    if unknown:
        raise TypeError(
            f"{parsed!r} got unknown variable(s) {', '.join(unknown)};"
            f" its variables are {', '.join(parsed.variables)}"
        )
    missing = [name for name in parsed.variables if name in parsed.depends_on and name not in values]
    if missing:
        raise TypeError(f"{parsed!r} needs a value for {', '.join(missing)}")
    arrays = {name: np.asarray(value, dtype=np.float64) for name, value in values.items()}
    return arrays, np.broadcast_shapes(*(array.shape for array in arrays.values()))


def parse_expression(
    source: str | int | float,
    variables: Iterable[str] = ("x", "y", "t"),
    where: str = "expression",
) -> Expression:
    """Check and compile an expression given as text or as a number.

    ``source`` is the text of the expression, or an int or float (as TOML gives
    numbers), which is turned into its repr. ``variables`` are the names the expression
    may use besides the constants ``pi`` and ``e``. ``where`` names the place in the case
    for error messages, e.g. ``"boundary.traction[0].value[1]"``.

    Raises CaseError with a one-line message ``<where> = <source>: <problem>`` for bad
    input: a type other than str/int/float (bool and None included), a non-finite
    number, an empty string, a syntax error, or anything outside the whitelist of
    :mod:`vpcontact.expressions.language`. Raises ValueError if ``variables`` themselves are invalid
    (not identifiers, repeated, or clashing with a function or constant name).
    """
    variables = check_variables(variables)
    text = _source_text(source, where)
    compiler = Compiler(text, variables, where)
    evaluate, depends_on = compiler.compile_source()
    return Expression(text, variables, where, evaluate, depends_on)


def values_at(source, where: str, points: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """The expression (or number) ``source`` of the case key ``where`` in the coordinates ``names`` (x, y[, z]) at
    ``points`` (d, k): k floats, not checked (a value that is not finite is for the caller to report)."""
    expression = parse_expression(source, names, where=where)
    with np.errstate(all="ignore"):
        return np.broadcast_to(expression(**dict(zip(names, points))), points.shape[1:]).astype(float)


def _source_text(source: object, where: str) -> str:
    """The text to parse for ``source``: a str as given, an int or float as its repr."""
    if isinstance(source, str):
        return source
    if isinstance(source, bool) or not isinstance(source, (int, float, np.integer, np.floating)):
        raise CaseError(
            f"{where} = {shown(' '.join(repr(source).split()))}: expected a number or an expression string,"
            f" got {type(source).__name__}"
        )
    try:
        value = float(source)
    except OverflowError:
        value = math.inf
    if math.isinf(value) and isinstance(source, (int, np.integer)):
        raise CaseError(f"{where}: integer out of the float64 range")
    if not math.isfinite(value):
        raise CaseError(f"{where} = {value!r}: not a finite number")
    if isinstance(source, (int, np.integer)):
        return repr(int(source))
    return repr(value)
