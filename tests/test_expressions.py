"""Tests of vpcontact.expressions: values, broadcasting, dependencies, pickling, rejections."""

from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pytest

from vpcontact.errors import CaseError
from vpcontact.expressions.language import CONSTANT_NAMES, FUNCTION_NAMES, MAX_DEPTH
from vpcontact.expressions.parse import Expression, parse_expression

X = np.array([-1.5, -0.25, 0.0, 0.3, 0.5, 2.0])
Y = np.array([2.0, 1.0, 0.5, -1.0, 3.0, 0.75])
WHERE = "boundary.traction[0].value[1]"


def rejection(source: object, **kwargs: object) -> str:
    """The message of the CaseError raised when parsing ``source``."""
    with pytest.raises(CaseError) as info:
        parse_expression(source, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    return message


# --- values ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("-1000*t", lambda x, y, t: -1000.0 * t + 0 * x),
        ("0.01*(x-0.5)**2", lambda x, y, t: 0.01 * (x - 0.5) ** 2),
        ("sin(pi*x)*exp(-t)", lambda x, y, t: np.sin(np.pi * x) * np.exp(-t)),
        ("max(0, y - 1)", lambda x, y, t: np.maximum(0.0, y - 1.0)),
        ("x*y - t/2 + 3 % 2", lambda x, y, t: x * y - t / 2 + 1.0),
        ("-x + +y", lambda x, y, t: -x + y),
        ("x % 0.4", lambda x, y, t: np.mod(x, 0.4)),
        ("2**-x", lambda x, y, t: 2.0 ** (-x)),
        ("-x**2", lambda x, y, t: -(x**2)),
        ("e**x", lambda x, y, t: np.exp(x)),
        ("7/2", lambda x, y, t: 3.5 + 0 * x),
        ("1_000 + 0x10", lambda x, y, t: 1016.0 + 0 * x),
    ],
)
def test_values_match_numpy_with_scalar_t(source, expected):
    t = 0.7
    result = parse_expression(source)(x=X, y=Y, t=t)
    assert isinstance(result, np.ndarray)
    assert result.dtype == np.float64
    assert result.shape == X.shape
    np.testing.assert_allclose(result, expected(X, Y, t), rtol=1e-14, atol=0)


def test_integer_literals_are_float():
    assert parse_expression("7/2")() == 3.5
    assert parse_expression("-7 % 3")() == 2.0


def test_integer_arrays_are_evaluated_as_float():
    result = parse_expression("x/2", variables=("x",))(x=np.array([1, 2, 3]))
    np.testing.assert_array_equal(result, [0.5, 1.0, 1.5])


def test_broadcasts_column_against_row():
    x = np.linspace(0.0, 1.0, 4)[:, None]
    t = np.array([0.0, 1.0, 2.0])
    result = parse_expression("x*t")(x=x, t=t)
    assert result.shape == (4, 3)
    np.testing.assert_array_equal(result, x * t)


@pytest.mark.parametrize("source", ["0", "3.5", "pi", "2*e - 1"])
def test_constants_broadcast_to_shape_of_all_inputs(source):
    expression = parse_expression(source)
    expected = {"0": 0.0, "3.5": 3.5, "pi": math.pi, "2*e - 1": 2 * math.e - 1}[source]
    result = expression(x=np.zeros((2, 3)), y=np.zeros(3), t=1.0)
    assert isinstance(result, np.ndarray)
    assert result.shape == (2, 3)
    np.testing.assert_array_equal(result, np.full((2, 3), expected))


def test_unused_array_variables_set_the_shape():
    result = parse_expression("-1000*t")(x=X, y=Y, t=0.002)
    np.testing.assert_array_equal(result, np.full(X.shape, -2.0))


def test_scalar_inputs_give_a_float():
    result = parse_expression("x + t")(x=1.0, t=2.0)
    assert type(result) is float
    assert result == 3.0
    assert type(parse_expression("0")()) is float


def test_result_is_a_new_writable_array():
    x = X.copy()
    result = parse_expression("x", variables=("x",))(x=x)
    result[0] = 99.0
    assert x[0] == X[0]


