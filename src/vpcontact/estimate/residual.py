"""The residual a posteriori error estimator of a time level (P1 displacement, P0 stress; 2D and 3D).

With σ_h constant on each element (div σ_h = 0 inside it), the residual of the discrete equilibrium
at t_n lives in the elements (f0), on the interior facets (the jump of σ_h n), on the Neumann boundary
(σ_h n − f2) and on Γ3 (σ_h n against the discrete contact traction −P_h ν_h). Per element K, with
h_K its longest edge, h_E the longest edge of a facet E, μ_K its shear modulus and the facets' terms
given to the element they bound (an interior facet's half to each of its two elements)::

    η_K² = 1/(2μ_K) [ h_K² ‖f0‖²_K                                         "body_force"
                    + Σ_{E ⊂ ∂K interior} ½ h_E ‖[σ_h n]‖²_E                "jump"
                    + Σ_{E ⊂ ∂K ∩ Γ_N} h_E ‖(σ_h n − f2)_free‖²_E            "neumann"
                    + Σ_{E ⊂ ∂K ∩ Γ3} h_E ‖r_τ‖²_E + h_E ‖r·n‖²_E ]         "contact_tangential", "contact_normal"
         + Σ_{E ⊂ ∂K ∩ Γ3} ∫_E λ_h (g − d_h)⁺ da                           "complementarity"

- Γ_N: every boundary facet not on Γ3, with the tractions f2(t_n) of the parts it belongs to (0 on a
  free surface); on a facet of a Dirichlet part (or all of whose nodes a node set holds) only the components
  left free count ("free": a roller's tangential component), so a clamped facet (Γ1) contributes nothing;
- r = σ_h n + P_h ν_h on a facet of Γ3, with P_h ν_h = Σ_i φ_i q_i ν_i the P1 interpolant of the nodal
  contact tractions, q_i = ρK(ξ_i)p(d_i) + λ_i/w_i (compliance + rigid pressure of the level's contact
  row, its nodal normals ν_i): the traction the lumped contact quadrature of the discrete problem
  applies. r_τ = r − (r·n)n. Where ν_i = n (normals of the body) r·n = σ_ν,h + P_h and r_τ = σ_τ,h;
- λ_h, d_h: the P1 interpolants of the rigid pressures λ_i/w_i and of the penetrations d_i; (g − d_h)⁺
  the interpolant of the nodal (g_i − d_i)⁺ (0 where g = ∞). It vanishes at the nodes (λ_i (g − d_i) =
  0 is the discrete complementarity) and measures where it fails between them.

The factor 1/(2μ_K) makes every term an energy (the units of ‖u − u_h‖_E² = ∫ ℰε(e):ε(e)), the
complementarity term is one already. Every integral is exact for these fields: σ_h n is constant on a
facet and the contact terms are P1 on it (∫_E φ_a φ_b = :math:`|E|` (1 + δ_ab) / (d(d + 1)) on a facet of d
vertices); f0 and f2 use the degree-4 rule of the load vector.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import Basis, ElementTetP1, ElementTriP1, FacetBasis, MeshTet1

from .estimators import Estimator
from .indicators import Indicators, Level
from ..mesh.simplex import facet_normals, longest_edges

#: The terms of the estimate, in the order of the outputs.
TERMS = ("body_force", "jump", "neumann", "contact_tangential", "contact_normal", "complementarity")
#: The degree of the quadrature of the loads (that of the load vector).
LOAD_ORDER = 4


@dataclass(frozen=True, eq=False)
class _Geometry:
    """What the estimator needs of a problem's mesh and boundary, computed once per problem."""

    h_element: np.ndarray  # (nelements,) longest edge h_K
    compliance: np.ndarray  # (nelements,) 1 / (2 μ_K)
    normal: np.ndarray  # (d, nfacets) unit normal, outward of the element f2t[0]
    measure: np.ndarray  # (nfacets,) |E|
    h_facet: np.ndarray  # (nfacets,) longest edge h_E
    interior: np.ndarray  # interior facet indices
    contact: np.ndarray  # facets of Γ3 (sorted: the columns of surface.facets)
    neumann: np.ndarray  # boundary facets not on Γ3
    free: np.ndarray  # (nneumann, d) True where a component of the Neumann residual counts
    neumann_points: np.ndarray | None  # (d, nneumann, q) quadrature points when tractions are given
    neumann_dx: np.ndarray | None  # (nneumann, q) their weights
    tractions: list  # (rows into `neumann`, density) of each traction
    body_points: np.ndarray | None  # (d, nelements, q) quadrature points when body forces are given
    body_dx: np.ndarray | None  # (nelements, q)


