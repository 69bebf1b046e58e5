"""Rigid-body motions of a mesh: the null space of the elastic stiffness, body by body.

Each connected body of the mesh (elements joined through nodes) has d translations and d(d − 1)/2
rotations (3 in 2D, 6 in 3D), which strain nothing: A z = 0 in exact arithmetic. Rotations are taken
about the body's centroid and scaled by its size, so every mode has entries of order one in any
unit of length. Two uses:

- a motion that neither the Dirichlet conditions nor the contact normals hold makes the problem
  singular (refused before any computation: ``RigidModes.unheld``);
- the motions the Dirichlet conditions leave free (``RigidModes.free_basis``) are held only by
  contact: the step solvers evaluate the elastic forces with them removed, A u = A (u − Z Zᵀu),
  because a large rigid motion held by a soft layer otherwise costs digits (A annihilates it only to
  rounding, ε E per row).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

#: A combination of a body's modes counts as held when the constraints move it by more than this,
#: relative (in the squared, Gram-matrix sense) to the body's most constrained combination.
HELD = 1e-12


def bodies(elements: np.ndarray, nodes: int) -> tuple[int, np.ndarray]:
    """The connected bodies of a mesh with ``elements`` (nodes per element, elements): their number
    and the body of every node (a node that no element uses is a body of its own)."""
    rows = elements.ravel()
    cols = np.roll(elements, -1, axis=0).ravel()
    graph = sp.coo_matrix((np.ones(rows.size, dtype=np.int8), (rows, cols)), shape=(nodes, nodes))
    return connected_components(graph, directed=False)


@dataclass(frozen=True)
class RigidModes:
    """The rigid motions of every body: ``matrix`` (ndofs, count · per_body), column b · per_body + k
    the motion k of body b (translations first, then rotations in the planes xy, yz, zx)."""

    matrix: sp.csc_matrix
    count: int
    per_body: int
    body: np.ndarray  # body of each node
    centroid: np.ndarray  # (d, count)
    size: np.ndarray  # (count,) root-mean-square distance of the nodes to the centroid

    @classmethod
    def of_mesh(cls, points: np.ndarray, elements: np.ndarray, nodal_dofs: np.ndarray) -> "RigidModes":
        """``points`` (d, nodes), ``elements`` (nodes per element, elements), ``nodal_dofs`` (d, nodes)."""
        d, n = points.shape
        count, body = bodies(elements, n)
        per_body = d * (d + 1) // 2
        nodes = np.bincount(body, minlength=count)
        centroid = np.vstack([np.bincount(body, weights=x, minlength=count) for x in points]) / nodes
        x = points - centroid[:, body]
        size = np.sqrt(np.bincount(body, weights=np.sum(x * x, axis=0), minlength=count) / nodes)
        size = np.where(size > 0.0, size, 1.0)
        x = x / size[body]
        first = body * per_body
        rows, cols, values = [], [], []
        for c in range(d):  # translations
            rows.append(nodal_dofs[c]), cols.append(first + c), values.append(np.ones(n))
        for k, (a, b) in enumerate([(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]):  # rotation in the a-b plane
            rows += [nodal_dofs[a], nodal_dofs[b]]
            cols += [first + d + k] * 2
            values += [-x[b], x[a]]
        matrix = sp.csc_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
                               shape=(nodal_dofs.size, count * per_body))
        return cls(matrix, count, per_body, body, centroid, size)

    def grams(self, *constraints: sp.spmatrix) -> np.ndarray:
        """Σ (C Z_b)ᵀ (C Z_b) over the ``constraints`` C (rows over all dofs), for every body b:
        (count, per_body, per_body). A constraint row may couple bodies only if it is a dof selection
        or a contact normal (one node each): the result is then exactly block diagonal."""
        p = self.per_body
        blocks = np.zeros((self.count, p, p))
        for C in constraints:
            seen = (sp.csr_matrix(C) @ self.matrix).tocsc()
            gram = (seen.T @ seen).tocoo()
            np.add.at(blocks, (gram.row // p, gram.row % p, gram.col % p), gram.data)
        return blocks

    def unheld(self, *constraints: sp.spmatrix) -> tuple[np.ndarray, np.ndarray]:
        """The motions the ``constraints`` do not hold: for each body b their number k_b and orthonormal
        combinations of its modes, the first k_b of which span them (least held first): (count,),
        (count, per_body, per_body)."""
        values, vectors = np.linalg.eigh(self.grams(*constraints))
        free = np.count_nonzero(values <= HELD * np.maximum(values[:, -1:], 1.0), axis=1)
        return free, vectors

    def free_basis(self, free: np.ndarray) -> np.ndarray:
        """An orthonormal basis, over the ``free`` dofs, of the motions that vanish on every other dof
        (the motions the Dirichlet conditions leave free): (free dofs, k), k ≥ 0."""
        fixed = np.ones(self.matrix.shape[0], dtype=bool)
        fixed[free] = False
        values, vectors = np.linalg.eigh(self.grams(sp.eye(fixed.size, format="csr")[fixed]))
        loose = values <= HELD * np.maximum(values[:, -1:], 1.0)
        if not loose.any():
            return np.zeros((free.size, 0))
        b, k = np.nonzero(loose)  # the free combinations: few, and only in bodies held by contact alone
        p = self.per_body
        rows = b.repeat(p) * p + np.tile(np.arange(p), b.size)  # the modes of body b
        combinations = sp.csc_matrix((vectors[b, :, k].ravel(), (rows, np.arange(b.size).repeat(p))),
                                     shape=(self.matrix.shape[1], b.size))
        motions = (self.matrix @ combinations).toarray()[free]
        basis, _ = np.linalg.qr(motions)
        return basis