def test_unused_variables_may_be_omitted():
    assert parse_expression("2*t")(t=1.5) == 3.0


def test_missing_variable_is_a_type_error():
    with pytest.raises(TypeError, match="needs a value for t"):
        parse_expression("x + t")(x=X)


def test_unknown_variable_is_a_type_error():
    with pytest.raises(TypeError, match="unknown variable"):
        parse_expression("x")(x=X, z=1.0)


def test_custom_variables():
    expression = parse_expression("s*r", variables=("s", "r"))
    assert expression.variables == ("s", "r")
    assert expression(s=2.0, r=3.0) == 6.0
    assert "unknown name 't'" in rejection("t", variables=("s", "r"))


@pytest.mark.parametrize("variables", [("x", "x"), ("x", "sin"), ("pi",), ("1x",), ("lambda",)])
def test_invalid_variables_are_a_value_error(variables):
    with pytest.raises(ValueError) as info:
        parse_expression("1", variables=variables)
    assert not isinstance(info.value, CaseError)


def test_floating_point_warnings_are_not_silenced():
    expression = parse_expression("1/x")
    with pytest.warns(RuntimeWarning, match="divide by zero"):
        expression(x=np.array([0.0, 1.0]))
    with np.errstate(divide="ignore"):
        np.testing.assert_array_equal(expression(x=np.array([0.0, 2.0])), [np.inf, 0.5])


def test_constant_overflow_gives_inf_not_an_exception():
    with np.errstate(over="ignore"):
        assert parse_expression("10.0**100 * 10.0**100 * 10.0**100 * 10.0**100")() == math.inf


# --- functions ------------------------------------------------------------------------

FUNCTION_CASES = {
    "abs": ("abs(x)", np.abs(X)),
    "sqrt": ("sqrt(y + 1.5)", np.sqrt(Y + 1.5)),
    "exp": ("exp(x)", np.exp(X)),
    "log": ("log(y + 2)", np.log(Y + 2)),
    "log10": ("log10(y + 2)", np.log10(Y + 2)),
    "sin": ("sin(x)", np.sin(X)),
    "cos": ("cos(x)", np.cos(X)),
    "tan": ("tan(x)", np.tan(X)),
    "asin": ("asin(x/2)", np.arcsin(X / 2)),
    "acos": ("acos(x/2)", np.arccos(X / 2)),
    "atan": ("atan(x)", np.arctan(X)),
    "atan2": ("atan2(y, x)", np.arctan2(Y, X)),
    "sinh": ("sinh(x)", np.sinh(X)),
    "cosh": ("cosh(x)", np.cosh(X)),
    "tanh": ("tanh(x)", np.tanh(X)),
    "floor": ("floor(x)", np.array([-2.0, -1.0, 0.0, 0.0, 0.0, 2.0])),
    "ceil": ("ceil(x)", np.array([-1.0, -0.0, 0.0, 1.0, 1.0, 2.0])),
    "min": ("min(x, y)", np.array([-1.5, -0.25, 0.0, -1.0, 0.5, 0.75])),
    "max": ("max(x, y)", np.array([2.0, 1.0, 0.5, 0.3, 3.0, 2.0])),
    "sign": ("sign(x)", np.array([-1.0, -1.0, 0.0, 1.0, 1.0, 1.0])),
    "heaviside": ("heaviside(x)", np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])),
}


def test_function_cases_cover_all_functions():
    assert set(FUNCTION_CASES) == set(FUNCTION_NAMES)
    assert CONSTANT_NAMES == ("pi", "e")


