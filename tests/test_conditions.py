"""Tests of vpcontact.expressions.conditions: values against Python's and NumPy's own comparisons, NaN,
broadcasting, pickling, refusals."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from vpcontact.errors import CaseError
from vpcontact.expressions.conditions import Condition, parse_condition
from vpcontact.expressions.parse import parse_expression

XYZ = ("x", "y", "z")
WHERE = "boundary.dirichlet[2].where"
RNG = np.random.default_rng(28)
# small integers as floats: equalities and ties in chains happen often
X, Y, Z = (RNG.integers(-3, 4, size=400).astype(float) for _ in range(3))


def rejection(source: object, variables=XYZ) -> str:
    """The message of the CaseError raised when parsing the condition ``source`` at WHERE."""
    with pytest.raises(CaseError) as info:
        parse_condition(source, variables, where=WHERE)
    message = str(info.value)
    assert "\n" not in message
    return message


def python_values(source: str, x, y, z) -> np.ndarray:
    """The condition computed point by point by Python itself (its precedence, chains, and/or/not): the
    independent reference; valid where no value is NaN (Python's nan != 1 is True)."""
    names = {"abs": abs, "sqrt": math.sqrt, "min": min, "max": max, "pi": math.pi}
    code = compile(source, "<condition>", "eval")
    return np.array([bool(eval(code, {"__builtins__": {}}, {**names, "x": a, "y": b, "z": c}))
                     for a, b, c in zip(x.tolist(), y.tolist(), z.tolist())])


# --- values ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("x < y", lambda x, y, z: np.less(x, y)),
        ("x <= y", lambda x, y, z: np.less_equal(x, y)),
        ("x > y", lambda x, y, z: np.greater(x, y)),
        ("x >= y", lambda x, y, z: np.greater_equal(x, y)),
        ("x == y", lambda x, y, z: np.equal(x, y)),
        ("x != y", lambda x, y, z: np.not_equal(x, y)),
        ("0 <= x <= 1", lambda x, y, z: (0 <= x) & (x <= 1)),
        ("x < y < z", lambda x, y, z: (x < y) & (y < z)),
        ("x < y > z", lambda x, y, z: (x < y) & (y > z)),
        ("-1 < x <= y != z", lambda x, y, z: (-1 < x) & (x <= y) & (y != z)),
        ("abs(z - 1) < 1e-9", lambda x, y, z: np.abs(z - 1) < 1e-9),
        ("x**2 + y**2 <= 4 and z > 0", lambda x, y, z: (x**2 + y**2 <= 4) & (z > 0)),
        ("x < 0 or y < 0 and z < 0", lambda x, y, z: (x < 0) | ((y < 0) & (z < 0))),
        ("(x < 0 or y < 0) and z < 0", lambda x, y, z: ((x < 0) | (y < 0)) & (z < 0)),
        ("not x < 0 and y < 0", lambda x, y, z: ~(x < 0) & (y < 0)),
        ("not (x < 0 and y < 0)", lambda x, y, z: ~((x < 0) & (y < 0))),
        ("not not x == 1", lambda x, y, z: x == 1),
        ("max(x, y) >= 2*pi - 5", lambda x, y, z: np.maximum(x, y) >= 2 * np.pi - 5),
    ],
)
def test_values_match_numpy(source, expected):
    held = parse_condition(source, XYZ)(x=X, y=Y, z=Z)
    assert held.dtype == np.bool_ and held.shape == X.shape
    np.testing.assert_array_equal(held, expected(X, Y, Z))
    assert 0 < held.sum() < held.size  # the points test both outcomes


ATOMS = ("x < y", "x <= 1", "0 <= x < y", "y == z", "x + y != 1", "abs(z) >= 2", "x*y > -2", "-1 < z <= x != y",
         "sqrt(x**2 + y**2) < 2", "min(x, z) == max(y, -1)", "x > pi - 4")


