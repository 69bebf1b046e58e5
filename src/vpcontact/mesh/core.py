"""Triangle (2D) and tetrahedral (3D) meshes (P1) with named boundary parts.

`Mesh` wraps a `skfem.MeshTri` or `skfem.MeshTet` and names sets of its boundary facets
("parts"): edges in 2D, triangles in 3D. Meshes come from `half_disc` (the paper's half
ball), `rectangle`, `quarter_ball` (its 3D analogue), `block` or `read_mesh` (any triangle
or tetrahedron file meshio reads, e.g. gmsh .msh 2.2 / 4.1).

Facet and node indices are those of the wrapped skfem mesh. skfem sorts the node
indices of every triangle (``MeshTri.sort_t``), and a file's tetrahedra keep their own
order, so ``mesh.mesh.t`` has no fixed orientation; skfem's P1 assembly and facet
normals do not depend on it.
"""

from __future__ import annotations

import contextlib
import io
import itertools
import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.spatial import Delaunay
import skfem

from . import ball, msh22
from ..inputs import check_regular_file
from ..errors import CaseError, shown
from ..memory import available_memory
from .checks_2d import check_finite, check_triangles
from .checks_3d import check_tetrahedra
from .checks_arrays import check_mesh

if TYPE_CHECKING:
    import meshio

NormalField = Callable[[np.ndarray], np.ndarray]
Projection = Callable[[np.ndarray], np.ndarray]

