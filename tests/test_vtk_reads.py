"""Every field file a run writes, read by VTK itself (the library ParaView reads them with), not by our
own reader nor by meshio (which is lenient: it read the VTU files whose connectivity VTK 9.3+ refuses):

- each ``.vtu`` by ``vtkXMLUnstructuredGridReader`` with no error nor warning (of the reader, of the
  objects it uses, or printed by the library), all its cells of the right type, every array with its
  number of components, its type (integers stay integers) and its values: equal to the user's other
  files of the run (solution.npz, contact.csv and history.csv read by pandas), to quantities computed
  here from what VTK read (von Mises from the stress, the contact force from the pressure), and to the
  run's own arrays in memory;
- each ``.pvd`` as ParaView reads a collection: every file it names beside it and read, at the times of
  the field steps (and by pyvista's PVDReader where pyvista is installed);
- each ``.xdmf`` (``output.xdmf``) by VTK's XDMF reader: the times, and at each one the grid and the arrays
  of the VTU file of that step.

The runs: 2D and 3D bodies of two materials (one viscoplastic, so z is written) with the error estimate,
XDMF and all three contact states, through the command line; two contact parts of two layer families (a
layer parameter a part has not: NaN) in 2D and 3D, written by ``vpcontact.write_run``; the 3D block without
XDMF; an adaptive run (the fields of each cycle). And ``result.to_pyvista(step)`` is the body file VTK
reads; the writer's every kind of array comes back from VTK as written."""

import copy
import os
import sys
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import tomli_w
from vtkmodules.util.misc import calldata_type
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import VTK_STRING, vtkOutputWindow, vtkStringOutputWindow
from vtkmodules.vtkCommonDataModel import VTK_LINE, VTK_POLY_LINE, VTK_TETRA, VTK_TRIANGLE
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

import vpcontact
from conftest import block_3d_case, half_disc_case, run_cli
from test_3d_runs import ball_case
from test_contact_parts import LAYERS, split_case, two_parts_form
from vpcontact.laws.contact import STATUS_NAMES
from vpcontact.results.columns import CONTACT_ARRAYS
from vpcontact.io.vtu import Grid as VtuGrid, write_vtu

#: VTK's cell types of the body and of the contact part, by dimension.
BODY_CELLS = {2: VTK_TRIANGLE, 3: VTK_TETRA}
CONTACT_CELLS = {2: VTK_LINE, 3: VTK_TRIANGLE}
#: The arrays of the field files: point data of the body, cell data of the body (z and error_indicator
#: when the run has them), point data of the contact part (and its layer parameters).
BODY_POINT_ARRAYS = {"displacement": 3}
BODY_CELL_ARRAYS = {"stress": 9, "von_mises": 1, "material": 1, "E": 1, "nu": 1}
CONTACT_POINT_ARRAYS = {**dict.fromkeys(CONTACT_ARRAYS, 1), "pressure": 1, "normal": 3, "contact_force": 3,
                        "displacement": 3}
#: The arrays that are integers (VTK Int32), and the names of the components of a 3 × 3 tensor.
INTEGERS = {"material", "status", "part"}
TENSOR = ["XX", "XY", "XZ", "YX", "YY", "YZ", "ZX", "ZY", "ZZ"]
#: The two materials of the coated bodies, by region: the coating softer and viscoplastic.
MATERIALS = [{"region": "core", "E": 1000.0, "nu": 0.3},
             {"region": "coating", "E": 300.0, "nu": 0.4,
              "viscoplastic": {"law": "perzyna", "eta": 0.5, "yield_stress": 1.0}}]


# --- reading with VTK ------------------------------------------------------------------------------
@dataclass
class Grid:
    """An unstructured grid as VTK read it: points (n, 3), VTK cell types (k,), cells (k, nodes), the point
    and cell arrays (n,) or (n, components) in the NumPy type of VTK's array, and the component names of
    each array that has them."""

    points: np.ndarray
    types: np.ndarray
    cells: np.ndarray
    point_data: dict[str, np.ndarray]
    cell_data: dict[str, np.ndarray]
    component_names: dict[str, list[str]]