def _build_geometry(problem) -> _Geometry:
    mesh = problem.mesh
    skmesh, d = mesh.mesh, mesh.dim
    p, t, f2t = skmesh.p, skmesh.t, skmesh.f2t
    centroids = p[:, t].mean(axis=1)
    normal, measure = facet_normals(p, skmesh.facets, centroids[:, f2t[0]])  # outward of the elements f2t[0]
    mu = np.broadcast_to(np.asarray(problem.elasticity.lame[1], dtype=float), (t.shape[1],))
    boundary = np.flatnonzero(f2t[1] < 0)
    surface = problem.surface
    contact = np.unique(np.concatenate([mesh.facets(part) for part in surface.parts])) if surface.parts \
        else np.zeros(0, dtype=np.int64)
    neumann = np.setdiff1d(boundary, contact)
    free = np.ones((neumann.size, d), dtype=bool)
    for item, entry in zip(problem.options.boundary.dirichlet, problem.constraints.entries):
        if item.where is None and item.at is None:
            rows = _rows(neumann, mesh.facets(item.part))
        else:  # a node set: the facets whose every node it holds (none for a point)
            rows = np.flatnonzero(np.isin(skmesh.facets[:, neumann], entry.nodes).all(axis=0))
        free[rows[:, None], list(entry.components)] = False
    scalar = ElementTetP1() if isinstance(skmesh, MeshTet1) else ElementTriP1()
    loads = problem.loads
    neumann_points = neumann_dx = body_points = body_dx = None
    tractions = [(_rows(neumann, facets), density) for facets, density in loads.tractions]
    if tractions and neumann.size:
        facet_basis = FacetBasis(skmesh, scalar, facets=neumann, intorder=LOAD_ORDER)
        neumann_points, neumann_dx = np.asarray(facet_basis.global_coordinates()), facet_basis.dx
    if loads.body_forces:
        element_basis = Basis(skmesh, scalar, intorder=LOAD_ORDER)
        body_points, body_dx = np.asarray(element_basis.global_coordinates()), element_basis.dx
    return _Geometry(longest_edges(p, t), 1.0 / (2.0 * mu), normal, measure, longest_edges(p, skmesh.facets),
                     np.flatnonzero(f2t[1] >= 0), contact, neumann, free, neumann_points, neumann_dx, tractions,
                     body_points, body_dx)