def random_condition(rng: np.random.Generator, depth: int) -> str:
    """A random condition of ATOMS joined by and/or/not, parenthesized or not (precedence decides)."""
    if depth == 0 or rng.random() < 0.25:
        return ATOMS[rng.integers(len(ATOMS))]
    parts = [random_condition(rng, depth - 1) for _ in range(rng.integers(2, 4))]
    parts = [f"not {part}" if rng.random() < 0.3 else part for part in parts]
    text = parts[0] + "".join(f" {('and', 'or')[rng.integers(2)]} {part}" for part in parts[1:])
    return f"({text})" if rng.random() < 0.5 else text


def test_random_conditions_agree_with_python_point_by_point():
    """Python evaluates every condition at every point with its own precedence of not/and/or and its chains."""
    rng = np.random.default_rng(1)
    x, y, z = X[:60], Y[:60], Z[:60]
    sources = {random_condition(rng, 3) for _ in range(150)}
    assert len(sources) > 100 and any("not" in source for source in sources)
    for source in sources:
        np.testing.assert_array_equal(parse_condition(source, XYZ)(x=x, y=y, z=z), python_values(source, x, y, z),
                                      err_msg=source)


def test_nan_fails_every_comparison_and_not_negates():
    x = np.array([-4.0, 0.0, 1.0, 4.0])  # sqrt(-4) is NaN
    with np.errstate(invalid="ignore"):
        held = {source: parse_condition(source, XYZ)(x=x) for source in (
            "sqrt(x) < 1", "sqrt(x) >= 1", "sqrt(x) == sqrt(x)", "sqrt(x) != 1", "sqrt(x) != sqrt(x)",
            "not sqrt(x) < 1", "-1 < sqrt(x) < 5", "sqrt(x) < 1 or x < 0")}
    assert held["sqrt(x) < 1"].tolist() == [False, True, False, False]
    assert held["sqrt(x) >= 1"].tolist() == [False, False, True, True]
    assert held["sqrt(x) == sqrt(x)"].tolist() == [False, True, True, True]
    assert held["sqrt(x) != 1"].tolist() == [False, True, False, True]
    assert held["sqrt(x) != sqrt(x)"].tolist() == [False] * 4
    assert held["not sqrt(x) < 1"].tolist() == [True, False, True, True]
    assert held["-1 < sqrt(x) < 5"].tolist() == [False, True, True, True]
    assert held["sqrt(x) < 1 or x < 0"].tolist() == [True, True, False, False]


def test_infinity_compares_as_a_number():
    with np.errstate(divide="ignore"):
        held = parse_condition("1/x > 1e300", ("x",))(x=np.array([0.0, -0.0, 1.0]))
    assert held.tolist() == [True, False, False]


def test_broadcasting_scalars_and_unused_variables():
    condition = parse_condition("x < y", XYZ)
    held = condition(x=np.arange(3.0)[:, None], y=np.array([0.0, 1.0, 2.0, 3.0]), z=0.0)
    assert held.shape == (3, 4)
    np.testing.assert_array_equal(held, np.arange(3.0)[:, None] < np.arange(4.0))
    assert condition(x=1, y=2) is True and condition(x=2, y=1) is False
    constant = parse_condition("pi > 3", XYZ)
    assert constant.depends_on == frozenset()
    assert constant(x=np.zeros(5)).tolist() == [True] * 5 and constant() is True
    assert parse_condition("z == 0.5", XYZ)(x=np.zeros((2, 3)), z=0.5).shape == (2, 3)
    assert parse_condition("0 <= x <= 1 or z > y", XYZ).depends_on == frozenset(XYZ)


def test_an_unknown_or_missing_variable_is_a_type_error():
    condition = parse_condition("x < y", XYZ)
    with pytest.raises(TypeError, match="unknown variable"):
        condition(x=1, y=1, t=0)
    with pytest.raises(TypeError, match="needs a value for y"):
        condition(x=1)
    with pytest.raises(ValueError, match="clashes"):
        parse_condition("x < 1", ("x", "pi"))


