"""A mesh file read into a `Mesh`: a gmsh file (.msh 2.2 / 4.1) or any triangle or tetrahedron file meshio reads.

A gmsh 2.2 text file is read with NumPy (`vpcontact.mesh.gmsh.read_msh22`), any other file with meshio,
imported then. What the file holds becomes a checked Mesh as a mesh in memory does
(`vpcontact.mesh.from_cells`): the cells are checked (linear triangles or tetrahedra only, a plane 2D body),
the physical groups become the parts and regions (`vpcontact.mesh.physical_groups`), and the mesh must cover
a body once (`vpcontact.mesh.checks`).
"""

from __future__ import annotations

import contextlib
import io
import os
from typing import TYPE_CHECKING

from ..inputs import check_regular_file
from ..errors import CaseError, shown
from . import gmsh, physical_groups
from .from_cells import mesh_from_cells
from .mesh import Mesh

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

    names = gmsh.physical_names(label) or physical_groups.field_names(data)
    return mesh_from_cells(f"mesh file '{label}'", data, names, file=label)


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
