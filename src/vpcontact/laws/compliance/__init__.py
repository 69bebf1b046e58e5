"""The normal compliance functions p(r) of the soft layer (2.19), by their names in ``contact.p``.

Each law is a module of this package, named after it, whose ``LAW`` (:class:`~vpcontact.laws.spec.Law`)
makes the law's object with ``make(**parameters)``: a class whose attributes are the parameters (each a
number, or an array with one value per contact node: p(x, r) varies along Γ3; or a table's points and its
extrapolation, :mod:`vpcontact.laws.tabulated`), called on the array of
the penetrations r at the contact nodes and with a ``derivative`` method on it (the generalized one where
p has a kink). Its parameters are keys of the layer itself (``contact.exponent``), required with that law
and refused with the others. A new law is one module here and its name in COMPLIANCE.
"""

from ...registry import Registry

#: The laws of contact.p, in the order messages list them.
COMPLIANCE = Registry(__name__, ("positive_part", "power", "table"), "LAW")
