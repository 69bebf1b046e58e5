"""P1 elasticity on triangles and tetrahedra in vectorized NumPy: the kernels behind assembly.py.

On a simplex T with vertices x_0, …, x_d the gradients ∇λ_a of the barycentric coordinates are constant
and |T| = |det J| / d! (`vpcontact.mesh.simplex.barycentric_gradients`). The displacement dof (a, c) of T is
``nodal_dofs[c, t[a]]`` of the basis, its shape function φ_(a,c) = λ_a e_c, and

    ε(u)|_T = sym(Σ_a u_(a,·) ⊗ ∇λ_a),        (Bᵀz)_(a,c) = Σ_T |T| Σ_j z_cj^sym ∂_j λ_a,
    K_T[(a,c), (b,e)] = |T| (λ ∂_c λ_a ∂_e λ_b + μ ∂_e λ_a ∂_c λ_b + μ δ_ce ∇λ_a·∇λ_b).

The stiffness is summed in chunks of elements into a pattern of d × d node blocks built once, so the
memory it needs beyond the matrix itself is bounded by the chunk, not by the 144 entries of every
tetrahedron at once.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError
from ..memory import available_memory
from ..mesh.simplex import barycentric_gradients

#: Elements whose stiffness blocks are computed at once (about 40 MB of blocks per chunk in 3D).
CHUNK = 2**15
#: Elements whose node pairs are added to the pattern at once (about 70 MB of pairs in 3D): each
#: addition costs the size of the pattern, so fewer, larger chunks.
PATTERN_CHUNK = 8 * CHUNK


@dataclass(frozen=True)
class SimplexGeometry:
    """The constant gradients of the P1 shape functions and the volumes of a mesh's simplices, with the
    dofs of each element in the numbering of the displacement basis; the elements are the last axis
    (the long, contiguous one every vectorized operation runs along)."""

    gradients: np.ndarray  # (d + 1, d, elements): ∂_j λ_a on each element
    volumes: np.ndarray  # (elements,): |T|
    cells: np.ndarray  # (d + 1, elements): the nodes of each element (the mesh's array)
    dofs: np.ndarray  # (d + 1, d, elements): nodal_dofs[c, cells[a]], in the dtype of nodal_dofs (int32)
    ndofs: int

    @property
    def dim(self) -> int:
        return self.gradients.shape[1]

    def of(self, elements: np.ndarray) -> "SimplexGeometry":
        """The geometry of the elements ``elements`` (indices, in the order given) alone, on the same dofs."""
        return SimplexGeometry(self.gradients[..., elements], self.volumes[elements], self.cells[:, elements],
                               self.dofs[..., elements], self.ndofs)


_GEOMETRIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def geometry(basis) -> SimplexGeometry:
    """The SimplexGeometry of a P1 vector basis (scikit-fem's), computed once per basis."""
    found = _GEOMETRIES.get(basis)
    if found is None:
        mesh = basis.mesh
        cells = np.ascontiguousarray(mesh.t)
        d, elements = mesh.p.shape[0], cells.shape[1]
        gradients, volumes = np.empty((d + 1, d, elements)), np.empty(elements)
        for start in range(0, elements, CHUNK):  # chunks: the temporaries stay small
            part = slice(start, start + CHUNK)
            gradients[:, :, part], volumes[part] = barycentric_gradients(mesh.p, cells[:, part])
        dofs = np.ascontiguousarray(basis.nodal_dofs[:, cells].transpose(1, 0, 2))
        found = _GEOMETRIES[basis] = SimplexGeometry(gradients, volumes, cells, dofs, int(basis.N))
    return found


def strains(g: SimplexGeometry, u: np.ndarray) -> np.ndarray:
    """ε(u) on each element, shape (d, d, elements)."""
    nodal = u[g.dofs]  # (d + 1, d, elements): u_c at the nodes of each element
    gradient = nodal[0][:, None] * g.gradients[0][None]  # [c, j]: ∂_j u_c = Σ_a u_(a,c) ∂_j λ_a
    for a in range(1, g.dim + 1):
        gradient += nodal[a][:, None] * g.gradients[a][None]
    return 0.5 * (gradient + gradient.transpose(1, 0, 2))


def stress_work(g: SimplexGeometry, z: np.ndarray) -> np.ndarray:
    """Bᵀz = ∫_Ω z : ε(v) dx for a stress z (d, d, elements) constant on each element."""
    weighted = 0.5 * (z + z.transpose(1, 0, 2)) * g.volumes
    forces = np.einsum("cjn,ajn->acn", weighted, g.gradients)
    return np.bincount(g.dofs.ravel(), forces.ravel(), minlength=g.ndofs)


def node_pattern(cells: np.ndarray, nodes: int) -> sp.csr_matrix:
    """The pattern (sorted, no duplicates) of node pairs sharing an element of ``cells`` (d + 1,
    elements), summed over chunks."""
    pattern = sp.csr_matrix((nodes, nodes), dtype=np.int8)
    for start in range(0, cells.shape[1], PATTERN_CHUNK):
        chunk = cells[:, start:start + PATTERN_CHUNK]
        rows, cols = np.broadcast_arrays(chunk[:, None], chunk[None, :])
        rows, cols = rows.ravel(), cols.ravel()
        ones = np.ones(rows.size, dtype=np.int8)
        pattern = pattern + sp.csr_matrix((ones, (rows, cols)), shape=(nodes, nodes))
        pattern.data[:] = 1
    pattern.sort_indices()
    return pattern


def assembly_bytes(blocks: int, dim: int, elements: int) -> int:
    """Bytes :func:`elastic_stiffness` allocates at its peak (beyond its geometry) for a pattern of ``blocks`` node
    blocks over ``elements`` elements: while it sums the chunks, per block its d² values (8 bytes each), the CSR
    entries made of them (12 bytes each), its pattern entry and key (16 bytes), and the chunk's buffers and
    temporaries (1.2 times its two buffers of d²(d + 1)² values an element); before, the pattern's chunks
    (26 bytes per node pair of an element). Measured by tracemalloc: the estimate 1.03 and 0.99 times the peak on
    the quarter ball at 24k and 103k dofs, 0.93 times on the half disc at 37k."""
    chunk = min(CHUNK, elements)
    summing = blocks * (20 * dim * dim + 16) + 1.2 * 2 * 8 * dim**2 * (dim + 1) ** 2 * chunk
    pattern = blocks * 13 + 26 * (dim + 1) ** 2 * min(PATTERN_CHUNK, elements)
    return int(max(summing, pattern))


def check_assembly_memory(blocks: int, dim: int, elements: int) -> None:
    """CaseError, before the stiffness' values are allocated, if its assembly (:func:`assembly_bytes`) needs more
    memory than is available."""
    needed, available = assembly_bytes(blocks, dim, elements), available_memory()
    if needed > available:
        raise CaseError(f"the stiffness matrix of {elements:,} elements ({blocks * dim * dim:,} entries) needs about "
                        f"{needed / 2**30:.3g} GiB to assemble, more than the {available / 2**30:.3g} GiB of memory "
                        f"available here: use a coarser mesh (a larger mesh.h, or fewer elements in the mesh file)")


def elastic_stiffness(g: SimplexGeometry, lam, mu, nodes: int, nodal_dofs: np.ndarray) -> sp.csr_matrix:
    """The stiffness A = Σ_T K_T of Lamé parameters λ, μ (numbers, or one value per element), in the
    dof numbering ``nodal_dofs`` (d, nodes); CaseError if its assembly would not fit in the memory available."""
    d = g.dim
    pattern = node_pattern(g.cells, nodes)
    check_assembly_memory(pattern.nnz, d, g.volumes.size)
    keys = np.repeat(np.arange(nodes, dtype=np.int64), np.diff(pattern.indptr)) * nodes + pattern.indices
    blocks = np.zeros((pattern.nnz, d, d))
    lam = np.broadcast_to(np.asarray(lam, dtype=float), g.volumes.shape)
    mu = np.broadcast_to(np.asarray(mu, dtype=float), g.volumes.shape)
    # chunks of elements in the order of their lowest node: each chunk adds to a short range of blocks
    order = np.argsort(g.cells.min(axis=0), kind="stable")
    shape = (d, d, d + 1, d + 1)
    buffers = np.empty((2, *shape, min(CHUNK, order.size)))  # K and a term of it, reused by every chunk
    for start in range(0, order.size, CHUNK):  # arrays (…, elements): the long axis last is the fast one
        part = order[start:start + CHUNK]
        K, term = buffers[:, ..., :part.size]
        G = np.ascontiguousarray(g.gradients[:, :, part].transpose(1, 0, 2))  # (c, a, elements): ∂_c λ_a
        lam_G, mu_G = lam[part] * g.volumes[part] * G, mu[part] * g.volumes[part] * G
        np.multiply(lam_G[:, None, :, None], G[None, :, None, :], out=K)  # [c, e, a, b]: λ|T| ∂_c λ_a ∂_e λ_b
        K += np.multiply(mu_G[None, :, :, None], G[:, None, None, :], out=term)  # μ|T| ∂_e λ_a ∂_c λ_b
        dot = np.einsum("ian,ibn->abn", mu_G, G)
        for c in range(d):
            K[c, c] += dot  # μ|T| δ_ce ∇λ_a·∇λ_b
        cells = g.cells[:, part].astype(np.int64)  # its keys below are node · nodes + node
        low, high = pattern.indptr[cells.min()], pattern.indptr[cells.max() + 1]  # the node rows it adds to
        where = np.searchsorted(keys[low:high], (cells[:, None] * nodes + cells[None, :]).ravel())  # [a, b, elements]
        first, last = where.min(), where.max() + 1
        where -= first
        for c, e in np.ndindex(d, d):
            blocks[low + first:low + last, c, e] += np.bincount(where, K[c, e].ravel(), minlength=last - first)
    A = sp.bsr_matrix((blocks, pattern.indices, pattern.indptr),
                      shape=(d * nodes, d * nodes)).tocsr()
    A.eliminate_zeros()  # as scikit-fem did: entries that cancel exactly (e.g. on axis-aligned elements)
    interleaved = np.arange(d * nodes).reshape(nodes, d).T
    if not np.array_equal(nodal_dofs, interleaved):  # A is numbered d·node + c: renumber it as the basis
        position = np.empty(d * nodes, dtype=np.int64)
        position[nodal_dofs.ravel()] = interleaved.ravel()
        A = A[position][:, position]
    return A