#: The skfem mesh type of each dimension.
SKFEM_MESH = {2: skfem.MeshTri, 3: skfem.MeshTet}
#: The gmsh physical groups of each dimension d: (those of the parts (dimension d − 1), of the body).
PHYSICAL_GROUPS = {2: ("Curve", "Surface"), 3: ("Surface", "Volume")}


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle (2D) or tetrahedral (3D) mesh with named boundary parts."""

    mesh: skfem.Mesh
    """The scikit-fem mesh, MeshTri1 or MeshTet1 (p: (d, nnodes), t: (d + 1, nelems)); its ``boundaries``
    hold the parts too."""
    parts: dict[str, np.ndarray]
    """Part name -> sorted int64 indices of boundary facets (columns of ``mesh.facets``)."""
    exact_normals: dict[str, NormalField]
    """Part -> f(points (d, ...)) -> unit outward normals, same shape; only where the geometry is known exactly."""
    file: str | None = None
    """The mesh file it was read from (None for a built-in shape)."""
    regions: dict[str, np.ndarray] = field(default_factory=dict)
    """Region name -> sorted int64 indices of elements (columns of ``mesh.t``): the groups of elements
    materials are assigned to; empty when the mesh does not group its elements (one region, the body)."""
    curved_parts: dict[str, Projection] = field(default_factory=dict)
    """Part -> f(points (d, k)) -> the nearest points (d, k) of the exact curve or surface the part lies on: the
    curved parts of a built-in shape, where refinement (`vpcontact.mesh.refinement`) moves its new nodes."""
    curved_interfaces: dict[tuple[str, str], Projection] = field(default_factory=dict)
    """(region, region) -> the projection onto the exact curve or surface between the two regions (a coated
    shape's interface), like ``curved_parts``."""

    def __post_init__(self):
        """Refuse arrays that cannot be a mesh (`vpcontact.mesh.checks_arrays`: a Mesh made in Python may hold
        anything) and keep the parts and regions as sorted int64 indices."""
        parts, regions = check_mesh(self)
        object.__setattr__(self, "parts", parts)
        object.__setattr__(self, "regions", regions)

    def facets(self, part: str | int) -> np.ndarray:
        """Facet indices of `part` (an int n means the part named str(n))."""
        name = str(part)
        if name not in self.parts and not self.parts:
            facet, body = PHYSICAL_GROUPS[self.dim]
            raise CaseError(f"unknown part '{name}': mesh file '{self.file}' has no parts; the parts of a mesh file "
                            f"are its physical {facet.lower()}s: in gmsh add Physical {facet}(\"{name}\") = {{...}}; "
                            f"for each part the case names (and a Physical {body} for the body) and mesh again")
        if name not in self.parts:
            raise CaseError(f"unknown part '{shown(name)}'; the mesh has parts: {', '.join(self.part_names)}")
        return self.parts[name]

    def nodes(self, part: str | int) -> np.ndarray:
        """Sorted unique node indices of the facets of `part`."""
        return np.unique(self.mesh.facets[:, self.facets(part)]).astype(np.int64)

    @property
    def dim(self) -> int:
        """The dimension d of the body: 2 (triangles) or 3 (tetrahedra)."""
        return self.mesh.p.shape[0]

    @property
    def part_names(self) -> list[str]:
        """The part names, sorted."""
        return sorted(self.parts)

    @cached_property
    def h(self) -> float:
        """The longest edge length."""
        p, t = self.mesh.p, self.mesh.t
        return float(max(np.sqrt(((p[:, t[i]] - p[:, t[j]]) ** 2).sum(axis=0)).max()
                         for i, j in itertools.combinations(range(t.shape[0]), 2)))

    @cached_property
    def centroids(self) -> np.ndarray:
        """The element centroids (d, nelements): where P0 data given as expressions are evaluated."""
        return self.mesh.p[:, self.mesh.t].mean(axis=1)

    @property
    def diameter(self) -> float:
        """The diameter (diagonal length) of the bounding box of the nodes."""
        p = self.mesh.p
        return float(np.linalg.norm(p.max(axis=1) - p.min(axis=1)))


def _positive(name: str, value: float) -> float:
    """`value` as a float, or CaseError unless it is a number (a NumPy one too; not a string or a bool), finite
    and > 0."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise CaseError(f"{name} = {shown(repr(value))}: expected a number > 0")
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise CaseError(f"{name} must be a positive number, got {value}")
    return value


#: Peak memory of a run per triangle (bytes): mesh, stiffness matrix, its factorization and the solver's
#: arrays. Measured (peak resident memory of `vpcontact run`, PARDISO): the paper's example with 145k
#: triangles 0.53 GB, with 580k triangles 1.79 GB, i.e. 3.1 kB per triangle; SuperLU (no MKL) needs
#: about twice as much. A run is refused when even this estimate exceeds the available memory.
BYTES_PER_TRIANGLE = 4000
#: The same per tetrahedron, for the method that needs least, the iterative one (no factor: the
#: factorizations of the direct methods are checked before they are made, by PARDISO's analysis and
#: the condensed method's guard). Measured (peak resident memory of the quarter ball's 11 steps,
#: ``python benchmarks/scaling.py --dim 3 --method iterative``): 324k tetrahedra 1.73 GB, 954k
#: tetrahedra 4.16 GB, i.e. 4.4–5.3 kB each.
BYTES_PER_TETRAHEDRON = 5500


def check_memory(elements: float, what: str, fix: str, dim: int = 2) -> None:
    """Refuse, before allocating, a mesh of about `elements` triangles (dim 2) or tetrahedra (dim 3) whose
    run would need more than the available memory; `what` names the mesh (e.g. "mesh.h = 0.001"), `fix`
    says what to change."""
    kind, per_element = {2: ("triangles", BYTES_PER_TRIANGLE), 3: ("tetrahedra", BYTES_PER_TETRAHEDRON)}[dim]
    needed = per_element * elements
    available = available_memory()
    if not needed <= available:
        count, size = (f"about {elements:.2g}", f"about {needed / 2**30:.3g}") if math.isfinite(needed) else \
            ("more than 1e+300", "more than 1e+290")
        raise CaseError(f"{what}: {count} {kind}, whose mesh, stiffness matrix and solver need {size} GiB, "
                        f"more than the {available / 2**30:.3g} GiB of memory available here: {fix}")


#: scikit-fem's tables of a mesh's facets (the facets, element to facets, facet to elements), attributes it
#: builds on first use and that depend only on the elements.
FACET_TABLES = ("_facets", "_t2f", "_f2t")


def with_parts(mesh, parts: dict[str, np.ndarray], built=None):
    """``mesh.with_boundaries(parts)`` (scikit-fem), keeping the facet tables already built on ``built`` (by
    default ``mesh``), a mesh of the same elements: with_boundaries copies the mesh without them, and building
    them again took 0.4–0.8 s at 475k triangles. A table scikit-fem no longer keeps under these names is
    simply built again."""
    named = mesh.with_boundaries(parts)
    source = mesh if built is None else built
    for name in FACET_TABLES:
        if name in vars(source) and name not in vars(named):
            setattr(named, name, getattr(source, name))
    return named


def _wrap(p: np.ndarray, t: np.ndarray, classify: Callable[[np.ndarray], dict[str, np.ndarray]],
          exact_normals: dict[str, NormalField], regions: dict[str, np.ndarray] | None = None,
          curved_parts: dict[str, Projection] | None = None,
          curved_interfaces: dict[tuple[str, str], Projection] | None = None) -> Mesh:
    """Build a `Mesh` from nodes `p` (d, n) and triangles or tetrahedra `t` (d + 1, m) (and its `regions`,
    its curved parts and interfaces).

    `classify(centroids (d, k))` returns part name -> boolean mask over the k boundary
    facets; the masks must partition the boundary (checked).
    """
    mesh = SKFEM_MESH[p.shape[0]](np.ascontiguousarray(p), np.ascontiguousarray(t))
    boundary = mesh.boundary_facets().astype(np.int64)
    masks = classify(mesh.p[:, mesh.facets[:, boundary]].mean(axis=1))
    if not np.array_equal(np.sum(list(masks.values()), axis=0), np.ones(boundary.size)):
        raise RuntimeError("boundary facets do not split exactly into the parts")
    parts = {name: boundary[mask] for name, mask in masks.items()}
    return Mesh(with_parts(mesh, parts), parts, exact_normals, regions=regions or {},
                curved_parts=curved_parts or {}, curved_interfaces=curved_interfaces or {})


@dataclass(frozen=True, eq=False)
class OntoSphere:
    """The projection of points (d, ...) onto the circle (d = 2) or sphere (d = 3) of `radius` around `center`
    (along the radius through the point). A class, not a closure: a mesh pickles (a result is sent between
    processes with its mesh)."""

    center: np.ndarray
    radius: float

    def __call__(self, x: np.ndarray) -> np.ndarray:
        at = self.center.reshape((-1,) + (1,) * (x.ndim - 1))
        offset = x - at
        return at + self.radius * offset / np.sqrt((offset**2).sum(axis=0))


@dataclass(frozen=True, eq=False)
class RadialNormal:
    """The outward unit normal (d, ...) of a circle or sphere around `center` at points (d, ...)."""

    center: np.ndarray

    def __call__(self, x: np.ndarray) -> np.ndarray:
        d = x - self.center.reshape((-1,) + (1,) * (x.ndim - 1))
        return d / np.sqrt((d**2).sum(axis=0))


@dataclass(frozen=True)
class ConstantNormal:
    """The normal field equal to `normal` everywhere."""

    normal: tuple[float, ...]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        out = np.empty_like(x, dtype=float)
        out[...] = np.reshape(self.normal, (-1,) + (1,) * (x.ndim - 1))
        return out


def onto_sphere(center: np.ndarray, radius: float) -> Projection:
    """The projection onto the circle or sphere of `radius` around `center` (:class:`OntoSphere`)."""
    return OntoSphere(np.asarray(center, dtype=float), float(radius))


def _signed_areas(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Signed areas of triangles `t` (positive when counter-clockwise)."""
    a, b, c = p[:, t[0]], p[:, t[1]], p[:, t[2]]
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _smooth(p: np.ndarray, t: np.ndarray, movable: np.ndarray, sweeps: int) -> np.ndarray:
    """Laplacian smoothing: each sweep moves the `movable` nodes to the mean of their
    neighbours; a sweep that would make a triangle's signed area drop below a tenth of
    its previous value (or invert it) is discarded and smoothing stops."""
    n = p.shape[1]
    i = np.concatenate((t[0], t[1], t[2]))
    j = np.concatenate((t[1], t[2], t[0]))
    adjacency = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(n, n)).tocsr()
    adjacency = ((adjacency + adjacency.T) > 0).astype(float)
    averaging = sp.diags(1.0 / np.asarray(adjacency.sum(axis=1)).ravel()) @ adjacency
    area = _signed_areas(p, t)
    for _ in range(sweeps):
        q = p.copy()
        q[:, movable] = (averaging @ p.T).T[:, movable]
        new_area = _signed_areas(q, t)
        if np.any(new_area < 0.1 * area):
            break
        p, area = q, new_area
    return p