def as_grid(grid) -> Grid:
    """The vtkUnstructuredGrid ``grid`` as NumPy arrays (its cells all of one number of nodes)."""
    offsets = vtk_to_numpy(grid.GetCells().GetOffsetsArray())
    connectivity = vtk_to_numpy(grid.GetCells().GetConnectivityArray())
    nodes = np.unique(np.diff(offsets))
    assert len(nodes) == 1 and offsets[0] == 0, offsets
    arrays, names = [{}, {}], {}
    for data, found in zip((grid.GetPointData(), grid.GetCellData()), arrays):
        for i in range(data.GetNumberOfArrays()):
            array = data.GetAbstractArray(i)
            found[array.GetName()] = vtk_to_numpy(array).copy()
            if array.HasAComponentName():
                names[array.GetName()] = [array.GetComponentName(c) for c in range(array.GetNumberOfComponents())]
    return Grid(vtk_to_numpy(grid.GetPoints().GetData()).copy(), cell_types(grid),
                connectivity.reshape(-1, nodes[0]).copy(), *arrays, names)


def cell_types(grid) -> np.ndarray:
    """The VTK type of each cell of ``grid``: GetCellTypes() from VTK 9.6 on, GetCellTypesArray() before."""
    try:
        types = grid.GetCellTypes()
    except TypeError:  # VTK < 9.6: GetCellTypes fills a vtkCellTypes
        types = grid.GetCellTypesArray()
    return vtk_to_numpy(types).copy()


class Messages:
    """Every error and warning VTK reports while a reader reads: those of the reader (its ErrorEvent and
    WarningEvent), those of the objects it uses (the XML parser, the pipeline: VTK's output window) and
    whatever the library prints on the standard error (its logger, the XDMF library)."""

    def __init__(self):
        self.found = []

    def watch(self, reader):
        for event in ("ErrorEvent", "WarningEvent"):
            reader.AddObserver(event, self._record)
        return reader

    @calldata_type(VTK_STRING)
    def _record(self, caller, event, message):
        self.found.append(f"{event}: {message}")

    def __enter__(self):
        self._window, self._previous = vtkStringOutputWindow(), vtkOutputWindow.GetInstance()
        vtkOutputWindow.SetInstance(self._window)
        sys.stderr.flush()
        self._stderr, self._saved = tempfile.TemporaryFile(), os.dup(2)
        os.dup2(self._stderr.fileno(), 2)
        return self

    def __exit__(self, *exc):
        os.dup2(self._saved, 2)
        os.close(self._saved)
        vtkOutputWindow.SetInstance(self._previous)
        self._stderr.seek(0)
        printed = self._stderr.read().decode(errors="replace")
        self._stderr.close()
        self.found += [text for text in (self._window.GetOutput(), printed) if text.strip()]


def read_vtu(path: Path) -> Grid:
    """``path`` read by vtkXMLUnstructuredGridReader; AssertionError with VTK's messages if it reported any."""
    with Messages() as messages:
        reader = messages.watch(vtkXMLUnstructuredGridReader())
        reader.SetFileName(str(path))
        reader.Update()
    assert not messages.found and reader.GetErrorCode() == 0, f"{path.name}: " + "\n".join(messages.found)
    return as_grid(reader.GetOutput())


def read_xdmf(path: Path) -> tuple[tuple[float, ...], list[Grid]]:
    """(times, grid at each time) of the XDMF time series ``path`` read by VTK's XDMF reader, with no message."""
    with Messages() as messages:
        reader = messages.watch(vtkXdmfReader())
        reader.SetFileName(str(path))
        reader.UpdateInformation()
        times = reader.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS())
        grids = []
        for t in times:
            reader.UpdateTimeStep(t)
            grids.append(as_grid(reader.GetOutputDataObject(0)))
    assert not messages.found, f"{path.name}: " + "\n".join(messages.found)
    return times, grids


# --- what the files must hold ----------------------------------------------------------------------
def collection(path: Path) -> list[tuple[float, str]]:
    """(time, file) of each data set of the PVD file ``path``, checked as ParaView reads a collection: a
    VTKFile of type Collection, each DataSet with a time, part 0 and a file beside the collection."""
    root = ET.parse(path).getroot()
    assert (root.tag, root.get("type")) == ("VTKFile", "Collection")
    entries = []
    for dataset in root.find("Collection").findall("DataSet"):
        name = dataset.get("file")
        assert dataset.get("part") == "0" and Path(name).name == name and (path.parent / name).is_file(), name
        entries.append((float(dataset.get("timestep")), name))
    times = [t for t, _ in entries]
    assert times == sorted(set(times)), times
    return entries


