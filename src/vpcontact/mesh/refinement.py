"""Conforming refinement of a `Mesh` that keeps the model's data: parts, regions, exact normals, curved boundaries.

`refine(mesh, marked)` refines the marked elements with scikit-fem's ``refined(marked)`` (red-green-blue
refinement of triangles, longest-edge bisection of tetrahedra; neighbours are refined as far as the mesh
needs to stay conforming), then carries the model's data over:

- every new element lies in one element of the old mesh, its parent; it is in the regions of its parent. A new
  element whose vertices are all old nodes is an old element kept whole (a piece of a split element has a new
  node, the midpoint of one of its edges), found by its vertices; the others are the old elements that were split
  containing their centroids;
- every new boundary facet lies in one boundary facet of the old mesh, its parent: the facet of the parent
  element (of the new facet's element) on which the new facet's centroid lies, the one opposite the vertex
  whose barycentric coordinate is 0 there; the new facet is in the parts of its parent;
- the exact normals and the curved parts and interfaces (``Mesh.curved_parts``, ``Mesh.curved_interfaces``)
  are the old mesh's; the new nodes of the facets of a curved part, or of the facets between elements of the
  two regions of a curved interface, are moved onto the exact curve or surface. A mesh file has none: its
  new nodes stay on its flat facets.

The refined mesh is nested in the old one before the projection; the projection must not turn an element
inside out (a curve much more curved than its elements are small): that is checked, element by element.

`refine_with_lineage` also returns the :class:`Lineage` of the refinement, what carries fields from the old mesh
to the new one (:mod:`vpcontact.adaptivity.transfer`): the parent of each new element and the P1 interpolation
of the old mesh at the new nodes, taken where the nodes were made (edge midpoints, before the projection onto
curved boundaries), so that its weights are those of the nested meshes: dyadic fractions, rounded to them.
"""

from __future__ import annotations

import numpy as np

from dataclasses import dataclass

import scipy.sparse as sp

from ..errors import CaseError, point
from .ball import quiet_bisection
from .checks_arrays import SKFEM_MESH
from .facets import refinable, with_facet_tables
from .locate import Locator, find_columns
from .mesh import Mesh, with_parts
from .simplex import determinants


#: The finest dyadic fraction a weight of `Lineage.interpolation` is rounded to (2^-20: twenty nested bisections).
DYADIC = 2.0 ** 20


@dataclass(frozen=True)
class Lineage:
    """How a refined mesh descends from the old one: ``parent`` (new elements,), the old element each new element
    lies in; ``interpolation`` (new nodes × old nodes, sparse), the P1 interpolation of the old mesh at the new
    nodes (an old node keeps its own value: the rows of the old nodes are the identity)."""

    parent: np.ndarray
    interpolation: sp.csr_matrix

    def then(self, later: "Lineage") -> "Lineage":
        """The lineage of this refinement followed by ``later``, a refinement of its mesh (the products of dyadic
        weights are dyadic: still exact)."""
        return Lineage(self.parent[later.parent], (later.interpolation @ self.interpolation).tocsr())


def refine(mesh: Mesh, marked) -> Mesh:
    """The conforming refinement of `mesh` that refines at least the elements `marked` (indices of columns
    of ``mesh.mesh.t``), with its parts, regions, exact normals and curved parts and interfaces."""
    return refine_with_lineage(mesh, marked)[0]


def refine_with_lineage(mesh: Mesh, marked) -> tuple[Mesh, Lineage]:
    """`refine` and the refinement's :class:`Lineage` (unmarked: the mesh itself, each element its own parent)."""
    old = mesh.mesh
    marked = np.unique(np.asarray(marked, dtype=np.int64))
    if marked.size and (marked[0] < 0 or marked[-1] >= old.t.shape[1]):
        raise ValueError(f"marked elements must be in 0 ... {old.t.shape[1] - 1}, got {marked[0]} ... {marked[-1]}")
    if not marked.size:
        return mesh, Lineage(np.arange(old.t.shape[1]), sp.identity(old.p.shape[1], format="csr"))
    kind = SKFEM_MESH[mesh.dim]
    with quiet_bisection():
        fine = with_facet_tables(refinable(kind(old.p, old.t)).refined(marked))
    parent = parents(old, fine)
    locator = Locator(old.p, old.t)
    boundary = fine.boundary_facets().astype(np.int64)
    parent_facet = _parent_facets(old, locator, fine, boundary, parent)
    parts = {name: boundary[np.isin(parent_facet, facets)] for name, facets in mesh.parts.items()}
    regions = {name: np.flatnonzero(np.isin(parent, elements)) for name, elements in mesh.regions.items()}
    p = _onto_curves(mesh, fine, parts, regions, first_new=old.p.shape[1])
    refined = kind(np.ascontiguousarray(p), np.ascontiguousarray(fine.t))
    lineage = Lineage(parent, _interpolation(locator, fine.p, old.p.shape[1], parent, fine.t))
    refined_mesh = Mesh(with_parts(refined, parts, built=fine), parts, mesh.exact_normals, mesh.file, regions,
                        mesh.curved_parts, mesh.curved_interfaces)
    return refined_mesh, lineage


