"""The language of expressions: what a case file's formula may contain, checked and compiled into NumPy.

A case file may give a value as a number or as a string such as ``"-1000*t"``,
``"0.01*(x-0.5)**2"`` or ``"sin(pi*x)*exp(-t)"`` (:mod:`vpcontact.expressions.parse` turns it into an
:class:`~vpcontact.expressions.parse.Expression`).

The text is never executed as Python. It is parsed with ``ast.parse(..., mode="eval")``
and every node of the tree is checked against a whitelist: numbers, the variables
given to :func:`~vpcontact.expressions.parse.parse_expression`, the constants ``pi`` and ``e``, the operators
``+ - * / ** %`` (binary) and ``+ -`` (unary), and calls of the functions in
:data:`FUNCTION_NAMES` by bare name with positional arguments. Anything else
(attributes, subscripts, strings, lambdas, comparisons, keyword arguments, unknown
names, ...) is a :class:`~vpcontact.errors.CaseError`. The checked tree is then turned
into a tree of small Python closures over NumPy operations, built once at parse time (:class:`Compiler`).
Comparisons and and/or/not make a condition, another kind of text over the same arithmetic
(:mod:`vpcontact.expressions.conditions`).

All numbers are float64 (integer literals are converted), so Python's unbounded
integers never appear; a constant exponent is limited to ``MAX_EXPONENT`` in absolute
value so that ``10**10**10`` is reported instead of silently giving ``inf``.

Messages show the source as ``<where> = "<source>"``; a long source (or a long part of it) is cut to
its first characters and its length (:func:`~vpcontact.errors.quoted`), so the reason is always read.
"""

from __future__ import annotations

import ast
import keyword
import math
import operator
from collections.abc import Callable, Iterable, Mapping
from functools import reduce
from typing import NamedTuple

import numpy as np

from ..errors import CaseError, quoted, shown

MAX_EXPONENT = 100.0
"""Largest absolute value allowed for an exponent that does not depend on a variable."""

MAX_DEPTH = 100
"""Deepest nesting of operations and calls allowed in one expression."""

_Value = np.ndarray | np.float64
Evaluator = Callable[[Mapping[str, np.ndarray]], _Value]


def _minimum(*values: _Value) -> _Value:
    """Elementwise minimum of two or more values (NaN propagates)."""
    return reduce(np.minimum, values)


def _maximum(*values: _Value) -> _Value:
    """Elementwise maximum of two or more values (NaN propagates)."""
    return reduce(np.maximum, values)


def _heaviside(value: _Value) -> _Value:
    """Heaviside step: 1 where value > 0, 0 where value <= 0 (NaN stays NaN)."""
    return np.heaviside(value, 0.0)


class _Function(NamedTuple):
    """A function callable from an expression, with the numbers of arguments it takes."""

    compute: Callable[..., _Value]
    min_args: int
    max_args: int | None  # None: no upper limit


_FUNCTIONS: dict[str, _Function] = {
    "abs": _Function(np.abs, 1, 1),
    "sqrt": _Function(np.sqrt, 1, 1),
    "exp": _Function(np.exp, 1, 1),
    "log": _Function(np.log, 1, 1),
    "log10": _Function(np.log10, 1, 1),
    "sin": _Function(np.sin, 1, 1),
    "cos": _Function(np.cos, 1, 1),
    "tan": _Function(np.tan, 1, 1),
    "asin": _Function(np.arcsin, 1, 1),
    "acos": _Function(np.arccos, 1, 1),
    "atan": _Function(np.arctan, 1, 1),
    "atan2": _Function(np.arctan2, 2, 2),
    "sinh": _Function(np.sinh, 1, 1),
    "cosh": _Function(np.cosh, 1, 1),
    "tanh": _Function(np.tanh, 1, 1),
    "floor": _Function(np.floor, 1, 1),
    "ceil": _Function(np.ceil, 1, 1),
    "min": _Function(_minimum, 2, None),
    "max": _Function(_maximum, 2, None),
    "sign": _Function(np.sign, 1, 1),
    "heaviside": _Function(_heaviside, 1, 1),
}

