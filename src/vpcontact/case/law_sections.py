"""The tables of the laws a case names (contact.stiffness, contact.p, material.viscoplastic), made from the registries.

``contact.stiffness`` and ``material.viscoplastic`` are tables with the key ``law`` (a name of
:data:`~vpcontact.laws.stiffness.STIFFNESS` or :data:`~vpcontact.laws.viscoplastic.VISCOPLASTIC`) and one key
per parameter of that law, all required; ``contact.p`` names a law of
:data:`~vpcontact.laws.compliance.COMPLIANCE`, whose parameters are keys of the layer itself
(``contact.exponent``), required with that law and refused with the others. The parameters of the contact
laws are numbers or expressions in the coordinates (the paper's K(x, ξ) and p(x, r), evaluated at the contact
nodes of their part by :func:`vpcontact.laws.contact.law_at_nodes`), or a table's lists of points and the name of
its extrapolation (``law = "table"``), checked together by the law's ``check`` (:class:`~vpcontact.laws.spec.Law`);
those of a viscoplastic law are numbers. The translation (:mod:`vpcontact.case.translate`) makes each table a law's
name and its parameters. A new law needs nothing here: its module and its name in its registry make its table and
its checks.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional, Union

from pydantic import BaseModel, Field, create_model, model_validator

from ..laws.compliance import COMPLIANCE
from ..laws.spec import Law, Parameter, ParameterError
from ..laws.stiffness import STIFFNESS
from ..laws.viscoplastic import VISCOPLASTIC
from ..registry import Registry
from .values import Section, layer_value


def _layer_parameter(parameter: Parameter):
    """A parameter of a contact law: a number within the parameter's bound or an expression in the coordinates; a
    table's points: a list of at least 2 finite numbers, each within the bound; a choice: one of its names."""
    if parameter.choices:
        return Literal[parameter.choices]
    if parameter.points:
        point = float if parameter.minimum is None else _number(parameter)
        return Annotated[list[point], Field(min_length=2)]
    return layer_value(parameter.minimum, parameter.strict)


def _number(parameter: Parameter):
    """A parameter of a viscoplastic law: a number within the parameter's bound."""
    if parameter.minimum is None:
        return float
    return Annotated[float, Field(gt=parameter.minimum) if parameter.strict else Field(ge=parameter.minimum)]


def _law_tables(registry: Registry[Law], value):
    """The tables of the laws of ``registry``, told apart by their key ``law``: for each law a section with the
    key ``law`` (its name) and one required key per parameter, of type ``value(parameter)``, in its order."""
    family = registry.package.rpartition(".")[2]
    return Annotated[Union[tuple(_table(law, family, value) for law in registry.values())], Field(discriminator="law")]


def _table(law: Law, family: str, value) -> type[BaseModel]:
    """The table of one law of ``family`` ("stiffness": PowerStiffnessSection), a module attribute (a case pickles)."""
    name = "".join(word.title() for word in (*law.name.split("_"), family, "section"))
    validators = {} if law.check is None else {"_check": model_validator(mode="after")(_checked(law))}
    table = create_model(name, __base__=Section, __doc__=law.summary, __module__=__name__, law=(Literal[law.name], ...),
                         __validators__=validators,
                         **{parameter.name: (value(parameter), ...) for parameter in law.parameters})
    globals()[name] = table
    return table


def _checked(law: Law):
    """The validator of ``law``'s table: its ``check`` of the parameters together, a message ".<key> = ...: ..."
    naming the bad key of the table (:func:`vpcontact.case.messages.describe` puts the table's key before it)."""

    def check(table):
        try:
            law.check(**{parameter.name: getattr(table, parameter.name) for parameter in law.parameters})
        except ParameterError as error:
            raise ValueError(f".{error}") from None
        return table

    return check


#: contact.stiffness: the table of a law of vpcontact.laws.stiffness (law = its name, its parameters, each a number
#: or an expression in the coordinates: the paper's K(x, ξ), (2.18)).
Stiffness = _law_tables(STIFFNESS, _layer_parameter)
#: material.viscoplastic: the table of a law of vpcontact.laws.viscoplastic (law = its name, its parameters).
Viscoplastic = _law_tables(VISCOPLASTIC, _number)
#: The names of the laws of each table that has a key ``law``, by the table's key (the messages list them).
LAW_TAGS = {"stiffness": STIFFNESS.names, "viscoplastic": VISCOPLASTIC.names}


def _compliance_parameters() -> dict[str, Parameter]:
    """The parameters of the laws p by name, each once."""
    return {parameter.name: parameter for law in COMPLIANCE.values() for parameter in law.parameters}


#: The keys of a layer that state its law p: ``p`` and the parameters of the laws p.
COMPLIANCE_KEYS = ("p", *_compliance_parameters())


def with_compliance(base: type[BaseModel], default: str | None) -> type[BaseModel]:
    """``base`` followed by the layer's keys of its law p: ``p``, a name of COMPLIANCE (``default`` when not given;
    None: optional), and the parameters of every law p (None when not given; see :func:`check_compliance`), each a
    number or an expression in the coordinates (the paper's p(x, r), (2.19))."""
    names = Literal[COMPLIANCE.names]
    return create_model(f"{base.__name__}Compliance", __base__=base, __module__=base.__module__,
                        p=(names if default is not None else Optional[names], default),
                        **{name: (Optional[_layer_parameter(parameter)], None)
                           for name, parameter in _compliance_parameters().items()})


def check_compliance(key: str, layer) -> None:
    """ValueError unless the layer of the case key ``key`` gives the parameters of its law p (``layer.p``; None
    for a law of the API), valid together (the law's ``check``: a table's points), and no other law's."""
    for name in COMPLIANCE_KEYS[1:]:
        users = [law.name for law in COMPLIANCE.values() if any(parameter.name == name for parameter in law.parameters)]
        if layer.p in users and getattr(layer, name) is None:
            raise ValueError(f"missing required value '{key}.{name}' (needed by {key}.p = \"{layer.p}\")")
        if layer.p not in users and getattr(layer, name) is not None:
            laws = " or ".join(f'"{user}"' for user in users)
            raise ValueError(f"{key}.{name} is only used with {key}.p = {laws} ({key}.p = \"{layer.p}\")")
    law = COMPLIANCE[layer.p] if layer.p is not None else None
    if law is not None and law.check is not None:
        try:
            law.check(**compliance_parameters(layer))
        except ParameterError as error:
            raise ValueError(f"{key}.{error}") from None


def compliance_parameters(layer) -> dict[str, Any]:
    """The parameters of a layer's law p (``layer.p``, a name of COMPLIANCE) by name: keys of the layer itself."""
    return {parameter.name: getattr(layer, parameter.name) for parameter in COMPLIANCE[layer.p].parameters}


def poisson_ratios(table) -> list[tuple[str, float]]:
    """(key, value) of the parameters of a ``material.viscoplastic`` table that are Poisson ratios."""
    return [(parameter.name, getattr(table, parameter.name)) for parameter in VISCOPLASTIC[table.law].parameters
            if parameter.poisson_ratio]
