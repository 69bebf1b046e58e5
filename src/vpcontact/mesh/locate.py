"""Finding the simplices of a mesh: the element that contains a point, the facet (or element) with given nodes.

`Locator` finds, for query points, an element containing each, vectorized: a k-d tree of the element
centroids gives candidate elements, barycentric coordinates decide which contains a point. A point in no
element (a finer mesh's nodes near a curved boundary lie outside a coarser mesh's inscribed polygon or
polyhedron) takes the nearest element (Euclidean distance from the point to the simplex); its barycentric
coordinates there, some negative, extrapolate a P1 field linearly. It serves the transfers between meshes
(`vpcontact.results.norms.transfer`) and refinement (`vpcontact.mesh.refinement`: the parent of a new element).

`find_columns` finds simplices by their nodes, in any order: the facets of a mesh file's physical groups,
the parent facets of a refined mesh's boundary.
"""

from __future__ import annotations

import itertools
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from .simplex import affine_inverse

INSIDE = 1e-12
"""A point is in an element when its barycentric coordinates are all ≥ −INSIDE."""
CANDIDATES = 8
"""Nearest element centroids tried first for each point."""
CHUNK = 100_000
"""Points located at once (bounds the (points, candidates, ...) work arrays)."""


def containing_elements(points, elements, x) -> np.ndarray:
    """For points x (d, q): the element (columns of ``elements``) of the mesh that contains each (the
    nearest one for a point outside the mesh): `Locator.locate`'s element."""
    locator = Locator(np.asarray(points, dtype=float), np.asarray(elements, dtype=np.int64))
    return locator.locate(np.asarray(x, dtype=float).T)[0]


class Locator:
    """Finds, for query points, a source element containing each (or the nearest one) and the
    barycentric coordinates of the point in it."""

    def __init__(self, points: np.ndarray, elements: np.ndarray):
        self.points = np.asarray(points, dtype=float)
        self.elements = np.asarray(elements, dtype=np.int64)
        inverse, _ = affine_inverse(self.points, self.elements)  # explicit formulas: ~10 times LAPACK's batched inv
        self.origin = np.ascontiguousarray(self.points[:, self.elements[0]])  # (d, m)
        self.inverse = np.ascontiguousarray(inverse)  # (d, d, m)

    @cached_property
    def centroids(self) -> np.ndarray:
        """The elements' centroids (m, d)."""
        return self.points[:, self.elements].mean(axis=1).T

    @cached_property
    def tree(self) -> cKDTree:
        """The k-d tree of the elements' centroids (made when a point is first located: `barycentric` needs none)."""
        return cKDTree(self.centroids)

    @cached_property
    def groups(self) -> list[tuple[np.ndarray, cKDTree, float]]:
        """The elements grouped by reach (the largest distance from the centroid to a vertex) within a factor 2, each
        group with its own tree and largest reach (see `_nearest`)."""
        centroids = self.centroids
        vertices = self.points[:, self.elements].transpose(2, 1, 0)  # (m, d + 1, d)
        reach = np.linalg.norm(vertices - centroids[:, None, :], axis=2).max(axis=1)
        group = np.floor(np.log2(np.maximum(reach, np.finfo(float).tiny))).astype(np.int64)
        return [(members, cKDTree(centroids[members]), float(reach[members].max()))
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
        element = np.concatenate([self._locate(x[s:s + CHUNK]) for s in range(0, x.shape[0], CHUNK)]
                                 or [np.zeros(0, dtype=np.int64)])
        return element, self.barycentric(x, element).T

    def _locate(self, x: np.ndarray) -> np.ndarray:
        """`locate`'s element for one chunk: the element of the nearest centroid if it contains the
        point; else, of the elements of the CANDIDATES nearest centroids, the one containing it
        (where its smallest barycentric coordinate is largest); else `_nearest`."""
        m = self.elements.shape[1]
        radius, element = self.tree.query(x)
        missed = np.flatnonzero(self.worst(x, element) < -INSIDE)
        candidates = self.tree.query(x[missed], np.arange(1, min(CANDIDATES, m) + 1))[1]
        worst = self.worst(x[missed], candidates)
        best = worst.argmax(axis=1)
        element[missed] = candidates[np.arange(missed.size), best]
        missed = missed[worst[np.arange(missed.size), best] < -INSIDE]
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
            k = min(4 * CANDIDATES, m)
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
        key = np.where(worst >= -INSIDE, -1.0 - worst, self.distance(x, candidates))
        return candidates[np.arange(q), key.argmin(axis=1)]


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


def find_columns(table: np.ndarray, query: np.ndarray) -> np.ndarray:
    """For each column of `query` (k, q), the index of the column of `table` (k, r) with the same
    numbers in any order, or -1 (the columns of `table` are distinct sets). One lexicographic sort of the
    columns' sorted numbers (``np.unique(..., axis=1)`` sorts them as rows of bytes: several times slower)."""
    both = np.sort(np.hstack((table, query)).astype(np.int64), axis=0)
    order = np.lexsort(both[::-1])  # the first row the primary key
    ordered = both[:, order]
    starts = np.r_[True, np.any(ordered[:, 1:] != ordered[:, :-1], axis=0)] if order.size else np.zeros(0, bool)
    group = np.empty(order.size, dtype=np.int64)
    group[order] = np.cumsum(starts) - 1
    column = np.full(group.max() + 1 if group.size else 0, -1, dtype=np.int64)
    column[group[:table.shape[1]]] = np.arange(table.shape[1])
    return column[group[table.shape[1]:]]