def half_disc(h: float, radius: float = 1.0, coating: float | None = None) -> Mesh:
    """Quasi-uniform mesh of the half disc {x > 0, x² + (y − R)² < R²} (center (0, R)).

    Parts: "axis" (x = 0), "bottom_arc" (arc from (0, 0) to (R, R)), "top_arc" (arc from
    (R, R) to (0, 2R)), all with exact outward normals, the arcs with their projection onto the
    circle (``curved_parts``). Requires 0 < h ≤ R.

    Each quarter arc has ceil((π/2)·R/h) facets of equal arc length, the axis ceil(2R/h)
    equal facets; (0, 0), (R, R) and (0, 2R) are nodes. Interior nodes: one layer parallel
    to the arc at depth √3/2·h, staggered against the arc nodes, and inside it a hexagonal
    lattice of spacing h. The triangulation is Delaunay (the lattice's own triangles away
    from the boundary, scipy's Delaunay near it); the interior nodes are then Laplacian-
    smoothed. The mesh is built for R = 1 and h/R, then scaled by R: the same triangles in any
    unit of length. Measured for R/h in [1, 300]: longest edge ≤ 1.45 h, smallest angle ≥ 27°;
    for R/h ≥ 5 the triangle count is within 5 % of (πR²/2)/(√3 h²/4).

    With a `coating` c (0 < c < R) the mesh has the regions "core" (distance to the center < R − c)
    and "coating" (their interface's projection in ``curved_interfaces``), and a conforming interface:
    the half circle of radius R − c is a line of nodes
    (`_coated_half_disc`); the parts and their facets on the arcs are the same. Measured for R/h in
    [5, 50] and h ≤ c ≤ R − h: smallest angle ≥ 25°, longest edge ≤ 1.41 h; a coating thinner than h
    is one layer of flat triangles (their height c against their length h); one not thicker than the
    depth of the arc's facets, R (1 − cos(π/(4 n))) ≈ h²/(8R), is refused.
    """
    h = _positive("h", h)
    R = _positive("radius", radius)
    if h > R:
        raise CaseError(f"h = {h} must not exceed the radius {R}")
    if coating is not None:
        coating = _coating(coating, R)
    with np.errstate(over="ignore", divide="ignore"):
        triangles = 0.5 * np.pi * R * R / (0.25 * np.sqrt(3.0) * h * h)
    check_memory(triangles, f"mesh.h = {h:g} on a half disc of radius {R:g}", "use a larger mesh.h")
    n_arc = int(np.ceil(0.5 * np.pi * R / h))
    if coating is None:
        n_axis = int(np.ceil(2.0 * R / h))
        p, t = _unit_half_disc(h / R, n_arc, n_axis)  # built for R = 1, then scaled: the same triangles in any unit
        p, regions = R * p, {}
    else:
        if not coating > R * (1.0 - math.cos(0.25 * np.pi / n_arc)):  # the interface would cross the arc's facets
            raise _too_thin(coating, h, R, "circle")
        p, t, regions, n_axis = _coated_half_disc(h / R, coating / R, n_arc)  # built for R = 1 too
        p = R * p
    center = np.array([0.0, R])
    radial, axis_normal = RadialNormal(center), ConstantNormal((-1.0, 0.0))

    def classify(mid: np.ndarray) -> dict[str, np.ndarray]:
        on_axis = mid[0] < 1e-9 * h
        return {"axis": on_axis, "bottom_arc": ~on_axis & (mid[1] < R), "top_arc": ~on_axis & (mid[1] > R)}

    arc = onto_sphere(center, R)
    interfaces = {} if coating is None else {("core", "coating"): onto_sphere(center, R - coating)}
    mesh = _wrap(p, t, classify, {"axis": axis_normal, "bottom_arc": radial, "top_arc": radial}, regions,
                 {"bottom_arc": arc, "top_arc": arc}, interfaces)
    used = np.bincount(t.ravel(), minlength=p.shape[1]) > 0
    if mesh.parts["bottom_arc"].size != n_arc or mesh.parts["axis"].size != n_axis or not used.all():
        raise RuntimeError("half_disc: the triangulation does not follow the boundary nodes or misses a node")
    return mesh


def _too_thin(coating: float, h: float, radius: float, boundary: str) -> CaseError:
    """The refusal of a coating thinner than the gap between the `boundary` ("circle" or "sphere") and the
    mesh's facets on it: the interface's nodes would lie beyond those facets."""
    return CaseError(f"mesh.coating = {coating:g} is too thin for mesh.h = {h:g}: the facets of the mesh on the "
                     f"{boundary} of radius {radius:g} cut about h^2 / (8 radius) deep into the body, deeper than the "
                     f"coating; use mesh.h < sqrt(8 radius coating) = {math.sqrt(8.0 * radius * coating):.3g} or a "
                     f"thicker coating")


def _coating(coating: float, radius: float) -> float:
    """`coating` as a float, or CaseError unless 0 < coating < radius."""
    coating = _positive("coating", coating)
    if not coating < radius:
        raise CaseError(f"coating = {coating:g} must be less than the radius {radius:g}: it is the thickness of the "
                        f"outer shell, the core has the radius (radius - coating)")
    return coating


def _coated_half_disc(h: float, c: float, n_arc: int) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], int]:
    """Nodes, counter-clockwise triangles, regions {"core", "coating"} and the number of axis facets of the
    half disc of radius R = 1 centred at (0, R) with a coating of thickness c, n_arc facets on each quarter
    of its arc (h and c relative to R).

    The core is `half_disc`'s mesh of radius R − c (size min(h, R − c)) moved to the center (0, R); its arc
    nodes are the interface. The coating holds L = max(1, round(c / (√3/2·h))) rows of nodes on the
    half circles of radius R − c + j·c/L (j = 1 ... L), ending on the axis: row j has ceil(π r_j / h)
    equal arcs, shifted by half of one for odd j below L (staggered against the row inside it), row L is
    `half_disc`'s arc (n_arc facets on each quarter, (R, R) a node). The coating's triangles are scipy's
    Delaunay triangles of the interface nodes and the rows (those between interface nodes only are the
    core's polygon and dropped); the interface chords are Delaunay edges, so no triangle crosses the
    interface."""
    R = 1.0
    inner = R - c
    h_core = min(h, inner)
    n_core = int(np.ceil(0.5 * np.pi * inner / h_core))
    n_core_axis = int(np.ceil(2.0 * inner / h_core))
    core_p, core_t = _unit_half_disc(h_core / inner, n_core, n_core_axis)
    core_p = inner * core_p + np.array([[0.0], [c]])
    interface = np.arange(2 * n_core + 1)  # the core's arc nodes, from (0, c) to (0, 2R − c)

    L = max(1, round(c / (0.5 * np.sqrt(3.0) * h)))
    rows = []
    for j in range(1, L + 1):
        r = R if j == L else inner + j * c / L
        arcs = 2 * n_arc if j == L else int(np.ceil(np.pi * r / h))
        angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, arcs + 1)
        if j % 2 and j < L:  # staggered: the middles of the arcs, and the two ends on the axis
            angle = np.concatenate((angle[:1], 0.5 * (angle[1:] + angle[:-1]), angle[-1:]))
        row = np.vstack((r * np.cos(angle), R + r * np.sin(angle)))
        row[0, [0, -1]] = 0.0
        if j == L:
            row[:, n_arc] = (R, R)
        rows.append(row)
    p = np.hstack([core_p] + rows)
    nodes = np.concatenate((interface, np.arange(core_p.shape[1], p.shape[1])))
    t = nodes[Delaunay(p[:, nodes].T).simplices.T]
    t = t[:, ~(t < interface.size).all(axis=0)]
    flip = _signed_areas(p, t) < 0
    t[1:, flip] = t[2:0:-1, flip]
    regions = {"core": np.arange(core_t.shape[1], dtype=np.int64),
               "coating": np.arange(core_t.shape[1], core_t.shape[1] + t.shape[1], dtype=np.int64)}
    return p, np.hstack((core_t, t)), regions, n_core_axis + 2 * L


