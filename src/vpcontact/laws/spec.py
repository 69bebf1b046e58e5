"""What a law of a case declares: its name, a one-line summary, its named parameters and their bounds.

A law's module (one per law, in the package of its family: ``laws.stiffness``, ``laws.compliance``,
``laws.viscoplastic``) defines the law's object and ``LAW``, a :class:`Law`; its family's registry lists it by
name. The case schema makes the law's table from ``LAW`` (a key per parameter, checked against its bounds,
:mod:`vpcontact.case.law_sections`), the translation makes the table a
:class:`~vpcontact.problem.options.LawChoice` (the law's name and its parameters), and the problem finds the law by
that name in its registry and makes its object with ``LAW.make`` (:func:`vpcontact.laws.contact.law_at_nodes`,
:mod:`vpcontact.laws.materials`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Parameter:
    """A parameter of a law: its key in the case, what it is, and the values it admits: any finite number, or at
    least ``minimum`` (more than it when ``strict``), or a Poisson ratio admissible for the material's 2D
    hypothesis (``poisson_ratio``: −1 < ν < 0.5, ν ≤ 0.5 in plane stress)."""

    name: str
    summary: str
    minimum: float | None = None
    strict: bool = False
    poisson_ratio: bool = False


@dataclass(frozen=True)
class Law:
    """A law as a case names it: ``name`` (its case name, "power"), a one-line ``summary``, its ``parameters`` in
    the order of its table, and ``make``, which makes the law's object from their values by keyword (and, for a
    viscoplastic law, the material's 2D ``hypothesis``; see the family's package)."""

    name: str
    summary: str
    parameters: tuple[Parameter, ...]
    make: Callable[..., Any]

    def made(self, value: Callable[[Parameter], Any], **context) -> Any:
        """The law's object with each parameter's value ``value(parameter)`` and the family's ``context``."""
        return self.make(**{parameter.name: value(parameter) for parameter in self.parameters}, **context)
