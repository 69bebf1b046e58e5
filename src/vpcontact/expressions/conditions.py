"""Conditions of a case file: where something holds, e.g. ``"abs(z - 0.02) < 1e-9"``, checked and evaluated with NumPy.

:func:`parse_condition` turns a string into a :class:`Condition`: a callable that tells, for arrays of
coordinates, where the condition holds (a boolean array). A condition is made of

- comparisons ``< <= > >= == !=`` of arithmetic expressions of the language of
  :mod:`vpcontact.expressions.language` (numbers, the variables, ``pi``, ``e``, the functions), chained as in
  Python: ``0 <= x <= 1`` is ``0 <= x and x <= 1`` (``x`` computed once);
- ``and``, ``or``, ``not`` and parentheses, with Python's precedence: ``not`` binds tighter than ``and``,
  ``and`` tighter than ``or``, so ``not a or b and c`` is ``(not a) or (b and c)``.

Its top is a comparison or one of ``and``, ``or``, ``not``, whose operands are conditions again; the two
sides of a comparison are numbers, not conditions (``(x < 1) == (y < 1)`` and ``x + (y < 1)`` are refused),
and ``x + 1`` alone is no condition. Every part is computed at every point (no short circuit: vectorized).

Undefined values: a comparison with NaN (``sqrt(x)`` at ``x < 0``, ``0/0``) is False, ``!=`` too (unlike IEEE
754, where ``nan != 1`` is true): a comparison holds only where both sides are numbers, so a point where
an expression is undefined is never selected by a comparison; ``not`` negates as written,
``not (sqrt(x) < 1)`` holds there. ``inf`` compares as a number (``1/x > 0`` holds at ``x = +0``).
Floating-point warnings are not silenced here (as for :class:`~vpcontact.expressions.parse.Expression`): the
caller evaluates under ``np.errstate``.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Callable, Iterable

import numpy as np

from ..errors import CaseError, brief
from .language import MAX_DEPTH, Compiler, Evaluator, check_variables
from .parse import Expression

EXAMPLE = '"abs(z - 0.02) < 1e-9"'
"""The condition messages show as an example."""


def _not_equal(left, right):
    """``left != right`` where both are numbers: False where either is NaN (see the module's docstring)."""
    return np.less(left, right) | np.greater(left, right)


_COMPARISONS: dict[type[ast.cmpop], Callable] = {
    ast.Lt: np.less,
    ast.LtE: np.less_equal,
    ast.Gt: np.greater,
    ast.GtE: np.greater_equal,
    ast.Eq: np.equal,
    ast.NotEq: _not_equal,
}

_REFUSED_COMPARISONS: dict[type[ast.cmpop], str] = {
    ast.Is: "is",
    ast.IsNot: "is not",
    ast.In: "in",
    ast.NotIn: "not in",
}

_CONNECTIVES: dict[type[ast.boolop], Callable] = {ast.And: np.logical_and, ast.Or: np.logical_or}

# Binary operators of other languages a user may write for and, or (``~`` for not: compile_unary).
_OTHER_LOGIC = {ast.BitAnd: ("&", "and"), ast.BitOr: ("|", "or"), ast.BitXor: ("^", "or")}


def is_condition(node: ast.AST) -> bool:
    """Whether ``node`` is a comparison, ``and``/``or`` or ``not``: the nodes whose value is true or false."""
    negation = isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not)
    return negation or isinstance(node, (ast.Compare, ast.BoolOp))


