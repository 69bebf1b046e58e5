"""The contact nodes' dofs in their normal frame: the full-system Newton matrix made symmetric
positive definite.

The full Newton system of ``full`` (DESIGN §3)

    J Δu + N_𝒜ᵀ Δλ_𝒜 = r_u,    N_𝒜 Δu = c_𝒜,    J = A + Nᵀ diag(T) N,

is a saddle-point system. Each row of N is one contact node's normal on that node's free dofs, and
no two rows share a dof. A Householder reflection H_i of node i's free dofs maps its row n_i onto a
single dof (the one where |n_i| is largest), n_iᵀ H_i = s_i e_k with |s_i| = |n_i|; with Q the
block-diagonal orthogonal matrix of these reflections (Q = Qᵀ = Q⁻¹, the identity away from the
contact nodes), Δu = Q Δû gives N Q = diag(s) E, E selecting each node's normal dof. Then

    Q J Q = Q A Q + Eᵀ diag(s² T) E      (the compliance tangent lands on the diagonal),

and the constraint fixes the active nodes' normal dofs, Δû_ν = c / s: the system on the other dofs
is a principal submatrix of Q J Q, symmetric positive definite like J. It is solved with the
constrained dofs kept in place (their rows and columns replaced by their diagonal entry), so the
matrix keeps one sparsity pattern whatever the active set: a direct solver analyses it once and only
refactors its values; the multipliers come back from the constrained rows,
Δλ_i = (r̂ − Q J Q Δû)_ν / s_i.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

#: A contact row shorter than this (relative to the longest) has no free normal: its node is clamped
#: along the normal (a corner shared with a Dirichlet part), and its penetration cannot change.
CLAMPED = 1e-12


class NormalFrame:
    """Q, s and the normal dofs of the contact operator N (m × n, one node per row, rows on
    disjoint dofs); ``rotate(A)`` is Q A Q with its pattern kept for :meth:`constrained`."""

    def __init__(self, N: sp.csr_matrix):
        N = sp.csr_matrix(N)
        N.sort_indices()
        m, n = N.shape
        counts = np.diff(N.indptr)
        if np.bincount(N.indices, minlength=n).max(initial=0) > 1:
            raise ValueError("two contact rows share a dof: the normal frame needs one node per row")
        width = counts.max(initial=1)
        position = np.arange(N.nnz) - np.repeat(N.indptr[:-1], counts)
        rows = np.repeat(np.arange(m), counts)
        values = np.zeros((m, width))
        dofs = np.full((m, width), -1)
        values[rows, position], dofs[rows, position] = N.data, N.indices
        length = np.linalg.norm(values, axis=1)
        self.has_normal = length > CLAMPED * length.max(initial=0.0)
        pivot = np.argmax(np.abs(values), axis=1)
        sign = np.where(values[np.arange(m), pivot] >= 0.0, 1.0, -1.0)
        e = values / np.where(self.has_normal, length, 1.0)[:, None]
        v = e.copy()
        v[np.arange(m), pivot] += sign  # H = I − 2 v vᵀ / vᵀv maps e to −sign · e_pivot
        blocks = np.eye(width)[None] - 2.0 * v[:, :, None] * v[:, None, :] / np.sum(v * v, axis=1)[:, None, None]
        blocks[~self.has_normal] = np.eye(width)
        stored = (dofs[:, :, None] >= 0) & (dofs[:, None, :] >= 0)
        block_rows = np.broadcast_to(dofs[:, :, None], blocks.shape)[stored]
        block_cols = np.broadcast_to(dofs[:, None, :], blocks.shape)[stored]
        untouched = np.setdiff1d(np.arange(n), N.indices)
        self.Q = sp.csr_matrix((np.concatenate([blocks[stored], np.ones(untouched.size)]),
                                (np.concatenate([block_rows, untouched]), np.concatenate([block_cols, untouched]))),
                               shape=(n, n))
        self.scale = np.where(self.has_normal, -sign * length, 0.0)  # s_i
        self.normal_dof = dofs[np.arange(m), pivot]  # of every row (meaningful where has_normal)
        self._pattern = None

    def normal_operator(self) -> sp.csr_matrix:
        """N Q = diag(s) E: each row's one entry s_i at its node's normal dof (none for a clamped node)."""
        rows = np.flatnonzero(self.has_normal)
        return sp.csr_matrix((self.scale[rows], (rows, self.normal_dof[rows])),
                             shape=(self.scale.size, self.Q.shape[0]))

    def rotate(self, A: sp.spmatrix, columns: sp.spmatrix | None = None) -> sp.csr_matrix:
        """Q A Q, whose pattern (with every diagonal entry stored) :meth:`constrained` keeps. ``columns``: the Q
        of A's columns where A is one MPI rank's rows, its columns its own dofs first and then its ghosts (the
        frames of the ghosts' contact nodes too; :mod:`vpcontact.parallel.dofs`); None: A is square, Q both."""
        rotated = sp.csr_matrix(self.Q @ A @ (self.Q if columns is None else columns))
        rows = A.shape[0]
        rotated = rotated + sp.diags(np.zeros(rows), shape=A.shape, format="csr")  # the diagonal stored, even a zero
        rotated.sort_indices()
        self._pattern = rotated
        rows = np.repeat(np.arange(rows, dtype=rotated.indices.dtype), np.diff(rotated.indptr))
        self._diagonal_position = np.flatnonzero(rotated.indices == rows)  # one per row
        return rotated

    def tangent_diagonal(self, T: np.ndarray) -> np.ndarray:
        """s² T at the normal dofs (zero elsewhere): Q Nᵀ diag(T) N Q = Eᵀ diag(s² T) E."""
        diagonal = np.zeros(self._pattern.shape[0])
        with_normal = self.has_normal
        diagonal[self.normal_dof[with_normal]] = self.scale[with_normal] ** 2 * T[with_normal]
        return diagonal

    def constrained(self, diagonal: np.ndarray, fixed: np.ndarray) -> sp.csr_matrix:
        """Q A Q + diag(``diagonal``) with the rows and columns of the ``fixed`` dofs (a boolean
        mask over the columns, which begin with the rows' dofs) reduced to their diagonal entry: the same stored
        pattern for every mask."""
        pattern, on_diagonal = self._pattern, self._diagonal_position
        data = pattern.data.copy()
        data[on_diagonal] += diagonal
        kept = data[on_diagonal]
        data[np.repeat(fixed[: pattern.shape[0]], np.diff(pattern.indptr)) | fixed[pattern.indices]] = 0.0
        data[on_diagonal] = kept
        return sp.csr_matrix((data, pattern.indices, pattern.indptr), shape=pattern.shape)

    def normal_dofs(self, nodes: np.ndarray) -> np.ndarray:
        """A mask over the dofs: the normal dofs of the contact nodes ``nodes`` (a mask over the rows)
        that have a free normal."""
        mask = np.zeros(self._pattern.shape[0], dtype=bool)
        mask[self.normal_dof[nodes & self.has_normal]] = True
        return mask