def von_mises(stress: np.ndarray) -> np.ndarray:
    """√(3/2 s:s) of the 3 × 3 stresses (k, 9), s the deviator."""
    tensors = stress.reshape(-1, 3, 3)
    deviator = tensors - np.trace(tensors, axis1=1, axis2=2)[:, None, None] * np.eye(3) / 3
    return np.sqrt(1.5 * np.einsum("kij,kij->k", deviator, deviator))


def assert_close(actual, expected, name):
    """Equal to 1e-12 of the largest value (exactly where the values are exact)."""
    expected = np.asarray(expected, dtype=float)
    scale = np.nanmax(np.abs(expected)) if np.isfinite(expected).any() else 0.0
    np.testing.assert_allclose(actual, expected, rtol=1e-12, atol=1e-12 * scale, err_msg=name)


def padded(vectors: np.ndarray) -> np.ndarray:
    """Vectors (n, d) as (n, 3), z = 0 in 2D."""
    return np.column_stack([vectors, np.zeros((len(vectors), 3 - vectors.shape[1]))])


def check_arrays(grid: Grid, expected: dict[str, int], layer: set[str], center: str):
    """The arrays of ``grid`` at ``center`` ("point" or "cell") are ``expected`` (name: components) and the
    names ``layer`` (scalars), each of its number of components, integers where it must be."""
    arrays = getattr(grid, f"{center}_data")
    assert set(arrays) == set(expected) | layer, (center, sorted(arrays))
    for name, values in arrays.items():
        components = expected.get(name, 1)
        assert values.shape == ((len(values),) if components == 1 else (len(values), components)), name
        assert values.dtype == (np.int32 if name in INTEGERS else np.float64), (name, values.dtype)
        assert grid.component_names.get(name, TENSOR) == TENSOR, name  # 9 components: XX … ZZ


def check_fields(fields: Path, dim: int, xdmf: bool) -> dict[int, tuple[Grid, Grid]]:
    """Read every file of the run's folder ``fields`` with VTK and check it against the run's other files
    (check_body, check_contact); the PVD collections list every VTU file at the times of solution.npz; the
    XDMF series (``xdmf``: there, else absent) hold the VTU files' grids. Returns {step: (body, contact)
    as VTK read them}."""
    run = fields.parent
    solution = dict(np.load(run / "solution.npz"))
    table = pd.read_csv(run / "contact.csv", keep_default_na=False, na_values=[""])
    history = pd.read_csv(run / "history.csv")
    body_files, contact_files = collection(fields / "body.pvd"), collection(fields / "contact.pvd")
    assert {name for _, name in body_files + contact_files} == {p.name for p in fields.glob("*.vtu")}
    steps = solution["steps"].tolist()
    assert [t for t, _ in body_files] == [t for t, _ in contact_files] == solution["times"].tolist()
    assert [name for _, name in body_files] == [f"body_{n:05d}.vtu" for n in steps]
    assert [name for _, name in contact_files] == [f"contact_{n:05d}.vtu" for n in steps]
    read = {}
    for k, n in enumerate(steps):
        body = read_vtu(fields / f"body_{n:05d}.vtu")
        check_body(body, {name: values[k] if name in ("displacement", "stress", "z") else values
                          for name, values in solution.items()}, history[history["step"] == n].iloc[-1], dim)
        contact = read_vtu(fields / f"contact_{n:05d}.vtu")
        rows = table[table["step"] == n]
        rows = rows[rows["substep"] == rows["substep"].max()]  # those at t_n
        np.testing.assert_array_equal(rows["node"], solution["contact_nodes"])
        check_contact(contact, rows, history[history["step"] == n].iloc[-1], solution["xi"][k], body, dim)
        read[n] = body, contact
    assert (fields / "body.xdmf").exists() == (fields / "contact.xdmf").exists() == xdmf
    if xdmf:
        for series, index in (("body", 0), ("contact", 1)):
            times, grids = read_xdmf(fields / f"{series}.xdmf")
            assert list(times) == solution["times"].tolist()
            for n, grid in zip(steps, grids):
                check_same_grid(grid, read[n][index], series == "contact" and dim == 2)
    return read


