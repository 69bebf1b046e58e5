"""``output.xdmf``: the fields as an XDMF/HDF5 time series beside the VTU files, read back by meshio's
TimeSeriesReader: the mesh once, every field at every field step equal to the VTU files' and the run's,
the steps' times t_n, and an HDF5 file that holds the mesh once and grows by the fields only."""

import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

import vpcontact
from conftest import half_disc_case
from test_3d_runs import ball_case


def written(tmp_path, case: dict, name: str = "run"):
    """The result of ``case`` with ``output.xdmf`` and the folder it was written to."""
    result = vpcontact.solve({**case, "output": {**case["output"], "xdmf": True}})
    return result, vpcontact.write_run(result, tmp_path / name)


def read_series(path):
    """(points, cells, [(t, point data, cell data) of each step]) of an XDMF time series."""
    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        steps = [reader.read_data(k) for k in range(reader.num_steps)]
    return points, cells, steps


@pytest.mark.parametrize("dim", [2, 3])
def test_the_series_holds_the_vtu_fields_at_every_step(tmp_path, dim):
    case = half_disc_case(h=0.2, load=60.0) if dim == 2 else ball_case(h=0.4)
    case["output"]["field_steps"] = [3, 7, 11]
    result, out = written(tmp_path, case)
    fields = out / "fields"
    for series in ("body", "contact"):
        points, cells, steps = read_series(fields / f"{series}.xdmf")
        vtus = [meshio.read(fields / f"{series}_{n:05d}.vtu") for n in (3, 7, 11)]
        np.testing.assert_array_equal(points, vtus[0].points)  # 2D points padded with z = 0, as in the VTU files
        assert points.shape[1] == 3 and (dim == 3 or not points[:, 2].any())
        assert [c.type for c in cells] == [c.type for c in vtus[0].cells]
        np.testing.assert_array_equal(cells[0].data, vtus[0].cells[0].data)
        assert [t for t, _, _ in steps] == [result.discretization.times[n - 1] for n in (3, 7, 11)]
        for (t, point_data, cell_data), vtu in zip(steps, vtus):
            assert set(point_data) == set(vtu.point_data) and set(cell_data) == set(vtu.cell_data)
            for name, values in point_data.items():
                np.testing.assert_array_equal(values, vtu.point_data[name], err_msg=name)
            for name, values in cell_data.items():
                np.testing.assert_array_equal(values[0], vtu.cell_data[name][0], err_msg=name)
    # and equal to the run's own arrays
    _, _, steps = read_series(fields / "body.xdmf")
    for (_, point_data, cell_data), n in zip(steps, (3, 7, 11)):
        np.testing.assert_array_equal(point_data["displacement"][:, :dim], result.fields[n].displacement)
        np.testing.assert_array_equal(cell_data["stress"][0].reshape(-1, 3, 3)[:, :dim, :dim], result.fields[n].stress)
    _, _, steps = read_series(fields / "contact.xdmf")
    xi = result.contact_history("xi", substeps=False)
    for (_, point_data, _), n in zip(steps, (3, 7, 11)):
        np.testing.assert_array_equal(point_data["xi"], xi[n - 1])


def test_the_mesh_is_stored_once(tmp_path):
    """Every step's grid points to the one /mesh of the HDF5 file, whose size is the mesh's bytes once plus
    the fields' bytes of each step (computed from the VTU files), and a little per array."""
    case = half_disc_case(h=0.035)
    case["time"]["steps"] = 5
    case["output"]["field_steps"] = "all"
    _, out = written(tmp_path, case)
    fields = out / "fields"
    grids = ET.parse(fields / "body.xdmf").getroot().findall("./Domain/Grid/Grid")
    assert len(grids) == 5
    assert {g.find("./Topology/DataItem").text for g in grids} == {"body.h5:/mesh/cells"}
    assert {g.find("./Geometry/DataItem").text for g in grids} == {"body.h5:/mesh/points"}
    first = meshio.read(fields / "body_00001.vtu")
    mesh_bytes = 8 * first.points.size + 8 * first.cells[0].data.size
    field_bytes = sum(meshio.read(fields / f"body_{n:05d}.vtu").point_data["displacement"].nbytes +
                      sum(values[0].nbytes for values in meshio.read(fields / f"body_{n:05d}.vtu").cell_data.values())
                      for n in range(1, 6))
    with h5py.File(fields / "body.h5") as handle:
        arrays = []
        handle.visititems(lambda name, item: arrays.append(name) if isinstance(item, h5py.Dataset) else None)
    overhead = (fields / "body.h5").stat().st_size - mesh_bytes - field_bytes
    assert 0 <= overhead < 1024 * len(arrays) + 4096 < mesh_bytes, (overhead, len(arrays), mesh_bytes)


def test_overwrite_replaces_the_series(tmp_path):
    """A run without output.xdmf written over one with it leaves no XDMF or HDF5 file (nor temporaries)."""
    case = half_disc_case(h=0.2)
    case["output"]["field_steps"] = "final"
    _, out = written(tmp_path, case)
    assert {p.name for p in (out / "fields").glob("*.xdmf")} == {"body.xdmf", "contact.xdmf"}
    vpcontact.write_run(vpcontact.solve(case), out, overwrite=True)
    assert sorted(p.name for p in (out / "fields").iterdir()) == ["body.pvd", "body_00011.vtu", "contact.pvd",
                                                                  "contact_00011.vtu"]