def parents(old, fine) -> np.ndarray:
    """The element of the scikit-fem mesh ``old`` that each element of its nested refinement ``fine`` (whose first
    nodes are old's) lies in. An element of ``fine`` whose vertices are all old nodes is an element of ``old`` kept
    whole: found by its vertices. The others, pieces of the split elements, are located by their centroids among
    the split elements only (those not kept whole), which near a singularity are few."""
    t = np.asarray(fine.t)
    parent = np.full(t.shape[1], -1, dtype=np.int64)
    whole = np.flatnonzero((t < old.p.shape[1]).all(axis=0))
    parent[whole] = find_columns(old.t, t[:, whole])
    split = np.ones(old.t.shape[1], dtype=bool)
    split[parent[whole][parent[whole] >= 0]] = False
    pieces, candidates = np.flatnonzero(parent < 0), np.flatnonzero(split)
    if pieces.size:
        located, _ = Locator(old.p, old.t[:, candidates]).locate(fine.p[:, t[:, pieces]].mean(axis=1).T)
        parent[pieces] = candidates[located]
    return parent


def _interpolation(locator: Locator, points: np.ndarray, old_nodes: int, parent: np.ndarray,
                   elements: np.ndarray) -> sp.csr_matrix:
    """The P1 interpolation (len(points) × old_nodes) of the old mesh (``locator``'s, its first ``old_nodes`` nodes
    the same as the new mesh's) at the nested new ``points`` (d, nodes): each new node in the parent of one of the
    new ``elements`` that hold it, its barycentric coordinates there rounded to dyadic fractions (exact for nested
    midpoints) where they are within 1e-9 of one."""
    new = np.arange(old_nodes, points.shape[1])
    holder = np.zeros(points.shape[1], dtype=np.int64)
    holder[elements.ravel()] = np.tile(np.arange(elements.shape[1]), elements.shape[0])  # any element holding it
    element = parent[holder[new]]
    weights = locator.barycentric(points[:, new].T, element)  # (d + 1, new)
    dyadic = np.round(weights * DYADIC) / DYADIC
    weights = np.where(np.abs(weights - dyadic) < 1e-9, dyadic, weights)
    rows = np.concatenate([np.arange(old_nodes), np.repeat(new, weights.shape[0])])
    columns = np.concatenate([np.arange(old_nodes), locator.elements[:, element].T.ravel()])
    values = np.concatenate([np.ones(old_nodes), weights.T.ravel()])
    keep = values != 0.0
    return sp.csr_matrix((values[keep], (rows[keep], columns[keep])), shape=(points.shape[1], old_nodes))


def _parent_facets(old, locator: Locator, fine, facets: np.ndarray, parent: np.ndarray) -> np.ndarray:
    """The facet of the `old` mesh (column of ``old.facets``) that each facet `facets` of the refined mesh `fine`
    lies in, given the `parent` (old element) of each new element and the `locator` of the old elements."""
    element = parent[fine.f2t[0, facets]]
    centroid = fine.p[:, fine.facets[:, facets]].mean(axis=1)
    opposite = locator.barycentric(centroid.T, element).argmin(axis=0)  # the vertex the facet does not touch
    vertices = locator.elements[:, element]
    keep = np.arange(vertices.shape[0])[:, None] != opposite[None, :]
    nodes = vertices.T[keep.T].reshape(-1, vertices.shape[0] - 1).T
    return find_columns(old.facets, nodes)


def _onto_curves(mesh: Mesh, fine, parts: dict[str, np.ndarray], regions: dict[str, np.ndarray],
                 first_new: int) -> np.ndarray:
    """The nodes of `fine` with its new nodes (index ≥ `first_new`) on the curved parts and interfaces of
    `mesh` moved onto them; CaseError if that turns an element inside out."""
    p = fine.p.copy()
    surfaces = [(fine.facets[:, parts[name]], project) for name, project in mesh.curved_parts.items()]
    inner = fine.f2t[1] >= 0
    for (a, b), project in mesh.curved_interfaces.items():
        in_a, in_b = (_mask(regions[name], fine.t.shape[1]) for name in (a, b))
        between = inner & ((in_a[fine.f2t[0]] & in_b[fine.f2t[1]]) | (in_b[fine.f2t[0]] & in_a[fine.f2t[1]]))
        surfaces.append((fine.facets[:, between], project))
    moved = []
    for nodes, project in surfaces:
        new = np.unique(nodes[nodes >= first_new])
        p[:, new] = project(fine.p[:, new])
        moved.append(new)
    if moved:
        _check_not_folded(fine, p, np.unique(np.concatenate(moved)))
    return p


def _mask(indices: np.ndarray, size: int) -> np.ndarray:
    """The boolean mask of `indices` among `size` items."""
    mask = np.zeros(size, dtype=bool)
    mask[indices] = True
    return mask


def _check_not_folded(fine, p: np.ndarray, moved: np.ndarray) -> None:
    """CaseError if moving the `moved` nodes of `fine` to `p` turns one of its elements inside out or flat."""
    before, after = determinants(fine.p, fine.t), determinants(p, fine.t)
    folded = np.flatnonzero(~(after * np.sign(before) > 0.0))
    if folded.size:
        raise CaseError(f"refining the mesh turns {folded.size} element(s) inside out near "
                        f"{point(p[:, fine.t[:, folded[0]]].mean(axis=1))} when their new "
                        f"nodes are moved onto the curved boundary or interface: the elements there are too large "
                        f"for its curvature; start from a smaller mesh.h")
