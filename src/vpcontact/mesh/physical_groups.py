"""The physical groups of a gmsh file as the parts and regions of its `Mesh`.

A gmsh file puts its cells in physical groups (meshio's ``cell_data["gmsh:physical"]``, and in a 4.1 file
also ``cell_sets`` by name). The groups of the body's dimension (physical surfaces in 2D, volumes in 3D)
are the regions: `body_elements` gives the elements and the (element, group) pairs, `regions` the regions.
The groups of the facets' dimension (physical curves in 2D, surfaces in 3D) are the parts: `parts`. A
group is named by its tag number (str) and, if the file names it, by its name too; two groups of one
dimension with one name are refused (`check_unique_names`). A group known only by its name (a named boundary
or subdomain of a scikit-fem mesh, a cell set of a meshio.Mesh without a physical tag) is given a tag here, an
``internal`` one: it names nothing, the group is keyed by its name only.

`label` names the mesh in messages: "mesh file 'punch.msh'", "the gmsh model 'punch'", "the meshio.Mesh".
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import CaseError
from .cells import SIMPLICES
from .locate import find_columns

if TYPE_CHECKING:
    import meshio


def field_names(data: meshio.Mesh) -> list[tuple[int, int, str]]:
    """(dimension, tag, name) of each physical group meshio's ``field_data`` names (name -> [tag, dimension])."""
    return [(int(value[1]), int(value[0]), name) for name, value in data.field_data.items() if np.size(value) == 2]


def check_unique_names(label: str, names: list[tuple[int, int, str]], dim: int) -> None:
    """CaseError if two physical groups of the parts' dimension, or two of the body's, of a `dim`-dimensional
    mesh have one name (meshio would keep only one of them)."""
    for body in (False, True):
        group = SIMPLICES[dim - 1 + body].gmsh_group
        what = "region" if body else "part"
        tags: dict[str, int] = {}
        for group_dim, tag, name in names:
            if group_dim == dim - 1 + body and tags.setdefault(name, tag) != tag:
                raise CaseError(f"{label}: two physical {group.lower()}s are named '{name}' (groups "
                                f"{tags[name]} and {tag}); a {what} of that name would hold only one of them: give "
                                f"each group its own name, or put all its {group.lower()}s in one Physical "
                                f"{group}(\"{name}\") = {{...}};")


def body_elements(data: meshio.Mesh, names: list[tuple[int, int, str]],
                  dim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nodes (d + 1, m) (file numbering) of the body's elements (triangles in 2D, tetrahedra in 3D) in file
    order, their positions (m,) among the file's cells of their kind (from 1, for messages), and their physical
    groups: (element, tag) pairs (2, k), tags > 0.

    An element in several physical groups is one element of each: a gmsh 2.2 file writes it once per group
    (as cells with the same nodes and different tags, merged here into the first of them); a 4.1 file once,
    meshio's cell_data keeping its entity's first group and its cell_sets each named group's cells. Cells
    with the same nodes that are not all in distinct physical groups (a cell written twice in one group, or
    without a group) are all kept: the mesh checks refuse them as a region covered twice."""
    kind = SIMPLICES[dim].cell_type
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


def regions(label: str, names: list[tuple[int, int, str]], dim: int, members: np.ndarray,
            internal: frozenset[int] = frozenset()) -> dict[str, np.ndarray]:
    """Region name -> sorted element indices, from the distinct (element, physical tag) pairs `members` (2, k),
    sorted by element: one region per tag (named by its number, unless the tag is `internal`) and, if the file
    names the group, by its name too."""
    by_tag = {int(tag): members[0, members[1] == tag] for tag in _distinct(members[1])}
    return _named(label, by_tag, names, dim, internal)


def _named(label: str, by_tag: dict[int, np.ndarray], names: list[tuple[int, int, str]], dim: int,
           internal: frozenset[int]) -> dict[str, np.ndarray]:
    """The groups `by_tag` of dimension `dim` keyed by their tag number (str; not an `internal` tag) and by the
    name `names` gives them; CaseError for a name that is another group's number."""
    named = {str(tag): members for tag, members in by_tag.items() if tag not in internal}
    for group_dim, tag, name in names:
        if group_dim != dim or tag not in by_tag:
            continue
        if name in named and not np.array_equal(named[name], by_tag[tag]):
            raise CaseError(f"{label}: physical name '{name}' (group {tag}) clashes with physical group {name}")
        named[name] = by_tag[tag]
    return named


def parts(label: str, mesh, data: meshio.Mesh, names: list[tuple[int, int, str]], renumber: np.ndarray,
          dim: int, internal: frozenset[int] = frozenset()) -> dict[str, np.ndarray]:
    """Part name -> sorted boundary facets of the skfem `mesh` read from the file `label` (`renumber`: the
    mesh's node of each node of the file, -1 for none): the facet cells of each physical group of the parts'
    dimension, by tag number (unless `internal`) and, if the file names the group, by its name too; CaseError
    for a cell that is not a boundary facet."""
    facet_nodes, facet_tags = _physical_facets(data, names, SIMPLICES[dim - 1].cell_type, dim - 1)
    parts: dict[str, np.ndarray] = {}
    if not facet_tags.size:
        return parts
    known = (facet_nodes >= 0) & (facet_nodes < renumber.size)  # a damaged file may name other nodes
    nodes = np.where(known, renumber[np.where(known, facet_nodes, 0)], -1)
    boundary = mesh.boundary_facets().astype(np.int64)
    found = find_columns(mesh.facets[:, boundary], nodes)
    bad = np.flatnonzero((nodes < 0).any(axis=0) | (found < 0))
    if bad.size:
        group = _group(int(facet_tags[bad[0]]), names, dim - 1, internal)
        what, kind = SIMPLICES[dim - 1].cell_type, SIMPLICES[dim - 1].facet_name
        facet_group, body_group = SIMPLICES[dim - 1].gmsh_group, SIMPLICES[dim].gmsh_group
        raise CaseError(f"{label}: {what} of {group} is not a boundary "
                        f"{kind} of the {SIMPLICES[dim].plural} ({bad.size} such {what}s): a part must lie on "
                        f"the boundary of the body; remove inner {facet_group.lower()}s from that physical group, "
                        f"or add the {body_group.lower()} they bound to the Physical {body_group}")
    facets = boundary[found]
    by_tag = {int(tag): np.unique(facets[facet_tags == tag]) for tag in np.unique(facet_tags)}
    return _named(label, by_tag, names, dim - 1, internal)


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


def _group(tag: int, names: list[tuple[int, int, str]], dim: int, internal: frozenset[int]) -> str:
    """A physical group in a message: "physical group 3", or "group 'contact'" for an `internal` tag."""
    if tag in internal:
        return next(f"group '{name}'" for group_dim, group_tag, name in names if (group_dim, group_tag) == (dim, tag))
    return f"physical group {tag}"


def _distinct(keys: np.ndarray) -> np.ndarray:
    """The distinct integers of `keys`, sorted (np.unique, without its slower hashing of large arrays)."""
    keys = np.sort(keys)
    new = np.ones(keys.size, dtype=bool)
    new[1:] = keys[1:] != keys[:-1]
    return keys[new]