def _unit_half_disc(h: float, n_arc: int, n_axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (2, n) and counter-clockwise triangles (3, m) of `half_disc` for R = 1 and h (relative to R), with
    n_arc facets on each quarter arc and n_axis on the axis: the arc's 2 n_arc + 1 nodes first, from (0, 0)
    counter-clockwise to (0, 2), then the axis' inner nodes downwards, then the interior nodes."""
    R = 1.0
    # Boundary: the arc counter-clockwise from (0, 0) to (0, 2R), then the axis downwards.
    angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * n_arc + 1)
    arc = np.vstack((R * np.cos(angle), R + R * np.sin(angle)))
    arc[0, [0, -1]] = 0.0
    arc[:, n_arc] = (R, R)
    axis_y = 2.0 * R * np.arange(n_axis - 1, 0, -1) / n_axis
    axis = np.vstack((np.zeros_like(axis_y), axis_y))

    # A layer of nodes at depth √3/2·h below the arc, between the arc nodes (spacing ≥ 0.8 h
    # when the mesh is so coarse that the inner circle is much shorter than the arc). Nodes
    # nearer than √3/2·h to the axis (at the corners) are moved out to x = √3/2·h, and
    # dropped if that brings them within h/2 of a node that was not moved.
    dx = 0.5 * np.sqrt(3.0) * h
    n_layer = max(0, min(2 * n_arc, int(np.ceil(np.pi * (R - dx) / (0.8 * h)))))
    layer_angle = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * n_layer + 1)[1::2]
    layer = np.vstack(((R - dx) * np.cos(layer_angle), R + (R - dx) * np.sin(layer_angle)))
    clamped = layer[0] < dx
    layer[0, clamped] = dx
    gap = np.linalg.norm(layer[:, clamped, None] - layer[:, None, ~clamped], axis=0).min(axis=1, initial=np.inf)
    layer = np.hstack((layer[:, ~clamped], layer[:, clamped][:, gap >= 0.5 * h]))

    # Interior: hexagonal lattice of spacing h, point (k, i) at k·a + i·b + (0, R) with
    # a = (√3/2·h, h/2), b = (0, h), k ≥ 1 (columns parallel to the axis); points closer
    # than h/2 to the layer's circle are dropped.
    n_col = int(R / dx)
    i_min = int(np.floor(-R / h - 0.5 * n_col)) - 1
    K, I = np.meshgrid(np.arange(1, n_col + 1), np.arange(i_min, int(np.ceil(R / h)) + 2), indexing="ij")
    lattice = np.stack((K * dx, R + (0.5 * K + I) * h))
    radius_of = np.hypot(lattice[0], lattice[1] - R)
    kept = radius_of <= R - dx - 0.5 * h

    p = np.hstack((arc, axis, layer, lattice[:, kept]))
    n_boundary = arc.shape[1] + axis.shape[1]
    index = np.full(kept.shape, -1, dtype=np.int64)
    index[kept] = np.arange(n_boundary + layer.shape[1], p.shape[1])

    # Far from the boundary the Delaunay triangulation is the lattice's own: take its
    # triangles there ("core": all vertices of column ≥ 2, 2h inside the layer's circle) and
    # triangulate only the remaining points. Cell (k, i) of the lattice holds the triangles
    # (k,i),(k+1,i),(k,i+1) and (k+1,i),(k+1,i+1),(k,i+1), both counter-clockwise.
    core_node = kept & (K >= 2) & (radius_of <= R - dx - 2.0 * h)
    lower = core_node[:-1, :-1] & core_node[1:, :-1] & core_node[:-1, 1:]
    upper = core_node[1:, :-1] & core_node[1:, 1:] & core_node[:-1, 1:]
    core_t = np.hstack((
        np.vstack((index[:-1, :-1][lower], index[1:, :-1][lower], index[:-1, 1:][lower])),
        np.vstack((index[1:, :-1][upper], index[1:, 1:][upper], index[:-1, 1:][upper])),
    ))
    inner = np.bincount(core_t.ravel(), minlength=p.shape[1]) == 6
    rest = np.flatnonzero(~inner)
    t = rest[Delaunay(p[:, rest].T).simplices.T]
    # drop the triangles filling the core: their centroid lies in a core lattice cell
    kf = p[0, t].mean(axis=0) / dx
    i_f = (p[1, t].mean(axis=0) - R) / h - 0.5 * kf
    k0, i0 = np.floor(kf).astype(np.int64), np.floor(i_f).astype(np.int64)
    in_upper = (kf - k0) + (i_f - i0) > 1.0
    # cell (k, i) is entry (k, i - i_min + 1) of the padded masks; out of range -> False border
    k0 = np.clip(k0, 0, lower.shape[0] + 1)
    i0 = np.clip(i0 - i_min + 1, 0, lower.shape[1] + 1)
    in_core = np.where(in_upper, np.pad(upper, 1)[k0, i0], np.pad(lower, 1)[k0, i0])
    t = t[:, ~in_core]
    flip = _signed_areas(p, t) < 0
    t[1:, flip] = t[2:0:-1, flip]
    t = np.hstack((core_t, t))
    p = _smooth(p, t, np.arange(p.shape[1]) >= n_boundary, sweeps=6)
    return p, t


def rectangle(width: float, height: float, h: float) -> Mesh:
    """Structured mesh of [0, width] × [0, height] (`skfem.MeshTri.init_tensor`) with
    ceil(width/h) × ceil(height/h) equal cells, each cut into two triangles.

    Parts "left" (x = 0), "right" (x = width), "bottom" (y = 0), "top" (y = height),
    all with exact normals.
    """
    width = _positive("width", width)
    height = _positive("height", height)
    h = _positive("h", h)
    with np.errstate(over="ignore"):
        triangles = 2.0 * np.ceil(width / h) * np.ceil(height / h)
    check_memory(triangles,
                 f"mesh.h = {h:g} on a {width:g} x {height:g} rectangle", "use a larger mesh.h")
    nx, ny = int(np.ceil(width / h)), int(np.ceil(height / h))
    tensor = skfem.MeshTri.init_tensor(np.linspace(0.0, width, nx + 1), np.linspace(0.0, height, ny + 1))
    tol = 1e-9 * min(width / nx, height / ny)

    def classify(mid: np.ndarray) -> dict[str, np.ndarray]:
        return {
            "left": mid[0] < tol,
            "right": mid[0] > width - tol,
            "bottom": mid[1] < tol,
            "top": mid[1] > height - tol,
        }

    normals = {"left": (-1.0, 0.0), "right": (1.0, 0.0), "bottom": (0.0, -1.0), "top": (0.0, 1.0)}
    return _wrap(tensor.p, tensor.t, classify, {name: ConstantNormal(n) for name, n in normals.items()})