FUNCTION_NAMES: tuple[str, ...] = tuple(_FUNCTIONS)
"""Names of the functions an expression may call, e.g. ``atan2(y, x)``, ``max(0, y - 1)``."""

_CONSTANTS: dict[str, np.float64] = {"pi": np.float64(math.pi), "e": np.float64(math.e)}

CONSTANT_NAMES: tuple[str, ...] = tuple(_CONSTANTS)
"""Names of the mathematical constants an expression may use."""

_BINARY_OPERATORS: dict[type[ast.operator], Callable[[_Value, _Value], _Value]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.Mod: operator.mod,
}

_UNARY_OPERATORS: dict[type[ast.unaryop], Callable[[_Value], _Value]] = {
    ast.UAdd: operator.pos,
    ast.USub: operator.neg,
}

_OPERATOR_SYMBOLS: dict[type[ast.AST], str] = {
    ast.FloorDiv: "//",
    ast.MatMult: "@",
    ast.LShift: "<<",
    ast.RShift: ">>",
    ast.BitOr: "|",
    ast.BitXor: "^",
    ast.BitAnd: "&",
    ast.Invert: "~",
    ast.Not: "not",
}

# The problem reported for a construct outside the whitelist.
_REJECTED_CONSTRUCTS: dict[type[ast.AST], str] = {
    ast.Slice: "slices are not allowed",
    ast.Lambda: "lambda is not allowed",
    ast.Compare: "comparisons are not allowed",
    ast.BoolOp: "'and'/'or' are not allowed",
    ast.IfExp: "conditional expressions (a if c else b) are not allowed",
    ast.NamedExpr: "assignment expressions (:=) are not allowed",
    ast.Starred: "starred expressions are not allowed",
    ast.Tuple: "tuples are not allowed",
    ast.List: "lists are not allowed",
    ast.Set: "sets are not allowed",
    ast.Dict: "dicts are not allowed",
    ast.ListComp: "comprehensions are not allowed",
    ast.SetComp: "comprehensions are not allowed",
    ast.DictComp: "comprehensions are not allowed",
    ast.GeneratorExp: "comprehensions are not allowed",
    ast.JoinedStr: "strings are not allowed",
    ast.Await: "await is not allowed",
    ast.Yield: "yield is not allowed",
    ast.YieldFrom: "yield is not allowed",
}


def check_variables(variables: Iterable[str]) -> tuple[str, ...]:
    """Return ``variables`` as a tuple after checking they can be used as names."""
    names = tuple(variables)
    for name in names:
        if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
            raise ValueError(f"expression variable {name!r} is not a valid name")
        if name in _FUNCTIONS or name in _CONSTANTS:
            raise ValueError(f"expression variable {name!r} clashes with a function or constant name")
    if len(set(names)) != len(names):
        raise ValueError(f"expression variables {names!r} contain a repeated name")
    return names


