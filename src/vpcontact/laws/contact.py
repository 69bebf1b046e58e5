"""The contact condition (2.5) at the nodes of Γ3: the layer's law from p and K(ξ) (:mod:`vpcontact.laws.compliance`,
:mod:`vpcontact.laws.stiffness`, or Python laws), one law over the parts of Γ3, and the nodes' states.

Node-to-rigid contact: node i of Γ3 (:mod:`vpcontact.fem.contact_surface`: its unit normal ν_i, weight w_i and
initial gap g0_i) has the penetration d_i = u(x_i)·ν_i − g0_i. The soft layer pushes back with the nodal force::

    w_i ρ K(ξ_i) p(d_i),   ξ_i^n = ξ_i^{n−1} + k (d_i^n)^+   (the implicit rectangle rule for (2.15)),

and the rigid base adds a multiplier λ_i ≥ 0 once d_i reaches g.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import CaseError, point, quoted
from ..expressions.parse import values_at
from ..mesh.cells import coordinates as coordinates_names
from .compliance import COMPLIANCE
from .spec import Law
from .stiffness import STIFFNESS

#: Node states reported per contact node and step.
SEPARATED, IN_COMPLIANCE, AT_LIMIT = 0, 1, 2
STATUS_NAMES = ("separated", "in_compliance", "at_limit")


@dataclass(frozen=True)
class CallableLaw:
    """A user law f with its derivative df (both vectorized over NumPy arrays), for p or K.

    Without df the derivative is the central difference (f(r + δ) − f(r − δ)) / 2δ with
    δ = 1e-7 max|r| over the nodes (r's own scale, so the same in any unit; 1e-7 when every r is 0):
    Newton then converges fast but not quadratically.
    """

    function: Callable[[np.ndarray], np.ndarray]
    function_derivative: Callable[[np.ndarray], np.ndarray] | None = None

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return np.asarray(self.function(r), dtype=float) * np.ones_like(r, dtype=float)

    def derivative(self, r: np.ndarray) -> np.ndarray:
        if self.function_derivative is not None:
            return np.asarray(self.function_derivative(r), dtype=float) * np.ones_like(r, dtype=float)
        scale = np.abs(r).max(initial=0.0)
        delta = 1e-7 * (scale if scale > 0.0 else 1.0)
        return (self(r + delta) - self(r - delta)) / (2.0 * delta)


@dataclass(frozen=True, eq=False)
class AtNodes:
    """A law f(r, x) of the API with x bound to the (d, m) coordinates of the contact nodes: a law of r
    over the contact nodes."""

    function: Callable[[np.ndarray, np.ndarray], np.ndarray]
    coordinates: np.ndarray = field(repr=False)

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return self.function(r, self.coordinates)


@dataclass(frozen=True, eq=False)
class PiecewiseLaw:
    """Laws of different families on the parts of Γ3 (e.g. K power on one part, constant on another):
    ``laws[j]`` at the contact nodes where ``owner == j``, its parameters given at those nodes only.
    Evaluated, like every law, on arrays over all the contact nodes."""

    laws: tuple
    owner: np.ndarray  # (m,) the index of each contact node's law

    def _each(self, method: str, r: np.ndarray) -> np.ndarray:
        values = np.empty(np.shape(r))
        for j, law in enumerate(self.laws):
            mine = self.owner == j
            values[mine] = getattr(law, method)(r[mine])
        return values

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return self._each("__call__", r)

    def derivative(self, r: np.ndarray) -> np.ndarray:
        return self._each("derivative", r)


def law_at_nodes(law: Law, parameters: Mapping, key: str, points: np.ndarray):
    """The object of ``law`` (a law K or p of the registries) on a contact part whose nodes are ``points`` (d, k):
    each of its parameters, ``parameters[name]`` of the case key ``key.name``, a number or an expression's values
    at the nodes (:func:`layer_parameter`, checked against the parameter's bound), or a table's points or
    choice as they are (the same at every node of the part)."""
    def value(parameter):
        if not parameter.per_node:
            return parameters[parameter.name]
        return layer_parameter(f"{key}.{parameter.name}", parameters[parameter.name], parameter.minimum,
                               points=points, strict=parameter.strict)

    return law.made(value)


def layer_parameter(where: str, value, minimum: float | None = None, *, points: np.ndarray, strict: bool = False):
    """The layer parameter of the case key ``where``: a number as it is; an expression's values at the
    contact nodes ``points`` (d, k), refused (naming the node) where they are not finite or below
    ``minimum`` (or equal to it, when ``strict``)."""
    if not isinstance(value, str):
        return float(value)
    names, count = coordinates_names(points.shape[0]), points.shape[1]
    values = values_at(value, where, points, names)
    if minimum is None:
        wrong = ~np.isfinite(values)
    else:
        wrong = ~np.isfinite(values) | ~(values > minimum if strict else values >= minimum)
    if wrong.any():
        node = np.flatnonzero(wrong)[0]
        expected = "finite" if minimum is None else f"a finite number {'>' if strict else '>='} {minimum:g}"
        raise CaseError(f"{where} = {quoted(value)} is {values[node]:g} at the contact node ({', '.join(names)}) = "
                        f"{point(points[:, node])} ({wrong.sum()} of {count} nodes): expected {expected} at every "
                        f"node of the contact part")
    return values.copy()


def per_node(values: list, owner: np.ndarray) -> float | np.ndarray:
    """One value per contact node from ``values[j]`` (a number, or an array at the nodes where
    ``owner == j``); the number itself when every part has the same number."""
    if all(np.ndim(value) == 0 for value in values) and len(set(values)) == 1:
        return values[0]
    merged = np.empty(owner.size)
    for j, value in enumerate(values):
        merged[owner == j] = value
    return merged


def merged_law(laws: list, owner: np.ndarray):
    """One law over all the contact nodes from ``laws[j]`` at the nodes where ``owner == j``: the same
    family everywhere gives that family with its parameters per_node, different families (or laws
    without named parameters, or tables, whose points are not per node) a PiecewiseLaw."""
    first = laws[0]
    if len(laws) == 1:
        return first
    declared = _declared(first)
    if (declared is None or any(type(law) is not type(first) for law in laws)
            or not all(parameter.per_node for parameter in declared.parameters)):
        return PiecewiseLaw(tuple(laws), owner)
    return declared.made(lambda parameter: per_node([getattr(law, parameter.name) for law in laws], owner))


def law_parameters(law, m: int) -> dict[str, np.ndarray]:
    """The named parameters of ``law`` at the m contact nodes (NaN at the nodes of a PiecewiseLaw's part
    whose law has not that parameter): its numbers, not a table's points; none for a Python law (its
    parameters are unknown)."""
    if isinstance(law, PiecewiseLaw):
        values: dict[str, np.ndarray] = {}
        for j, part_law in enumerate(law.laws):
            mine = law.owner == j
            for name, value in law_parameters(part_law, int(mine.sum())).items():
                values.setdefault(name, np.full(m, np.nan))[mine] = value
        return values
    declared = _declared(law)
    if declared is None:
        return {}
    return {p.name: np.broadcast_to(np.asarray(getattr(law, p.name), dtype=float), (m,)) for p in declared.parameters
            if p.per_node}


def _declared(law) -> Law | None:
    """The law of the registries (K or p) whose object ``law`` is, None for a law of the API."""
    declared = (entry for registry in (STIFFNESS, COMPLIANCE) for entry in registry.values() if type(law) is entry.make)
    return next(declared, None)


def layer_parameters() -> tuple[str, ...]:
    """The layer's parameters per contact node, in the order of the outputs' columns: g, then those of the
    laws K and p in the order of their registries (their numbers: a table's points are not per node)."""
    names = [p.name for registry in (STIFFNESS, COMPLIANCE) for law in registry.values() for p in law.parameters
             if p.per_node]
    return ("g", *dict.fromkeys(names))


@dataclass(frozen=True)
class ContactLaw:
    """The soft layer of thickness g on the rigid base: ρ K(ξ) p(d) while d < g, d ≤ g always. g is a
    number (inf: no rigid base) or one thickness per contact node (a layer that varies along Γ3)."""

    p: Callable
    stiffness: Callable
    g: float | np.ndarray
    rho: float = 1.0

    def limit(self, nodes: np.ndarray) -> float | np.ndarray:
        """g at the contact nodes ``nodes`` (an index or a mask)."""
        return self.g if np.ndim(self.g) == 0 else self.g[nodes]

    def parameters(self, m: int) -> dict[str, np.ndarray]:
        """The local layer parameters at the m contact nodes, in the order of layer_parameters(): g, those
        of K (c_v, alpha, beta or value) and the exponent of p = power, where the laws have them."""
        values = {"g": np.broadcast_to(np.asarray(self.g, dtype=float), (m,)),
                  **law_parameters(self.stiffness, m), **law_parameters(self.p, m)}
        return {name: values[name] for name in layer_parameters() if name in values}

    def K(self, xi: np.ndarray) -> np.ndarray:
        """ρ K(ξ): the stiffness coefficient in force (the paper's K_ρ)."""
        return self.rho * self.stiffness(xi)

    def violation(self, d: np.ndarray, xi: np.ndarray) -> tuple[str, int, float, str, float] | None:
        """The first contact node where K(ξ) or p(d) is not a finite number ≥ 0 (a user's law that turns
        negative, a law evaluated beyond its range, an overflow): (the law, "K(ξ)" or "p(r)"; the node's index;
        the value; the argument's name, "ξ" or "r"; its value at the node), K checked first; None when both
        laws are valid at every node."""
        with np.errstate(all="ignore"):  # the values that are not valid are reported
            for law, values, name, argument in (("K(ξ)", self.stiffness(xi), "ξ", xi), ("p(r)", self.p(d), "r", d)):
                values = np.broadcast_to(np.asarray(values, dtype=float), np.shape(argument))
                wrong = np.flatnonzero(~(np.isfinite(values) & (values >= 0.0)))
                if wrong.size:
                    i = int(wrong[0])
                    return law, i, float(values[i]), name, float(argument[i])
        return None

    def pressure(self, d: np.ndarray, xi_prev: np.ndarray, k: float) -> tuple[np.ndarray, np.ndarray]:
        """Compliance pressure ρ K(ξ_prev + k d⁺) p(d) and its derivative in d (the generalized one).

        The derivative is ρ [K p'(d) + K'(ξ) k H(d) p(d)]: the history ξ depends on the current
        penetration (implicit rule), which is what makes the step problem non-variational.
        """
        xi = xi_prev + k * np.maximum(d, 0.0)
        K = self.rho * self.stiffness(xi)
        dK = self.rho * self.stiffness.derivative(xi) * k * (d > 0.0)
        p = self.p(d)
        return K * p, K * self.p.derivative(d) + dK * p


def node_status(d: np.ndarray, active: np.ndarray) -> np.ndarray:
    """SEPARATED where d ≤ 0, AT_LIMIT where the rigid multiplier is active, else IN_COMPLIANCE."""
    status = np.where(d > 0.0, IN_COMPLIANCE, SEPARATED)
    return np.where(active, AT_LIMIT, status).astype(np.int8)