def quarter_ball(h: float, radius: float = 1.0, h_bottom: float | None = None, coating: float | None = None) -> Mesh:
    """Tetrahedral mesh of the quarter ball {x > 0, y > 0, x² + y² + (z − R)² < R²} (center (0, 0, R)).

    Parts: "sym_x" (x = 0), "sym_y" (y = 0), "top" (the sphere above z = R), "bottom" (the
    sphere below it; the two split by facet centroids), all with exact outward normals, "top" and
    "bottom" with their projection onto the sphere (``curved_parts``).
    Requires 0 < h ≤ R and, if given, 0 < h_bottom ≤ h.

    Two octants of the ball, each the image of a structured grid of n³ cells on the cube [0, 1]³
    (n = ceil(1.5 R/h)) under the equiangular cube-to-ball map, each cell cut into 6 tetrahedra
    (`vpcontact.mesh.ball`): 12 n³ tetrahedra, the nodes of the spherical parts on the sphere (to
    rounding), the plane z = R a plane of nodes, and (0, 0, 0), (0, 0, 2R), (R, 0, R), (0, R, R)
    nodes. Measured for R/h in [1, 30]: longest edge ≤ h (0.84 h to 0.99 h for R/h ≥ 3), smallest
    dihedral angle ≥ 29° (the median tetrahedron's smallest 45°), largest ≤ 115°, longest edge over
    the inscribed sphere's diameter ≤ 2 √6 (√6 for a regular tetrahedron).

    With h_bottom < h, the tetrahedra within 10 h_bottom of the bottom point (0, 0, 0) are bisected
    until their longest edge is at most h_bottom, those at a distance d farther out until it is at
    most h_bottom + 0.5 (d − 10 h_bottom) (and h), and after each bisection the new nodes on the
    sphere are moved onto it (`vpcontact.mesh.ball.graded_towards_bottom`): a contact patch of radius a
    up to 10 h_bottom is meshed with h_bottom throughout. Measured for R/h ≥ 4 and h/h_bottom up to
    30: smallest dihedral angle ≥ 20°, largest ≤ 149° (16° and 154° for h = R); about 15k to 30k
    tetrahedra in the fine zone, whatever h_bottom. The mesh is built for R = 1, h/R and
    h_bottom/R, then scaled by R: the same tetrahedra in any unit of length.

    With a `coating` c (0 < c < R) the mesh has the regions "core" (distance to the center < R − c)
    and "coating" (their interface's projection in ``curved_interfaces``), and a conforming interface:
    the nodes are moved along their radii so that the shell
    of nodes nearest the radius R − c (at least one layer of cells on each side) lies on the sphere of
    that radius, and the grading bisects the cells before they are mapped onto the ball, so that the
    nodes it adds on that sphere lie on it too (`vpcontact.mesh.ball.coated_tetrahedra`). Measured for R/h
    in [4, 16] and h ≤ c ≤ R − h: smallest dihedral angle ≥ 24°, largest ≤ 117°, longest edge ≤ 1.08 h;
    graded (R/h in [1, 4], h_bottom = h/5 ≤ c ≤ R/2): smallest ≥ 14°, largest ≤ 160°. A coating thinner
    than the elements is one layer of flat tetrahedra; one that folds them (thinner than about h²/(8R),
    the depth of the facets on the sphere) is refused.
    """
    h = _positive("h", h)
    R = _positive("radius", radius)
    if h > R:
        raise CaseError(f"h = {h} must not exceed the radius {R}")
    if h_bottom is not None:
        h_bottom = _positive("h_bottom", h_bottom)
        if h_bottom > h:
            raise CaseError(f"h_bottom = {h_bottom} must not exceed h = {h}: it is the finer size at the bottom")
    if coating is not None:
        coating = _coating(coating, R) / R
    radius, h, h_bottom = R, h / R, None if h_bottom is None else h_bottom / R  # built for R = 1, then scaled
    check_memory(ball.estimated_tetrahedra(h, h_bottom), f"mesh.h = {h * radius:g}"
                 + ("" if h_bottom is None else f" and mesh.h_bottom = {h_bottom * radius:g}")
                 + f" on a quarter ball of radius {radius:g}", "use a larger mesh.h", dim=3)
    n = int(np.ceil(ball.CELLS_PER_RADIUS / h))
    regions = {}
    if coating is None:
        p, t = ball.structured_tetrahedra(n)
        if h_bottom is not None and h_bottom < h:
            p, t = ball.graded_towards_bottom(p, t, h, h_bottom)
    else:
        p, t, side = ball.coated_tetrahedra(n, coating, h, h_bottom)
        if not np.all(ball.signed_volumes(p, t) > 0.0):
            raise _too_thin(coating * radius, h * radius, radius, "sphere")
    if not np.all(ball.signed_volumes(p, t) > 0.0):
        raise RuntimeError("quarter_ball: a tetrahedron is flat or inverted")
    if coating is not None:
        inside, outside = (side[t] < 0).any(axis=0), (side[t] > 0).any(axis=0)
        if np.any(inside == outside):
            raise RuntimeError("quarter_ball: a tetrahedron is on both sides of the coating's interface, or on it")
        regions = {"core": np.flatnonzero(inside), "coating": np.flatnonzero(outside)}
    p = radius * p
    h, R = h * radius, radius
    center = np.array([0.0, 0.0, R])
    radial = RadialNormal(center)

    def classify(centroid: np.ndarray) -> dict[str, np.ndarray]:
        on_x, on_y = centroid[0] < 1e-9 * h, centroid[1] < 1e-9 * h
        sphere = ~on_x & ~on_y
        return {"sym_x": on_x, "sym_y": on_y, "top": sphere & (centroid[2] >= R), "bottom": sphere & (centroid[2] < R)}

    normals = {"sym_x": ConstantNormal((-1.0, 0.0, 0.0)), "sym_y": ConstantNormal((0.0, -1.0, 0.0)), "top": radial,
               "bottom": radial}
    sphere = onto_sphere(center, R)
    interfaces = {} if coating is None else {("core", "coating"): onto_sphere(center, R * (1.0 - coating))}
    return _wrap(p, t, classify, normals, regions, {"top": sphere, "bottom": sphere}, interfaces)