class Compiler:
    """Checks the syntax tree of one expression and builds its evaluator closure.

    A subclass may compile another kind of text over the same arithmetic (the conditions of
    :mod:`vpcontact.expressions.conditions`): ``kind`` names it in messages, :meth:`compile_tree` compiles the
    parsed tree's top and :meth:`syntax_hint` adds a hint to a syntax error.
    """

    kind = "expression"

    def __init__(self, source: str, variables: tuple[str, ...], where: str) -> None:
        self.source = source
        self.variables = variables
        self.where = where
        # Leading whitespace would be an "unexpected indent"; it is stripped before
        # parsing and its extent kept to report positions in the original text.
        self.body = source.strip()
        self.lead = source[: len(source) - len(source.lstrip())]

    def error(self, problem: str) -> CaseError:
        """A CaseError ``<where> = "<source>": <problem>`` (source quoted as in TOML, a long one cut)."""
        return CaseError(f"{self.where} = {quoted(self.source)}: {problem}")

    def compile_source(self) -> tuple[Evaluator, frozenset[str]]:
        """Parse the source, check it and return its evaluator and the variables it uses."""
        if not self.body:
            raise self.error(f"empty {self.kind}")
        try:
            # The newline makes the parser report an incomplete expression ("2*") at the
            # column after its end instead of at column 0.
            tree = ast.parse(self.body + "\n", mode="eval")
        except SyntaxError as exc:
            if exc.msg.startswith("Exceeds the limit"):  # an integer literal of more than 4300 digits
                raise self.error("a number of thousands of digits, out of the float64 range") from None
            raise self.error(f"not a valid {self.kind} ({exc.msg}{self.position(exc)}){self.syntax_hint()}") from None
        except ValueError as exc:  # e.g. null bytes on some Python versions
            raise self.error(f"not a valid {self.kind} ({exc})") from None
        except (RecursionError, MemoryError):
            raise self.error(f"nested too deeply (more than {MAX_DEPTH} levels)") from None
        return self.compile_tree(tree.body)

    def compile_tree(self, node: ast.AST) -> tuple[Evaluator, frozenset[str]]:
        """Compile the top of the parsed tree: an arithmetic expression."""
        return self.compile(node, 1)

    def syntax_hint(self) -> str:
        """What to add to the message of a syntax error in the source: nothing for an expression."""
        return ""

    def position(self, exc: SyntaxError) -> str:
        """`` at column C`` (or `` at line L, column C``) of a syntax error in the source."""
        if exc.lineno is None or exc.offset is None or exc.offset < 1:
            return ""
        line, column = exc.lineno, exc.offset
        if line == 1:
            column += len(self.lead) - (self.lead.rfind("\n") + 1)
        line += self.lead.count("\n")
        if "\n" in self.source.rstrip():
            return f" at line {line}, column {column}"
        return f" at column {column}"

    def segment(self, node: ast.AST) -> str:
        """The source text of ``node`` (a long one cut, see :func:`~vpcontact.errors.shown`)."""
        return shown(ast.get_source_segment(self.body, node) or type(node).__name__)

    def compile(self, node: ast.AST, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """Check ``node`` and return its evaluator and the variables occurring in it."""
        if depth > MAX_DEPTH:
            raise self.error(f"nested too deeply (more than {MAX_DEPTH} levels)")
        if isinstance(node, ast.Constant):
            return self.compile_constant(node)
        if isinstance(node, ast.Name):
            return self.compile_name(node)
        if isinstance(node, ast.UnaryOp):
            return self.compile_unary(node, depth)
        if isinstance(node, ast.BinOp):
            return self.compile_binary(node, depth)
        if isinstance(node, ast.Call):
            return self.compile_call(node, depth)
        if isinstance(node, ast.Attribute):
            raise self.error(f"attribute access '.{node.attr}' is not allowed")
        if isinstance(node, ast.Subscript):
            raise self.error(f"subscripts like '{self.segment(node)}' are not allowed")
        raise self.error(_REJECTED_CONSTRUCTS.get(type(node), f"'{self.segment(node)}' is not allowed"))

    def compile_constant(self, node: ast.Constant) -> tuple[Evaluator, frozenset[str]]:
        """A number literal, as a float64 constant; other literals are rejected."""
        value = node.value
        if isinstance(value, bool):
            raise self.error(f"booleans ({value}) are not allowed")
        if value is None:
            raise self.error("None is not allowed")
        if isinstance(value, (str, bytes)):
            raise self.error("strings are not allowed")
        if isinstance(value, complex):
            raise self.error(f"complex numbers ({self.segment(node)}) are not allowed")
        if not isinstance(value, (int, float)):
            raise self.error(f"'{self.segment(node)}' is not allowed")
        try:
            number = np.float64(float(value))
        except OverflowError:
            number = np.float64(math.inf)
        if not np.isfinite(number):
            raise self.error(f"number {self.segment(node)} is out of the float64 range")
        return (lambda values: number), frozenset()

    def compile_name(self, node: ast.Name) -> tuple[Evaluator, frozenset[str]]:
        """A variable (looked up at evaluation) or a constant (pi, e)."""
        name = node.id
        if name in self.variables:
            return (lambda values: values[name]), frozenset({name})
        if name in _CONSTANTS:
            constant = _CONSTANTS[name]
            return (lambda values: constant), frozenset()
        if name in _FUNCTIONS:
            raise self.error(f"'{name}' is a function; call it as {name}(...)")
        raise self.error(f"unknown name '{shown(name)}' (allowed: {self.allowed_names()})")

    def compile_unary(self, node: ast.UnaryOp, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """Unary plus or minus."""
        apply = _UNARY_OPERATORS.get(type(node.op))
        if apply is None:
            raise self.error(f"operator '{_OPERATOR_SYMBOLS[type(node.op)]}' is not allowed (allowed: + -)")
        operand, names = self.compile(node.operand, depth + 1)
        return (lambda values: apply(operand(values))), names

    def compile_binary(self, node: ast.BinOp, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """``+ - * / ** %``; a ``**`` with a constant exponent must keep it within MAX_EXPONENT."""
        apply = _BINARY_OPERATORS.get(type(node.op))
        if apply is None:
            raise self.error(
                f"operator '{_OPERATOR_SYMBOLS[type(node.op)]}' is not allowed (allowed: + - * / ** %)"
            )
        left, left_names = self.compile(node.left, depth + 1)
        right, right_names = self.compile(node.right, depth + 1)
        if isinstance(node.op, ast.Pow) and not right_names:
            with np.errstate(all="ignore"):
                exponent = float(right({}))
            if not abs(exponent) <= MAX_EXPONENT:
                text = self.segment(node.right)
                if text != f"{exponent:g}":
                    text += f" (= {exponent:g})"
                raise self.error(
                    f"exponent {text} is too large (a constant exponent must be at most"
                    f" {MAX_EXPONENT:g} in absolute value)"
                )
        return (lambda values: apply(left(values), right(values))), left_names | right_names

    def compile_call(self, node: ast.Call, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """A whitelisted function called by bare name with the right number of positional arguments."""
        if not isinstance(node.func, ast.Name):
            raise self.error(f"only functions called by name can be called, not '{self.segment(node.func)}'")
        name = node.func.id
        function = _FUNCTIONS.get(name)
        if function is None:
            if name in self.variables or name in _CONSTANTS:
                raise self.error(f"'{name}' is not a function")
            raise self.error(f"unknown function '{shown(name)}' (allowed: {', '.join(FUNCTION_NAMES)})")
        if node.keywords:
            raise self.error(f"keyword arguments are not allowed (in the call of {name})")
        if any(isinstance(arg, ast.Starred) for arg in node.args):
            raise self.error(f"starred arguments are not allowed (in the call of {name})")
        count = len(node.args)
        if count < function.min_args or (function.max_args is not None and count > function.max_args):
            raise self.error(f"{name}() takes {_arity(function)}, got {count}")
        compiled = [self.compile(arg, depth + 1) for arg in node.args]
        arguments = [evaluate for evaluate, _ in compiled]
        names = frozenset().union(*(arg_names for _, arg_names in compiled))
        compute = function.compute
        return (lambda values: compute(*[argument(values) for argument in arguments])), names

    def allowed_names(self) -> str:
        """``x, y, t, pi, e and the functions abs, sqrt, ...`` for error messages."""
        return f"{', '.join(self.variables + CONSTANT_NAMES)} and the functions {', '.join(FUNCTION_NAMES)}"


def _arity(function: _Function) -> str:
    """``1 argument``, ``2 arguments`` or ``at least 2 arguments``."""
    count = function.min_args
    plural = "argument" if count == 1 else "arguments"
    if function.max_args is None:
        return f"at least {count} {plural}"
    return f"{count} {plural}"