def check_body(body: Grid, solution: dict, history: pd.Series, dim: int):
    """The body at a field step as VTK read it against ``solution`` (solution.npz, its fields at that step):
    the points, the elements, their arrays; displacement, stress and z equal, von Mises that of the stress;
    the error indicator's (Σ η_K²)^½ the step's error estimate in ``history`` (its row of history.csv)."""
    elements = solution["triangles" if dim == 2 else "tetrahedra"].T
    np.testing.assert_array_equal(body.points, padded(solution["points"].T))
    assert (body.types == BODY_CELLS[dim]).all() and len(body.types) == len(elements)
    np.testing.assert_array_equal(body.cells, elements)
    check_arrays(body, BODY_POINT_ARRAYS, set(), "point")
    check_arrays(body, {**BODY_CELL_ARRAYS, **({"z": 9} if "z" in solution else {}),
                        **({"error_indicator": 1} if "error_estimate" in history else {})}, set(), "cell")
    np.testing.assert_array_equal(body.point_data["displacement"], padded(solution["displacement"]))
    stress = body.cell_data["stress"].reshape(-1, 3, 3)
    np.testing.assert_array_equal(stress[:, :dim, :dim], solution["stress"])
    assert not stress[:, :dim, dim:].any() and not stress[:, dim:, :dim].any()  # 2D: σ13 = σ23 = 0
    assert_close(body.cell_data["von_mises"], von_mises(body.cell_data["stress"]), "von_mises")
    if "z" in solution:
        np.testing.assert_array_equal(body.cell_data["z"].reshape(-1, 3, 3)[:, :dim, :dim], solution["z"])
    if "error_estimate" in history:
        assert_close(np.sqrt((body.cell_data["error_indicator"] ** 2).sum()), history["error_estimate"],
                     "error_indicator")


def check_contact(contact: Grid, rows: pd.DataFrame, history: pd.Series, xi: np.ndarray, body: Grid, dim: int):
    """The contact part at a field step as VTK read it against ``rows`` (those of contact.csv at t_n, one per
    node): the points, the contact arrays, the status by its name, the normals, the layer parameters (NaN
    for an empty cell); ξ that of solution.npz; the pressure the sum of its parts, the contact force −w p ν
    and its sum the contact force of ``history`` (the step's row of history.csv); the displacement the
    body's at the node."""
    axes = "xyz"[:dim]
    layer = set(rows.columns[rows.columns.get_loc("substep") + 1:])
    assert len(rows) == len(contact.points) == len(xi)
    np.testing.assert_array_equal(contact.points, padded(rows[list(axes)].to_numpy()))
    assert (contact.types == CONTACT_CELLS[dim]).all() and len(contact.types) > 0
    assert contact.cells.shape[1] == dim and contact.cells.max() < len(contact.points)
    check_arrays(contact, CONTACT_POINT_ARRAYS, layer, "point")
    data = contact.point_data
    for name in CONTACT_ARRAYS[:-1]:
        np.testing.assert_array_equal(data[name], rows[name], err_msg=name)
    np.testing.assert_array_equal(np.asarray(STATUS_NAMES)[data["status"]], rows["status"])
    np.testing.assert_array_equal(data["xi"], xi)
    np.testing.assert_array_equal(data["pressure"], data["pressure_compliance"] + data["pressure_rigid"])
    normal = padded(rows[[f"normal_{c}" for c in axes]].to_numpy())
    np.testing.assert_array_equal(data["normal"], normal)
    assert_close(data["contact_force"], -normal * (rows["weight"].to_numpy() * data["pressure"])[:, None],
                 "contact_force")
    assert_close(data["contact_force"].sum(axis=0)[:dim], history[[f"contact_force_{c}" for c in axes]],
                 "the contact force of history.csv")
    np.testing.assert_array_equal(data["displacement"], body.point_data["displacement"][rows["node"]])
    for name in layer - {"part"}:
        np.testing.assert_array_equal(data[name], rows[name].astype(float), err_msg=name)