def block(width: float, depth: float, height: float, h: float) -> Mesh:
    """Structured tetrahedral mesh of [0, width] × [0, depth] × [0, height] (`skfem.MeshTet.init_tensor`)
    with ceil(width/h) × ceil(depth/h) × ceil(height/h) equal cells, each cut into six tetrahedra
    around its diagonal from (0, 0, 0) to (1, 1, 1).

    Parts "left" (x = 0), "right" (x = width), "front" (y = 0), "back" (y = depth), "bottom" (z = 0),
    "top" (z = height), all with exact normals.
    """
    width, depth, height = _positive("width", width), _positive("depth", depth), _positive("height", height)
    h = _positive("h", h)
    sizes = (width, depth, height)
    with np.errstate(over="ignore"):
        counts = np.ceil(np.array(sizes) / h)
        tetrahedra = 6.0 * counts.prod()
    check_memory(tetrahedra, f"mesh.h = {h:g} on a {width:g} x {depth:g} x {height:g} block",
                 "use a larger mesh.h", dim=3)
    cells = counts.astype(np.int64)
    tensor = skfem.MeshTet.init_tensor(*(np.linspace(0.0, size, n + 1) for size, n in zip(sizes, cells)))
    tol = 1e-9 * min(size / n for size, n in zip(sizes, cells))

    def classify(centroid: np.ndarray) -> dict[str, np.ndarray]:
        x, y, z = centroid
        return {"left": x < tol, "right": x > width - tol, "front": y < tol, "back": y > depth - tol,
                "bottom": z < tol, "top": z > height - tol}

    normals = {"left": (-1.0, 0.0, 0.0), "right": (1.0, 0.0, 0.0), "front": (0.0, -1.0, 0.0),
               "back": (0.0, 1.0, 0.0), "bottom": (0.0, 0.0, -1.0), "top": (0.0, 0.0, 1.0)}
    return _wrap(tensor.p, tensor.t, classify, {name: ConstantNormal(n) for name, n in normals.items()})


def read_mesh(path: str | os.PathLike) -> Mesh:
    """Read a triangle (2D) or tetrahedral (3D) mesh with meshio (gmsh .msh 2.2 / 4.1, or any format
    meshio reads).

    The dimension comes from the cells: a file with "tetra" cells is 3D, its body the tetrahedra and
    its parts the "triangle" cells of physical surfaces; a file without cells of dimension 3 is 2D, its
    body the "triangle" cells and its parts the "line" cells of physical curves (its z coordinates
    must be zero and are dropped). Lines and vertices (and in 3D triangles of no physical group) may
    be there too; other cells are refused: quadrilaterals and hexahedra, prisms and pyramids,
    second-order cells. So are meshes that do not cover a body once (`vpcontact.mesh.checks_2d`,
    `vpcontact.mesh.checks_3d`: non-finite coordinates, zero areas or volumes, duplicate nodes,
    folds, overlaps, hinges). Nodes that no triangle (2D) or tetrahedron (3D) uses are dropped and the
    rest renumbered in their file order. Every facet cell of a physical group (tag > 0) joins the part
    named by the tag number (str) and, if the file names that physical group, by its name too (a facet
    may be in several named groups); each such facet must be a boundary facet of the mesh. Two physical
    groups of the parts' dimension with one name are refused. Facet cells without a physical tag (or
    tag 0, gmsh's "none") are ignored. The physical groups of the body's dimension (physical surfaces in
    2D, volumes in 3D) are the regions, keyed like the parts (tag number and name; two such groups with
    one name are refused); an element in several of them is one element of each (`_body_elements`),
    elements of none are in no region, and a file without them has no regions. No exact normals. The
    orientation of the cells in the file is not used. Any problem raises CaseError naming the file.
    """
    if not isinstance(path, (str, os.PathLike)) or not isinstance(os.fspath(path), str):
        raise CaseError(f"mesh file = {shown(repr(path))}: expected a file's name (a string or a path)")
    label = os.fspath(path)
    check_regular_file(path, "mesh file")
    data = msh22.read(path)  # a plain gmsh 2.2 text file, read with NumPy
    if data is None:
        data = _read_with_meshio(path, label)

    names = _physical_names(label) or [(int(v[1]), int(v[0]), k) for k, v in data.field_data.items() if np.size(v) == 2]
    dim = 3 if any(block.dim == 3 for block in data.cells) else 2
    _check_cell_types(label, data.cells, dim)
    _check_unique_names(label, names, dim, body=False)
    _check_unique_names(label, names, dim, body=True)
    facet = CELLS[dim][1]
    t, position, members = _body_elements(data, names, dim)
    if not t.size:
        raise CaseError(_no_triangles(label, data, names))
    check_memory(t.shape[1], f"mesh file '{label}'", "use a coarser mesh", dim=dim)
    outside = (t < 0) | (t >= len(data.points))
    if outside.any():
        k = np.flatnonzero(outside.any(axis=0))[0]
        raise CaseError(f"mesh file '{label}': {ELEMENT_NAMES[dim][0]} {position[k]} refers to node "
                        f"{t[outside[:, k], k][0] + 1}, but the file has nodes 1 to {len(data.points)}: the file is "
                        f"damaged")
    used, t = np.unique(t, return_inverse=True)
    t = t.reshape(dim + 1, -1)
    renumber = np.full(len(data.points), -1, dtype=np.int64)
    renumber[used] = np.arange(used.size)

    points = np.asarray(data.points, dtype=float)[used].T
    check_finite(label, points, used + 1)
    if dim == 2:
        points = _plane(label, data, names, points)
        check_triangles(label, points, t, used + 1, position)
    else:
        check_tetrahedra(label, points, t, used + 1, position)

    mesh = SKFEM_MESH[dim](np.ascontiguousarray(points), np.ascontiguousarray(t))
    facet_nodes, facet_tags = _physical_facets(data, names, facet, dim - 1)
    parts: dict[str, np.ndarray] = {}
    if facet_tags.size:
        known = (facet_nodes >= 0) & (facet_nodes < renumber.size)  # a damaged file may name other nodes
        nodes = np.where(known, renumber[np.where(known, facet_nodes, 0)], -1)
        boundary = mesh.boundary_facets().astype(np.int64)
        found = find_columns(mesh.facets[:, boundary], nodes)
        bad = np.flatnonzero((nodes < 0).any(axis=0) | (found < 0))
        if bad.size:
            what, kind = {2: ("line", "edge"), 3: ("triangle", "face")}[dim]
            facet_group, body_group = PHYSICAL_GROUPS[dim]
            raise CaseError(f"mesh file '{label}': {what} of physical group {facet_tags[bad[0]]} is not a boundary "
                            f"{kind} of the {ELEMENT_NAMES[dim][1]} ({bad.size} such {what}s): a part must lie on "
                            f"the boundary of the body; remove inner {facet_group.lower()}s from that physical group, "
                            f"or add the {body_group.lower()} they bound to the Physical {body_group}")
        facets = boundary[found]
        for tag in np.unique(facet_tags):
            parts[str(tag)] = np.unique(facets[facet_tags == tag])
        for group_dim, tag, name in names:
            if group_dim != dim - 1 or str(tag) not in parts:
                continue
            if name in parts and not np.array_equal(parts[name], parts[str(tag)]):
                raise CaseError(
                    f"mesh file '{label}': physical name '{name}' (group {tag}) clashes with physical group {name}"
                )
            parts[name] = parts[str(tag)]
    return Mesh(with_parts(mesh, parts), parts, {}, label, _regions(label, names, dim, members))


