"""``[contact]``: the contact condition (2.5) on Γ3, a soft layer of thickness g on a rigid base, on one
part or on several (``contact.parts``), with its stiffness law K (2.18) and its law p (their tables:
:mod:`vpcontact.case.law_sections`)."""

from __future__ import annotations

import math
from collections.abc import Collection
from typing import Annotated, Any, Optional

from pydantic import AfterValidator, Field, ValidationInfo, model_validator

from ..errors import brief
from .law_sections import COMPLIANCE_KEYS, Stiffness, check_compliance, with_compliance
from .values import Expression, NonNegativeFloat, Part, Section, Thickness, finite, show


#: The lengths a vector contact.normal may have: only its direction counts (it is divided by its length), and
#: squares of its entries must neither underflow nor overflow in float64 (so [0, 0, -1e-200] is refused).
NORMAL_LENGTHS = (1e-100, 1e100)


def _normal(value):
    """contact.normal: "body", or a nonzero vector of 2 or 3 finite numbers (made floats) whose length is in
    NORMAL_LENGTHS."""
    if value == "body":
        return value
    if not (isinstance(value, list) and 2 <= len(value) <= 3 and
            all(isinstance(c, (int, float)) and not isinstance(c, bool) and finite(c) for c in value)):
        raise ValueError(f"contact.normal = {show(value)}: expected \"body\" or a vector of 2 or 3 finite numbers, "
                         f"the foundation's outward direction seen from the body (e.g. [0, 0, -1])")
    vector = [float(c) for c in value]
    length = math.hypot(*vector)
    if not length > 0:
        raise ValueError(f"contact.normal = {brief(vector)}: expected \"body\" or a nonzero vector (the "
                         f"foundation's outward direction seen from the body, e.g. [0, 0, -1])")
    if not NORMAL_LENGTHS[0] <= length <= NORMAL_LENGTHS[1]:
        raise ValueError(f"contact.normal = {brief(vector)}: its length {length:.3g} is outside "
                         f"[{NORMAL_LENGTHS[0]:g}, {NORMAL_LENGTHS[1]:g}], where it is made a unit vector without "
                         f"underflow or overflow; give the direction with entries of order 1, e.g. [0, 0, -1]")
    return vector


#: The keys of one layer: stated in [contact] for one contact part, in each entry of contact.parts for several.
LAYER_KEYS = ("part", "g", "gap", *COMPLIANCE_KEYS, "stiffness")
#: The keys of the whole contact, one value for all its parts.
GLOBAL_CONTACT_KEYS = ("rho", "probe", "normal")


class _PartLayer(Section):
    """The keys of a contact part's layer before those of its law p (contact.p and its parameters, see
    :func:`~vpcontact.case.law_sections.with_compliance`)."""

    part: Part
    g: Thickness
    gap: Expression = 0.0


class ContactPartSection(with_compliance(_PartLayer, "positive_part")):
    """One part of Γ3 with its own layer (an entry of contact.parts)."""

    stiffness: Stiffness

    @model_validator(mode="before")
    @classmethod
    def _no_global_key(cls, data):
        if isinstance(data, dict):
            for key in GLOBAL_CONTACT_KEYS:
                if key in data:
                    raise ValueError(f"{key} is one value for the whole contact, not a part's: state it once in "
                                     f"[contact] (contact.{key})")
        return data


class _ContactLayer(Section):
    """The keys of the one-part form's layer before those of its law p (contact.p, default "positive_part" with
    part, and its parameters)."""

    part: Optional[Part] = None
    g: Thickness = None
    gap: Optional[Expression] = None  # default 0 with part


class ContactSection(with_compliance(_ContactLayer, None)):
    """The contact condition (2.5) on Γ3: soft layer of thickness g on a rigid base. Γ3 is one part
    (``part`` and its layer's keys here) or several (``parts``: a list of parts, each with its layer); a
    node where two parts meet takes the layer of the one listed first. rho, probe and normal are the
    whole contact's."""

    rho: NonNegativeFloat = 1.0
    probe: Optional[Annotated[list[float], Field(min_length=2, max_length=3)]] = None
    normal: Annotated[Any, AfterValidator(_normal)] = "body"
    stiffness: Optional[Stiffness] = None
    parts: Optional[Annotated[list[ContactPartSection], Field(min_length=1)]] = None

    @model_validator(mode="after")
    def _one_form(self, info: ValidationInfo):
        """One part or several; ``info.context["python_laws"]``: the laws (``p``, ``stiffness``) given as Python
        objects instead (vpcontact.compose), which the one-part form then leaves out."""
        python_laws = (info.context or {}).get("python_laws", ())
        if self.parts is None:
            self._one_part(python_laws)
        else:
            self._several_parts()
        for key, layer in self.layers():
            check_compliance(key, layer)
        return self

    def _one_part(self, python_laws: Collection[str]) -> None:
        for key in ("part", "g", "stiffness"):
            if getattr(self, key) is None and key not in python_laws:
                hint = " (or contact.parts, a list of parts each with its layer)" if key == "part" else ""
                raise ValueError(f"missing required value 'contact.{key}'{hint}")
        self.gap = 0.0 if self.gap is None else self.gap
        if "p" not in python_laws:
            self.p = "positive_part" if self.p is None else self.p

    def _several_parts(self) -> None:
        given = [key for key in LAYER_KEYS if getattr(self, key) is not None]
        if given:
            raise ValueError(f"contact.{given[0]} is given with contact.parts: each entry of contact.parts states "
                             f"its own layer ({', '.join(LAYER_KEYS)}); move contact.{given[0]} into the entries")
        names = [str(entry.part) for entry in self.parts]
        for j, name in enumerate(names):
            if name in names[:j]:
                raise ValueError(f"contact.parts[{j}].part = {show(name)} is also contact.parts[{names.index(name)}]"
                                 f".part: each part has one layer")

    def layers(self) -> list[tuple[str, "ContactSection | ContactPartSection"]]:
        """(key, layer) of each contact part, in order: ("contact", self) for one part, else
        ("contact.parts[j]", entry); a layer has the attributes LAYER_KEYS."""
        if self.parts is None:
            return [("contact", self)]
        return [(f"contact.parts[{j}]", entry) for j, entry in enumerate(self.parts)]