def test_pickle_equality_and_text():
    condition = parse_condition("abs(z - 0.02) < 1e-9 and x >= 0", XYZ, where=WHERE)
    loaded = pickle.loads(pickle.dumps(condition))
    assert isinstance(loaded, Condition) and loaded == condition and hash(loaded) == hash(condition)
    assert loaded.where == WHERE and loaded.variables == XYZ
    z = np.array([0.02, 0.02 + 1e-8, 0.02])
    np.testing.assert_array_equal(loaded(x=np.array([0.0, 0.0, -1.0]), z=z), [True, False, False])
    assert str(condition) == "abs(z - 0.02) < 1e-9 and x >= 0"
    assert repr(condition) == "Condition('abs(z - 0.02) < 1e-9 and x >= 0', variables=('x', 'y', 'z'))"
    assert condition != parse_condition("abs(z - 0.02) < 1e-9 and x >= 0", ("z", "x"))
    assert condition != parse_expression("x", XYZ)


# --- refusals -------------------------------------------------------------------------


def test_a_value_that_is_no_condition_names_the_key_and_gives_an_example():
    assert rejection("x + 1") == (f'{WHERE} = "x + 1": not a condition; expected a comparison such as '
                                  f'"abs(z - 0.02) < 1e-9" (combined with and, or, not)')


@pytest.mark.parametrize(
    ("source", "problem"),
    [
        ("abs(z - 0.02)", "not a condition; expected a comparison such as"),
        ("x", "not a condition; expected"),
        ("1", "not a condition; expected"),
        ("x < 1 and y", "'y' is not a condition; each side of and, or and what follows not is a comparison"),
        ("not x", "'x' is not a condition"),
        ("x < 1 or 2", "'2' is not a condition"),
        ("(x < 1) == (y < 1)", "'x < 1' is a condition where a number is expected"),
        ("x + (y < 1) > 0", "'y < 1' is a condition where a number is expected"),
        ("abs(x < 1) > 0", "'x < 1' is a condition where a number is expected"),
        ("x < 1 & y < 2", "operator '&' is not allowed; combine conditions with and, or, not (write and for &)"),
        ("x < 1 | y < 2", "operator '|' is not allowed; combine conditions with and, or, not (write or for |)"),
        ("~(x < 1)", "operator '~' is not allowed; negate a condition with not"),
        ("x < 1 && y < 2", "not a valid condition (invalid syntax at column 8); combine conditions with and, or, not"),
        ("z = 0.02", "not a valid condition (invalid syntax at column 3); equality is written =="),
        ("x is 1", "'is' is not allowed (allowed: < <= > >= == !=)"),
        ("x in y", "'in' is not allowed"),
        ("x < 1 if y < 0 else x > 1", "not a condition; expected"),
        ("t < 1", "unknown name 't' (allowed: x, y, z, pi, e and the functions abs,"),
        ("x.real < 1", "attribute access '.real' is not allowed"),
        ("x < True", "booleans (True) are not allowed"),
        ("x < 1e999", "number 1e999 is out of the float64 range"),
        ("x ** 1000 < 1", "exponent 1000 is too large"),
        ("x < ", "not a valid condition (invalid syntax"),
        ("", "empty condition"),
        ("   ", "empty condition"),
        ("not " * 120 + "x < 1", "nested too deeply (more than 100 levels)"),
        ("(x < 1 and " * 120 + "x < 1" + ")" * 120, "nested too deeply"),
    ],
)
def test_refusals_are_one_line_naming_the_key(source, problem):
    message = rejection(source)
    assert message.startswith(f"{WHERE} = \""), message
    assert problem in message, message


@pytest.mark.parametrize("source", [1.0, 0, True, None, ["x < 1"]])
def test_a_value_that_is_no_string_is_refused(source):
    message = rejection(source)
    assert message.startswith(f"{WHERE} = ")
    assert f'expected a condition string such as "abs(z - 0.02) < 1e-9", got {type(source).__name__}' in message


def test_expressions_still_refuse_comparisons():
    with pytest.raises(CaseError, match="comparisons are not allowed"):
        parse_expression("abs(z - 0.02) < 1e-9", XYZ)
    with pytest.raises(CaseError, match="'and'/'or' are not allowed"):
        parse_expression("x and y", XYZ)