def check_same_grid(grid: Grid, vtu: Grid, polylines: bool = False):
    """``grid`` (of an XDMF file) is the VTU file's: points, cells, arrays, their types and values (NaN
    where the VTU file has NaN). XDMF has no linear line cell: a 2D contact part's segments are poly lines
    of 2 points there (``polylines``)."""
    np.testing.assert_array_equal(grid.points, vtu.points)
    np.testing.assert_array_equal(grid.cells, vtu.cells)
    np.testing.assert_array_equal(grid.types, np.where(vtu.types == VTK_LINE, VTK_POLY_LINE, vtu.types)
                                  if polylines else vtu.types)
    for center in ("point_data", "cell_data"):
        mine, theirs = getattr(grid, center), getattr(vtu, center)
        assert set(mine) == set(theirs), center
        for name, values in mine.items():
            assert values.dtype == theirs[name].dtype, name
            np.testing.assert_array_equal(values, theirs[name], err_msg=name)


def check_against_result(read: dict[int, tuple[Grid, Grid]], result):
    """The arrays VTK read equal the run's own (``result``, in memory): σ33 of the plane reduction, the
    history z, the error indicator, each element's material, E and ν, the contact arrays at t_n and the
    layer parameters (the part of each node by its index in contact.parts)."""
    view, dim = result.discretization, result.dim
    surface = view.surface
    contact_rows = {name: result.contact_history(name, substeps=False) for name in CONTACT_ARRAYS}
    assert sorted(read) == sorted(result.fields)
    for n, (body, contact) in read.items():
        fields = result.fields[n]
        stress = body.cell_data["stress"].reshape(-1, 3, 3)
        assert_close(stress[:, :dim, :dim], fields.stress, "stress")
        assert_close(stress[:, 2, 2], fields.stress33 if dim == 2 else fields.stress[:, 2, 2], "stress33")
        assert_close(body.cell_data["von_mises"], fields.von_mises, "von_mises")
        np.testing.assert_array_equal(body.cell_data["material"], view.material)
        assert_close(body.cell_data["E"], view.materials.E, "E")
        assert_close(body.cell_data["nu"], view.materials.nu, "nu")
        assert ("z" in body.cell_data) == (fields.z is not None)
        if fields.z is not None:
            z = body.cell_data["z"].reshape(-1, 3, 3)
            assert_close(z[:, :dim, :dim], fields.z, "z")
            assert not z[:, dim:, :].any() and not z[:, :, dim:].any()
        assert ("error_indicator" in body.cell_data) == (fields.error_indicator is not None)
        if fields.error_indicator is not None:
            assert_close(body.cell_data["error_indicator"], fields.error_indicator, "error_indicator")
        assert_close(body.point_data["displacement"], padded(fields.displacement), "displacement")
        np.testing.assert_array_equal(contact.cells, surface.facets.T)
        for name in CONTACT_ARRAYS:
            assert_close(contact.point_data[name], contact_rows[name][n - 1], name)
        for name, values in view.layer.items():
            if name == "part":
                np.testing.assert_array_equal(np.asarray(surface.parts)[contact.point_data["part"]], values)
            else:
                np.testing.assert_array_equal(contact.point_data[name], np.asarray(values, dtype=float), name)


# --- the writer ------------------------------------------------------------------------------------
@pytest.mark.parametrize("cell_type, vtk_type, nodes", [("line", VTK_LINE, 2), ("triangle", VTK_TRIANGLE, 3),
                                                        ("tetra", VTK_TETRA, 4)])
def test_vtk_reads_every_kind_of_array_written(tmp_path, cell_type, vtk_type, nodes):
    """write_vtu's arrays as VTK reads them: floats as Float64, Int32 and Int64 as such, booleans as UInt8,
    scalars of one component, vectors of 3, tensors of 9 named XX … ZZ, a name XML must escape; the cells
    one by one, each of its type."""
    rng = np.random.default_rng(5)
    points, cells = rng.random((9, 3)), rng.integers(0, 9, size=(6, nodes))
    point_data = {"u": rng.random((9, 3)), 'a<b & "c"': rng.random(9), "n": np.arange(9, dtype=np.int64) - 2**40}
    cell_data = {"sigma": rng.random((6, 9)), "material": np.arange(6, dtype=np.int32),
                 "flag": np.array([True, False, True, True, False, False]), "s": np.array([np.nan, -1, 0, 1, 2, 3.5])}
    write_vtu(tmp_path / "grid.vtu", VtuGrid(points, cell_type, cells), point_data, cell_data)
    grid = read_vtu(tmp_path / "grid.vtu")
    np.testing.assert_array_equal(grid.points, points)
    np.testing.assert_array_equal(grid.cells, cells)
    assert (grid.types == vtk_type).all() and len(grid.types) == 6
    for written, read in ((point_data, grid.point_data), (cell_data, grid.cell_data)):
        assert list(read) == list(written)
        for name, values in written.items():
            assert read[name].dtype == (np.uint8 if values.dtype == bool else values.dtype), name
            np.testing.assert_array_equal(read[name], values, err_msg=name)
    assert grid.component_names == {"sigma": TENSOR}


