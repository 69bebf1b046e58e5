"""The writers of a run directory written without meshio and with each value turned into text once:
the VTU files read back (by meshio) as the arrays of the run, contact.csv byte for byte what csv.writer
writes row by row, solution.npz the same arrays."""

import csv
import io
import math

import meshio
import numpy as np
import pytest

import vpcontact
from conftest import half_disc_case, solved
from test_contact_parts import LAYERS, split_case, two_parts_form
from vpcontact.laws.contact import STATUS_NAMES
from vpcontact.results.columns import CONTACT_ARRAYS
from vpcontact.io.vtu import Grid, write_vtu
from vpcontact.io.run import write_run


def test_a_vtu_file_reads_back_as_the_arrays_written(tmp_path):
    """Every kind of array (scalars and vectors; float, Int32, Int64, bool) and a name that XML must escape
    come back from meshio with their values, for 2D and 3D cells."""
    rng = np.random.default_rng(3)
    for cell_type, nodes in (("triangle", 3), ("tetra", 4), ("line", 2)):
        points, cells = rng.random((7, 3)), rng.integers(0, 7, size=(5, nodes))
        point_data = {"u": rng.random((7, 3)), 'a<b & "c"': rng.random(7), "n": np.arange(7, dtype=np.int64)}
        cell_data = {"sigma": rng.random((5, 9)), "material": np.arange(5, dtype=np.int32),
                     "flag": np.array([True, False, True, True, False]), "s": -rng.random(5)}
        path = tmp_path / f"{cell_type}.vtu"
        write_vtu(path, Grid(points, cell_type, cells), point_data, cell_data)
        back = meshio.read(path)
        assert np.array_equal(back.points, points)
        assert [(block.type, block.data.tolist()) for block in back.cells] == [(cell_type, cells.tolist())]
        assert back.point_data.keys() == point_data.keys() and back.cell_data.keys() == cell_data.keys()
        for name, values in point_data.items():
            assert np.array_equal(back.point_data[name], values), name
        for name, values in cell_data.items():
            assert np.array_equal(back.cell_data[name][0], values), name


def test_a_vtu_array_of_the_wrong_length_is_refused(tmp_path):
    grid = Grid(np.zeros((3, 3)), "triangle", [[0, 1, 2]])
    with pytest.raises(ValueError, match="'u': 2 values for 3"):
        write_vtu(tmp_path / "x.vtu", grid, {"u": np.zeros((2, 3))})
    assert not (tmp_path / "x.vtu").exists()


def two_part_result(tmp_path, dim):
    """A run with two contact parts of two layer families (text and empty cells in contact.csv) in 2D
    (the half disc) or 3D (the block), every step a field step."""
    case, part, _ = split_case(tmp_path, dim)
    case = two_parts_form(dict(case), part, LAYERS["two families"])
    case["output"] = {"field_steps": "all"}
    return solved(case)


def contact_csv_row_by_row(problem, result) -> bytes:
    """contact.csv as csv.writer writes the rows one at a time (the writer before it was vectorized)."""
    surface = problem.surface
    layer = problem.law.parameters(surface.size)  # from the problem's law, not from the result's view of it
    if len(surface.parts) > 1:
        layer["part"] = np.asarray(surface.parts)[surface.owner]
    axes = "xyz"[:result.dim]
    buffer = io.StringIO(newline="")
    writer = csv.writer(buffer)
    writer.writerow(["step", "t", "node", *axes, *(f"normal_{c}" for c in axes), "weight", *CONTACT_ARRAYS,
                     "substep", *layer])
    for r, row in enumerate(result.rows):
        for j in range(surface.size):
            values = [result.contact[name][r][j] for name in CONTACT_ARRAYS]
            values[-1] = STATUS_NAMES[int(values[-1])]
            cells = [int(row["step"]), float(result.times[r]), int(surface.nodes[j]),
                     *(float(x) for x in surface.coordinates[:, j]), *(float(n) for n in surface.normals[:, j]),
                     float(surface.weights[j]), *(float(v) for v in values[:-1]), values[-1], int(row["substep"])]
            for column in layer.values():
                value = column[j]
                cells.append(None if isinstance(value, float) and math.isnan(value) else
                             value.item() if hasattr(value, "item") else value)
            writer.writerow(cells)
    return buffer.getvalue().encode()


@pytest.mark.parametrize("dim", [2, 3])
def test_the_run_directory_holds_the_arrays_of_the_run(tmp_path, dim):
    """contact.csv byte for byte as csv.writer writes it row by row (floats as repr, empty cells, the part
    names); the body and contact VTU files of every field step and solution.npz hold the run's arrays."""
    problem, result = two_part_result(tmp_path, dim)
    out = write_run(result, tmp_path / "run")
    assert (out / "contact.csv").read_bytes() == contact_csv_row_by_row(problem, result)
    assert len(result.fields) == 11
    surface, mesh = result.discretization.surface, result.discretization.mesh.mesh
    solution = np.load(out / "solution.npz")
    for k, (step, fields) in enumerate(sorted(result.fields.items())):
        body = meshio.read(out / "fields" / f"body_{step:05d}.vtu")
        assert np.array_equal(body.points[:, :dim], mesh.p.T) and not body.points[:, dim:].any()
        assert np.array_equal(body.cells[0].data, mesh.t.T)
        assert np.array_equal(body.point_data["displacement"][:, :dim], fields.displacement)
        stress = body.cell_data["stress"][0].reshape(-1, 3, 3)
        assert np.array_equal(stress[:, :dim, :dim], fields.stress)
        assert np.array_equal(body.cell_data["von_mises"][0], fields.von_mises)
        assert np.array_equal(body.cell_data["E"][0], result.discretization.materials.E)
        contact = meshio.read(out / "fields" / f"contact_{step:05d}.vtu")
        assert np.array_equal(contact.points[:, :dim], surface.coordinates.T)
        row = np.flatnonzero(result.ends_step() & (result.series("step") == step))[0]
        for name in CONTACT_ARRAYS:
            assert np.array_equal(contact.point_data[name], result.contact[name][row]), name
        assert np.array_equal(contact.point_data["part"], surface.owner)
        assert np.array_equal(solution["displacement"][k], fields.displacement)
        assert np.array_equal(solution["stress"][k], fields.stress)
    assert not np.isnan(contact.point_data["value"]).all() and np.isnan(contact.point_data["value"]).any()


def test_only_the_field_steps_asked_for_are_written(tmp_path):
    """field_steps = "none": no fields/ and no solution.npz (contact.csv still has every step); a list of
    steps: the VTU files of those steps alone."""
    case = half_disc_case(h=0.25)
    result = vpcontact.solve(case)
    out = write_run(result, tmp_path / "none")
    assert not (out / "fields").exists() and not (out / "solution.npz").exists()
    assert (out / "contact.csv").read_text().count("\n") == 1 + 11 * result.discretization.surface.size
    case["output"] = {"field_steps": [3, 11]}
    out = write_run(vpcontact.solve(case), tmp_path / "two")
    assert sorted(p.name for p in (out / "fields").iterdir()) == [
        "body.pvd", "body_00003.vtu", "body_00011.vtu", "contact.pvd", "contact_00003.vtu", "contact_00011.vtu"]
    assert np.load(out / "solution.npz")["steps"].tolist() == [3, 11]
