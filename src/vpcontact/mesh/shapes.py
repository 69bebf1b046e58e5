"""The built-in shapes: the half disc and the rectangle (triangles), the quarter ball and the block (tetrahedra).

Each is a `Mesh` with named parts and the exact outward normals of its parts; the curved ones (the half
disc's arcs, the quarter ball's sphere) with their projections onto the exact circle or sphere, where
refinement moves its new nodes (``Mesh.curved_parts``). The half disc and the quarter ball may have a
coating: the regions "core" and "coating" and a conforming interface between them. Their nodes and
elements are made by `vpcontact.mesh.disc` and `vpcontact.mesh.ball`; a mesh too large for the memory
available is refused before it is made (`vpcontact.mesh.mesh.check_memory`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import skfem

from ..errors import CaseError, shown
from . import ball, disc
from .checks_arrays import SKFEM_MESH
from .facets import with_facet_tables
from .mesh import ConstantNormal, Mesh, NormalField, Projection, RadialNormal, check_memory, onto_sphere, with_parts
from .simplex import determinants


def _positive(name: str, value: float) -> float:
    """`value` as a float, or CaseError unless it is a number (a NumPy one too; not a string or a bool), finite
    and > 0."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise CaseError(f"{name} = {shown(repr(value))}: expected a number > 0")
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise CaseError(f"{name} must be a positive number, got {value}")
    return value


def _wrap(p: np.ndarray, t: np.ndarray, classify: Callable[[np.ndarray], dict[str, np.ndarray]],
          exact_normals: dict[str, NormalField], regions: dict[str, np.ndarray] | None = None,
          curved_parts: dict[str, Projection] | None = None,
          curved_interfaces: dict[tuple[str, str], Projection] | None = None) -> Mesh:
    """Build a `Mesh` from nodes `p` (d, n) and triangles or tetrahedra `t` (d + 1, m) (and its `regions`,
    its curved parts and interfaces).

    `classify(centroids (d, k))` returns part name -> boolean mask over the k boundary
    facets; the masks must partition the boundary (checked).
    """
    mesh = with_facet_tables(SKFEM_MESH[p.shape[0]](np.ascontiguousarray(p), np.ascontiguousarray(t)))
    boundary = mesh.boundary_facets().astype(np.int64)
    masks = classify(mesh.p[:, mesh.facets[:, boundary]].mean(axis=1))
    if not np.array_equal(np.sum(list(masks.values()), axis=0), np.ones(boundary.size)):
        raise RuntimeError("boundary facets do not split exactly into the parts")
    parts = {name: boundary[mask] for name, mask in masks.items()}
    return Mesh(with_parts(mesh, parts), parts, exact_normals, regions=regions or {},
                curved_parts=curved_parts or {}, curved_interfaces=curved_interfaces or {})


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
    the half circle of radius R − c is a line of nodes (`vpcontact.mesh.disc.coated_half_disc`); the parts
    and their facets on the arcs are the same. Measured for R/h in [5, 50] and h ≤ c ≤ R − h: smallest
    angle ≥ 25°, longest edge ≤ 1.41 h; a coating thinner than h is one layer of flat triangles (their
    height c against their length h); one not thicker than the depth of the arc's facets,
    R (1 − cos(π/(4 n))) ≈ h²/(8R), is refused.
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
        p, t = disc.unit_half_disc(h / R, n_arc, n_axis)  # built for R = 1, then scaled: the same triangles in any unit
        p, regions = R * p, {}
    else:
        if not coating > R * (1.0 - math.cos(0.25 * np.pi / n_arc)):  # the interface would cross the arc's facets
            raise _too_thin(coating, h, R, "circle")
        p, t, regions, n_axis = disc.coated_half_disc(h / R, coating / R, n_arc)  # built for R = 1 too
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
        if not np.all(determinants(p, t) > 0.0):
            raise _too_thin(coating * radius, h * radius, radius, "sphere")
    if not np.all(determinants(p, t) > 0.0):
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
