"""gmsh's mesh files (.msh): MSH 2.2 text files read with NumPy, and a `Mesh` written as one.

Reading. `read_msh22` reads what meshio reads from a MSH 2.2 text file, without its Python loop over
the elements (and without importing meshio): 0.05 s instead of 0.4 s for 30,000 triangles. Only plain,
well-formed files take this way: nodes numbered by distinct positive integers, elements of the linear
types vpcontact uses (points, lines, triangles, tetrahedra), each with its two tags (physical and
elementary group) and nodes of the file. Any other file (a 4.1 or binary file, or anything unexpected in
a 2.2 text file) is left to meshio (`read_msh22` returns None): its messages and its handling of odd files
stay the same. `physical_names` reads the names of the physical groups from the head of any gmsh file.
What the elements and groups become (the body, its parts and regions) is `vpcontact.mesh.read`'s.

Writing. `write_mesh` writes gmsh's format 2.2 (text) with meshio: the elements (triangles in 2D,
tetrahedra in 3D) and the facets of the parts (lines in 2D, triangles in 3D), each in the physical groups
of its regions or parts; the names become the file's physical names. A part or region named by a number n
(a group of a mesh file without a name) is physical group n; a name that holds the same elements or facets
as such a number is that group's name, any other name gets a group number of its own. An element or facet
in several groups is written once for each (gmsh 2.2's own way); an element in no region has the group 0
(none). The exact normals and curved boundaries of a built-in shape are not part of the file: read back,
it is a mesh file (normals averaged from the facets, new nodes of a refinement on its flat facets).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .cells import SIMPLICES
from .mesh import Mesh

#: The simplices read here (points, lines, triangles, tetrahedra) by gmsh's element type number.
ELEMENT_TYPES = {simplex.gmsh: simplex for simplex in SIMPLICES}
#: The nodes of a cell by gmsh's element type number (0: a type not read here).
NODES_PER_CELL = np.zeros(max(ELEMENT_TYPES) + 1, dtype=np.int64)
NODES_PER_CELL[list(ELEMENT_TYPES)] = [simplex.dim + 1 for simplex in ELEMENT_TYPES.values()]
#: Whether each byte separates numbers in a text file (as whitespace).
BLANK = np.isin(np.arange(256), np.frombuffer(b" \t\n\r\x0b\x0c", dtype=np.uint8))
#: A line of the $PhysicalNames section of a gmsh file: dimension, tag, "name".
PHYSICAL_NAME = re.compile(rb'\s*(\d+)\s+(\d+)\s+"(.*)"\s*')


@dataclass
class CellBlock:
    """A run of consecutive elements of one type, as meshio's CellBlock: nodes (cells, nodes per cell)."""

    type: str
    data: np.ndarray
    dim: int


@dataclass
class MeshData:
    """What meshio.read returns for a MSH 2.2 file, as far as `vpcontact.mesh.read.read_mesh` uses it."""

    points: np.ndarray  # (nodes, 3)
    cells: list[CellBlock]
    cell_data: dict[str, list[np.ndarray]]  # "gmsh:physical", "gmsh:geometrical": one array per block
    field_data: dict[str, np.ndarray] = field(default_factory=dict)  # physical name -> [tag, dimension]
    cell_sets: dict = field(default_factory=dict)  # none in a 2.2 file


def read_msh22(path: str | Path) -> MeshData | None:
    """The mesh of the MSH 2.2 text file ``path``, or None if it is not one this module reads (see the
    module docstring)."""
    try:
        with open(path, "rb") as handle:
            if handle.readline(64).strip() != b"$MeshFormat" or handle.readline(64).split()[:2] != [b"2.2", b"0"]:
                return None
            handle.seek(0)
            text = handle.read()
    except OSError:  # meshio's reading of the file reports it
        return None
    sections = _sections(text)
    if b"Nodes" not in sections or b"Elements" not in sections:
        return None
    try:
        found = _nodes(sections[b"Nodes"])
        blocks = _elements(sections[b"Elements"], found[1]) if found is not None else None
    except ValueError:  # a number that is not one, or a count that is not
        return None
    if blocks is None:
        return None
    names = {match[3].decode("utf-8", "replace"): np.array([int(match[2]), int(match[1])])
             for line in sections.get(b"PhysicalNames", b"").splitlines()
             if (match := PHYSICAL_NAME.fullmatch(line.strip()))}
    return MeshData(found[0], [block for block, _, _ in blocks],
                    {"gmsh:physical": [physical for _, physical, _ in blocks],
                     "gmsh:geometrical": [geometrical for _, _, geometrical in blocks]}, names)


