"""L² norms of discrete solutions and their differences against a reference solution.

A `Snapshot` is a discrete solution at one time: P1 displacement (nodal values) and P0 stress
(one symmetric tensor per element) on a simplex mesh (triangles in 2D, tetrahedra in 3D).
`differences` compares a solution with a reference on the reference's mesh (the paper's
convergence study)::

    V = ‖ε(I_ref u_h − u_ref)‖_{L²(Ω_ref)},   Q = ‖Π_ref σ_h − σ_ref‖_{L²(Ω_ref)},
    U = ‖I_ref u_h − u_ref‖_{L²(Ω_ref)},

where I_ref interpolates u_h at the reference nodes and Π_ref evaluates σ_h at the reference
element centroids (`transfer`). The norms are exact for these fields: ε(v) of a P1 field and a
P0 stress are constant on each element, so ‖·‖² is Σ_T :math:`|T|` · (the tensor's Frobenius norm)²; a
P1 field's square is integrated exactly by its element mass matrix.

Point location in `transfer` is vectorized: a k-d tree of the source element centroids gives
candidate elements, barycentric coordinates decide which contains a point. A point in no
source element (a finer mesh's nodes near a curved boundary lie outside a coarser mesh's
inscribed polygon or polyhedron) takes the nearest source element (Euclidean distance from the
point to the simplex), and the P1 field is extrapolated linearly from it (its barycentric
coordinates, some negative).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..mesh.simplex import affine_inverse

_INSIDE = 1e-12
"""A point is in an element when its barycentric coordinates are all ≥ −_INSIDE."""
_CANDIDATES = 8
"""Nearest element centroids tried first for each point."""
_CHUNK = 100_000
"""Points located at once (bounds the (points, candidates, ...) work arrays)."""


@dataclass(frozen=True, eq=False)
class Snapshot:
    """A discrete solution at one time: its mesh, nodal displacement (nnodes, d), element stress
    (nelements, d, d)."""

    points: np.ndarray
    """Node coordinates (d, nnodes)."""
    elements: np.ndarray
    """Node indices of the elements (d + 1, nelements), any orientation."""
    displacement: np.ndarray
    """P1 displacement, its values at the nodes (nnodes, d)."""
    stress: np.ndarray
    """P0 stress, one symmetric tensor per element (nelements, d, d)."""
    lame: np.ndarray | None = None
    """The Lamé parameters (λ, μ) of each element (2, nelements), for the energy norm; None: not known."""

    def __post_init__(self):
        d = np.shape(self.points)[0] if np.ndim(self.points) == 2 else 0
        nnodes, nelements = np.shape(self.points)[-1], np.shape(self.elements)[-1]
        expected = {"points": (d, nnodes), "elements": (d + 1, nelements), "displacement": (nnodes, d),
                    "stress": (nelements, d, d)}
        if d not in (2, 3):
            raise ValueError(f"Snapshot.points has shape {np.shape(self.points)}, expected (d, nnodes) with d = 2 or 3")
        for name, shape in expected.items():
            if np.shape(getattr(self, name)) != shape:
                raise ValueError(f"Snapshot.{name} has shape {np.shape(getattr(self, name))}, expected {shape}")


def _affine(points: np.ndarray, elements: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per element with vertices v0, …, vd: v0 (m, d), the inverse (m, d, d) of J = [v1 − v0, …, vd − v0]
    (so the barycentric coordinates (λ_1, …, λ_d) of x are J⁻¹(x − v0)) and det J (m,), whose
    absolute value is d! times the element's measure."""
    inverse, det = affine_inverse(points, elements)  # explicit formulas: ~10 times LAPACK's batched inv
    return points[:, elements[0]].T, np.ascontiguousarray(inverse.transpose(2, 0, 1)), det