def _read_with_meshio(path: str | os.PathLike, label: str) -> meshio.Mesh:
    """meshio's reading of a mesh file; CaseError naming the file if meshio cannot read it."""
    import meshio  # only for the files msh22 does not read

    # meshio prints its per-format failures and then calls sys.exit(1) when no reader
    # accepts the file; other problems surface as assorted exceptions.
    with contextlib.redirect_stdout(io.StringIO()) as said, contextlib.redirect_stderr(said):
        try:
            return meshio.read(path)
        except (Exception, SystemExit) as exc:
            failure = exc
    reason = str(failure) if isinstance(failure, Exception) else said.getvalue()
    reason = " ".join(reason.replace("Error:", "").split()) or type(failure).__name__
    raise CaseError(f"cannot read mesh file '{label}': {reason}") from failure


def _regions(label: str, names: list[tuple[int, int, str]], dim: int, members: np.ndarray) -> dict[str, np.ndarray]:
    """Region name -> sorted element indices, from the distinct (element, physical tag) pairs `members` (2, k),
    sorted by element: one region per tag (named by its number) and, if the file names the group, by its
    name too."""
    regions = {str(tag): members[0, members[1] == tag] for tag in _distinct(members[1])}
    for group_dim, tag, name in names:
        if group_dim != dim or str(tag) not in regions:
            continue
        if name in regions and not np.array_equal(regions[name], regions[str(tag)]):
            raise CaseError(f"mesh file '{label}': physical name '{name}' (group {tag}) clashes with physical group "
                            f"{name}")
        regions[name] = regions[str(tag)]
    return regions


#: The meshio cell types of each dimension: (the body's, the parts').
CELLS = {2: ("triangle", "line"), 3: ("tetra", "triangle")}
#: How messages name the body's cells: (one, several).
ELEMENT_NAMES = {2: ("triangle", "triangles"), 3: ("tetrahedron", "tetrahedra")}


def find_columns(table: np.ndarray, query: np.ndarray) -> np.ndarray:
    """For each column of `query` (k, q), the index of the column of `table` (k, r) with the same
    numbers in any order, or -1 (the columns of `table` are distinct sets)."""
    both = np.sort(np.hstack((table, query)), axis=0)
    _, group = np.unique(both, axis=1, return_inverse=True)
    group = group.ravel()
    column = np.full(group.max() + 1 if group.size else 0, -1, dtype=np.int64)
    column[group[:table.shape[1]]] = np.arange(table.shape[1])
    return column[group[table.shape[1]:]]


def _plane(label: str, data: meshio.Mesh, names: list[tuple[int, int, str]], points: np.ndarray) -> np.ndarray:
    """The x, y rows of the nodes `points` of a 2D mesh; CaseError if a z coordinate is not zero."""
    if points.shape[0] == 3:
        scale = max(float(np.abs(points[:2]).max()), 1.0)
        if np.abs(points[2]).max() > 1e-12 * scale:
            surfaces = any(dim == 2 for dim, _, _ in names) or any(
                tags is not None and np.any(np.asarray(tags) > 0)
                for block, tags in zip(data.cells, data.cell_data.get("gmsh:physical", [None] * len(data.cells)))
                if block.type == "triangle")
            if surfaces:
                raise CaseError(f"mesh file '{label}' is not a 2D mesh (nonzero z coordinates) and has no tetrahedra, "
                                f"only triangles of physical surfaces: when a model has physical groups, gmsh saves "
                                f"only their elements; add a Physical Volume for the body (e.g. Physical "
                                f"Volume(\"body\") = {{1}};) and mesh again")
            raise CaseError(f"mesh file '{label}' is not a 2D mesh (nonzero z coordinates) and has no tetrahedra: "
                            f"mesh the volume in 3D (gmsh -3), or put a plane body's nodes in the plane z = 0")
        points = points[:2]
    return points


def _check_cell_types(label: str, cells: list, dim: int) -> None:
    """Refuse cells other than the linear cells of a `dim`-dimensional mesh (triangles or tetrahedra, and
    cells of lower dimension), with the gmsh setting to change."""
    counts: dict[str, int] = {}
    for block in cells:
        counts[block.type] = counts.get(block.type, 0) + len(block.data)
    allowed = ("vertex", "line", "triangle", "tetra")[:dim + 1]
    others = {kind: count for kind, count in counts.items() if kind not in allowed}
    if not others:
        return
    listed = ", ".join(f"{count} {kind}" for kind, count in others.items())
    element, elements = ELEMENT_NAMES[dim]
    solids = {kind: count for kind, count in others.items() if kind.startswith(("hexahedron", "wedge", "pyramid"))}
    if solids:
        raise CaseError(f"mesh file '{label}' has {', '.join(f'{c} {k}' for k, c in solids.items())} cells and "
                        f"{counts.get('tetra', 0)} tetrahedra: vpcontact uses linear tetrahedra only; mesh without "
                        f"recombination: Mesh.RecombineAll = 0, Mesh.Recombine3DAll = 0, no Recombine Surface or "
                        f"Volume and no Recombine in Extrude")
    quadrilaterals = sum(count for kind, count in others.items() if kind.startswith("quad"))
    if quadrilaterals:
        raise CaseError(f"mesh file '{label}' has {quadrilaterals} quadrilaterals and "
                        f"{counts.get(CELLS[dim][0], 0)} {elements}: vpcontact uses linear {elements} only; mesh "
                        f"without recombination: Mesh.RecombineAll = 0 and no Recombine Surface")
    if any(kind.startswith(("tetra", "triangle", "line")) for kind in others):
        raise CaseError(f"mesh file '{label}' has second-order or higher-order elements ({listed}): use first-order "
                        f"elements: Mesh.ElementOrder = 1 (gmsh -order 1)")
    raise CaseError(f"mesh file '{label}' has cells that are not linear {elements} ({listed}): vpcontact uses linear "
                    f"{elements} only")


def _no_triangles(label: str, data: meshio.Mesh, names: list[tuple[int, int, str]]) -> str:
    """Why a mesh file has no triangles, and the fix."""
    curves = any(dim == 1 for dim, _, _ in names) or any(
        tags is not None and np.any(np.asarray(tags) > 0)
        for block, tags in zip(data.cells, data.cell_data.get("gmsh:physical", [None] * len(data.cells)))
        if block.type == "line")
    if curves:
        return (f"mesh file '{label}' has no triangles, only lines of physical curves: when a model has physical "
                f"groups, gmsh saves only their elements; add a Physical Surface for the body (e.g. "
                f"Physical Surface(\"body\") = {{1}};) and mesh again")
    return f"mesh file '{label}' has no triangles: mesh the surface in 2D (gmsh -2) and save it"


#: A line of the $PhysicalNames section of a gmsh file: dimension, tag, "name".
_PHYSICAL_NAME = re.compile(rb'\s*(\d+)\s+(\d+)\s+"(.*)"\s*')


