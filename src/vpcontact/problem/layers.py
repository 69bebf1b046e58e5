"""The contact law of a problem: the layer of each contact part (its thickness g, its laws p and K (2.18),
(2.19), each named in :data:`~vpcontact.laws.compliance.COMPLIANCE` or :data:`~vpcontact.laws.stiffness.STIFFNESS`
with its parameters, each parameter a number or an expression in the coordinates) at the nodes the part owns,
merged into one law over the contact nodes."""

from __future__ import annotations

from typing import Callable

from ..fem.contact_surface import ContactSurface
from ..laws.compliance import COMPLIANCE
from ..laws.contact import ContactLaw, law_at_nodes, layer_parameter, merged_law, per_node
from ..laws.python_laws import LawOfNodes
from ..laws.stiffness import STIFFNESS
from .options import ContactOptions


def contact_law(contact: ContactOptions, surface: ContactSurface, p: Callable | None,
                stiffness_law: Callable | None) -> ContactLaw:
    """The layer of each contact part at the nodes it owns (its keys' numbers, or expressions evaluated
    there), merged into one law over the contact nodes (see contact.merged_law); ``p`` and
    ``stiffness_law`` of the API, when given, replace the case's on every part."""
    ps, stiffnesses, limits = [], [], []
    for j, layer in enumerate(contact.layers):
        key, points = layer.key, surface.coordinates[:, surface.owner == j]
        if p is None:
            ps.append(law_at_nodes(COMPLIANCE[layer.p.law], layer.p.parameters, key, points))
        if stiffness_law is None:
            stiffnesses.append(law_at_nodes(STIFFNESS[layer.stiffness.law], layer.stiffness.parameters,
                                            f"{key}.stiffness", points))
        limits.append(layer_parameter(f"{key}.g", layer.g, 0.0, points=points, strict=True))
    owner = surface.owner
    p, stiffness_law = (law.at(surface.coordinates) if isinstance(law, LawOfNodes) else law
                        for law in (p, stiffness_law))
    return ContactLaw(p=merged_law(ps, owner) if p is None else p, g=per_node(limits, owner), rho=contact.rho,
                      stiffness=merged_law(stiffnesses, owner) if stiffness_law is None else stiffness_law)