def _rows(sorted_facets: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """The positions in ``sorted_facets`` of those of ``facets`` it holds."""
    facets = facets[np.isin(facets, sorted_facets)]
    return np.searchsorted(sorted_facets, facets)


def _density(density, points: np.ndarray, t: float) -> np.ndarray:
    """A load density's components (d, ...) at ``points`` (d, ...) and time t."""
    return np.stack([np.broadcast_to(np.asarray(c, dtype=float), points.shape[1:]) for c in density(*points, t)])


def _p1_square(values: np.ndarray, measure: np.ndarray) -> np.ndarray:
    """∫_E |v_h|² of P1 fields on facets with vertex values ``values`` (vertices, nf[, d]): |E| (Σ_a |v_a|² +
    |Σ_a v_a|²) / (n (n + 1)), n the number of vertices."""
    n = values.shape[0]
    squares = (values**2).sum(axis=0) + values.sum(axis=0) ** 2
    if squares.ndim > 1:
        squares = squares.sum(axis=-1)
    return measure * squares / (n * (n + 1))


def _p1_product(a: np.ndarray, b: np.ndarray, measure: np.ndarray) -> np.ndarray:
    """∫_E a_h b_h of two scalar P1 fields with vertex values (vertices, nf): |E| (Σ_a a_a b_a + Σ a Σ b) / (n (n + 1))."""
    n = a.shape[0]
    return measure * ((a * b).sum(axis=0) + a.sum(axis=0) * b.sum(axis=0)) / (n * (n + 1))


class ResidualEstimator:
    """The estimator of one problem: its mesh's facets, boundary parts and quadrature prepared once, then
    ``estimator(level)`` for every level of a run of that problem."""

    def __init__(self, problem):
        self.problem = problem
        self.geometry = _build_geometry(problem)

    def __call__(self, level: Level) -> Indicators:
        if level.problem is not self.problem:
            raise ValueError("this estimator was prepared for another problem")
        return _indicators(level, self.geometry)


def estimate(level: Level) -> Indicators:
    """The residual estimator's squared element indicators η_K² of ``level``, by term (see the module)."""
    return _indicators(level, _build_geometry(level.problem))


def _indicators(level: Level, geometry: _Geometry) -> Indicators:
    problem = level.problem
    skmesh = problem.mesh.mesh
    nelements = skmesh.t.shape[1]
    f2t = skmesh.f2t
    sigma = np.asarray(level.fields.stress, dtype=float)  # (nelements, d, d)
    traction = np.einsum("fij,jf->fi", sigma[f2t[0]], geometry.normal)  # σ_h n of the first element, (nf, d)

    def per_element(elements: np.ndarray, values: np.ndarray) -> np.ndarray:
        return np.bincount(elements, weights=values, minlength=nelements)

    terms = dict.fromkeys(TERMS)
    body = np.zeros(nelements)
    if geometry.body_points is not None:
        f0 = sum(_density(density, geometry.body_points, level.t) for density in problem.loads.body_forces)
        body = geometry.h_element**2 * np.einsum("dkq,kq->k", f0**2, geometry.body_dx)
    terms["body_force"] = geometry.compliance * body

    inner = geometry.interior
    jump = traction[inner] - np.einsum("fij,jf->fi", sigma[f2t[1, inner]], geometry.normal[:, inner])
    half = 0.5 * geometry.h_facet[inner] * geometry.measure[inner] * (jump**2).sum(axis=1)
    terms["jump"] = geometry.compliance * (per_element(f2t[0, inner], half) + per_element(f2t[1, inner], half))

    facets = geometry.neumann
    residual = traction[facets][:, :, None]  # (nN, d, 1): σ_h n, constant on each facet
    dx = geometry.measure[facets][:, None]
    if geometry.neumann_points is not None:
        f2 = np.zeros_like(geometry.neumann_points)
        for rows, density in geometry.tractions:
            f2[:, rows] += _density(density, geometry.neumann_points[:, rows], level.t)
        residual, dx = residual - f2.transpose(1, 0, 2), geometry.neumann_dx
    square = np.einsum("fdq,fq->fd", residual**2, dx)
    neumann = geometry.h_facet[facets] * (square * geometry.free).sum(axis=1)
    terms["neumann"] = geometry.compliance * per_element(f2t[0, facets], neumann)

    terms.update(_contact_terms(level, geometry, traction, per_element))
    return Indicators(terms)


def _contact_terms(level: Level, geometry: _Geometry, traction: np.ndarray, per_element) -> dict[str, np.ndarray]:
    """The Γ3 terms: the tangential and normal parts of r = σ_h n + P_h ν_h and the complementarity."""
    problem, facets = level.problem, geometry.contact
    surface = problem.surface
    elements = problem.mesh.mesh.f2t[0, facets]
    corners = surface.facets  # (d, nc): contact-node indices of each Γ3 facet
    contact = level.contact
    pressure = contact["pressure_compliance"] + contact["pressure_rigid"]
    normal, measure, h = geometry.normal[:, facets], geometry.measure[facets], geometry.h_facet[facets]
    r = traction[facets][None] + (pressure[corners][..., None] * surface.normals[:, corners].transpose(1, 2, 0))
    normal_part = np.einsum("afd,df->af", r, normal)  # (vertices, nc)
    tangential = r - normal_part[..., None] * normal.T[None]
    g = np.broadcast_to(np.asarray(problem.law.g, dtype=float), pressure.shape)
    room = np.where(np.isfinite(g), np.maximum(g - contact["penetration"], 0.0), 0.0)
    compliance = geometry.compliance[elements]
    return {
        "contact_tangential": per_element(elements, compliance * h * _p1_square(tangential, measure)),
        "contact_normal": per_element(elements, compliance * h * _p1_square(normal_part, measure)),
        "complementarity": per_element(elements, _p1_product(contact["pressure_rigid"][corners], room[corners], measure)),
    }


ESTIMATOR = Estimator(
    name="residual",
    summary="The residual estimator: the element, jump, Neumann and contact residuals of σ_h and the complementarity.",
    terms=TERMS,
    prepare=ResidualEstimator,
)
