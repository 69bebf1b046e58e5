"""L² norms of discrete solutions and their differences against a reference solution.

A `Snapshot` is a discrete solution at one time: P1 displacement (nodal values) and P0 stress
(one symmetric tensor per element) on a triangle mesh. `differences` compares a solution with a
reference on the reference's mesh (the paper's convergence study):

    V = ‖ε(I_ref u_h − u_ref)‖_{L²(Ω_ref)},   Q = ‖Π_ref σ_h − σ_ref‖_{L²(Ω_ref)},

where I_ref interpolates u_h at the reference nodes and Π_ref evaluates σ_h at the reference
element centroids (`transfer`). The norms are exact for these fields: ε(v) of a P1 field and a
P0 stress are constant on each element, so ‖·‖² is Σ_T |T| · (the tensor's Frobenius norm)².

Point location in `transfer` is vectorized: a k-d tree of the source element centroids gives
candidate elements, barycentric coordinates decide which contains a point. A point in no
source element (a finer mesh's nodes near a curved boundary lie outside a coarser mesh's
inscribed polygon) takes the nearest source element, Euclidean distance point–triangle, and the
P1 field is extrapolated linearly from it (its barycentric coordinates, some negative).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

_INSIDE = 1e-12
"""A point is in an element when its barycentric coordinates are all ≥ −_INSIDE."""
_CANDIDATES = 8
"""Nearest element centroids tried first for each point."""
_CHUNK = 100_000
"""Points located at once (bounds the (points, candidates, ...) work arrays)."""


@dataclass(frozen=True, eq=False)
class Snapshot:
    """A discrete solution at one time: its mesh, nodal displacement (nnodes, 2), element stress (nelements, 2, 2)."""

    points: np.ndarray
    """Node coordinates (2, nnodes)."""
    triangles: np.ndarray
    """Node indices of the elements (3, nelements), any orientation."""
    displacement: np.ndarray
    """P1 displacement, its values at the nodes (nnodes, 2)."""
    stress: np.ndarray
    """P0 stress, one symmetric tensor per element (nelements, 2, 2)."""

    def __post_init__(self):
        nnodes, nelements = np.shape(self.points)[-1], np.shape(self.triangles)[-1]
        expected = {"points": (2, nnodes), "triangles": (3, nelements), "displacement": (nnodes, 2),
                    "stress": (nelements, 2, 2)}
        for name, shape in expected.items():
            if np.shape(getattr(self, name)) != shape:
                raise ValueError(f"Snapshot.{name} has shape {np.shape(getattr(self, name))}, expected {shape}")


def _affine(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per element with vertices (a, b, c): a (m, 2), the inverse (m, 2, 2) of J = [b − a, c − a]
    (so the barycentric coordinates (λ_b, λ_c) of x are J⁻¹(x − a)) and det J (m,), whose
    absolute value is twice the area."""
    a, b, c = (points[:, triangles[i]].T for i in range(3))
    J = np.stack((b - a, c - a), axis=2)
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    inverse = np.stack((np.stack((J[:, 1, 1], -J[:, 0, 1]), axis=1),
                        np.stack((-J[:, 1, 0], J[:, 0, 0]), axis=1)), axis=1) / det[:, None, None]
    return a, inverse, det


