"""The stiffness coefficients K(ξ) of the soft layer (2.18), by their names in ``contact.stiffness.law``.

Each law is a module of this package, named after it, whose ``LAW`` (:class:`~vpcontact.laws.spec.Law`)
makes the law's object with ``make(**parameters)``: a class whose attributes are the parameters (each a
number, or an array with one value per contact node: K(x, ξ) varies along Γ3; or a table's points and its
extrapolation, :mod:`vpcontact.laws.tabulated`), called on the array of ξ at the contact nodes and with a
``derivative`` method on it. A new law is one module here and its name
in STIFFNESS.
"""

from ...registry import Registry

#: The laws of contact.stiffness.law, in the order messages list them.
STIFFNESS = Registry(__name__, ("power", "constant", "exponential", "table"), "LAW")