def _physical_names(path: str) -> list[tuple[int, int, str]]:
    """(dimension, tag, name) of every physical group a gmsh file names (none for other files).

    The $PhysicalNames section is text, also in binary files, and comes before the nodes: only the
    head of the file is read."""
    found = []
    with open(path, "rb") as handle:
        if handle.readline(64).strip() != b"$MeshFormat":
            return found
        section = b"$MeshFormat"
        for line in iter(lambda: handle.readline(4096), b""):
            line = line.strip()
            if line.startswith(b"$"):
                if line.startswith(b"$End"):
                    continue
                if line != b"$PhysicalNames":
                    break
                section = line
                handle.readline(64)  # the number of names
            elif section == b"$PhysicalNames" and (match := _PHYSICAL_NAME.fullmatch(line)):
                found.append((int(match[1]), int(match[2]), match[3].decode("utf-8", "replace")))
    return found


def _check_unique_names(label: str, names: list[tuple[int, int, str]], dim: int, body: bool) -> None:
    """CaseError if two physical groups of the parts' dimension (`body` False) or of the body's (`body` True)
    of a `dim`-dimensional mesh have one name (meshio would keep only one of them)."""
    group = PHYSICAL_GROUPS[dim][body]
    what = "region" if body else "part"
    tags: dict[str, int] = {}
    for group_dim, tag, name in names:
        if group_dim == dim - 1 + body and tags.setdefault(name, tag) != tag:
            raise CaseError(f"mesh file '{label}': two physical {group.lower()}s are named '{name}' (groups "
                            f"{tags[name]} and {tag}); a {what} of that name would hold only one of them: give each "
                            f"group its own name, or put all its {group.lower()}s in one Physical {group}(\"{name}\") "
                            f"= {{...}};")


def _body_elements(data: meshio.Mesh, names: list[tuple[int, int, str]],
                   dim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nodes (d + 1, m) (file numbering) of the body's elements (triangles in 2D, tetrahedra in 3D) in file
    order, their positions (m,) among the file's cells of their kind (from 1, for messages), and their physical
    groups: (element, tag) pairs (2, k), tags > 0.

    An element in several physical groups is one element of each: a gmsh 2.2 file writes it once per group
    (as cells with the same nodes and different tags, merged here into the first of them); a 4.1 file once,
    meshio's cell_data keeping its entity's first group and its cell_sets each named group's cells. Cells
    with the same nodes that are not all in distinct physical groups (a cell written twice in one group, or
    without a group) are all kept: the mesh checks refuse them as a region covered twice."""
    kind = CELLS[dim][0]
    physical = data.cell_data.get("gmsh:physical", [None] * len(data.cells))
    offset = np.cumsum([0] + [len(block.data) if block.type == kind else 0 for block in data.cells])
    cells = [block.data.T for block in data.cells if block.type == kind]
    if not cells:
        return np.zeros((dim + 1, 0), dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros((2, 0), dtype=np.int64)
    t = np.hstack(cells).astype(np.int64)
    tags = np.concatenate([np.zeros(len(block.data), dtype=np.int64) if block_tags is None
                           else np.maximum(np.asarray(block_tags, dtype=np.int64), 0)  # 0: no group
                           for block, block_tags in zip(data.cells, physical) if block.type == kind])
    occurrences, groups = [np.arange(tags.size)[tags > 0]], [tags[tags > 0]]
    for group_dim, tag, name in names:
        for b, members in enumerate(data.cell_sets.get(name, []) if group_dim == dim else []):
            if data.cells[b].type == kind and members is not None and len(members):
                occurrences.append(offset[b] + np.asarray(members, dtype=np.int64))
                groups.append(np.full(len(members), tag, dtype=np.int64))

    # cells with the same nodes (`same`: one number for each set of nodes), merged when all of them have
    # distinct tags > 0 (the first kept); one sort, and 1D keys (set · (largest tag + 1) + tag) for pairs
    nodes = np.sort(t, axis=0)
    order = np.lexsort(nodes[::-1])
    starts = np.concatenate(([True], (nodes[:, order[1:]] != nodes[:, order[:-1]]).any(axis=0)))
    same = np.empty(tags.size, dtype=np.int64)
    same[order] = np.cumsum(starts) - 1
    start = np.flatnonzero(starts)
    count = np.diff(np.append(start, tags.size))
    scale = int(tags.max(initial=0)) + 1
    distinct = np.bincount(_distinct(same * scale + tags) // scale, minlength=count.size)
    merged = (count > 1) & (distinct == count) & (np.minimum.reduceat(tags[order], start) > 0)
    first = order[start]  # the first cell of each set: the sort is stable
    keep = ~merged[same] | (np.arange(tags.size) == first[same])
    new_index = np.cumsum(keep) - 1
    element = np.where(merged[same], new_index[first[same]], new_index)
    groups = np.concatenate(groups)
    scale = int(groups.max(initial=0)) + 1
    pairs = _distinct(element[np.concatenate(occurrences)] * scale + groups)
    return t[:, keep], np.flatnonzero(keep) + 1, np.vstack((pairs // scale, pairs % scale))


def _distinct(keys: np.ndarray) -> np.ndarray:
    """The distinct integers of `keys`, sorted (np.unique, without its slower hashing of large arrays)."""
    keys = np.sort(keys)
    new = np.ones(keys.size, dtype=bool)
    new[1:] = keys[1:] != keys[:-1]
    return keys[new]


def _physical_facets(data: meshio.Mesh, names: list[tuple[int, int, str]], kind: str,
                     part_dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (d, k) (file numbering) and physical tags (k,) of the `kind` cells ("line" or "triangle")
    of physical groups of dimension `part_dim`; a cell in several groups appears once for each.

    In a gmsh 2.2 file a cell is written once per group; in a 4.1 file once, with its entity's groups
    listed in the file's entities, of which meshio's cell_data keeps only the first while its
    cell_sets list each named group's cells."""
    physical = data.cell_data.get("gmsh:physical", [None] * len(data.cells))
    nodes = [np.zeros((part_dim + 1, 0), dtype=np.int64)]
    tags = [np.zeros(0, dtype=np.int64)]
    for block, block_tags in zip(data.cells, physical):
        if block.type == kind and block_tags is not None:
            block_tags = np.asarray(block_tags, dtype=np.int64)
            nodes.append(block.data[block_tags > 0].T)
            tags.append(block_tags[block_tags > 0])
    for dim, tag, name in names:
        if dim != part_dim:
            continue
        for block, members in zip(data.cells, data.cell_sets.get(name, [])):
            if block.type == kind and members is not None and len(members):
                nodes.append(block.data[np.asarray(members, dtype=np.int64)].T)
                tags.append(np.full(len(members), tag, dtype=np.int64))
    return np.hstack(nodes).astype(np.int64), np.concatenate(tags)