# --- the runs --------------------------------------------------------------------------------------
def coated_case(dim: int) -> dict:
    """A 2D half disc or a 3D quarter ball of two materials by region (the coating viscoplastic), on a gap
    that leaves nodes in all three contact states at every field step; the error estimate; XDMF."""
    if dim == 2:
        case = half_disc_case(h=0.15, load=60.0)
        case["mesh"]["coating"], case["contact"]["gap"] = 0.3, "0.2*x*x"
    else:
        case = ball_case(h=0.4)
        case["mesh"]["coating"], case["contact"]["gap"] = 0.35, "0.1*(x*x + y*y)"
    case["material"] = copy.deepcopy(MATERIALS)
    case["output"] = {"field_steps": [3, 7, 11], "xdmf": True, "error_estimate": True, "progress": False}
    return case


@pytest.fixture(scope="module", params=[2, 3], ids=["2d", "3d"])
def coated(request, tmp_path_factory):
    """(run directory, result in memory, dimension) of coated_case written by ``vpcontact run``."""
    folder = tmp_path_factory.mktemp(f"coated_{request.param}d")
    path = folder / "case.toml"
    path.write_text(tomli_w.dumps(coated_case(request.param)))
    status, _, stderr = run_cli("run", path, "--out", folder / "out", "--quiet")
    assert status == 0, stderr
    return folder / "out", vpcontact.solve(path), request.param


def test_vtk_reads_every_file_of_a_run_of_two_materials(coated):
    """Every VTU file VTK reads whole, as the other files of the run say (the history z, the estimate, the
    materials), all three contact states; the XDMF series as the VTU files; and as the run in memory."""
    out, result, dim = coated
    read = check_fields(out / "fields", dim, xdmf=True)
    assert sorted(read) == [3, 7, 11]
    for n, (body, contact) in read.items():
        assert set(body.cell_data["material"]) == {0, 1}
        for index, material in enumerate(MATERIALS):  # E and ν of each element: those of its region's material
            mine = body.cell_data["material"] == index
            assert (body.cell_data["E"][mine] == material["E"]).all() and (body.cell_data["nu"][mine] == material["nu"]).all()
        z = np.abs(body.cell_data["z"]).max(axis=1)
        assert z[body.cell_data["material"] == 1].max() > 0 and not z[body.cell_data["material"] == 0].any()
        assert set(contact.point_data["status"]) == {0, 1, 2}  # separated, in compliance, at the limit
        separated = contact.point_data["status"] == 0
        assert (contact.point_data["penetration"][separated] <= 0).all()
        assert (contact.point_data["penetration"][~separated] > 0).all()
        assert set(contact.point_data) == set(CONTACT_POINT_ARRAYS) | {"g", "c_v", "alpha", "beta"}
        assert (contact.point_data["g"] == 0.2).all()
    check_against_result(read, result)


@pytest.mark.parametrize("dim", [2, 3])
def test_vtk_reads_the_files_of_two_contact_parts(tmp_path, dim):
    """Two contact parts of two layer families: each node's part (an integer, its index in contact.parts)
    and the parameters of its law (NaN where its law has not that parameter), in the VTU and XDMF files."""
    case, part, _ = split_case(tmp_path, dim)
    case = two_parts_form(dict(case), part, LAYERS["two families"])
    case["output"] = {"field_steps": [2, 5, 11], "xdmf": True}
    result = vpcontact.solve(case)
    out = vpcontact.write_run(result, tmp_path / "run")
    read = check_fields(out / "fields", dim, xdmf=True)
    check_against_result(read, result)
    contact = read[11][1].point_data
    assert set(contact["part"]) == {0, 1}
    assert np.isnan(contact["value"][contact["part"] == 0]).all() and (contact["value"][contact["part"] == 1] == 300).all()
    assert (contact["c_v"][contact["part"] == 0] == 100).all() and np.isnan(contact["c_v"][contact["part"] == 1]).all()


