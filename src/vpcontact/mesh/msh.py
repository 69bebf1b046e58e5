"""A `Mesh` written as a gmsh file that ``mesh.file`` reads back: its nodes, elements, parts and regions.

`write_mesh` writes gmsh's format 2.2 (text) with meshio: the elements (triangles in 2D, tetrahedra in 3D)
and the facets of the parts (lines in 2D, triangles in 3D), each in the physical groups of its regions or
parts; the names become the file's physical names. A part or region named by a number n (a group of a mesh
file without a name) is physical group n; a name that holds the same elements or facets as such a number is
that group's name, any other name gets a group number of its own. An element or facet in several groups is
written once for each (gmsh 2.2's own way); an element in no region has the group 0 (none). The exact
normals and curved boundaries of a built-in shape are not part of the file: read back, it is a mesh file
(normals averaged from the facets, new nodes of a refinement on its flat facets).
"""

from __future__ import annotations

import os

import numpy as np

from .core import CELLS, Mesh


def write_mesh(mesh: Mesh, path: str | os.PathLike) -> None:
    """Write `mesh` to `path` as a gmsh 2.2 text file (see the module docstring)."""
    import meshio  # only when a mesh is written (the last mesh of an adaptive run)

    dim = mesh.dim
    body, facet = CELLS[dim]
    points = np.vstack((mesh.mesh.p, np.zeros((3 - dim, mesh.mesh.p.shape[1])))).T
    cells, tags, names = [], [], {}
    groups = {dim: _groups(mesh.regions), dim - 1: _groups(mesh.parts)}
    elements = mesh.mesh.t
    in_region = np.zeros(elements.shape[1], dtype=bool)
    for tag, name, members in groups[dim]:
        cells.append((body, elements[:, members].T))
        tags.append(np.full(members.size, tag))
        in_region[members] = True
        names[name] = (tag, dim)
    if not in_region.all():
        cells.append((body, elements[:, ~in_region].T))
        tags.append(np.zeros(int((~in_region).sum()), dtype=np.int64))
    for tag, name, members in groups[dim - 1]:
        cells.append((facet, mesh.mesh.facets[:, members].T))
        tags.append(np.full(members.size, tag))
        names[name] = (tag, dim - 1)
    data = meshio.Mesh(points, cells, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                       field_data={name: np.array(value) for name, value in names.items() if name is not None})
    meshio.write(path, data, file_format="gmsh22", binary=False)


def _groups(named: dict[str, np.ndarray]) -> list[tuple[int, str | None, np.ndarray]]:
    """(physical tag, name or None, members) of the groups of `named` (parts or regions by name): a numeric
    name is its tag; a name with the same members as a numeric one names that group; other names get new
    tags above the numeric ones."""
    numbers = {int(name): members for name, members in named.items() if name.isdecimal()}
    groups = {tag: [None, members] for tag, members in numbers.items()}
    following = max(numbers, default=0) + 1
    for name, members in sorted(named.items()):
        if name.isdecimal():
            continue
        same = [tag for tag, (label, group) in groups.items() if label is None and np.array_equal(group, members)]
        if same:
            groups[same[0]][0] = name
        else:
            groups[following] = [name, members]
            following += 1
    return [(tag, name, members) for tag, (name, members) in sorted(groups.items())]
