"""The fields of a run as VTK files (ParaView, VTK, meshio), written with NumPy alone: in ``fields/``,
``body_NNNNN.vtu`` and (with contact) ``contact_NNNNN.vtu`` at each field step n, the data of
:mod:`vpcontact.results.frames`, and their ParaView collections ``body.pvd`` and ``contact.pvd``, one
dataset per field step at its time t_n.

A VTU file is a VTK XML unstructured grid whose arrays are written inline in VTK's uncompressed
binary format: base64 of an array's length in bytes (a UInt64) followed by its little-endian bytes,
header and data encoded together, as VTK's own writer does. Without compression, writing costs little
more than copying the arrays to disk. (Raw appended data would be smaller, but meshio's reader can mix
up its arrays.) The points and cells of a body are the same at every field step: a :class:`Grid`
encodes them once, and each file written on it encodes only its data.

The elements follow VTK's XML format (``VTKFile type="UnstructuredGrid"``, one ``Piece``): ``Points``
one Float64 array of 3 components; ``Cells`` the arrays ``connectivity`` (the node numbers of every
cell one after the other, one component: VTK 9.3 and later read no cell at all from a connectivity of
several components), ``offsets`` (where each cell's nodes end in it) and ``types`` (UInt8, VTK's cell
type numbers); ``NumberOfComponents`` only on arrays of more than one, and the 9 components of a
tensor named XX, XY, … ZZ (row by row), as ParaView shows them.
"""

from __future__ import annotations

import base64
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..mesh.cells import CELL_TYPES
from ..results.frames import field_frames, field_meshes
from . import directory
from .files import replacing

FILES = ("fields/body.pvd", "fields/contact.pvd", "fields/body_*.vtu", "fields/contact_*.vtu")

#: VTK's name of each NumPy type written.
VTK_TYPES = {np.dtype("<f8"): "Float64", np.dtype("<i8"): "Int64", np.dtype("<i4"): "Int32", np.dtype("u1"): "UInt8"}
#: The names of the components of a 3 × 3 tensor, written row by row
#: (:func:`vpcontact.results.frames.tensors_in_space`).
TENSOR_COMPONENTS = ("XX", "XY", "XZ", "YX", "YY", "YZ", "ZX", "ZY", "ZZ")


class Grid:
    """The points (n, 3) and cells (k, nodes per cell) of one cell type: the ``Points`` and ``Cells``
    elements of a VTU file, encoded once for every file written on this grid (the connectivity is the
    cells' rows one after the other)."""

    def __init__(self, points: np.ndarray, cell_type: str, cells: np.ndarray):
        self.points, self.cells = len(points), len(cells)
        fits = max(self.points, self.cells * np.shape(cells)[1]) < 2**31
        index = np.int32 if fits else np.int64  # connectivity and offsets in 4 bytes if they fit
        cells = np.asarray(cells, dtype=index)
        offsets = np.arange(1, self.cells + 1, dtype=index) * cells.shape[1]
        types = np.full(self.cells, CELL_TYPES[cell_type].vtk, dtype=np.uint8)
        self.xml = "\n".join(["<Points>", _data_array("Points", points), "</Points>", "<Cells>",
                              _data_array("connectivity", cells.ravel()), _data_array("offsets", offsets),
                              _data_array("types", types), "</Cells>"])


def write_vtu(path: str | Path, grid: Grid, point_data: Mapping[str, np.ndarray] = {},
              cell_data: Mapping[str, np.ndarray] = {}) -> None:
    """Write ``grid`` with ``point_data`` (arrays of grid.points rows) and ``cell_data`` (of grid.cells rows)
    to ``path``: an array of shape (rows,) is a scalar, (rows, c) a vector or tensor of c components;
    floats are written as Float64, integers as Int32 (if they are) or Int64, booleans as UInt8."""
    for data, rows in ((point_data, grid.points), (cell_data, grid.cells)):
        for name, values in data.items():
            if len(values) != rows:
                raise ValueError(f"'{name}': {len(values)} values for {rows} points or cells")
    with open(path, "w", encoding="utf-8") as handle:
        handle.write("\n".join([
            '<?xml version="1.0"?>',
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
            "<UnstructuredGrid>", f'<Piece NumberOfPoints="{grid.points}" NumberOfCells="{grid.cells}">',
            "<PointData>", *(_data_array(name, values) for name, values in point_data.items()), "</PointData>",
            "<CellData>", *(_data_array(name, values) for name, values in cell_data.items()), "</CellData>",
            grid.xml, "</Piece>", "</UnstructuredGrid>", "</VTKFile>", ""]))


def _data_array(name: str, values: np.ndarray) -> str:
    """One DataArray element: ``values`` (n,) or (n, components) in VTK's uncompressed binary format (see the
    module docstring), the components of a 9-component array named as those of a tensor."""
    values = np.asarray(values)
    kind = values.dtype.kind
    dtype = "<f8" if kind == "f" else "u1" if kind in "bu" and values.itemsize == 1 else \
        "<i4" if values.dtype == np.int32 else "<i8"
    values = np.ascontiguousarray(values, dtype=dtype)
    components = f' NumberOfComponents="{values.shape[1]}"' if values.ndim == 2 else ""
    if values.ndim == 2 and values.shape[1] == len(TENSOR_COMPONENTS):
        components += "".join(f' ComponentName{i}="{c}"' for i, c in enumerate(TENSOR_COMPONENTS))
    encoded = base64.b64encode(np.uint64(values.nbytes).tobytes() + values.tobytes()).decode("ascii")
    return (f'<DataArray type="{VTK_TYPES[values.dtype]}" Name={quoteattr(name)}{components} format="binary">'
            f"{encoded}</DataArray>")


def wanted(result) -> bool:
    """A run that kept fields (``output.field_steps``) has their files."""
    return bool(result.fields)


def write(result, out: Path) -> None:
    """``out``/fields: body_NNNNN.vtu and contact_NNNNN.vtu at each field step of ``result``, and their PVD
    collections."""
    folder = Path(out) / "fields"
    directory.mkdir(folder)
    body_mesh, contact_mesh = field_meshes(result.discretization)
    body_grid = Grid(*body_mesh)
    contact_grid = Grid(*contact_mesh) if contact_mesh is not None else None
    body, contact = [], []
    for frame in field_frames(result):
        name = f"body_{frame.step:05d}.vtu"
        with replacing(folder / name) as temporary:
            write_vtu(temporary, body_grid, frame.body_points, frame.body_cells)
        body.append((frame.t, name))
        if frame.contact_points is not None:
            name = f"contact_{frame.step:05d}.vtu"
            with replacing(folder / name) as temporary:
                write_vtu(temporary, contact_grid, frame.contact_points)
            contact.append((frame.t, name))
    write_pvd(folder / "body.pvd", body)
    if contact:
        write_pvd(folder / "contact.pvd", contact)


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """A ParaView collection: one dataset per time (``entries``: (t, file name))."""
    root = ET.Element("VTKFile", type="Collection", version="0.1")
    collection = ET.SubElement(root, "Collection")
    for t, name in entries:
        ET.SubElement(collection, "DataSet", timestep=repr(float(t)), part="0", file=name)
    with replacing(path) as temporary:
        ET.ElementTree(root).write(temporary, xml_declaration=True, encoding="utf-8")
