"""What a law of a case declares: its name, a one-line summary, its named parameters and their bounds.

A law's module (one per law, in the package of its family: ``laws.stiffness``, ``laws.compliance``,
``laws.viscoplastic``) defines the law's object and ``LAW``, a :class:`Law`; its family's registry lists it by
name. The case schema makes the law's table from ``LAW`` (a key per parameter, checked against its bounds,
:mod:`vpcontact.case.law_sections`), the translation makes the table a
:class:`~vpcontact.problem.options.LawChoice` (the law's name and its parameters), and the problem finds the law by
that name in its registry and makes its object with ``LAW.make`` (:func:`vpcontact.laws.contact.law_at_nodes`,
:mod:`vpcontact.laws.materials`).

A parameter is a number by default (of a contact law: a number or an expression in the coordinates, one value per
contact node); it may instead be a list of ``points`` (a table's abscissae or values, the same at every node of
its part) or one of the names ``choices`` (how a table is extrapolated). The checks that relate parameters (a
table's lists of the same length, its abscissae increasing) are the law's ``check``, called with the parameters'
values by keyword before the law is made, raising a :class:`ParameterError` that names the bad one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..errors import brief, quoted


class ParameterError(ValueError):
    """A bad value of a law's parameter ``name``, as the message "<name> = <value>: <what is expected>" (the case
    schema puts the key of the law's table before it: ``contact.stiffness.xi = [...]: ...``)."""

    def __init__(self, name: str, value, expected: str):
        super().__init__(f"{name} = {quoted(value) if isinstance(value, str) else brief(value)}: {expected}")
        self.name = name


@dataclass(frozen=True)
class Parameter:
    """A parameter of a law: its key in the case, what it is, and the values it admits: any finite number, or at
    least ``minimum`` (more than it when ``strict``), or a Poisson ratio admissible for the material's 2D
    hypothesis (``poisson_ratio``: −1 < ν < 0.5, ν ≤ 0.5 in plane stress); or, with ``points``, a list of at least
    2 finite numbers (each at least ``minimum`` when given), or, with ``choices``, one of these names."""

    name: str
    summary: str
    minimum: float | None = None
    strict: bool = False
    poisson_ratio: bool = False
    points: bool = False
    choices: tuple[str, ...] = ()

    @property
    def per_node(self) -> bool:
        """Is it a number (one value per contact node for a contact law), neither points nor a choice?"""
        return not self.points and not self.choices


@dataclass(frozen=True)
class Law:
    """A law as a case names it: ``name`` (its case name, "power"), a one-line ``summary``, its ``parameters`` in
    the order of its table, and ``make``, which makes the law's object from their values by keyword (and, for a
    viscoplastic law, the material's 2D ``hypothesis``; see the family's package); ``check``, when given, checks
    the parameters together (called with their values by keyword; a :class:`ParameterError` naming the bad one)."""

    name: str
    summary: str
    parameters: tuple[Parameter, ...]
    make: Callable[..., Any]
    check: Callable[..., None] | None = None

    def made(self, value: Callable[[Parameter], Any], **context) -> Any:
        """The law's object with each parameter's value ``value(parameter)`` and the family's ``context`` (its
        parameters checked together first, when the law has a ``check``)."""
        values = {parameter.name: value(parameter) for parameter in self.parameters}
        if self.check is not None:
            self.check(**values)
        return self.make(**values, **context)