def test_vtk_reads_the_files_of_a_3d_run_without_xdmf(tmp_path):
    result = vpcontact.solve(block_3d_case())
    out = vpcontact.write_run(result, tmp_path / "run")
    read = check_fields(out / "fields", 3, xdmf=False)
    check_against_result(read, result)
    assert {"z", "error_indicator"}.isdisjoint(read[11][0].cell_data)  # elastic, without the estimate
    assert set(read[11][1].point_data["status"]) == {0, 1, 2}


def test_vtk_reads_the_fields_of_every_cycle_of_an_adaptive_run(tmp_path):
    case = half_disc_case(h=0.25)
    case["adapt"] = {"cycles": 2, "theta": 0.5}
    case["output"] = {"field_steps": [5, 11], "progress": False}
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    status, _, stderr = run_cli("run", path, "--out", tmp_path / "run", "--quiet")
    assert status == 0, stderr
    folders = sorted((tmp_path / "run").rglob("fields"))
    assert [f.relative_to(tmp_path / "run").as_posix() for f in folders] == ["cycles/1/fields", "cycles/2/fields"]
    cells = [len(check_fields(folder, 2, xdmf=False)[11][0].cells) for folder in folders]
    assert cells[1] > cells[0]  # the second cycle's refined mesh


def test_a_file_vtk_cannot_read_whole_fails_the_check(coated):
    """The check catches what VTK reports: the connectivity of several components written before (VTK read
    no cell of it), and a file cut short."""
    out, _, _ = coated
    good = (out / "fields" / "body_00011.vtu").read_text()
    bad = out.parent / "bad.vtu"
    bad.write_text(good.replace('Name="connectivity" format', 'Name="connectivity" NumberOfComponents="3" format'))
    with pytest.raises(AssertionError, match="connectivity"):
        read_vtu(bad)
    bad.write_text(good[: len(good) // 2])
    with pytest.raises(AssertionError, match="Error parsing XML"):
        read_vtu(bad)
    bad.unlink()


def test_to_pyvista_is_the_body_file_vtk_reads(coated):
    """result.to_pyvista(step) holds the points, cells and arrays of the body's VTU file of that step."""
    pytest.importorskip("pyvista")  # optional: the extra "pyvista"
    out, result, _ = coated
    for n in result.fields:
        vtu, grid = read_vtu(out / "fields" / f"body_{n:05d}.vtu"), as_grid(result.to_pyvista(n))
        np.testing.assert_array_equal(grid.points, vtu.points)
        np.testing.assert_array_equal(grid.cells, vtu.cells)
        np.testing.assert_array_equal(grid.types, vtu.types)
        for center in ("point_data", "cell_data"):
            assert getattr(grid, center).keys() == getattr(vtu, center).keys()
            for name, values in getattr(grid, center).items():
                assert values.dtype == getattr(vtu, center)[name].dtype, name
                assert_close(values, getattr(vtu, center)[name], name)


def test_pyvista_reads_the_collections(coated):
    """pyvista's PVDReader (ParaView's reading of a .pvd, in Python): the field steps' times, and at each
    the one data set of that step's file with all its cells."""
    pyvista = pytest.importorskip("pyvista")  # optional: the extra "pyvista"
    out, result, _ = coated
    times = [float(result.discretization.times[n - 1]) for n in sorted(result.fields)]
    for series in ("body", "contact"):
        reader = pyvista.get_reader(out / "fields" / f"{series}.pvd")
        assert isinstance(reader, pyvista.PVDReader) and reader.time_values == times
        for t, n in zip(times, sorted(result.fields)):
            reader.set_active_time_value(t)
            blocks = reader.read()
            vtu = read_vtu(out / "fields" / f"{series}_{n:05d}.vtu")
            assert len(blocks) == 1 and blocks[0].n_cells == len(vtu.cells) > 0
            np.testing.assert_array_equal(blocks[0].point_data["displacement"], vtu.point_data["displacement"])
