"""The contact law of a problem: the layer of each contact part (its thickness g, its laws p and K (2.18),
(2.19), each parameter a number or an expression in the coordinates) at the nodes the part owns, merged into
one law over the contact nodes."""

from __future__ import annotations

from functools import partial
from typing import Callable

import numpy as np

from ..errors import CaseError, quoted
from ..expressions.parse import values_at
from ..fem.space import coordinates
from ..laws.contact import (ConstantStiffness, ContactLaw, ContactSurface, ExponentialStiffness, PositivePart, Power,
                            PowerStiffness, merged_law, per_node)
from ..laws.python_laws import LawOfNodes
from .options import ContactOptions, LawChoice


def contact_law(contact: ContactOptions, surface: ContactSurface, p: Callable | None,
                stiffness_law: Callable | None) -> ContactLaw:
    """The layer of each contact part at the nodes it owns (its keys' numbers, or expressions evaluated
    there), merged into one law over the contact nodes (see contact.merged_law); ``p`` and
    ``stiffness_law`` of the API, when given, replace the case's on every part."""
    ps, stiffnesses, limits = [], [], []
    for j, layer in enumerate(contact.layers):
        key = layer.key
        at = partial(_layer_parameter, points=surface.coordinates[:, surface.owner == j])
        if p is None:
            ps.append(PositivePart() if layer.p == "positive_part" else
                      Power(at(f"{key}.exponent", layer.exponent, 1.0)))
        if stiffness_law is None:
            stiffnesses.append(_stiffness_law(layer.stiffness, f"{key}.stiffness", at))
        limits.append(at(f"{key}.g", layer.g, 0.0, strict=True))
    owner = surface.owner
    p, stiffness_law = (law.at(surface.coordinates) if isinstance(law, LawOfNodes) else law
                        for law in (p, stiffness_law))
    return ContactLaw(p=merged_law(ps, owner) if p is None else p, g=per_node(limits, owner), rho=contact.rho,
                      stiffness=merged_law(stiffnesses, owner) if stiffness_law is None else stiffness_law)


def _stiffness_law(choice: LawChoice, key: str, at: Callable):
    """K(x, ξ) of the stiffness law ``choice`` (2.18) of the case key ``key``: each parameter a number, or an
    expression in the coordinates evaluated by ``at`` at the nodes of its part."""
    s = choice.parameters
    if choice.law == "power":
        return PowerStiffness(at(f"{key}.c_v", s["c_v"], 0.0), at(f"{key}.alpha", s["alpha"], 0.0),
                              at(f"{key}.beta", s["beta"]))
    if choice.law == "constant":
        return ConstantStiffness(at(f"{key}.value", s["value"], 0.0))
    return ExponentialStiffness(at(f"{key}.c_v", s["c_v"], 0.0), at(f"{key}.alpha", s["alpha"]))


def _layer_parameter(where: str, value, minimum: float | None = None, *, points: np.ndarray, strict: bool = False):
    """The layer parameter of the case key ``where``: a number as it is; an expression's values at the
    contact nodes ``points`` (d, k), refused (naming the node) where they are not finite or below
    ``minimum`` (or equal to it, when ``strict``)."""
    if not isinstance(value, str):
        return float(value)
    names, count = coordinates(points.shape[0]), points.shape[1]
    values = values_at(value, where, points, names)
    if minimum is None:
        wrong = ~np.isfinite(values)
    else:
        wrong = ~np.isfinite(values) | ~(values > minimum if strict else values >= minimum)
    if wrong.any():
        node = np.flatnonzero(wrong)[0]
        at = ", ".join(f"{c:.6g}" for c in points[:, node])
        expected = "finite" if minimum is None else f"a finite number {'>' if strict else '>='} {minimum:g}"
        raise CaseError(f"{where} = {quoted(value)} is {values[node]:g} at the contact node ({', '.join(names)}) = "
                        f"({at}) ({wrong.sum()} of {count} nodes): expected {expected} at every node of the "
                        f"contact part")
    return values.copy()
