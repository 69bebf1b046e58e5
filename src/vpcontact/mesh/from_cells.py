"""Cells and physical groups, in meshio's form, made a checked `Mesh`: the one way from a mesh file
(`vpcontact.mesh.read`), a meshio.Mesh, a scikit-fem mesh (`vpcontact.mesh.memory`) or the open gmsh model
(`vpcontact.mesh.gmsh_model`) to a body with parts and regions.

`mesh_from_cells` takes what meshio gives for a gmsh file: the points, the cell blocks, the physical tag of
each cell (``cell_data["gmsh:physical"]``) and the named groups (``cell_sets``), with the (dimension, tag,
name) of every named physical group. It checks the cells (linear triangles or tetrahedra only, a plane 2D
body), makes the physical groups the parts and regions (`vpcontact.mesh.physical_groups`), and refuses a
mesh that does not cover a body once (`vpcontact.mesh.checks`): each problem in one CaseError that names the
mesh by its `label` ("mesh file 'punch.msh'", "the gmsh model 'punch'", "the meshio.Mesh", …).
"""

from __future__ import annotations

import numpy as np

from ..errors import CaseError
from . import physical_groups
from .cells import SIMPLICES
from .checks import check_finite
from .checks_2d import check_triangles
from .checks_3d import check_tetrahedra
from .checks_arrays import SKFEM_MESH
from .facets import with_facet_tables
from .mesh import Mesh, check_memory, with_parts


def mesh_from_cells(label: str, data, names: list[tuple[int, int, str]], file: str | None = None,
                    internal: frozenset[int] = frozenset(), first: int = 1) -> Mesh:
    """The checked `Mesh` of the cells `data` (a meshio.Mesh, or anything with its ``points``, ``cells``,
    ``cell_data`` and ``cell_sets``) and the named physical groups `names` ((dimension, tag, name) each); see
    `vpcontact.mesh.read.read_mesh` for what is accepted and what becomes of the groups. Groups of an
    `internal` tag are keyed by their name only; nodes and elements are numbered from `first` in messages (1:
    a file's numbering, 0: Python's indices); `file` is the Mesh's file."""
    dim = 3 if any(block.dim == 3 for block in data.cells) else 2
    _check_cell_types(label, data.cells, dim)
    physical_groups.check_unique_names(label, names, dim)
    t, position, members = physical_groups.body_elements(data, names, dim)
    if not t.size:
        raise CaseError(_no_elements(label, data, names))
    check_memory(t.shape[1], label, "use a coarser mesh", dim=dim)
    position = position - 1 + first
    outside = (t < 0) | (t >= len(data.points))
    if outside.any():
        k = np.flatnonzero(outside.any(axis=0))[0]
        holder = "the mesh" if file is None else "the file"
        raise CaseError(f"{label}: {SIMPLICES[dim].name} {position[k]} refers to node "
                        f"{t[outside[:, k], k][0] + first}, but {holder} has nodes {first} to "
                        f"{len(data.points) - 1 + first}: {holder} is damaged")
    used, t = np.unique(t, return_inverse=True)
    t = t.reshape(dim + 1, -1)
    renumber = np.full(len(data.points), -1, dtype=np.int64)
    renumber[used] = np.arange(used.size)

    points = np.asarray(data.points, dtype=float)[used].T
    check_finite(label, points, used + first)
    if dim == 2:
        points = _plane(label, data, names, points)
        check_triangles(label, points, t, used + first, position)
    else:
        check_tetrahedra(label, points, t, used + first, position)

    mesh = with_facet_tables(SKFEM_MESH[dim](np.ascontiguousarray(points), np.ascontiguousarray(t)))
    parts = physical_groups.parts(label, mesh, data, names, renumber, dim, internal)
    return Mesh(with_parts(mesh, parts), parts, {}, file, physical_groups.regions(label, names, dim, members, internal))


