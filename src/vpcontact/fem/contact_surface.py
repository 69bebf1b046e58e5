"""The contact nodes of Γ3: the finite-element geometry the contact condition (2.5) is written on.

Node-to-rigid contact: node i of Γ3 carries a unit normal ν_i (the body's outward normal, the paper's u_ν, or
the fixed direction of a flat foundation), a weight w_i (its share of the measure of Γ3, lumped boundary
quadrature) and an initial gap g0_i to the foundation along ν_i; N, with (N u)_i = u(x_i)·ν_i, maps the
displacement to the nodes' normal displacements (the penetration is d = N u − g0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp

from ..errors import CaseError, point, quoted
from ..mesh.mesh import Mesh
from ..mesh.cells import coordinates as coordinates_names
from .facet_basis import facet_basis


@dataclass(frozen=True)
class ContactSurface:
    """Nodes of Γ3 with normals ν_i, lumped weights w_i and initial gaps g0_i.

    ``operator`` is the sparse m × ndofs matrix N with (N u)_i = u(x_i)·ν_i; ``facets`` (d, nf) are
    the facets of Γ3 (segments in 2D, triangles in 3D) as tuples of contact-node indices; ``parts`` the
    names of the contact parts Γ3 is made of, ``owner`` (m,) the index in ``parts`` of each node's part
    (a node where parts meet belongs to the first one listed).
    """

    nodes: np.ndarray
    coordinates: np.ndarray  # (d, m)
    normals: np.ndarray  # (d, m)
    weights: np.ndarray  # (m,)
    gap0: np.ndarray  # (m,)
    operator: sp.csr_matrix
    facets: np.ndarray
    parts: tuple[str, ...]
    owner: np.ndarray

    @property
    def size(self) -> int:
        return self.nodes.size

    def nearest_node(self, point) -> int:
        """Index (into the contact nodes) of the node nearest to ``point`` (any finite point: the offsets are
        scaled so that their squares cannot overflow)."""
        offsets = self.coordinates - np.reshape(point, (-1, 1))
        scale = np.abs(offsets).max(initial=0.0)
        return int(np.argmin(np.sum((offsets / scale if scale > 0 else offsets) ** 2, axis=0)))


def contact_surface(mesh: Mesh, parts, nodal_dofs: np.ndarray, gap=None, direction=None) -> ContactSurface:
    """Build the contact nodes of Γ3, the union of ``parts`` (a part, or a list of parts that share no
    facet; a node where they meet belongs to the first one listed): weights w_i = ∫_Γ3 φ_i da (a d-th
    of the measure of each adjacent facet); normals: the fixed unit ``direction`` (a flat foundation,
    ``contact.normal``) when given, else the exact ones where the mesh knows the geometry of the node's
    part, else the measure-weighted average of the adjacent facets' outward normals (facet measures
    and normals from scikit-fem's FacetBasis); ``gap(x, y[, z])`` gives g0 (default 0), along the
    normal: one function, or one per part (each at the nodes of its part)."""
    skmesh, d = mesh.mesh, mesh.dim
    parts = list(parts) if isinstance(parts, (list, tuple)) else [parts]
    gaps = list(gap) if isinstance(gap, (list, tuple)) else [gap] * len(parts)
    facets = _union_of_parts(mesh, parts)
    geometry, _ = facet_basis(skmesh, facets, skmesh.elem(), 1)
    measure = geometry.dx.sum(axis=1)  # (nf,)
    outward = geometry.normals[:, :, 0]  # (d, nf): constant on a flat facet
    corners = skmesh.facets[:, facets]  # (d, nf)
    nodes, local = np.unique(corners.ravel(), return_inverse=True)
    local = local.reshape(corners.shape)
    m = nodes.size
    owner = np.zeros(m, dtype=np.int64)
    for j in reversed(range(len(parts))):  # the first part listed is written last: it keeps the shared nodes
        owner[np.searchsorted(nodes, mesh.nodes(parts[j]))] = j
    weights = np.bincount(local.ravel(), weights=np.tile(measure / d, d), minlength=m)
    coordinates = skmesh.p[:, nodes]
    if direction is not None:
        normals = np.repeat(np.asarray(direction, dtype=float)[:, None] / np.linalg.norm(direction), m, axis=1)
    else:
        exact = [mesh.exact_normals.get(str(part)) for part in parts]
        normals = np.empty((d, m))
        if any(known is None for known in exact):
            summed = np.vstack([np.bincount(local.ravel(), weights=np.tile(outward[c] * measure, d), minlength=m)
                                for c in range(d)])
            normals = summed / np.linalg.norm(summed, axis=0)
        for j, known in enumerate(exact):
            if known is not None:
                mine = owner == j
                normals[:, mine] = np.asarray(known(coordinates[:, mine]), dtype=float)
    gap0 = np.zeros(m)
    for j, part_gap in enumerate(gaps):
        if part_gap is not None:
            mine = owner == j
            gap0[mine] = _initial_gap(part_gap, coordinates[:, mine])
    rows = np.repeat(np.arange(m), d)
    cols = nodal_dofs[:, nodes].T.ravel()
    operator = sp.csr_matrix((normals.T.ravel(), (rows, cols)), shape=(m, nodal_dofs.size))
    return ContactSurface(nodes, coordinates, normals, weights, gap0, operator, local, tuple(map(str, parts)), owner)


def _union_of_parts(mesh: Mesh, parts: list) -> np.ndarray:
    """The sorted facets of the contact parts, refused when a part has none or two parts share some (a
    facet of Γ3 has one layer)."""
    sets = [mesh.facets(part) for part in parts]
    for part, facets in zip(parts, sets):
        if facets.size == 0:
            raise CaseError(f"contact part '{part}' has no facets")
    for j in range(1, len(parts)):
        for i in range(j):
            shared = np.intersect1d(sets[i], sets[j]).size
            if shared:
                raise CaseError(f"contact parts '{parts[i]}' and '{parts[j]}' share {shared} facets: a facet of "
                                f"the contact surface has one layer; list parts that do not overlap")
    return np.unique(np.concatenate(sets))


def _initial_gap(gap: Callable, points: np.ndarray) -> np.ndarray:
    """g0 = gap(x, y[, z]) at ``points`` (d, k), refused where it is not finite."""
    d, k = points.shape
    with np.errstate(all="ignore"):  # a gap that is not finite is reported below
        gap0 = np.broadcast_to(gap(**dict(zip(coordinates_names(d), points))), (k,)).copy()
    bad = np.flatnonzero(~np.isfinite(gap0))
    if bad.size:
        where = getattr(gap, "where", None)  # an expression of the case knows its key
        name = f"{where} = {quoted(gap.source)}" if where is not None else "contact.gap"
        raise CaseError(f"{name}: not finite ({gap0[bad[0]]}) at the contact node ({', '.join(coordinates_names(d))}) "
                        f"= {point(points[:, bad[0]])}; the initial gap must be finite at every node of the contact "
                        f"part")
    return gap0


def empty_surface(ndofs: int, dim: int) -> ContactSurface:
    """The contact surface of a case without contact: no nodes."""
    none = np.zeros(0)
    return ContactSurface(np.zeros(0, dtype=np.int64), np.zeros((dim, 0)), np.zeros((dim, 0)), none, none,
                          sp.csr_matrix((0, ndofs)), np.zeros((dim, 0), dtype=np.int64), (),
                          np.zeros(0, dtype=np.int64))
