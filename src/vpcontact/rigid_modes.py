"""Rigid-body motions of a mesh: the null space of the elastic stiffness.

Each connected body of the mesh has d translations and d(d − 1)/2 rotations (3 in 2D, 6 in 3D),
which strain nothing: A z = 0 in exact arithmetic. Rotations are taken about the body's centroid
and scaled by its size, so every mode has entries of order one in any unit of length.

The modes left free by the Dirichlet conditions (the combinations that vanish on every fixed dof)
are the motions held by nothing but contact: the step solvers evaluate the elastic forces on the
displacement with those motions removed, A u = A (u − Z Zᵀu), because a large rigid motion held by a
soft layer otherwise costs digits (A annihilates it only to rounding, ε E per row).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

#: A combination of modes counts as fixed when the Dirichlet conditions move it by less than this,
#: relative to the largest entry of the modes (which are of order one).
NULL_TOLERANCE = 1e-10


def bodies(elements: np.ndarray, nodes: int) -> tuple[int, np.ndarray]:
    """The connected bodies of a mesh with ``elements`` (nodes per element, elements): their number
    and the body of every node (nodes that no element uses form bodies of their own)."""
    corners = elements.shape[0]
    rows = np.concatenate([elements[i] for i in range(corners - 1)])
    cols = np.concatenate([elements[i + 1] for i in range(corners - 1)])
    graph = sp.coo_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(nodes, nodes))
    return connected_components(graph, directed=False)


def rigid_modes(points: np.ndarray, elements: np.ndarray, nodal_dofs: np.ndarray) -> np.ndarray:
    """The rigid motions of every body, as columns over all dofs: (ndofs, bodies · d(d + 1)/2).

    ``points`` (d, nodes), ``elements`` (nodes per element, elements), ``nodal_dofs`` (d, nodes)."""
    d, n = points.shape
    count, body = bodies(elements, n)
    per_body = d * (d + 1) // 2
    modes = np.zeros((nodal_dofs.size, count * per_body))
    sizes = np.bincount(body, minlength=count)
    centroid = np.vstack([np.bincount(body, weights=x, minlength=count) for x in points]) / sizes
    x = points - centroid[:, body]
    extent = np.sqrt(np.bincount(body, weights=np.sum(x * x, axis=0), minlength=count) / sizes)
    x = x / np.where(extent > 0.0, extent, 1.0)[body]
    first = body * per_body
    for c in range(d):  # translations
        modes[nodal_dofs[c], first + c] = 1.0
    for k, (a, b) in enumerate([(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]):  # rotations in the a-b plane
        modes[nodal_dofs[a], first + d + k] = -x[b]
        modes[nodal_dofs[b], first + d + k] = x[a]
    return modes


def free_rigid_modes(modes: np.ndarray, free: np.ndarray) -> np.ndarray:
    """An orthonormal basis, over the ``free`` dofs, of the rigid motions that vanish on every other
    dof (the motions the Dirichlet conditions leave free): (free dofs, k), k ≥ 0."""
    fixed = np.ones(modes.shape[0], dtype=bool)
    fixed[free] = False
    k = modes.shape[1]
    if k == 0:
        return np.zeros((free.size, 0))
    held = sla.qr(modes[fixed], mode="r")[0][:k] if fixed.any() else np.zeros((0, k))  # same singular values
    _, singular, vt = np.linalg.svd(np.vstack([held, np.zeros((k - held.shape[0], k))]))
    combinations = vt[singular <= NULL_TOLERANCE * max(1.0, np.abs(modes).max())].T
    if combinations.shape[1] == 0:
        return np.zeros((free.size, 0))
    basis, _ = sla.qr(modes[free] @ combinations, mode="economic")
    return basis
