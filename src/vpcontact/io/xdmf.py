"""XDMF time series of the fields (``output.xdmf = true``): the mesh written once, the fields per step.

For each of the body and the contact part (with contact), two files in ``fields/``:

- ``body.h5`` (HDF5): ``/mesh/points`` (n, 3) and ``/mesh/cells`` (k, nodes per cell) once, then the
  arrays of each field step n in ``/steps/NNNNN/<name>``;
- ``body.xdmf`` (XDMF 3, XML): a temporal collection with one grid per field step, at its time t_n,
  whose topology and geometry point to the one ``/mesh`` of the HDF5 file and whose attributes point to
  that step's arrays.

VTK's ``vtkXdmfReader`` (ParaView's "XDMF Reader"; the tests read every series with it), ParaView's Xdmf3
readers, VisIt and meshio's ``meshio.xdmf.TimeSeriesReader`` read them; a run of a thousand field steps
stores its mesh once (the VTU files of ``fields/body.pvd`` store it in each file). The arrays are those of
the VTU files (:func:`vpcontact.results.frames.field_frames`), of the same types (integers as Int); a 2D contact
part's segments are a Polyline topology of 2 nodes per element (XDMF has no linear line cell: VTK reads
them as poly lines of 2 points, meshio as lines). Each file is written atomically, the HDF5 file before
the XDMF file that describes it.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from ..mesh.cells import CELL_TYPES
from ..results.frames import field_frames, field_meshes
from .files import replacing

FILES = ("fields/body.h5", "fields/body.xdmf", "fields/contact.h5", "fields/contact.xdmf")

#: XDMF's attribute type of an array by its number of components per point or cell.
ATTRIBUTE_TYPES = {1: "Scalar", 3: "Vector", 9: "Tensor"}
#: XDMF's number type of each NumPy kind.
NUMBER_TYPES = {"f": "Float", "i": "Int", "u": "UInt"}


def wanted(result) -> bool:
    """Asked for (``output.xdmf``), by a run that kept fields (``output.field_steps``)."""
    return bool(result.output.xdmf) and bool(result.fields)


def write(result, out: Path) -> None:
    """body.h5 and body.xdmf, and with contact contact.h5 and contact.xdmf, in ``out``/fields (which the VTU
    files made), with the fields at every field step of ``result``. The steps' arrays are made and written
    one step at a time; h5py is imported by the runs that write XDMF only."""
    import h5py

    folder = Path(out) / "fields"
    body_mesh, contact_mesh = field_meshes(result.discretization)
    meshes = {"body": body_mesh, **({"contact": contact_mesh} if contact_mesh is not None else {})}
    steps = {name: [] for name in meshes}  # (step, t, {center: {array: (shape, dtype)}}) of each series
    with ExitStack() as stack:
        files = {}
        for name, (points, _, cells) in meshes.items():
            temporary = stack.enter_context(replacing(Path(folder) / f"{name}.h5"))
            files[name] = stack.enter_context(h5py.File(temporary, "w"))
            files[name]["mesh/points"] = points
            files[name]["mesh/cells"] = np.asarray(cells, dtype=np.int64)
        for frame in field_frames(result):
            data = {"body": {"Node": frame.body_points, "Cell": frame.body_cells},
                    "contact": {"Node": frame.contact_points, "Cell": {}}}
            for name, handle in files.items():
                for arrays in data[name].values():
                    for array, values in arrays.items():
                        handle[f"steps/{frame.step:05d}/{array}"] = values
                steps[name].append((frame.step, frame.t, {center: {array: (values.shape, values.dtype)
                                                                   for array, values in arrays.items()}
                                                          for center, arrays in data[name].items()}))
    for name, (points, cell_type, cells) in meshes.items():
        _write_description(Path(folder) / f"{name}.xdmf", (points.shape, cell_type, np.shape(cells)), steps[name])


def _write_description(path: Path, mesh: tuple, steps: list[tuple]) -> None:
    """The XDMF file ``path`` of the HDF5 file beside it of the same stem: the mesh's (shape of the points,
    cell type, shape of the cells) and the (step, t, {center: {array: (shape, dtype)}}) of each field step."""
    points, cell_type, cells = mesh
    h5 = path.with_suffix(".h5").name
    integers = np.dtype(np.int64)
    root = ET.Element("Xdmf", Version="3.0")
    collection = ET.SubElement(ET.SubElement(root, "Domain"), "Grid", Name=path.stem, GridType="Collection",
                               CollectionType="Temporal")
    for step, t, data in steps:
        grid = ET.SubElement(collection, "Grid", Name=f"step {step}", GridType="Uniform")
        ET.SubElement(grid, "Time", Value=repr(float(t)))
        topology = ET.SubElement(grid, "Topology", TopologyType=CELL_TYPES[cell_type].xdmf,
                                 NumberOfElements=str(cells[0]))
        if cell_type == "line":
            topology.set("NodesPerElement", str(cells[1]))
        _data_item(topology, f"{h5}:/mesh/cells", cells, integers)
        _data_item(ET.SubElement(grid, "Geometry", GeometryType="XYZ"), f"{h5}:/mesh/points", points,
                   np.dtype(np.float64))
        for center, arrays in data.items():
            for name, (shape, dtype) in arrays.items():
                attribute = ET.SubElement(grid, "Attribute", Name=name, Center=center,
                                          AttributeType=ATTRIBUTE_TYPES[1 if len(shape) == 1 else shape[1]])
                _data_item(attribute, f"{h5}:/steps/{step:05d}/{name}", shape, dtype)
    ET.indent(root)
    with replacing(path) as temporary:
        ET.ElementTree(root).write(temporary, xml_declaration=True, encoding="utf-8")


def _data_item(parent: ET.Element, where: str, shape: tuple, dtype: np.dtype) -> None:
    """A DataItem of ``parent``: the HDF5 dataset ``where`` ("file.h5:/path") of that shape and type."""
    item = ET.SubElement(parent, "DataItem", Dimensions=" ".join(map(str, shape)), Format="HDF",
                         NumberType=NUMBER_TYPES[dtype.kind], Precision=str(dtype.itemsize))
    item.text = where