@pytest.mark.parametrize("name", sorted(FUNCTION_CASES))
def test_function_values(name):
    source, expected = FUNCTION_CASES[name]
    np.testing.assert_allclose(parse_expression(source)(x=X, y=Y), expected, rtol=1e-14, atol=0)


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("abs(-2.5)", 2.5),
        ("sqrt(16)", 4.0),
        ("exp(1)", math.e),
        ("log(e**2)", 2.0),
        ("log10(1000)", 3.0),
        ("sin(pi/2)", 1.0),
        ("cos(pi)", -1.0),
        ("tan(pi/4)", 1.0),
        ("asin(1)", math.pi / 2),
        ("acos(-1)", math.pi),
        ("atan(1)", math.pi / 4),
        ("atan2(1, -1)", 3 * math.pi / 4),
        ("sinh(1)", (math.e - 1 / math.e) / 2),
        ("cosh(1)", (math.e + 1 / math.e) / 2),
        ("tanh(0.5)", math.tanh(0.5)),
        ("floor(-2.5)", -3.0),
        ("ceil(-2.5)", -2.0),
        ("sign(-3)", -1.0),
        ("heaviside(0)", 0.0),
        ("heaviside(1e-300)", 1.0),
        ("heaviside(-5)", 0.0),
        ("min(3, -1, 2)", -1.0),
        ("max(3, -1, 2, 7.5)", 7.5),
    ],
)
def test_function_values_at_points(source, expected):
    assert parse_expression(source)() == pytest.approx(expected, rel=1e-15, abs=1e-15)


def test_min_max_are_elementwise_with_broadcasting():
    t = np.array([0.0, 1.0, 2.0])
    result = parse_expression("min(x, t, 1.5)")(x=np.array([[0.5], [3.0]]), t=t)
    np.testing.assert_array_equal(result, [[0.0, 0.5, 0.5], [0.0, 1.0, 1.5]])
    result = parse_expression("max(0, x - 1, -t)")(x=X, t=0.0)
    np.testing.assert_array_equal(result, np.maximum(0.0, X - 1.0))


def test_heaviside_keeps_nan():
    assert math.isnan(parse_expression("heaviside(x)")(x=math.nan))


# --- dependencies, identity, pickling -------------------------------------------------


@pytest.mark.parametrize(
    ("source", "depends_on"),
    [
        ("-1000*t", {"t"}),
        ("0", set()),
        ("pi*e", set()),
        ("0.01*(x-0.5)**2", {"x"}),
        ("sin(pi*x)*exp(-t)", {"x", "t"}),
        ("max(0, y - 1)", {"y"}),
        ("atan2(y, x) + 0*t", {"x", "y", "t"}),
    ],
)
def test_depends_on(source, depends_on):
    result = parse_expression(source).depends_on
    assert isinstance(result, frozenset)
    assert result == depends_on


def test_numbers_become_their_repr():
    assert parse_expression(5).source == "5"
    assert parse_expression(-2.5e-3).source == "-0.0025"
    assert parse_expression(np.float64(1.5)).source == "1.5"
    assert parse_expression(np.int64(-3)).source == "-3"
    np.testing.assert_array_equal(parse_expression(-2.5e-3)(x=X), np.full(X.shape, -2.5e-3))
    assert parse_expression(0.1)() == 0.1


def test_source_is_kept_as_given_and_shown_by_repr():
    expression = parse_expression("  -1000 * t ")
    assert expression.source == "  -1000 * t "
    assert str(expression) == "  -1000 * t "
    assert "'  -1000 * t '" in repr(expression)
    assert expression(t=2.0) == -2000.0


def test_equality_and_hash():
    a = parse_expression("x+1")
    assert a == parse_expression("x+1", where="elsewhere")
    assert hash(a) == hash(parse_expression("x+1"))
    assert a != parse_expression("1+x")
    assert a != parse_expression("x+1", variables=("x",))


def test_pickle_round_trip_gives_same_values():
    expression = parse_expression("sin(pi*x)*exp(-t) + max(0, y - 1)", where=WHERE)
    copy = pickle.loads(pickle.dumps(expression))
    assert isinstance(copy, Expression)
    assert copy == expression
    assert copy.where == WHERE
    assert copy.depends_on == expression.depends_on
    np.testing.assert_array_equal(copy(x=X, y=Y, t=0.3), expression(x=X, y=Y, t=0.3))


def test_pickle_keeps_custom_variables():
    copy = pickle.loads(pickle.dumps(parse_expression("a*b", variables=("a", "b"))))
    assert copy.variables == ("a", "b")
    assert copy(a=2.0, b=4.0) == 8.0


