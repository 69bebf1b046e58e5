"""Meshes from memory: a meshio.Mesh or a scikit-fem mesh with named boundaries made a checked `Mesh`, as a mesh
file is (`vpcontact.mesh.from_cells`: the same cells, the same groups, the same checks and messages); and
`from_object`, which tells a mesh in memory (those two, or the ``gmsh`` module: its open model,
`vpcontact.mesh.gmsh_model.from_gmsh`) from other values ``compose(mesh=...)`` takes.

A meshio.Mesh is what meshio reads from a file, or one made in Python: its physical groups
(``cell_data["gmsh:physical"]``, named by ``field_data``) and its named ``cell_sets`` are the parts (facet
cells) and regions (body cells), as `vpcontact.mesh.read.read_mesh` makes them of a file; a cell set that no
``field_data`` entry numbers is keyed by its name only. A scikit-fem ``MeshTri1`` or ``MeshTet1``: its named
boundaries (``with_boundaries``) are the parts and its named subdomains (``with_subdomains``) the regions, by
name (meshio's bookkeeping sets, "gmsh:…", left out); it must name the boundaries the problem uses (a mesh
without them is refused). Messages number nodes
and elements as Python indexes them, from 0.
"""

from __future__ import annotations

import types

import numpy as np
import skfem

from ..errors import CaseError, brief
from . import physical_groups
from .cells import SIMPLICES
from .checks_arrays import SKFEM_MESH, index_sets
from .from_cells import mesh_from_cells
from .gmsh import CellBlock, MeshData
from .mesh import Mesh


def from_meshio(mesh) -> Mesh:
    """The checked `Mesh` of a meshio.Mesh (see the module docstring)."""
    import meshio

    if not isinstance(mesh, meshio.Mesh):
        raise CaseError(f"mesh = a {type(mesh).__name__}: expected a meshio.Mesh")
    _check_cell_sets(mesh)
    names = physical_groups.field_names(mesh)
    tags = [tag for _, tag, _ in names] + [int(np.max(block_tags, initial=0))
                                           for block_tags in mesh.cell_data.get("gmsh:physical", [])]
    following, internal = max(tags, default=0) + 1, set()
    numbered = {name for _, _, name in names}
    for name, members in mesh.cell_sets.items():
        if name in numbered or name.startswith("gmsh:"):
            continue
        for dim in sorted({block.dim for block, cells in zip(mesh.cells, members) if cells is not None and len(cells)}):
            names.append((dim, following, name))
            internal.add(following)
            following += 1
    return mesh_from_cells("the meshio.Mesh", mesh, names, internal=frozenset(internal), first=0)


def _check_cell_sets(mesh) -> None:
    """CaseError for a cell set of a meshio.Mesh that names cells its blocks do not have (meshio's bookkeeping
    sets, "gmsh:…", are not sets of cells)."""
    for name, members in mesh.cell_sets.items():
        if name.startswith("gmsh:"):
            continue
        for block, cells in zip(mesh.cells, members):
            cells = np.asarray([] if cells is None else cells)
            if cells.size and (cells.ndim != 1 or cells.dtype.kind not in "iu" or cells.min() < 0
                               or cells.max() >= len(block.data)):
                raise CaseError(f"the meshio.Mesh: cell_sets[{name!r}] = {brief(cells)} for its {len(block.data)} "
                                f"{block.type} cells: expected indices of those cells, 0 to {len(block.data) - 1}")


def from_skfem(mesh) -> Mesh:
    """The checked `Mesh` of a scikit-fem MeshTri1 or MeshTet1 with named boundaries (see the module
    docstring)."""
    kind = type(mesh).__name__
    if type(mesh) not in SKFEM_MESH.values():
        raise CaseError(f"mesh = a scikit-fem {kind}: vpcontact uses linear triangles (skfem.MeshTri1) or "
                        f"tetrahedra (skfem.MeshTet1); for other elements save the mesh with triangles or "
                        f"tetrahedra")
    label, dim = f"the scikit-fem {kind}", {cls: d for d, cls in SKFEM_MESH.items()}[type(mesh)]
    if not mesh.boundaries:
        raise CaseError(f"mesh = a scikit-fem {kind} without named boundaries: the problem's parts (contact, "
                        f"Dirichlet, traction) are named boundaries: m.with_boundaries({{\"contact\": lambda x: "
                        f"..., ...}}), or pass vpcontact.mesh.Mesh(m, parts={{name: boundary facets}}, "
                        f"exact_normals={{}})")
    groups = {dim - 1: index_sets("boundaries", _named(mesh.boundaries), mesh.facets.shape[1], "facets", "mesh"),
              dim: index_sets("subdomains", _named(mesh.subdomains or {}), mesh.t.shape[1], "elements", "mesh")}
    cells = [CellBlock(SIMPLICES[dim].cell_type, mesh.t.T, dim), CellBlock(SIMPLICES[dim - 1].cell_type,
                                                                            mesh.facets.T, dim - 1)]
    names, sets = [], {}
    for group_dim, named in groups.items():
        for name, members in named.items():
            names.append((group_dim, len(names) + 1, name))
            sets.setdefault(name, [np.zeros(0, dtype=np.int64)] * 2)[dim - group_dim] = members
    data = MeshData(np.asarray(mesh.p, dtype=float).T, cells, {}, cell_sets=sets)
    return mesh_from_cells(label, data, names, internal=frozenset(range(1, len(names) + 1)), first=0)


def _named(sets):
    """A scikit-fem mesh's boundaries or subdomains without meshio's bookkeeping sets ("gmsh:bounding_entities",
    which scikit-fem keeps when it loads a gmsh file)."""
    if not isinstance(sets, dict):
        return sets  # refused by index_sets
    return {name: members for name, members in sets.items() if not (isinstance(name, str) and name.startswith("gmsh:"))}


def from_object(value) -> Mesh | None:
    """The checked `Mesh` of a mesh in memory: a scikit-fem mesh, a meshio.Mesh, or the ``gmsh`` module (its
    open model); None for any other value."""
    if isinstance(value, skfem.Mesh):
        return from_skfem(value)
    if type(value).__module__.split(".")[0] == "meshio":
        return from_meshio(value)
    if isinstance(value, types.ModuleType) and value.__name__ == "gmsh":
        from .gmsh_model import from_gmsh

        return from_gmsh()
    return None
