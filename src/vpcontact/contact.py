"""The contact condition (2.5) at the nodes of Γ3: laws p and K(ξ), nodal normals and weights.

Node-to-rigid contact: node i of Γ3 carries a unit outward normal ν_i, a weight w_i (its share of
the measure of Γ3, lumped boundary quadrature), an initial gap g0_i to the foundation, and the
penetration d_i = u(x_i)·ν_i − g0_i. The soft layer pushes back with the nodal force
    w_i ρ K(ξ_i) p(d_i),   ξ_i^n = ξ_i^{n−1} + k (d_i^n)^+   (the implicit rectangle rule for (2.15)),
and the rigid base adds a multiplier λ_i ≥ 0 once d_i reaches g.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp

from .errors import CaseError, quoted
from .expressions import Expression
from .mesh import Mesh

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
    """p(r) = (r⁺)^m with m ≥ 1 (Lipschitz on bounded sets; p'(0) = 1 when m = 1)."""

    exponent: float

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return np.maximum(r, 0.0) ** self.exponent

    def derivative(self, r: np.ndarray) -> np.ndarray:
        if self.exponent == 1.0:
            return PositivePart().derivative(r)
        return self.exponent * np.maximum(r, 0.0) ** (self.exponent - 1.0)


# --- stiffness coefficients K(ξ) (2.18) --------------------------------------------------------
@dataclass(frozen=True)
class PowerStiffness:
    """K(ξ) = c_v (1 + α ξ)^β: the paper's law; β > 0 hardens, β < 0 softens, α = 0 is constant."""

    c_v: float
    alpha: float
    beta: float

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * (1.0 + self.alpha * xi) ** self.beta

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * self.alpha * self.beta * (1.0 + self.alpha * xi) ** (self.beta - 1.0)


@dataclass(frozen=True)
class ConstantStiffness:
    """K(ξ) = value (value = 0: the Signorini condition with gap g)."""

    value: float

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return np.full_like(xi, self.value, dtype=float)

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return np.zeros_like(xi, dtype=float)


@dataclass(frozen=True)
class ExponentialStiffness:
    """K(ξ) = c_v exp(α ξ): α > 0 hardens, α < 0 softens."""

    c_v: float
    alpha: float

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


@dataclass(frozen=True)
class ContactLaw:
    """The soft layer of thickness g on the rigid base: ρ K(ξ) p(d) while d < g, d ≤ g always."""

    p: Callable
    stiffness: Callable
    g: float
    rho: float = 1.0

    def K(self, xi: np.ndarray) -> np.ndarray:
        """ρ K(ξ): the stiffness coefficient in force (the paper's K_ρ)."""
        return self.rho * self.stiffness(xi)

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

    ``operator`` is the sparse m × ndofs matrix N with (N u)_i = u(x_i)·ν_i; ``segments`` (2, nf)
    are the facets of Γ3 as pairs of contact-node indices.
    """

    nodes: np.ndarray
    coordinates: np.ndarray  # (2, m)
    normals: np.ndarray  # (2, m)
    weights: np.ndarray  # (m,)
    gap0: np.ndarray  # (m,)
    operator: sp.csr_matrix
    segments: np.ndarray

    @property
    def size(self) -> int:
        return self.nodes.size

    def nearest_node(self, point) -> int:
        """Index (into the contact nodes) of the node nearest to ``point`` (any finite point: the offsets are
        scaled so that their squares cannot overflow)."""
        offsets = self.coordinates - np.reshape(point, (2, 1))
        scale = np.abs(offsets).max(initial=0.0)
        return int(np.argmin(np.sum((offsets / scale if scale > 0 else offsets) ** 2, axis=0)))


def contact_surface(mesh: Mesh, part, nodal_dofs: np.ndarray, gap: Callable | None = None) -> ContactSurface:
    """Build the contact nodes of ``part``: weights = half the length of each adjacent facet,
    normals = the exact ones where the mesh knows the geometry, else the length-weighted average
    of the adjacent facets' outward normals; ``gap(x, y)`` gives g0 (default 0)."""
    skmesh = mesh.mesh
    facets = mesh.facets(part)
    if facets.size == 0:
        raise CaseError(f"contact part '{part}' has no facets")
    ends = skmesh.facets[:, facets]  # (2, nf)
    tangent = skmesh.p[:, ends[1]] - skmesh.p[:, ends[0]]
    length = np.linalg.norm(tangent, axis=0)
    normal = np.vstack([tangent[1], -tangent[0]]) / length
    # orient outward: away from the third vertex of the adjacent triangle
    element = skmesh.f2t[0, facets]
    centroid = skmesh.p[:, skmesh.t[:, element]].mean(axis=1)
    midpoint = 0.5 * (skmesh.p[:, ends[0]] + skmesh.p[:, ends[1]])
    normal *= np.where(np.sum(normal * (midpoint - centroid), axis=0) < 0.0, -1.0, 1.0)

    nodes, local = np.unique(ends.ravel(), return_inverse=True)
    local = local.reshape(ends.shape)
    m = nodes.size
    weights = np.bincount(local.ravel(), weights=np.tile(0.5 * length, 2), minlength=m)
    coordinates = skmesh.p[:, nodes]
    exact = mesh.exact_normals.get(str(part))
    if exact is not None:
        normals = np.asarray(exact(coordinates), dtype=float)
    else:
        summed = np.vstack(
            [np.bincount(local.ravel(), weights=np.tile(normal[c] * length, 2), minlength=m) for c in range(2)]
        )
        normals = summed / np.linalg.norm(summed, axis=0)
    gap0 = np.zeros(m)
    if gap is not None:
        with np.errstate(all="ignore"):  # a gap that is not finite is reported below
            gap0 = np.broadcast_to(gap(x=coordinates[0], y=coordinates[1]), (m,)).copy()
    bad = np.flatnonzero(~np.isfinite(gap0))
    if bad.size:
        name = f"{gap.where} = {quoted(gap.source)}" if isinstance(gap, Expression) else "contact.gap"
        x, y = coordinates[:, bad[0]]
        raise CaseError(f"{name}: not finite ({gap0[bad[0]]}) at the contact node (x, y) = ({x:.6g}, {y:.6g}); the "
                        f"initial gap must be finite at every node of the contact part")
    rows = np.repeat(np.arange(m), 2)
    cols = nodal_dofs[:, nodes].T.ravel()
    operator = sp.csr_matrix((normals.T.ravel(), (rows, cols)), shape=(m, nodal_dofs.size))
    return ContactSurface(nodes, coordinates, normals, weights, gap0, operator, local)


def empty_surface(ndofs: int) -> ContactSurface:
    """The contact surface of a case without contact: no nodes."""
    none = np.zeros(0)
    return ContactSurface(np.zeros(0, dtype=np.int64), np.zeros((2, 0)), np.zeros((2, 0)), none, none,
                          sp.csr_matrix((0, ndofs)), np.zeros((2, 0), dtype=np.int64))


def node_status(d: np.ndarray, active: np.ndarray) -> np.ndarray:
    """SEPARATED where d ≤ 0, AT_LIMIT where the rigid multiplier is active, else IN_COMPLIANCE."""
    status = np.where(d > 0.0, IN_COMPLIANCE, SEPARATED)
    return np.where(active, AT_LIMIT, status).astype(np.int8)
