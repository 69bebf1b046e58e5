"""The cells and the coordinates of a mesh, by dimension, as every file format and every message names
them: the one table.

A body of dimension d (2 or 3) has the elements ``SIMPLICES[d]`` (triangles, tetrahedra) and the boundary
facets ``SIMPLICES[d - 1]`` (lines, triangles); a mesh file may hold the lower ones too (vertices, lines).
Its points have the coordinates ``coordinates(d)``: vectors of a case (loads, probe, normal) and their
output columns (``contact_force_x``, …) have one entry per coordinate. Pure data: importing it imports
nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Simplex:
    """The linear simplex of one dimension and its names."""

    dim: int
    cell_type: str
    """meshio's cell type ("triangle", "tetra"), also in vpcontact's own field files."""
    name: str
    """One of them in a message: "triangle", "tetrahedron"."""
    plural: str
    """Several of them in a message: "triangles", "tetrahedra"; also the key of the elements in solution.npz."""
    facet_name: str | None
    """How a message names one as a facet of a body of one dimension more: "edge", "face"."""
    measure: str | None
    """Its measure in a message: "length", "area", "volume"."""
    flat: str | None
    """Where the corners of one of zero measure lie, in a message: "on one line", "in one plane"."""
    vtk: int
    """VTK's cell type number."""
    xdmf: str
    """XDMF's topology type."""
    gmsh: int
    """gmsh's element type number."""
    gmsh_group: str
    """gmsh's physical group of this dimension: "Curve", "Surface", "Volume"."""


#: The simplices by dimension: SIMPLICES[d] is the simplex of dimension d = 0, 1, 2, 3.
SIMPLICES = (
    Simplex(0, "vertex", "vertex", "vertices", "point", measure=None, flat=None, vtk=1, xdmf="Polyvertex", gmsh=15,
            gmsh_group="Point"),
    Simplex(1, "line", "line", "lines", "edge", measure="length", flat="at one point", vtk=3, xdmf="Polyline",
            gmsh=1, gmsh_group="Curve"),
    Simplex(2, "triangle", "triangle", "triangles", "face", measure="area", flat="on one line", vtk=5,
            xdmf="Triangle", gmsh=2, gmsh_group="Surface"),
    Simplex(3, "tetra", "tetrahedron", "tetrahedra", None, measure="volume", flat="in one plane", vtk=10,
            xdmf="Tetrahedron", gmsh=4, gmsh_group="Volume"),
)
#: The simplices by meshio's cell type.
CELL_TYPES = {simplex.cell_type: simplex for simplex in SIMPLICES}

#: The names of the coordinates, in order.
COORDINATES = ("x", "y", "z")


def coordinates(dim: int) -> tuple[str, ...]:
    """The coordinate names of a d-dimensional body: ("x", "y") or ("x", "y", "z")."""
    return COORDINATES[:dim]


def component(name: str) -> int:
    """The index of a coordinate by name: "x" → 0, "y" → 1, "z" → 2."""
    return COORDINATES.index(name)