class _Locator:
    """Finds, for query points, a source element containing each (or the nearest one) and the
    barycentric coordinates of the point in it."""

    def __init__(self, points: np.ndarray, triangles: np.ndarray):
        self.points = np.asarray(points, dtype=float)
        self.triangles = np.asarray(triangles, dtype=np.int64)
        origin, inverse, _ = _affine(self.points, self.triangles)
        self.origin = np.ascontiguousarray(origin.T)  # (2, m)
        self.inverse = np.ascontiguousarray(inverse.transpose(1, 2, 0))  # (2, 2, m)
        centroids = self.points[:, self.triangles].mean(axis=1).T
        self.tree = cKDTree(centroids)
        vertices = self.points[:, self.triangles].transpose(2, 1, 0)  # (m, 3, 2)
        # the largest distance from an element's centroid to one of its vertices
        self.reach = float(np.linalg.norm(vertices - centroids[:, None, :], axis=2).max())

    def barycentric(self, x: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """Barycentric coordinates (3, *elements.shape) of points x (q, 2) in elements (q,) or
        (q, k), in the order of the elements' vertices (rows of `triangles`)."""
        shape = (-1,) + (1,) * (elements.ndim - 1)
        dx = x[:, 0].reshape(shape) - self.origin[0, elements]
        dy = x[:, 1].reshape(shape) - self.origin[1, elements]
        inverse = self.inverse[:, :, elements]
        second = inverse[0, 0] * dx + inverse[0, 1] * dy
        third = inverse[1, 0] * dx + inverse[1, 1] * dy
        return np.stack((1.0 - second - third, second, third))

    def worst(self, x: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """The smallest barycentric coordinate of each point x (q, 2) in elements (q,) or (q, k)."""
        lam = self.barycentric(x, elements)
        return np.minimum(np.minimum(lam[0], lam[1]), lam[2])

    def distance(self, x: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """Euclidean distance (q, k) from x (q, 2) to the boundaries of elements (q, k) (the
        distance to the element itself for points outside it)."""
        vertices = self.points[:, self.triangles[:, elements]].transpose(2, 3, 1, 0)  # (q, k, 3, 2)
        start, edge = vertices, np.roll(vertices, -1, axis=2) - vertices
        along = np.einsum("qkvd,qkvd->qkv", x[:, None, None, :] - start, edge) / (edge**2).sum(axis=3)
        foot = start + np.clip(along, 0.0, 1.0)[..., None] * edge
        return np.linalg.norm(x[:, None, None, :] - foot, axis=3).min(axis=2)

    def locate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Element (q,) and barycentric coordinates (q, 3) for points x (q, 2), in chunks."""
        element = np.concatenate([self._locate(x[s:s + _CHUNK]) for s in range(0, x.shape[0], _CHUNK)]
                                 or [np.zeros(0, dtype=np.int64)])
        return element, self.barycentric(x, element).T

    def _locate(self, x: np.ndarray) -> np.ndarray:
        """`locate`'s element for one chunk: the element of the nearest centroid if it contains the
        point; else, of the elements of the _CANDIDATES nearest centroids, the one containing it
        (where its smallest barycentric coordinate is largest); else `_nearest`."""
        m = self.triangles.shape[1]
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
        """For points x (q, 2) whose nearest element centroid is at distance `radius` (q,): an
        element containing the point if any (largest smallest barycentric coordinate), else the
        element nearest to it. Both have their centroid within radius + reach of the point
        (the element of the nearest centroid is itself within `radius`), so the candidates are
        all elements with a centroid in that ball."""
        q, m = x.shape[0], self.triangles.shape[1]
        bound = (radius + self.reach) * (1.0 + 1e-12)
        k = min(4 * _CANDIDATES, m)
        while True:
            gap, candidates = self.tree.query(x, np.arange(1, k + 1))  # always (q, k)
            if k == m or np.all(gap[:, -1] > bound):
                break
            k = min(2 * k, m)
        worst = self.worst(x, candidates)
        # inside candidates rank by −1 − worst (< 0), the others by their distance (≥ 0)
        key = np.where(worst >= -_INSIDE, -1.0 - worst, self.distance(x, candidates))
        return candidates[np.arange(q), key.argmin(axis=1)]


def transfer(source: Snapshot, target_points, target_triangles) -> Snapshot:
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
    target_triangles = np.asarray(target_triangles, dtype=np.int64)
    locator = _Locator(source.points, source.triangles)
    element, weights = locator.locate(target_points.T)
    nodal = np.asarray(source.displacement, dtype=float)[locator.triangles[:, element]]  # (3, q, 2)
    displacement = np.einsum("qv,vqd->qd", weights, nodal)
    centroid_element, _ = locator.locate(target_points[:, target_triangles].mean(axis=1).T)
    stress = np.asarray(source.stress, dtype=float)[centroid_element]
    return Snapshot(target_points, target_triangles, displacement, stress)


def strain_norm(points, triangles, displacement) -> float:
    """‖ε(u)‖_{L²(Ω_h)} = (Σ_T |T| ε(u)|_T : ε(u)|_T)^½ for the P1 displacement u with nodal values
    `displacement` (nnodes, 2) on the mesh (points (2, nnodes), triangles (3, nelements)); exact,
    ε(u) = sym ∇u being constant on each element."""
    points = np.asarray(points, dtype=float)
    triangles = np.asarray(triangles, dtype=np.int64)
    _, inverse, det = _affine(points, triangles)
    u = np.asarray(displacement, dtype=float)[triangles]  # (3, m, 2)
    gradient = np.stack((u[1] - u[0], u[2] - u[0]), axis=2) @ inverse  # (m, 2, 2): ∂u_i/∂x_j
    strain = 0.5 * (gradient + gradient.transpose(0, 2, 1))
    return float(np.sqrt(np.sum(0.5 * np.abs(det) * (strain**2).sum(axis=(1, 2)))))


def stress_norm(points, triangles, stress) -> float:
    """‖σ‖_{L²(Ω_h)} = (Σ_T |T| σ_T : σ_T)^½ for the P0 stress `stress` (nelements, 2, 2) on the mesh
    (points (2, nnodes), triangles (3, nelements)); σ : σ = σ_ij σ_ij."""
    points = np.asarray(points, dtype=float)
    triangles = np.asarray(triangles, dtype=np.int64)
    _, _, det = _affine(points, triangles)
    stress = np.asarray(stress, dtype=float)
    return float(np.sqrt(np.sum(0.5 * np.abs(det) * (stress**2).sum(axis=(1, 2)))))


def differences(solution: Snapshot, reference: Snapshot) -> dict[str, float]:
    """{"V": ‖ε(u − u_ref)‖_{L²}, "Q": ‖σ − σ_ref‖_{L²}, "V_reference": ‖ε(u_ref)‖,
    "Q_reference": ‖σ_ref‖} computed on the reference mesh after transferring `solution` to it
    (`transfer`); no transfer when the meshes are identical (equal points and triangles arrays)."""
    same_mesh = (np.array_equal(solution.points, reference.points)
                 and np.array_equal(solution.triangles, reference.triangles))
    if not same_mesh:
        solution = transfer(solution, reference.points, reference.triangles)
    p, t = reference.points, reference.triangles
    return {
        "V": strain_norm(p, t, np.asarray(solution.displacement) - np.asarray(reference.displacement)),
        "Q": stress_norm(p, t, np.asarray(solution.stress) - np.asarray(reference.stress)),
        "V_reference": strain_norm(p, t, reference.displacement),
        "Q_reference": stress_norm(p, t, reference.stress),
    }