def _plane(label: str, data, names: list[tuple[int, int, str]], points: np.ndarray) -> np.ndarray:
    """The x, y rows of the nodes `points` of a 2D mesh; CaseError if a z coordinate is not zero."""
    if points.shape[0] == 3:
        scale = max(float(np.abs(points[:2]).max()), 1.0)
        if np.abs(points[2]).max() > 1e-12 * scale:
            surfaces = any(dim == 2 for dim, _, _ in names) or any(
                tags is not None and np.any(np.asarray(tags) > 0)
                for block, tags in zip(data.cells, data.cell_data.get("gmsh:physical", [None] * len(data.cells)))
                if block.type == "triangle")
            if surfaces:
                raise CaseError(f"{label} is not a 2D mesh (nonzero z coordinates) and has no tetrahedra, "
                                f"only triangles of physical surfaces: when a model has physical groups, gmsh saves "
                                f"only their elements; add a Physical Volume for the body (e.g. Physical "
                                f"Volume(\"body\") = {{1}};) and mesh again")
            raise CaseError(f"{label} is not a 2D mesh (nonzero z coordinates) and has no tetrahedra: "
                            f"mesh the volume in 3D (gmsh -3), or put a plane body's nodes in the plane z = 0")
        points = points[:2]
    return points


def _check_cell_types(label: str, cells: list, dim: int) -> None:
    """Refuse cells other than the linear cells of a `dim`-dimensional mesh (triangles or tetrahedra, and
    cells of lower dimension), with the gmsh setting to change."""
    counts: dict[str, int] = {}
    for block in cells:
        counts[block.type] = counts.get(block.type, 0) + len(block.data)
    allowed = [simplex.cell_type for simplex in SIMPLICES[:dim + 1]]
    others = {kind: count for kind, count in counts.items() if kind not in allowed}
    if not others:
        return
    listed = ", ".join(f"{count} {kind}" for kind, count in others.items())
    elements = SIMPLICES[dim].plural
    solids = {kind: count for kind, count in others.items() if kind.startswith(("hexahedron", "wedge", "pyramid"))}
    if solids:
        raise CaseError(f"{label} has {', '.join(f'{c} {k}' for k, c in solids.items())} cells and "
                        f"{counts.get('tetra', 0)} tetrahedra: vpcontact uses linear tetrahedra only; mesh without "
                        f"recombination: Mesh.RecombineAll = 0, Mesh.Recombine3DAll = 0, no Recombine Surface or "
                        f"Volume and no Recombine in Extrude")
    quadrilaterals = sum(count for kind, count in others.items() if kind.startswith("quad"))
    if quadrilaterals:
        raise CaseError(f"{label} has {quadrilaterals} quadrilaterals and "
                        f"{counts.get(SIMPLICES[dim].cell_type, 0)} {elements}: vpcontact uses linear {elements} "
                        f"only; mesh without recombination: Mesh.RecombineAll = 0 and no Recombine Surface")
    if any(kind.startswith(("tetra", "triangle", "line")) for kind in others):
        raise CaseError(f"{label} has second-order or higher-order elements ({listed}): use first-order "
                        f"elements: Mesh.ElementOrder = 1 (gmsh -order 1)")
    raise CaseError(f"{label} has cells that are not linear {elements} ({listed}): vpcontact uses linear "
                    f"{elements} only")


def _no_elements(label: str, data, names: list[tuple[int, int, str]]) -> str:
    """Why a mesh has no triangles, and the fix."""
    curves = any(dim == 1 for dim, _, _ in names) or any(
        tags is not None and np.any(np.asarray(tags) > 0)
        for block, tags in zip(data.cells, data.cell_data.get("gmsh:physical", [None] * len(data.cells)))
        if block.type == "line")
    if curves:
        return (f"{label} has no triangles, only lines of physical curves: when a model has physical "
                f"groups, gmsh saves only their elements; add a Physical Surface for the body (e.g. "
                f"Physical Surface(\"body\") = {{1}};) and mesh again")
    return f"{label} has no triangles: mesh the surface in 2D (gmsh -2) and save it"