class ConditionCompiler(Compiler):
    """Checks the syntax tree of one condition and builds its evaluator closure (the arithmetic inside its
    comparisons is the :class:`~vpcontact.expressions.language.Compiler`'s)."""

    kind = "condition"

    def compile_tree(self, node: ast.AST) -> tuple[Evaluator, frozenset[str]]:
        """The top must be a condition: ``x + 1`` is refused with an example of one."""
        return self.compile_condition(node, 1)

    def syntax_hint(self) -> str:
        """A hint for the usual slips: ``z = 0`` for ``z == 0``, ``&&`` and ``||`` for ``and`` and ``or``."""
        if re.search(r"&&|\|\|", self.body):
            return "; combine conditions with and, or, not"
        if re.search(r"(?<![<>=!])=(?!=)", self.body):
            return "; equality is written =="
        return ""

    def compile(self, node: ast.AST, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """An arithmetic operand of a comparison: a condition there is refused."""
        if is_condition(node):
            raise self.error(f"'{self.segment(node)}' is a condition where a number is expected (conditions are not "
                             f"compared or computed with; combine them with and, or, not)")
        return super().compile(node, depth)

    def compile_condition(self, node: ast.AST, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """A comparison, ``and``/``or`` or ``not``; anything else is refused as no condition."""
        if depth > MAX_DEPTH:
            raise self.error(f"nested too deeply (more than {MAX_DEPTH} levels)")
        if isinstance(node, ast.Compare):
            return self.compile_comparison(node, depth)
        if isinstance(node, ast.BoolOp):
            return self.compile_connective(node, depth)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
            operand, names = self.compile_condition(node.operand, depth + 1)
            return (lambda values: np.logical_not(operand(values))), names
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Invert):
            self.compile_unary(node, depth)  # refused with a hint
        if depth == 1:
            raise self.error(f"not a condition; expected a comparison such as {EXAMPLE} (combined with and, or, not)")
        raise self.error(f"'{self.segment(node)}' is not a condition; each side of and, or and what follows not "
                         f"is a comparison such as {EXAMPLE}")

    def compile_comparison(self, node: ast.Compare, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """``a < b``, or a chain ``a < b <= c``: every comparison of neighbours holds, each operand computed once."""
        for op in node.ops:
            if type(op) in _REFUSED_COMPARISONS:
                raise self.error(f"'{_REFUSED_COMPARISONS[type(op)]}' is not allowed (allowed: < <= > >= == !=)")
        compiled = [self.compile(operand, depth + 1) for operand in (node.left, *node.comparators)]
        operands = [evaluate for evaluate, _ in compiled]
        tests = [_COMPARISONS[type(op)] for op in node.ops]
        names = frozenset().union(*(operand_names for _, operand_names in compiled))

        def evaluate(values):
            computed = [operand(values) for operand in operands]
            held = tests[0](computed[0], computed[1])
            for k in range(1, len(tests)):
                held = held & tests[k](computed[k], computed[k + 1])
            return held

        return evaluate, names

    def compile_connective(self, node: ast.BoolOp, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """``a and b and ...`` or ``a or b or ...``, elementwise, every operand computed."""
        connect = _CONNECTIVES[type(node.op)]
        compiled = [self.compile_condition(operand, depth + 1) for operand in node.values]
        operands = [evaluate for evaluate, _ in compiled]
        names = frozenset().union(*(operand_names for _, operand_names in compiled))

        def evaluate(values):
            held = operands[0](values)
            for operand in operands[1:]:
                held = connect(held, operand(values))
            return held

        return evaluate, names

    def compile_binary(self, node: ast.BinOp, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """Arithmetic, with a hint where ``&``, ``|`` or ``^`` stands for and, or."""
        if type(node.op) in _OTHER_LOGIC:
            symbol, word = _OTHER_LOGIC[type(node.op)]
            raise self.error(f"operator '{symbol}' is not allowed; combine conditions with and, or, not "
                             f"(write {word} for {symbol})")
        return super().compile_binary(node, depth)

    def compile_unary(self, node: ast.UnaryOp, depth: int) -> tuple[Evaluator, frozenset[str]]:
        """Unary plus or minus, with a hint where ``~`` stands for not."""
        if isinstance(node.op, ast.Invert):
            raise self.error("operator '~' is not allowed; negate a condition with not")
        return super().compile_unary(node, depth)


class Condition(Expression):
    """A parsed condition in a fixed set of variables, evaluated with NumPy: an expression whose values are truths.

    Create one with :func:`parse_condition`. Calling it with the variables as keyword arguments (arrays or
    scalars, as float64) tells elementwise where it holds: a new boolean array of the broadcast shape of all
    the values passed, or a Python bool when every value is a scalar. Equal conditions have the same source and
    variables. Pickling stores only ``source``, ``variables`` and ``where`` and parses the text again when loaded.
    """

    __slots__ = ()
    _scalar = bool

    def __reduce__(self) -> tuple[Callable[..., Condition], tuple[str, tuple[str, ...], str]]:
        """Pickle as the call ``parse_condition(source, variables, where)``."""
        return parse_condition, (self.source, self.variables, self.where)


def parse_condition(source: str, variables: Iterable[str], where: str = "condition") -> Condition:
    """Check and compile the condition ``source``, a string such as ``"abs(z - 0.02) < 1e-9"``.

    ``variables`` are the names it may use besides ``pi`` and ``e``; ``where`` names the place in the case for
    error messages, e.g. ``"boundary.dirichlet[2].where"``.

    Raises CaseError with a one-line message ``<where> = "<source>": <problem>`` for bad input: not a string,
    empty, a syntax error, a top that is no comparison or and/or/not (``"x + 1"``), or anything the arithmetic
    of :mod:`vpcontact.expressions.language` refuses. Raises ValueError if ``variables`` themselves are invalid.
    """
    variables = check_variables(variables)
    if not isinstance(source, str):
        raise CaseError(f"{where} = {brief(source)}: expected a condition string such as {EXAMPLE}, "
                        f"got {type(source).__name__}")
    evaluate, depends_on = ConditionCompiler(source, variables, where).compile_source()
    return Condition(source, variables, where, evaluate, depends_on)
