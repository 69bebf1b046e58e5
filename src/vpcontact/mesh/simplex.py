"""The geometry of simplices (triangles and tetrahedra, their facets), vectorized over the simplices: the one
place that computes it.

A simplex T of dimension d has the vertices x_0, …, x_d (columns of ``points`` named by a column of ``cells``)
and the affine map of the reference simplex, with J = [x_1 − x_0, …, x_d − x_0]:

- det J is d! times the signed measure of T (area, volume): positive when x_1 − x_0, x_2 − x_0 turn
  counter-clockwise (2D) or x_1 − x_0, x_2 − x_0, x_3 − x_0 are right-handed (3D); |T| = |det J| / d!;
- the barycentric coordinates are affine, (λ_1, …, λ_d) = J⁻¹(x − x_0) and λ_0 = 1 − Σ_a λ_a, so their
  gradients are constant on T: ∇λ_a (a ≥ 1) is row a of J⁻¹ and ∇λ_0 = −Σ_a ∇λ_a.

J⁻¹ and det J come from explicit formulas (the 2 × 2 adjugate; in 3D the cross products of J's columns),
about ten times faster than LAPACK's batched inverse. The simplices are the last axis of every array (the
long, contiguous one every vectorized operation runs along).
"""

from __future__ import annotations

import itertools
import math

import numpy as np


def determinants(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """det J (elements,) of the simplices ``cells`` (d + 1, elements) of the nodes ``points`` (d, nodes): d!
    times their signed measures (see the module docstring)."""
    return _adjugate(points, cells)[1]


def measures(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """|T| (elements,): the areas (2D) or volumes (3D) of the simplices ``cells`` (d + 1, elements)."""
    return np.abs(determinants(points, cells)) / math.factorial(points.shape[0])


def affine_inverse(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """J⁻¹ (d, d, elements) and det J (elements,) of the simplices ``cells`` (d + 1, elements) of the nodes
    ``points`` (d, nodes): row k of J⁻¹ is ∇λ_(k+1), so (λ_1, …, λ_d) = J⁻¹(x − x_0). A degenerate element
    (det J = 0) gets infinite or NaN entries."""
    rows, det = _adjugate(points, cells)
    with np.errstate(divide="ignore", invalid="ignore"):
        return rows / det, det


def barycentric_gradients(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """∇λ_a (d + 1, d, elements) and |T| (elements,) of the simplices ``cells`` (d + 1, elements) of the
    nodes ``points`` (d, nodes); a degenerate element (det J = 0) gets infinite or NaN gradients."""
    inverse, det = affine_inverse(points, cells)
    with np.errstate(invalid="ignore"):
        gradients = np.concatenate([-inverse.sum(axis=0, keepdims=True), inverse])
    return gradients, np.abs(det) / math.factorial(points.shape[0])


def squared_edge_lengths(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """The squared lengths (edges, elements) of the d(d + 1)/2 edges of the simplices ``cells`` (d + 1,
    elements) of the nodes ``points`` (d, nodes), edge (a, b) for the vertices a < b in lexicographic order."""
    return np.stack([((points[:, cells[b]] - points[:, cells[a]]) ** 2).sum(axis=0)
                     for a, b in itertools.combinations(range(cells.shape[0]), 2)])


def edge_lengths(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """The lengths (edges, elements) of the edges of the simplices ``cells`` (as `squared_edge_lengths`)."""
    return np.sqrt(squared_edge_lengths(points, cells))


def longest_edges(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """The longest edge (elements,) of each simplex ``cells`` (k, elements) of ``points`` (d, nodes): the h_K
    of an element, or the h_E of a facet."""
    return edge_lengths(points, cells).max(axis=0)


def facet_normals(points: np.ndarray, facets: np.ndarray, inner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (d, nf) of the facets (d, nf) (edges in 2D, triangles in 3D) of the nodes ``points`` (d,
    nodes), pointing away from the points ``inner`` (d, nf) (e.g. the centroids of their elements), and
    their measures (nf,): lengths or areas."""
    d = points.shape[0]
    x = points[:, facets]  # (d, vertices, nf)
    if d == 2:
        edge = x[:, 1] - x[:, 0]
        normal = np.stack([edge[1], -edge[0]])
        measure = np.linalg.norm(normal, axis=0)
    else:
        normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], axis=0)
        measure = 0.5 * np.linalg.norm(normal, axis=0)
    normal = normal / np.linalg.norm(normal, axis=0)
    outward = np.sign(np.einsum("dn,dn->n", normal, x.mean(axis=1) - inner))
    return normal * outward, measure


def _adjugate(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """det J · J⁻¹ (d, d, elements) and det J (elements,) of the simplices ``cells`` (d + 1, elements): the
    2 × 2 adjugate; in 3D the rows of det J · J⁻¹ are the cross products of the other two columns of J."""
    x = points[:, cells]  # (d, d + 1, elements)
    J = x[:, 1:] - x[:, :1]  # J[i, k]: coordinate i of the edge x_(k+1) − x_0
    if points.shape[0] == 2:
        det = J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
        rows = np.stack([np.stack([J[1, 1], -J[0, 1]]), np.stack([-J[1, 0], J[0, 0]])])
    else:
        a, b, c = J[:, 0], J[:, 1], J[:, 2]
        rows = np.stack([_cross(b, c), _cross(c, a), _cross(a, b)])
        det = (a * rows[0]).sum(axis=0)
    return rows, det


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u × v of vectors (3, elements)."""
    return np.stack([u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]])