# --- rejections -----------------------------------------------------------------------


def test_unknown_name_message():
    message = rejection("-1000*tt", where=WHERE)
    assert message.startswith(
        f'{WHERE} = "-1000*tt": unknown name \'tt\' (allowed: x, y, t, pi, e and the functions abs, sqrt, '
    )
    assert message.endswith("sign, heaviside)")


def test_syntax_error_message():
    assert rejection("-1000*", where=WHERE) == (
        f'{WHERE} = "-1000*": not a valid expression (invalid syntax at column 7)'
    )
    assert rejection("x y") == 'expression = "x y": not a valid expression (invalid syntax at column 3)'


def test_syntax_error_column_counts_leading_whitespace_and_lines():
    assert rejection("  x y").endswith("(invalid syntax at column 5)")
    assert rejection("(1 +\n * 2)").endswith("(invalid syntax at line 2, column 2)")
    assert rejection("\n x y").endswith("(invalid syntax at line 2, column 4)")


@pytest.mark.parametrize("source", ["sin(x", "'abc", "x +* 2", "1 = 2", "import os", "x;y"])
def test_other_syntax_errors(source):
    assert ": not a valid expression (" in rejection(source)


@pytest.mark.parametrize(
    ("source", "problem"),
    [
        ("__import__('os')", "unknown function '__import__' (allowed: abs, sqrt,"),
        ("eval('1')", "unknown function 'eval'"),
        ("foo(x)", "unknown function 'foo'"),
        ("x.__class__", "attribute access '.__class__' is not allowed"),
        ("np.sin(x)", "only functions called by name can be called, not 'np.sin'"),
        ("(1).__class__.__bases__[0].__subclasses__()", "only functions called by name can be called"),
        ("x[0]", "subscripts like 'x[0]' are not allowed"),
        ("x[1:2]", "subscripts like 'x[1:2]' are not allowed"),
        ("lambda: 1", "lambda is not allowed"),
        ("(lambda: 1)()", "only functions called by name can be called, not 'lambda: 1'"),
        ("'os'", "strings are not allowed"),
        ("b'os'", "strings are not allowed"),
        ("f'{x}'", "strings are not allowed"),
        ("sqrt('4')", "strings are not allowed"),
        ("sqrt(x=4)", "keyword arguments are not allowed (in the call of sqrt)"),
        ("max(*x)", "starred arguments are not allowed (in the call of max)"),
        ("max(**x)", "keyword arguments are not allowed (in the call of max)"),
        ("sqrt(1, 2)", "sqrt() takes 1 argument, got 2"),
        ("sin()", "sin() takes 1 argument, got 0"),
        ("atan2(1)", "atan2() takes 2 arguments, got 1"),
        ("min(1)", "min() takes at least 2 arguments, got 1"),
        ("max()", "max() takes at least 2 arguments, got 0"),
        ("heaviside(x, 0.5)", "heaviside() takes 1 argument, got 2"),
        ("sin", "'sin' is a function; call it as sin(...)"),
        ("x(2)", "'x' is not a function"),
        ("pi(2)", "'pi' is not a function"),
        ("sin(x)(2)", "only functions called by name can be called, not 'sin(x)'"),
        ("True", "booleans (True) are not allowed"),
        ("x + False", "booleans (False) are not allowed"),
        ("None", "None is not allowed"),
        ("1j", "complex numbers (1j) are not allowed"),
        ("...", "'...' is not allowed"),
        ("x // 2", "operator '//' is not allowed (allowed: + - * / ** %)"),
        ("x @ y", "operator '@' is not allowed"),
        ("1 << 2", "operator '<<' is not allowed"),
        ("x ^ 2", "operator '^' is not allowed"),
        ("~x", "operator '~' is not allowed (allowed: + -)"),
        ("not x", "operator 'not' is not allowed"),
        ("x < 1", "comparisons are not allowed"),
        ("x and y", "'and'/'or' are not allowed"),
        ("x if y else t", "conditional expressions (a if c else b) are not allowed"),
        ("(y := 1)", "assignment expressions (:=) are not allowed"),
        ("x, y", "tuples are not allowed"),
        ("[x]", "lists are not allowed"),
        ("{x}", "sets are not allowed"),
        ("{1: x}", "dicts are not allowed"),
        ("[i for i in x]", "comprehensions are not allowed"),
        ("sin(i for i in x)", "comprehensions are not allowed"),
    ],
)
def test_rejected_constructs(source, problem):
    message = rejection(source, where=WHERE)
    assert message.startswith(f"{WHERE} = {json.dumps(source)}: ")
    assert problem in message


