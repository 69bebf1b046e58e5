"""A mesh file read into a `Mesh`: a gmsh file (.msh 2.2 / 4.1) or any triangle or tetrahedron file meshio reads.

A gmsh 2.2 text file is read with NumPy (`vpcontact.mesh.gmsh.read_msh22`), any other file with meshio,
imported then. The file's cells are checked (linear triangles or tetrahedra only, a plane 2D body), its
physical groups become the parts and regions (`vpcontact.mesh.physical_groups`), and the mesh must cover a
body once (`vpcontact.mesh.checks`).
"""

from __future__ import annotations

import contextlib
import io
import os
from typing import TYPE_CHECKING

import numpy as np

from ..inputs import check_regular_file
from ..errors import CaseError, shown
from . import gmsh, physical_groups
from .cells import SIMPLICES
from .checks import check_finite
from .checks_2d import check_triangles
from .checks_3d import check_tetrahedra
from .checks_arrays import SKFEM_MESH
from .mesh import Mesh, check_memory, with_parts

if TYPE_CHECKING:
    import meshio


def read_mesh(path: str | os.PathLike) -> Mesh:
    """Read a triangle (2D) or tetrahedral (3D) mesh with meshio (gmsh .msh 2.2 / 4.1, or any format
    meshio reads).

    The dimension comes from the cells: a file with "tetra" cells is 3D, its body the tetrahedra and
    its parts the "triangle" cells of physical surfaces; a file without cells of dimension 3 is 2D, its
    body the "triangle" cells and its parts the "line" cells of physical curves (its z coordinates
    must be zero and are dropped). Lines and vertices (and in 3D triangles of no physical group) may
    be there too; other cells are refused: quadrilaterals and hexahedra, prisms and pyramids,
    second-order cells. So are meshes that do not cover a body once (`vpcontact.mesh.checks`:
    non-finite coordinates, zero areas or volumes, duplicate nodes, folds, overlaps, hinges). Nodes that
    no triangle (2D) or tetrahedron (3D) uses are dropped and the rest renumbered in their file order. Every facet cell of a physical group (tag > 0) joins the part
    named by the tag number (str) and, if the file names that physical group, by its name too (a facet
    may be in several named groups); each such facet must be a boundary facet of the mesh. Two physical
    groups of the parts' dimension with one name are refused. Facet cells without a physical tag (or
    tag 0, gmsh's "none") are ignored. The physical groups of the body's dimension (physical surfaces in
    2D, volumes in 3D) are the regions, keyed like the parts (tag number and name; two such groups with
    one name are refused); an element in several of them is one element of each
    (`vpcontact.mesh.physical_groups.body_elements`), elements of none are in no region, and a file without
    them has no regions. No exact normals. The orientation of the cells in the file is not used. Any problem
    raises CaseError naming the file.
    """
    if not isinstance(path, (str, os.PathLike)) or not isinstance(os.fspath(path), str):
        raise CaseError(f"mesh file = {shown(repr(path))}: expected a file's name (a string or a path)")
    label = os.fspath(path)
    check_regular_file(path, "mesh file")
    data = gmsh.read_msh22(path)  # a plain gmsh 2.2 text file, read with NumPy
    if data is None:
        data = _read_with_meshio(path, label)

    names = gmsh.physical_names(label) or [(int(v[1]), int(v[0]), k) for k, v in data.field_data.items()
                                           if np.size(v) == 2]
    dim = 3 if any(block.dim == 3 for block in data.cells) else 2
    _check_cell_types(label, data.cells, dim)
    physical_groups.check_unique_names(label, names, dim)
    t, position, members = physical_groups.body_elements(data, names, dim)
    if not t.size:
        raise CaseError(_no_triangles(label, data, names))
    check_memory(t.shape[1], f"mesh file '{label}'", "use a coarser mesh", dim=dim)
    outside = (t < 0) | (t >= len(data.points))
    if outside.any():
        k = np.flatnonzero(outside.any(axis=0))[0]
        raise CaseError(f"mesh file '{label}': {SIMPLICES[dim].name} {position[k]} refers to node "
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
    parts = physical_groups.parts(label, mesh, data, names, renumber, dim)
    return Mesh(with_parts(mesh, parts), parts, {}, label, physical_groups.regions(label, names, dim, members))


def _read_with_meshio(path: str | os.PathLike, label: str) -> meshio.Mesh:
    """meshio's reading of a mesh file; CaseError naming the file if meshio cannot read it."""
    import meshio  # only for the files read_msh22 does not read

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
    allowed = [simplex.cell_type for simplex in SIMPLICES[:dim + 1]]
    others = {kind: count for kind, count in counts.items() if kind not in allowed}
    if not others:
        return
    listed = ", ".join(f"{count} {kind}" for kind, count in others.items())
    elements = SIMPLICES[dim].plural
    solids = {kind: count for kind, count in others.items() if kind.startswith(("hexahedron", "wedge", "pyramid"))}
    if solids:
        raise CaseError(f"mesh file '{label}' has {', '.join(f'{c} {k}' for k, c in solids.items())} cells and "
                        f"{counts.get('tetra', 0)} tetrahedra: vpcontact uses linear tetrahedra only; mesh without "
                        f"recombination: Mesh.RecombineAll = 0, Mesh.Recombine3DAll = 0, no Recombine Surface or "
                        f"Volume and no Recombine in Extrude")
    quadrilaterals = sum(count for kind, count in others.items() if kind.startswith("quad"))
    if quadrilaterals:
        raise CaseError(f"mesh file '{label}' has {quadrilaterals} quadrilaterals and "
                        f"{counts.get(SIMPLICES[dim].cell_type, 0)} {elements}: vpcontact uses linear {elements} "
                        f"only; mesh without recombination: Mesh.RecombineAll = 0 and no Recombine Surface")
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