def _measures(points: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """The elements' areas (2D) or volumes (3D)."""
    return np.abs(_affine(points, elements)[2]) / math.factorial(points.shape[0])


def _distance_to_simplices(x: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Euclidean distance (q, k) from points x (q, d) to simplices with ``vertices`` (q, k, d + 1, d):
    the least distance to the orthogonal projections of x on the affine hulls of the simplex's faces
    (vertices, edges, …) that fall inside their face. Exact in any dimension."""
    best = np.full(vertices.shape[:2], np.inf)
    corners = vertices.shape[2]
    point = x[:, None, :]
    for size in range(1, corners + 1):
        for face in itertools.combinations(range(corners), size):
            base = vertices[:, :, face[0], :]
            if size == 1:
                best = np.minimum(best, np.linalg.norm(point - base, axis=-1))
                continue
            E = vertices[:, :, face[1:], :] - base[:, :, None, :]  # (q, k, s − 1, d)
            gram = np.einsum("qkid,qkjd->qkij", E, E)
            mu = np.linalg.solve(gram, np.einsum("qkid,qkd->qki", E, point - base)[..., None])[..., 0]
            inside = (mu >= 0.0).all(axis=-1) & (mu.sum(axis=-1) <= 1.0)
            foot = base + np.einsum("qki,qkid->qkd", mu, E)
            best = np.where(inside, np.minimum(best, np.linalg.norm(point - foot, axis=-1)), best)
    return best


class Locator:
    """Finds, for query points, a source element containing each (or the nearest one) and the
    barycentric coordinates of the point in it."""

    def __init__(self, points: np.ndarray, elements: np.ndarray):
        self.points = np.asarray(points, dtype=float)
        self.elements = np.asarray(elements, dtype=np.int64)
        origin, inverse, _ = _affine(self.points, self.elements)
        self.origin = np.ascontiguousarray(origin.T)  # (d, m)
        self.inverse = np.ascontiguousarray(inverse.transpose(1, 2, 0))  # (d, d, m)
        centroids = self.points[:, self.elements].mean(axis=1).T
        self.tree = cKDTree(centroids)
        vertices = self.points[:, self.elements].transpose(2, 1, 0)  # (m, d + 1, d)
        # each element's reach: the largest distance from its centroid to one of its vertices; the
        # elements grouped by reach within a factor 2, each group with its own tree (see `_nearest`)
        reach = np.linalg.norm(vertices - centroids[:, None, :], axis=2).max(axis=1)
        group = np.floor(np.log2(np.maximum(reach, np.finfo(float).tiny))).astype(np.int64)
        self.groups = [(members, cKDTree(centroids[members]), float(reach[members].max()))
                       for members in (np.flatnonzero(group == g) for g in np.unique(group))]

    def barycentric(self, x: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """Barycentric coordinates ``(d + 1, *elements.shape)`` of points x (q, d) in elements (q,) or
        (q, k), in the order of the elements' vertices (rows of `elements`)."""
        d = x.shape[1]
        shape = (-1,) + (1,) * (elements.ndim - 1)
        offset = [x[:, c].reshape(shape) - self.origin[c, elements] for c in range(d)]
        inverse = self.inverse[:, :, elements]
        rest = [sum(inverse[i, c] * offset[c] for c in range(d)) for i in range(d)]
        return np.stack([1.0 - sum(rest), *rest])

    def worst(self, x: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """The smallest barycentric coordinate of each point x (q, d) in elements (q,) or (q, k)."""
        return self.barycentric(x, elements).min(axis=0)

    def distance(self, x: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """Euclidean distance (q, k) from x (q, d) to elements (q, k) (0 for points inside)."""
        vertices = self.points[:, self.elements[:, elements]].transpose(2, 3, 1, 0)  # (q, k, d + 1, d)
        return _distance_to_simplices(x, vertices)

    def locate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Element (q,) and barycentric coordinates (q, d + 1) for points x (q, d), in chunks."""
        element = np.concatenate([self._locate(x[s:s + _CHUNK]) for s in range(0, x.shape[0], _CHUNK)]
                                 or [np.zeros(0, dtype=np.int64)])
        return element, self.barycentric(x, element).T

    def _locate(self, x: np.ndarray) -> np.ndarray:
        """`locate`'s element for one chunk: the element of the nearest centroid if it contains the
        point; else, of the elements of the _CANDIDATES nearest centroids, the one containing it
        (where its smallest barycentric coordinate is largest); else `_nearest`."""
        m = self.elements.shape[1]
        radius, element = self.tree.query(x)
        missed = np.flatnonzero(self.worst(x, element) < -_INSIDE)
        candidates = self.tree.query(x[missed], np.arange(1, min(_CANDIDATES, m) + 1))[1]
        worst = self.worst(x[missed], candidates)
        best = worst.argmax(axis=1)
        element[missed] = candidates[np.arange(missed.size), best]
        missed = missed[worst[np.arange(missed.size), best] < -_INSIDE]
        element[missed] = self._nearest(x[missed], radius[missed])
        return element

    def _nearest(self, x: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """For points x (q, d) whose nearest element centroid is at distance `radius` (q,): an
        element containing the point if any (largest smallest barycentric coordinate), else the
        element nearest to it. Both are at most `radius` away (as is the element of the nearest
        centroid), so an element of reach r among them has its centroid within radius + r: the
        candidates are, in each group of elements, those with a centroid within radius + the group's
        largest reach (on a graded mesh the small elements' groups search small balls)."""
        q = x.shape[0]
        found = []
        for members, tree, reach in self.groups:
            m = members.size
            bound = (radius + reach) * (1.0 + 1e-12)
            k = min(4 * _CANDIDATES, m)
            while True:
                gap, nearest = tree.query(x, np.arange(1, k + 1))  # always (q, k)
                if k == m or np.all(gap[:, -1] > bound):
                    break
                k = min(2 * k, m)
            found.append(np.where(gap <= bound[:, None], members[nearest], -1))
        candidates = np.concatenate(found, axis=1)
        candidates = np.where(candidates < 0, candidates.max(axis=1, keepdims=True), candidates)  # a real one
        worst = self.worst(x, candidates)
        # inside candidates rank by −1 − worst (< 0), the others by their distance (≥ 0)
        key = np.where(worst >= -_INSIDE, -1.0 - worst, self.distance(x, candidates))
        return candidates[np.arange(q), key.argmin(axis=1)]


def transfer(source: Snapshot, target_points, target_elements) -> Snapshot:
    """The source solution on the target mesh: the P1 displacement interpolated at the target nodes
    (its value at each node = the source's P1 field evaluated there), the P0 stress evaluated at the
    target element centroids.

    A target node or centroid in no source element (a finer mesh's boundary nodes lie outside a
    coarser mesh's polygon inscribed in a curved boundary) takes the source element nearest to it
    (Euclidean distance): the displacement is that element's linear function extrapolated to the
    point, the stress that element's value. A point on the boundary between source elements
    (within 1e-12 in barycentric coordinates) takes the element where it lies deepest.
    """
    target_points = np.asarray(target_points, dtype=float)
    target_elements = np.asarray(target_elements, dtype=np.int64)
    locator = Locator(source.points, source.elements)
    element, weights = locator.locate(target_points.T)
    nodal = np.asarray(source.displacement, dtype=float)[locator.elements[:, element]]  # (d + 1, q, d)
    displacement = np.einsum("qv,vqd->qd", weights, nodal)
    centroid_element, _ = locator.locate(target_points[:, target_elements].mean(axis=1).T)
    stress = np.asarray(source.stress, dtype=float)[centroid_element]
    return Snapshot(target_points, target_elements, displacement, stress)


def strain_norm(points, elements, displacement) -> float:
    """‖ε(u)‖_{L²(Ω_h)} = (Σ_T :math:`|T|` ε(u)|_T : ε(u)|_T)^½ for the P1 displacement u with nodal values
    `displacement` (nnodes, d) on the mesh (points (d, nnodes), elements (d + 1, nelements)); exact,
    ε(u) = sym ∇u being constant on each element."""
    (strain,), measure = _strains(points, elements, displacement)
    return float(np.sqrt(_squares(measure, strain)))


def _strains(points, elements, *displacements) -> tuple[list[np.ndarray], np.ndarray]:
    """ε(u) (m, d, d) on each element of the P1 displacement with nodal values (nnodes, d) of each of
    ``displacements`` (the mesh's maps computed once for all), and the elements' measures (m,)."""
    points = np.asarray(points, dtype=float)
    elements = np.asarray(elements, dtype=np.int64)
    d = points.shape[0]
    _, inverse, det = _affine(points, elements)
    strains = []
    for displacement in displacements:
        u = np.asarray(displacement, dtype=float)[elements]  # (d + 1, m, d)
        gradient = sum((u[k + 1] - u[0])[:, :, None] * inverse[:, k, None, :] for k in range(d))  # ∂u_i/∂x_j
        strains.append(0.5 * (gradient + gradient.transpose(0, 2, 1)))
    return strains, np.abs(det) / math.factorial(d)


def _energies(strain: np.ndarray, measure: np.ndarray, lame) -> np.ndarray:
    """|T| (λ (tr ε)² + 2μ ε:ε) on each element of the strains ``strain`` (m, d, d)."""
    lam, mu = (np.asarray(value, dtype=float) for value in lame)
    trace = np.einsum("mii->m", strain)
    return measure * (lam * trace**2 + 2.0 * mu * (strain**2).sum(axis=(1, 2)))


def _squares(measure: np.ndarray, field: np.ndarray) -> float:
    """Σ_T |T| f_T : f_T of a field constant on each element (m, …)."""
    return float(np.sum(measure * (field**2).reshape(len(measure), -1).sum(axis=1)))


def element_energies(points, elements, displacement, lame) -> np.ndarray:
    """∫_T ℰε(u):ε(u) = :math:`|T|` (λ (tr ε)² + 2μ ε:ε) on each element T (m,) for the P1 displacement with nodal
    values ``displacement`` (nnodes, d); ``lame`` = (λ, μ), numbers or arrays over the elements (the
    isotropic ℰ of :class:`~vpcontact.laws.elasticity.Elasticity`; in 2D its plane hypothesis's λ)."""
    (strain,), measure = _strains(points, elements, displacement)
    return _energies(strain, measure, lame)


def energy_norm(points, elements, displacement, lame) -> float:
    """‖u‖_E = (∫_Ω ℰε(u):ε(u))^½ for the P1 displacement u (``element_energies``); exact."""
    return float(np.sqrt(element_energies(points, elements, displacement, lame).sum()))


def containing_elements(points, elements, x) -> np.ndarray:
    """For points x (d, q): the element (columns of ``elements``) of the mesh that contains each (the
    nearest one for a point outside the mesh), as :func:`transfer` locates them."""
    locator = Locator(np.asarray(points, dtype=float), np.asarray(elements, dtype=np.int64))
    return locator.locate(np.asarray(x, dtype=float).T)[0]


def stress_norm(points, elements, stress) -> float:
    """‖σ‖_{L²(Ω_h)} = (Σ_T :math:`|T|` σ_T : σ_T)^½ for the P0 stress `stress` (nelements, d, d) on the mesh
    (points (d, nnodes), elements (d + 1, nelements)); σ : σ = σ_ij σ_ij."""
    measure = _measures(np.asarray(points, dtype=float), np.asarray(elements, dtype=np.int64))
    return float(np.sqrt(_squares(measure, np.asarray(stress, dtype=float))))


def displacement_norm(points, elements, displacement) -> float:
    """‖u‖_{L²(Ω_h)} for the P1 displacement u with nodal values `displacement` (nnodes, d) on the mesh
    (points (d, nnodes), elements (d + 1, nelements)); exact (``_mean_squares``)."""
    points = np.asarray(points, dtype=float)
    elements = np.asarray(elements, dtype=np.int64)
    return float(np.sqrt(np.sum(_measures(points, elements) * _mean_squares(elements, displacement))))


def _mean_squares(elements: np.ndarray, displacement) -> np.ndarray:
    """(1/|T|) ∫_T |u|² on each element of the P1 displacement with nodal values (nnodes, d): on a
    simplex T with vertex values u_0, …, u_d, ∫_T λ_i λ_j = |T| (1 + δ_ij) / ((d + 1)(d + 2)), so
    ∫_T |u|² = |T| (Σ_i |u_i|² + |Σ_i u_i|²) / ((d + 1)(d + 2))."""
    d = elements.shape[0] - 1
    u = np.asarray(displacement, dtype=float)[elements]  # (d + 1, m, d)
    return ((u**2).sum(axis=(0, 2)) + (u.sum(axis=0) ** 2).sum(axis=1)) / ((d + 1) * (d + 2))


def differences(solution: Snapshot, reference: Snapshot) -> dict[str, float]:
    """{"V": ‖ε(u − u_ref)‖_{L²}, "Q": ‖σ − σ_ref‖_{L²}, "U": ‖u − u_ref‖_{L²}, "V_reference": ‖ε(u_ref)‖,
    "Q_reference": ‖σ_ref‖, "U_reference": ‖u_ref‖} computed on the reference mesh after transferring
    `solution` to it (`transfer`); no transfer when the meshes are identical (equal points and
    elements arrays). When the reference knows its Lamé parameters also "energy": ‖u − u_ref‖_E =
    (∫ ℰε(u − u_ref):ε(u − u_ref))^½ with the reference's ℰ, and "energy_reference": ‖u_ref‖_E. The
    reference mesh's affine maps are computed once for all of them."""
    same_mesh = (np.array_equal(solution.points, reference.points)
                 and np.array_equal(solution.elements, reference.elements))
    if not same_mesh:
        solution = transfer(solution, reference.points, reference.elements)
    p, t = np.asarray(reference.points, dtype=float), np.asarray(reference.elements, dtype=np.int64)
    u_ref = np.asarray(reference.displacement, dtype=float)
    error = np.asarray(solution.displacement, dtype=float) - u_ref
    (strain_error, strain_ref), measure = _strains(p, t, error, u_ref)
    stress_ref = np.asarray(reference.stress, dtype=float)
    energy = {}
    if reference.lame is not None:
        energy = {"energy": float(np.sqrt(_energies(strain_error, measure, reference.lame).sum())),
                  "energy_reference": float(np.sqrt(_energies(strain_ref, measure, reference.lame).sum()))}
    return {
        **energy,
        "V": float(np.sqrt(_squares(measure, strain_error))),
        "Q": float(np.sqrt(_squares(measure, np.asarray(solution.stress, dtype=float) - stress_ref))),
        "U": float(np.sqrt(np.sum(measure * _mean_squares(t, error)))),
        "V_reference": float(np.sqrt(_squares(measure, strain_ref))),
        "Q_reference": float(np.sqrt(_squares(measure, stress_ref))),
        "U_reference": float(np.sqrt(np.sum(measure * _mean_squares(t, u_ref)))),
    }
