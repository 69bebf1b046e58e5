"""The mesh of the model open in gmsh's Python module (gmsh's PyPI package) made a checked `Mesh`, read through
gmsh's API (no file), as the file gmsh would save of it is read (`vpcontact.mesh.from_cells`)::

    import gmsh
    gmsh.initialize(interruptible=False)   # gmsh's default (True) replaces Python's Ctrl-C handler for good
    ...                                    # geometry, physical groups, gmsh.model.mesh.generate(2)
    body = vpcontact.mesh.from_gmsh()      # or vpcontact.compose(gmsh, ...)

As in the file gmsh saves (``Mesh.SaveAll = 0``, its default): a model with physical groups gives the elements
of its physical groups only, each in each group of its entity; a model without any gives all its elements (a
mesh without parts). The nodes keep gmsh's order (nodes no element uses dropped), the elements the order of
their entities: the Mesh is that of the saved file, array for array. The physical groups of the facets'
dimension (curves in 2D, surfaces in 3D) are the parts, those of the body's dimension the regions, by number
and by name. Nodes and elements are numbered in messages by their position from 1, as in a file.
"""

from __future__ import annotations

import numpy as np

from ..errors import CaseError
from .from_cells import mesh_from_cells
from .gmsh import ELEMENT_TYPES, CellBlock, MeshData
from .mesh import Mesh

#: meshio's cell names by the family of gmsh's element names ("Triangle 6" -> "triangle6"), for the cells
#: vpcontact refuses (second order, quadrilaterals, …), named in its messages as in a file's.
FAMILIES = {"Point": "vertex", "Line": "line", "Triangle": "triangle", "Quadrilateral": "quad", "Tetrahedron": "tetra",
            "Hexahedron": "hexahedron", "Prism": "wedge", "Pyramid": "pyramid"}


def from_gmsh() -> Mesh:
    """The checked `Mesh` of the current model of gmsh's Python module (see the module docstring)."""
    try:
        import gmsh
    except ImportError:
        raise CaseError("mesh = the gmsh model: gmsh's Python module is not installed (pip install gmsh)") from None
    except OSError as error:  # the module is there, its library is not loadable
        raise CaseError(f"mesh = the gmsh model: gmsh's library does not load ({error}): install the system "
                        f"libraries it names (e.g. apt-get install libglu1-mesa libxcursor1 libxft2 "
                        f"libxinerama1)") from None
    if not gmsh.isInitialized():
        raise CaseError("mesh = the gmsh model: gmsh is not initialized: gmsh.initialize(), make the model and "
                        "mesh it (gmsh.model.mesh.generate) first")
    model = gmsh.model.getCurrent()
    label = f"the gmsh model '{model}'"
    tags, coordinates, _ = gmsh.model.mesh.getNodes()
    if not tags.size:
        raise CaseError(f"{label} has no mesh: gmsh.model.mesh.generate(2) (a plane body) or generate(3) first")
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(tags.size)
    groups = gmsh.model.getPhysicalGroups()
    names = [(dim, tag, name) for dim, tag in groups if (name := gmsh.model.getPhysicalName(dim, tag))]
    blocks, physical = [], []
    for dim, entity in gmsh.model.getEntities():
        entity_groups = gmsh.model.getPhysicalGroupsForEntity(dim, entity) if groups else [0]
        for kind, _, nodes in zip(*gmsh.model.mesh.getElements(dim, entity)):
            block = _block(gmsh, int(kind), index[nodes.astype(np.int64)])
            for group in entity_groups:
                blocks.append(block)
                physical.append(np.full(len(block.data), group, dtype=np.int32))
    data = MeshData(coordinates.reshape(-1, 3), blocks, {"gmsh:physical": physical})
    return mesh_from_cells(label, data, names)


def _block(gmsh, kind: int, nodes: np.ndarray) -> CellBlock:
    """The cells of gmsh's element type `kind` with the nodes `nodes` (flat, mesh indices), as meshio names
    them."""
    if kind in ELEMENT_TYPES:
        simplex = ELEMENT_TYPES[kind]
        return CellBlock(simplex.cell_type, nodes.reshape(-1, simplex.dim + 1), simplex.dim)
    name, dim, _, count, *_ = gmsh.model.mesh.getElementProperties(kind)
    family, _, _ = name.partition(" ")
    cell = FAMILIES.get(family, family.lower())
    simplest = {"vertex": 1, "line": 2, "triangle": 3, "quad": 4, "tetra": 4, "hexahedron": 8, "wedge": 6,
                "pyramid": 5}.get(cell)
    return CellBlock(cell if count == simplest else f"{cell}{count}", nodes.reshape(-1, count), dim)
