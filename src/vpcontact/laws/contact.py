"""The contact condition (2.5) at the nodes of Γ3: laws p and K(ξ), nodal normals and weights.

Node-to-rigid contact: node i of Γ3 carries a unit normal ν_i (the body's outward normal, the
paper's u_ν, or the fixed direction of a flat foundation), a weight w_i (its share of the measure of
Γ3, lumped boundary quadrature), an initial gap g0_i to the foundation along ν_i, and the
penetration d_i = u(x_i)·ν_i − g0_i. The soft layer pushes back with the nodal force::

    w_i ρ K(ξ_i) p(d_i),   ξ_i^n = ξ_i^{n−1} + k (d_i^n)^+   (the implicit rectangle rule for (2.15)),

and the rigid base adds a multiplier λ_i ≥ 0 once d_i reaches g.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Callable

import numpy as np
import scipy.sparse as sp
from skfem import FacetBasis

from ..errors import CaseError, quoted
from ..expressions.parse import Expression
from ..mesh.core import Mesh
from ..fem.space import coordinates as coordinates_names

#: Node states reported per contact node and step.
SEPARATED, IN_COMPLIANCE, AT_LIMIT = 0, 1, 2
STATUS_NAMES = ("separated", "in_compliance", "at_limit")


# --- normal compliance functions p (2.19) ------------------------------------------------------
@dataclass(frozen=True)
class PositivePart:
    """p(r) = r⁺, with the generalized derivative p'(r) = 1 for r ≥ 0 (so p'(0) = 1), else 0."""

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return np.maximum(r, 0.0)

    def derivative(self, r: np.ndarray) -> np.ndarray:
        return (r >= 0.0).astype(float)


@dataclass(frozen=True)
class Power:
    """p(r) = (r⁺)^m with m ≥ 1 (Lipschitz on bounded sets; p'(0) = 1 when m = 1); m is a number or one
    exponent per contact node (the paper's p(x, r), (2.19))."""

    exponent: float | np.ndarray

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return np.maximum(r, 0.0) ** self.exponent

    def derivative(self, r: np.ndarray) -> np.ndarray:
        """m (r⁺)^(m−1), and where m = 1 the derivative of r⁺ (1 for r ≥ 0, 0 below: (r⁺)^0 would be 1
        for r < 0 too)."""
        m = self.exponent
        return np.where(m == 1.0, PositivePart().derivative(r), m * np.maximum(r, 0.0) ** (m - 1.0))


# --- stiffness coefficients K(ξ) (2.18) --------------------------------------------------------
# Their parameters are numbers, or arrays with one value per contact node: the layer varies along Γ3,
# K(x, ξ) (the laws are evaluated on arrays of all the contact nodes).
@dataclass(frozen=True)
class PowerStiffness:
    """K(ξ) = c_v (1 + α ξ)^β: the paper's law; β > 0 hardens, β < 0 softens, α = 0 is constant."""

    c_v: float | np.ndarray
    alpha: float | np.ndarray
    beta: float | np.ndarray

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * (1.0 + self.alpha * xi) ** self.beta

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * self.alpha * self.beta * (1.0 + self.alpha * xi) ** (self.beta - 1.0)


@dataclass(frozen=True)
class ConstantStiffness:
    """K(ξ) = value (value = 0: the Signorini condition with gap g)."""

    value: float | np.ndarray

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return np.zeros_like(xi, dtype=float) + self.value

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return np.zeros_like(xi, dtype=float)


@dataclass(frozen=True)
class ExponentialStiffness:
    """K(ξ) = c_v exp(α ξ): α > 0 hardens, α < 0 softens."""

    c_v: float | np.ndarray
    alpha: float | np.ndarray

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * np.exp(self.alpha * xi)

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return self.alpha * self(xi)


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


#: The laws whose parameters are known by name (the columns of the layer in the outputs).
PARAMETRIC_LAWS = (PositivePart, Power, PowerStiffness, ConstantStiffness, ExponentialStiffness)
#: The layer's parameters per contact node, in the order of the outputs' columns.
LAYER_PARAMETERS = ("g", "c_v", "alpha", "beta", "value", "exponent")


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
    without named parameters) a PiecewiseLaw."""
    first = laws[0]
    if len(laws) == 1:
        return first
    if any(type(law) is not type(first) for law in laws) or not isinstance(first, PARAMETRIC_LAWS):
        return PiecewiseLaw(tuple(laws), owner)
    return type(first)(**{f.name: per_node([getattr(law, f.name) for law in laws], owner) for f in fields(first)})


def law_parameters(law, m: int) -> dict[str, np.ndarray]:
    """The named parameters of ``law`` at the m contact nodes (NaN at the nodes of a PiecewiseLaw's part
    whose law has not that parameter); none for a Python law (its parameters are unknown)."""
    if isinstance(law, PiecewiseLaw):
        values: dict[str, np.ndarray] = {}
        for j, part_law in enumerate(law.laws):
            mine = law.owner == j
            for name, value in law_parameters(part_law, int(mine.sum())).items():
                values.setdefault(name, np.full(m, np.nan))[mine] = value
        return values
    if isinstance(law, PARAMETRIC_LAWS):
        return {f.name: np.broadcast_to(np.asarray(getattr(law, f.name), dtype=float), (m,)) for f in fields(law)}
    return {}


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
        """The local layer parameters at the m contact nodes, in the order of LAYER_PARAMETERS: g, those
        of K (c_v, alpha, beta or value) and the exponent of p = power, where the laws have them."""
        values = {"g": np.broadcast_to(np.asarray(self.g, dtype=float), (m,)),
                  **law_parameters(self.stiffness, m), **law_parameters(self.p, m)}
        return {name: values[name] for name in LAYER_PARAMETERS if name in values}

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


# --- the contact nodes of Γ3 ---------------------------------------------------------------------
@dataclass(frozen=True)
class ContactSurface:
    """Nodes of Γ3 with normals ν_i, lumped weights w_i and initial gaps g0_i.

    ``operator`` is the sparse m × ndofs matrix N with (N u)_i = u(x_i)·ν_i; ``facets`` (d, nf) are
    the facets of Γ3 (segments in 2D, triangles in 3D) as tuples of contact-node indices; ``parts`` the
    names of the contact parts Γ3 is made of, ``owner`` (m,) the index in ``parts`` of each node's part
    (a node where parts meet belongs to the first one listed).
    """

    nodes: np.ndarray
    coordinates: np.ndarray  # (d, m)
    normals: np.ndarray  # (d, m)
    weights: np.ndarray  # (m,)
    gap0: np.ndarray  # (m,)
    operator: sp.csr_matrix
    facets: np.ndarray
    parts: tuple[str, ...]
    owner: np.ndarray

    @property
    def size(self) -> int:
        return self.nodes.size

    def nearest_node(self, point) -> int:
        """Index (into the contact nodes) of the node nearest to ``point`` (any finite point: the offsets are
        scaled so that their squares cannot overflow)."""
        offsets = self.coordinates - np.reshape(point, (-1, 1))
        scale = np.abs(offsets).max(initial=0.0)
        return int(np.argmin(np.sum((offsets / scale if scale > 0 else offsets) ** 2, axis=0)))


def contact_surface(mesh: Mesh, parts, nodal_dofs: np.ndarray, gap=None, direction=None) -> ContactSurface:
    """Build the contact nodes of Γ3, the union of ``parts`` (a part, or a list of parts that share no
    facet; a node where they meet belongs to the first one listed): weights w_i = ∫_Γ3 φ_i da (a d-th
    of the measure of each adjacent facet); normals: the fixed unit ``direction`` (a flat foundation,
    ``contact.normal``) when given, else the exact ones where the mesh knows the geometry of the node's
    part, else the measure-weighted average of the adjacent facets' outward normals (facet measures
    and normals from scikit-fem's FacetBasis); ``gap(x, y[, z])`` gives g0 (default 0), along the
    normal: one function, or one per part (each at the nodes of its part)."""
    skmesh, d = mesh.mesh, mesh.dim
    parts = list(parts) if isinstance(parts, (list, tuple)) else [parts]
    gaps = list(gap) if isinstance(gap, (list, tuple)) else [gap] * len(parts)
    facets = _union_of_parts(mesh, parts)
    geometry = FacetBasis(skmesh, skmesh.elem(), facets=facets, intorder=1)
    measure = geometry.dx.sum(axis=1)  # (nf,)
    outward = geometry.normals[:, :, 0]  # (d, nf): constant on a flat facet
    corners = skmesh.facets[:, facets]  # (d, nf)
    nodes, local = np.unique(corners.ravel(), return_inverse=True)
    local = local.reshape(corners.shape)
    m = nodes.size
    owner = np.zeros(m, dtype=np.int64)
    for j in reversed(range(len(parts))):  # the first part listed is written last: it keeps the shared nodes
        owner[np.searchsorted(nodes, mesh.nodes(parts[j]))] = j
    weights = np.bincount(local.ravel(), weights=np.tile(measure / d, d), minlength=m)
    coordinates = skmesh.p[:, nodes]
    if direction is not None:
        normals = np.repeat(np.asarray(direction, dtype=float)[:, None] / np.linalg.norm(direction), m, axis=1)
    else:
        exact = [mesh.exact_normals.get(str(part)) for part in parts]
        normals = np.empty((d, m))
        if any(known is None for known in exact):
            summed = np.vstack([np.bincount(local.ravel(), weights=np.tile(outward[c] * measure, d), minlength=m)
                                for c in range(d)])
            normals = summed / np.linalg.norm(summed, axis=0)
        for j, known in enumerate(exact):
            if known is not None:
                mine = owner == j
                normals[:, mine] = np.asarray(known(coordinates[:, mine]), dtype=float)
    gap0 = np.zeros(m)
    for j, part_gap in enumerate(gaps):
        if part_gap is not None:
            mine = owner == j
            gap0[mine] = _initial_gap(part_gap, coordinates[:, mine])
    rows = np.repeat(np.arange(m), d)
    cols = nodal_dofs[:, nodes].T.ravel()
    operator = sp.csr_matrix((normals.T.ravel(), (rows, cols)), shape=(m, nodal_dofs.size))
    return ContactSurface(nodes, coordinates, normals, weights, gap0, operator, local, tuple(map(str, parts)), owner)


def _union_of_parts(mesh: Mesh, parts: list) -> np.ndarray:
    """The sorted facets of the contact parts, refused when a part has none or two parts share some (a
    facet of Γ3 has one layer)."""
    sets = [mesh.facets(part) for part in parts]
    for part, facets in zip(parts, sets):
        if facets.size == 0:
            raise CaseError(f"contact part '{part}' has no facets")
    for j in range(1, len(parts)):
        for i in range(j):
            shared = np.intersect1d(sets[i], sets[j]).size
            if shared:
                raise CaseError(f"contact parts '{parts[i]}' and '{parts[j]}' share {shared} facets: a facet of "
                                f"the contact surface has one layer; list parts that do not overlap")
    return np.unique(np.concatenate(sets))


def _initial_gap(gap: Callable, points: np.ndarray) -> np.ndarray:
    """g0 = gap(x, y[, z]) at ``points`` (d, k), refused where it is not finite."""
    d, k = points.shape
    with np.errstate(all="ignore"):  # a gap that is not finite is reported below
        gap0 = np.broadcast_to(gap(**dict(zip(coordinates_names(d), points))), (k,)).copy()
    bad = np.flatnonzero(~np.isfinite(gap0))
    if bad.size:
        name = f"{gap.where} = {quoted(gap.source)}" if isinstance(gap, Expression) else "contact.gap"
        at = ", ".join(f"{c:.6g}" for c in points[:, bad[0]])
        raise CaseError(f"{name}: not finite ({gap0[bad[0]]}) at the contact node ({', '.join(coordinates_names(d))}) "
                        f"= ({at}); the initial gap must be finite at every node of the contact part")
    return gap0


def empty_surface(ndofs: int, dim: int) -> ContactSurface:
    """The contact surface of a case without contact: no nodes."""
    none = np.zeros(0)
    return ContactSurface(np.zeros(0, dtype=np.int64), np.zeros((dim, 0)), np.zeros((dim, 0)), none, none,
                          sp.csr_matrix((0, ndofs)), np.zeros((dim, 0), dtype=np.int64), (),
                          np.zeros(0, dtype=np.int64))


def node_status(d: np.ndarray, active: np.ndarray) -> np.ndarray:
    """SEPARATED where d ≤ 0, AT_LIMIT where the rigid multiplier is active, else IN_COMPLIANCE."""
    status = np.where(d > 0.0, IN_COMPLIANCE, SEPARATED)
    return np.where(active, AT_LIMIT, status).astype(np.int8)