def _sections(text: bytes) -> dict[bytes, bytes]:
    """The text between each "$Name" line and its "$EndName" line, by name."""
    sections, position = {}, 0
    while (start := text.find(b"$", position)) >= 0:
        head = text.find(b"\n", start)
        name = text[start + 1:head].strip()
        end = text.find(b"$End" + name, head)
        if head < 0 or end < 0:
            break
        sections[name] = text[head + 1:end]
        position = end + 4 + len(name)
    return sections


def _numbers(section: bytes, dtype) -> tuple[int, np.ndarray]:
    """The count on the first line of a section, and the numbers after it (ValueError if one is not)."""
    count, _, body = section.partition(b"\n")
    return int(count), np.fromstring(body.decode("ascii"), dtype=dtype, sep=" ")


def _nodes(section: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """The points (n, 3) of the $Nodes rows "number x y z", and the index of each node number (-1: none);
    None unless there are as many rows as the count says and their numbers are distinct positive integers."""
    count, numbers = _numbers(section, float)
    if numbers.size != 4 * count:
        return None
    rows = numbers.reshape(-1, 4)
    numbers = rows[:, 0]
    if not numbers.size or (numbers != np.round(numbers)).any() or numbers.min() < 1 or \
            numbers.max() > 4 * numbers.size + 1024:  # far sparser numbers: left to meshio
        return None
    numbers = numbers.astype(np.int64)
    index = np.full(numbers.max() + 1, -1, dtype=np.int64)
    index[numbers] = np.arange(numbers.size)
    if (index >= 0).sum() != numbers.size:  # a node number twice
        return None
    return np.ascontiguousarray(rows[:, 1:]), index


def _elements(section: bytes, index: np.ndarray) -> list[tuple[CellBlock, np.ndarray, np.ndarray]] | None:
    """The blocks of the $Elements rows "number type 2 physical elementary node…" (each run of one type a
    block, as meshio makes them) with their physical and elementary tags (int32); None for rows of other
    types, other numbers of tags or nodes, or nodes that are not in $Nodes."""
    count, tokens = _numbers(section, np.int64)
    text = np.frombuffer(section, dtype=np.uint8)
    blank = BLANK[text]
    starts = np.flatnonzero(~blank & np.concatenate(([True], blank[:-1])))  # the first byte of each number
    row = np.searchsorted(np.flatnonzero(text == ord("\n")), starts)  # row 0: the count
    lengths = np.bincount(row)[1:]  # numbers per row
    lengths = lengths[lengths > 0]
    if lengths.size != count or not count or lengths.sum() != tokens.size or lengths.min() < 5:
        return None
    first = np.cumsum(lengths) - lengths
    kinds, tags = tokens[first + 1], tokens[first + 2]
    if not ((kinds >= 0) & (kinds < NODES_PER_CELL.size)).all():
        return None
    if (NODES_PER_CELL[kinds] == 0).any() or (tags != 2).any() or (lengths != 5 + NODES_PER_CELL[kinds]).any():
        return None
    blocks = []
    for start, stop in _runs(kinds):
        simplex = ELEMENT_TYPES[int(kinds[start])]
        rows = first[start:stop]
        numbers = tokens[rows[:, None] + 5 + np.arange(simplex.dim + 1)]
        if numbers.min() < 1 or numbers.max() >= index.size or (index[numbers] < 0).any():
            return None
        blocks.append((CellBlock(simplex.cell_type, index[numbers], simplex.dim), tokens[rows + 3].astype(np.int32),
                       tokens[rows + 4].astype(np.int32)))
    return blocks


def _runs(values: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of equal consecutive values."""
    edges = np.concatenate(([0], np.flatnonzero(values[1:] != values[:-1]) + 1, [values.size]))
    return list(zip(edges[:-1].tolist(), edges[1:].tolist()))


def physical_names(path: str) -> list[tuple[int, int, str]]:
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
            elif section == b"$PhysicalNames" and (match := PHYSICAL_NAME.fullmatch(line)):
                found.append((int(match[1]), int(match[2]), match[3].decode("utf-8", "replace")))
    return found


def write_mesh(mesh: Mesh, path: str | os.PathLike) -> None:
    """Write `mesh` to `path` as a gmsh 2.2 text file (see the module docstring)."""
    import meshio  # only when a mesh is written (the last mesh of an adaptive run)

    dim = mesh.dim
    body, facet = SIMPLICES[dim].cell_type, SIMPLICES[dim - 1].cell_type
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