@pytest.mark.parametrize("name", FUNCTION_NAMES)
def test_arity_of_every_function_is_checked(name):
    accepted = {"atan2": range(2, 3), "min": range(2, 7), "max": range(2, 7)}.get(name, range(1, 2))
    for count in range(7):
        source = f"{name}({', '.join(['x'] * count)})"
        if count in accepted:
            parse_expression(source)
        else:
            assert f": {name}() takes " in rejection(source)


def test_source_with_quotes_is_shown_json_escaped_on_one_line():
    assert rejection("__import__(\"os\")\n").startswith('expression = "__import__(\\"os\\")\\n": unknown function')


@pytest.mark.parametrize(
    ("source", "literal"),
    [("1e309", "1e309"), ("-1e309", "1e309"), ("x + 2e400", "2e400"),
     ("1" + "0" * 400, "1" + "0" * 59 + "… (401 characters)")],  # a long literal is cut, its length given
)
def test_out_of_range_literal_rejected(source, literal):
    assert rejection(source).endswith(f": number {literal} is out of the float64 range")


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, np.float64("nan")])
def test_non_finite_float_rejected(value):
    assert rejection(value, where=WHERE) == f"{WHERE} = {float(value)!r}: not a finite number"


def test_huge_integer_rejected():
    assert rejection(10**400, where=WHERE) == f"{WHERE}: integer out of the float64 range"


@pytest.mark.parametrize(
    ("value", "type_name"),
    [(True, "bool"), (False, "bool"), (None, "NoneType"), ([1, 2], "list"), (1 + 2j, "complex"), (b"1", "bytes")],
)
def test_other_types_rejected(value, type_name):
    assert rejection(value, where=WHERE) == (
        f"{WHERE} = {value!r}: expected a number or an expression string, got {type_name}"
    )


@pytest.mark.parametrize("source", ["", "   ", "\n\t"])
def test_empty_string_rejected(source):
    assert rejection(source).endswith(": empty expression")


@pytest.mark.parametrize(
    ("source", "problem"),
    [
        ("10**10**10", "exponent 10**10 (= 1e+10) is too large"),
        ("x**1000", "exponent 1000 is too large"),
        ("2**-101", "exponent -101 is too large"),
        ("x**(50*3)", "exponent 50*3 (= 150) is too large"),
        ("2**(1/0)", "exponent 1/0 (= inf) is too large"),
        ("9**9**9**9", "is too large"),
    ],
)
def test_huge_constant_exponent_rejected(source, problem):
    message = rejection(source)
    assert problem in message
    assert message.endswith("(a constant exponent must be at most 100 in absolute value)")


def test_allowed_exponents():
    assert parse_expression("2**100")() == 2.0**100
    assert parse_expression("x**-100")(x=2.0) == 2.0**-100
    np.testing.assert_allclose(parse_expression("2**(10*x)")(x=X), 2.0 ** (10 * X))


@pytest.mark.parametrize(
    "source",
    ["-" * (MAX_DEPTH + 1) + "x", "+".join(["x"] * (MAX_DEPTH + 2)), "-" * 100_000 + "1", "1+" * 10_000 + "1"],
)
def test_deep_nesting_rejected(source):
    assert rejection(source).endswith(f": nested too deeply (more than {MAX_DEPTH} levels)")


def test_nesting_up_to_the_limit_is_accepted():
    assert parse_expression("-" * (MAX_DEPTH - 1) + "x")(x=1.0) == (-1.0) ** (MAX_DEPTH - 1)
