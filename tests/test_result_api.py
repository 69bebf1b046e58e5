"""Looking at a result from Python, in 2D and 3D: repr, the history and contact tables (pandas) against the
files the writers write and against Result.series / contact_history, result.plot's figures against the
numbers they draw, result.to_pyvista, and vpcontact.write_run with the refusals of `vpcontact run --out`."""

import io
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from matplotlib import colormaps
from matplotlib.collections import PathCollection, PolyCollection, TriMesh
from matplotlib.colors import Normalize, to_hex
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

import vpcontact
from vpcontact.case.translate import output_options
from vpcontact.results import plots
from vpcontact.laws.contact import STATUS_NAMES
from vpcontact.results.columns import INTEGER_COLUMNS
from vpcontact.results.result import REPR_MESSAGE
from conftest import block_3d_case, half_disc_case, snapshot_tree


def curved_2d_case():
    """The paper's half disc with a viscoplastic body (z ≠ 0), the error estimate (η_K) and Newton limited to
    4 iterations, so that a step is cut: the history has a sub-step row."""
    case = half_disc_case(h=0.25, load=20.0, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["material"]["viscoplastic"] = {"law": "relaxation", "mu": 2.0, "E_inf": 500.0, "nu_inf": 0.3}
    case["solver"]["max_iterations"] = 4
    case["output"] = {"field_steps": [5, 11], "error_estimate": True}
    return case



@pytest.fixture(scope="module")
def run_2d():
    result = vpcontact.solve(curved_2d_case())
    assert result.status == "complete" and result.step_cuts > 0 and len(result.rows) > result.steps
    return result


@pytest.fixture(scope="module")
def run_3d():
    result = vpcontact.solve(block_3d_case())
    assert set(result.contact_history("status")[-1]) == {0, 1, 2}  # every state occurs
    return result


@pytest.fixture(scope="module")
def written(run_2d, run_3d, tmp_path_factory):
    """The run directories of both runs, written by vpcontact.write_run."""
    folder = tmp_path_factory.mktemp("written")
    return {2: vpcontact.write_run(run_2d, folder / "2d"), 3: vpcontact.write_run(run_3d, folder / "3d")}


@pytest.fixture(params=[2, 3])
def dim(request):
    return request.param


@pytest.fixture
def run(dim, run_2d, run_3d):
    return {2: run_2d, 3: run_3d}[dim]


def step_rows(result):
    """Step n -> its history row at t_n, from the history's own columns: the last row of each step
    (an independent reading of the rule of Result.ends_step, for a complete run)."""
    steps = result.series("step").astype(int)
    return {n: int(np.flatnonzero(steps == n)[-1]) for n in range(1, result.steps + 1)}


# --- repr ------------------------------------------------------------------------------------------
def test_repr_is_one_short_line_of_the_run(run, dim):
    text = repr(run)
    assert "\n" not in text and len(text) < 160, text
    cuts = f", {run.step_cuts} step cut" if run.step_cuts else ""
    view = run.discretization
    assert text == (f"Result(complete, {dim}D, {view.mesh.mesh.p.size} dofs, {view.surface.size} contact nodes, "
                    f"11/11 steps{cuts}, method {run.method}, {run.wall_time_s:.3g} s)")
    assert run.method in ("condensed", "full", "iterative")


def test_repr_of_a_failed_run_adds_its_message_on_a_second_line():
    case = half_disc_case(h=0.25)
    case["solver"].update(max_iterations=1, max_step_cuts=0)
    result = vpcontact.solve(case)
    first, second = repr(result).split("\n")
    assert first.startswith("Result(failed, 2D, ") and ", 0/11 steps, " in first
    assert len(result.message) > REPR_MESSAGE  # cut: the whole is result.message
    assert second == f"  {result.message[:REPR_MESSAGE]} …" and "step 1 (t = 0.1) failed" in second


# --- tables ----------------------------------------------------------------------------------------
def test_history_is_history_csv(run, dim, written):
    table = run.history
    assert list(table.columns) == list(run.columns) and len(table) == len(run.rows)
    for column in table.columns:
        assert table[column].dtype == (np.int64 if column in INTEGER_COLUMNS else np.float64), column
    pd.testing.assert_frame_equal(table, pd.read_csv(written[dim] / "history.csv"), check_exact=True)


def test_history_rows_at_the_step_times_are_those_of_series(run_2d):
    table = run_2d.history
    at_steps = table[run_2d.ends_step()]
    assert len(table) > len(at_steps) == run_2d.steps == 11  # a step was cut: one row more
    assert at_steps["step"].tolist() == list(range(1, 12))
    np.testing.assert_array_equal(at_steps["t"], run_2d.discretization.times.at(np.arange(1, 12)))
    for column in table.columns:
        np.testing.assert_array_equal(at_steps[column], run_2d.series(column, substeps=False), err_msg=column)
        np.testing.assert_array_equal(table[column], run_2d.series(column), err_msg=column)
    assert table["error_estimate"].gt(0).all()


def test_contact_table_is_contact_csv_at_each_step(run, dim, written):
    """Every step's table equals the rows of contact.csv at t_n (the last sub-step of step n), bit for bit."""
    csv = pd.read_csv(written[dim] / "contact.csv")
    last = csv.groupby("step")["substep"].transform("max")
    for n in range(1, run.steps + 1):
        table = run.contact_table(n)
        rows = csv[(csv["step"] == n) & (csv["substep"] == last)].reset_index(drop=True)
        assert table.attrs == {"step": n, "t": rows["t"].iloc[0]}
        shared = [c for c in table.columns if c in rows.columns and c != "status"]
        assert len(shared) == 2 + 2 * dim + 5  # node, weight, coordinates, normal, contact arrays
        pd.testing.assert_frame_equal(table[shared], rows[shared], check_exact=True)
        assert table["status"].astype(str).tolist() == rows["status"].tolist()
    pd.testing.assert_frame_equal(run.contact_table(), run.contact_table(run.steps))  # the default: the last step


def test_contact_table_agrees_with_the_history_and_contact_history(run, dim):
    rows = step_rows(run)
    forces = np.column_stack([run.series(f"contact_force_{c}") for c in "xyz"[:dim]])
    for n, row in rows.items():
        table = run.contact_table(n)
        for name in ("penetration", "xi", "K", "pressure_compliance", "pressure_rigid"):
            np.testing.assert_array_equal(table[name], run.contact_history(name, substeps=False)[n - 1])
        pressure = table["pressure_compliance"] + table["pressure_rigid"]
        np.testing.assert_array_equal(table["normal_stress"], -pressure)
        assert table["normal_stress"][run.probe] == run.series("normal_stress_probe")[row]
        # the resultant of the nodal pressures, −Σ w_i p_i ν_i, is the history's contact force
        normals = table[[f"normal_{c}" for c in "xyz"[:dim]]].to_numpy()
        np.testing.assert_allclose(-(table["weight"] * pressure).to_numpy() @ normals, forces[row],
                                   rtol=1e-12, atol=1e-12 * np.abs(forces).max())
        counts = table["status"].value_counts()
        assert [counts[name] for name in STATUS_NAMES] == [run.series(c)[row] for c in
                                                          ("nodes_separated", "nodes_in_compliance", "nodes_at_limit")]
    assert list(table["status"].cat.categories) == list(STATUS_NAMES)
    np.testing.assert_array_equal(table["node"], run.discretization.surface.nodes)
    assert ("arc_length" in table.columns) == (dim == 2)


def test_arc_length_runs_along_the_bottom_arc(run_2d):
    """The half disc's Γ3 is the arc of the unit circle from its bottom (0, 0) to (1, 1): the arc length is
    the sum of the chords from the bottom node, under the angle and close to it, a quarter of 2π at the end."""
    table = run_2d.contact_table().sort_values("x")
    chords = np.hypot(np.diff(table["x"]), np.diff(table["y"]))
    np.testing.assert_allclose(table["arc_length"], np.concatenate([[0.0], np.cumsum(chords)]), rtol=1e-14)
    angle = np.arctan2(table["x"], 1.0 - table["y"])
    assert np.all(table["arc_length"] <= angle + 1e-14) and table["arc_length"].iloc[-1] > 0.99 * np.pi / 2


def test_contact_table_names_the_part_of_each_node(tmp_path):
    """Γ3 of two contact parts (the half disc's arc split at a node, as in tests/test_contact_parts.py): the
    part of each node, a category of the parts' names, is contact.csv's."""
    from vpcontact.mesh import half_disc
    from test_contact_parts import LAYERS, two_parts_form, write_split_mesh

    mesh = half_disc(0.25)
    x = mesh.mesh.p[0, mesh.nodes("bottom_arc")]
    write_split_mesh(tmp_path / "split.msh", mesh, "bottom_arc", float(x[np.argmin(np.abs(x - 0.5))]))
    case = half_disc_case(h=0.25)
    case["mesh"] = {"file": str(tmp_path / "split.msh")}
    result = vpcontact.solve(two_parts_form(case, "bottom_arc", LAYERS["two families"]))
    table = result.contact_table()
    assert list(table["part"].cat.categories) == ["bottom_arc_below", "bottom_arc_above"]
    assert set(table["part"]) == {"bottom_arc_below", "bottom_arc_above"}
    csv = pd.read_csv(vpcontact.write_run(result, tmp_path / "out") / "contact.csv")
    assert table["part"].astype(str).tolist() == csv[csv["step"] == 11]["part"].tolist()


@pytest.mark.parametrize("step, words", [(12, "step 12 is not a step the run has done (steps 1 to 11)"),
                                         (0, "step 0 is not a step"), (True, "expected a step number"),
                                         ("5", "expected a step number")])
def test_a_step_not_done_is_refused(run_2d, step, words):
    with pytest.raises(vpcontact.CaseError) as error:
        run_2d.contact_table(step)
    assert words in str(error.value)


# --- figures ---------------------------------------------------------------------------------------
def test_time_series_draws_the_history_columns(run_2d):
    columns = ["K_probe", "error_estimate"]
    figure = run_2d.plot.time_series(columns)
    history = run_2d.history
    for ax, column in zip(figure.axes, columns):
        (line,) = ax.get_lines()
        np.testing.assert_array_equal(line.get_xdata(), history["t"])
        np.testing.assert_array_equal(line.get_ydata(), history[column])


def state_counts(ax):
    """[separated, in compliance, at limit]: the points of the node-state scatters of a panel, by colour."""
    colors = {to_hex(color): state for state, color in plots.STATE_COLORS.items()}
    counts = [0, 0, 0]
    for collection in ax.collections:
        if isinstance(collection, PathCollection) and len(collection.get_offsets()):
            counts[colors[to_hex(collection.get_facecolor()[0])]] += len(collection.get_offsets())
    return counts


def test_contact_pressure_at_one_step(run, dim):
    figure = run.plot.contact_pressure(step=5)
    panel = figure.axes[0]
    table = run.contact_table(5)
    pressure = (table["pressure_compliance"] + table["pressure_rigid"]).to_numpy()
    if dim == 2:
        (line,) = panel.get_lines()
        np.testing.assert_array_equal(line.get_ydata(), pressure[np.argsort(table["arc_length"])])
    else:
        (patch,) = [c for c in panel.collections if isinstance(c, TriMesh)]
        np.testing.assert_array_equal(patch.get_array(), pressure)
    assert state_counts(panel) == table["status"].value_counts()[list(STATUS_NAMES)].tolist()


def test_states_draw_the_penetration_and_the_state_of_each_node(run, dim):
    figure = run.plot.states(step=8)
    panel = figure.axes[0]
    table = run.contact_table(8)
    assert panel.get_title(loc="left" if dim == 2 else "center").startswith(f"t = {table.attrs['t']:g}")
    assert state_counts(panel) == table["status"].value_counts()[list(STATUS_NAMES)].tolist()
    if dim == 2:
        order = np.argsort(table["arc_length"].to_numpy())
        penetration, limit = panel.get_lines()
        np.testing.assert_array_equal(penetration.get_xdata(), table["arc_length"].to_numpy()[order])
        np.testing.assert_array_equal(penetration.get_ydata(), table["penetration"].to_numpy()[order])
        np.testing.assert_array_equal(limit.get_ydata(), np.full(table.shape[0], 0.2))  # g of the case
        assert limit.get_linestyle() == "--"
        # at the limit means d = g: the markers of those nodes sit on the dashed line
        assert np.allclose(table["penetration"][table["status"] == "at_limit"], 0.2, rtol=1e-9)
    else:
        (patch,) = [c for c in panel.collections if isinstance(c, TriMesh)]
        np.testing.assert_array_equal(patch.get_array(), table["penetration"])


def facet_colors(values, everything):
    return colormaps[plots.STRESS_MAP](Normalize(everything.min(), everything.max())(values))


@pytest.mark.parametrize("field", ["sigma_xy", "displacement_y", "z_yy", "error_indicator", "sigma_zz"])
def test_the_deformed_2d_body_is_coloured_by_the_field_asked_for(run_2d, field):
    figure = run_2d.plot.deformed(step=5, field=field, scale=4.0)
    fields, mesh = run_2d.fields[5], run_2d.discretization.mesh.mesh
    expected = {"sigma_xy": fields.stress[:, 0, 1], "displacement_y": fields.displacement[:, 1],
                "z_yy": fields.z[:, 1, 1], "error_indicator": fields.error_indicator,
                "sigma_zz": fields.stress33}[field]
    body = figure.axes[0]
    if field == "displacement_y":  # per node: interpolated over each triangle
        (cells,) = [c for c in body.collections if isinstance(c, TriMesh)]
    else:
        (cells,) = [c for c in body.collections if isinstance(c, PolyCollection)]
        moved = mesh.p.T + 4.0 * fields.displacement
        np.testing.assert_allclose(np.array([path.vertices[:3] for path in cells.get_paths()]), moved[mesh.t.T],
                                   rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(cells.get_array(), expected)
    assert (cells.norm.vmin, cells.norm.vmax) == (expected.min(), expected.max())
    assert f"coloured by {field}" in figure.get_suptitle() and cells.colorbar.ax.get_ylabel() == field


@pytest.mark.parametrize("field", ["displacement", "sigma_yz"])
def test_the_deformed_3d_body_is_coloured_by_the_field_asked_for(run_3d, field):
    figure = run_3d.plot.deformed(field=field)
    figure.savefig(io.BytesIO(), format="png")  # the facets are projected when drawn
    (surface,) = [c for c in figure.axes[0].collections if isinstance(c, Poly3DCollection)]
    fields, mesh = run_3d.fields[11], run_3d.discretization.mesh.mesh
    boundary = mesh.boundary_facets()
    if field == "displacement":  # per node: each facet has the mean of its three nodes
        values = np.linalg.norm(fields.displacement, axis=1)
        shown = values[mesh.facets[:, boundary]].mean(axis=0)
    else:
        values = fields.stress[:, 1, 2]
        shown = values[mesh.f2t[0, boundary]]
    np.testing.assert_allclose(np.unique(surface.get_facecolor(), axis=0),
                               np.unique(facet_colors(shown, values), axis=0), atol=1e-12)
    # the colour bar spans the field's range (to the last bits matplotlib's limits keep of it)
    assert figure.axes[1].get_ylim() == pytest.approx((values.min(), values.max()), rel=1e-14, abs=0)


@pytest.mark.parametrize("fixture, field, words", [
    ("run_2d", "sigma_xxx", ["unknown field 'sigma_xxx'", "did you mean 'sigma_xx'", "valid fields: von_mises, "
                             "displacement, displacement_x, displacement_y, sigma_xx, sigma_xy, sigma_yy, sigma_zz, "
                             "z_xx, z_xy, z_yy, error_indicator"]),
    ("run_2d", "sigma_yx", ["did you mean 'sigma_xy'"]),
    ("run_2d", 3, ["unknown field 3"]),
    ("run_3d", "error_indicator", ["no error estimate", "output.error_estimate = true", "sigma_zz"]),
    ("run_3d", "z_xx", ["no viscoplastic history z", "valid fields: von_mises, displacement, displacement_x, "
                        "displacement_y, displacement_z, sigma_xx, sigma_xy, sigma_xz, sigma_yy, sigma_yz, sigma_zz"]),
])
def test_a_bad_field_name_is_a_case_error_naming_the_valid_ones(fixture, field, words, request):
    with pytest.raises(vpcontact.CaseError) as error:
        request.getfixturevalue(fixture).plot.deformed(field=field)
    message = str(error.value)
    assert "\n" not in message
    for word in words:
        assert word in message, (word, message)


# --- pyvista ---------------------------------------------------------------------------------------
def test_to_pyvista_holds_the_fields_of_the_step(run, dim):
    pyvista = pytest.importorskip("pyvista")  # the extra "pyvista" (140 MB of VTK) is not in "test"
    grid = run.to_pyvista(step=5)
    assert isinstance(grid, pyvista.UnstructuredGrid)
    fields, mesh = run.fields[5], run.discretization.mesh.mesh
    points = np.zeros((mesh.p.shape[1], 3))
    points[:, :dim] = mesh.p.T
    np.testing.assert_array_equal(grid.points, points)
    np.testing.assert_array_equal(grid.cells_dict[{2: pyvista.CellType.TRIANGLE, 3: pyvista.CellType.TETRA}[dim]],
                                  mesh.t.T)
    np.testing.assert_array_equal(grid.point_data["displacement"][:, :dim], fields.displacement)
    assert not grid.point_data["displacement"][:, dim:].any()
    stress = grid.cell_data["stress"].reshape(-1, 3, 3)
    np.testing.assert_array_equal(stress[:, :dim, :dim], fields.stress)
    np.testing.assert_array_equal(stress[:, 2, 2], fields.stress33 if dim == 2 else fields.stress[:, 2, 2])
    np.testing.assert_array_equal(grid.cell_data["von_mises"], fields.von_mises)
    assert ("z" in grid.cell_data, "error_indicator" in grid.cell_data) == ((dim == 2,) * 2)
    if dim == 2:
        np.testing.assert_array_equal(grid.cell_data["z"].reshape(-1, 3, 3)[:, :2, :2], fields.z)
        np.testing.assert_array_equal(grid.cell_data["error_indicator"], fields.error_indicator)
    assert grid.field_data["t"][0] == pytest.approx(0.5, rel=1e-15) and grid.field_data["step"][0] == 5
    assert run.to_pyvista().field_data["step"][0] == 11  # the default: the last field step
    with pytest.raises(vpcontact.CaseError, match=r"step 4 has no fields: the run kept them at steps \[5, 11\]"):
        run.to_pyvista(step=4)


def test_to_pyvista_without_pyvista_says_how_to_install_it(run_2d, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyvista", None)  # import pyvista raises ImportError
    with pytest.raises(vpcontact.CaseError, match="pip install pyvista"):
        run_2d.to_pyvista()


# --- write -----------------------------------------------------------------------------------------
def test_write_refuses_a_directory_that_is_not_empty_and_deletes_nothing(run_2d, tmp_path):
    out = tmp_path / "run"
    (out / "notes").mkdir(parents=True)
    (out / "notes" / "plan.txt").write_text("mine")
    (out / "case.toml").write_text("# my case")
    before = snapshot_tree(out)
    with pytest.raises(vpcontact.CaseError) as error:
        vpcontact.write_run(run_2d, out)
    assert isinstance(error.value, FileExistsError)  # as before, for code that catches that
    assert "\n" not in str(error.value) and f"'{out}' is not empty" in str(error.value)
    assert "overwrite=True" in str(error.value)
    assert snapshot_tree(out) == before
    # overwrite=True writes the outputs beside the user's files, which stay as they are
    assert vpcontact.write_run(run_2d, out, overwrite=True) == out
    after = snapshot_tree(out)
    assert {name: after[name] for name in before} == before
    assert {"summary.json", "history.csv", "contact.csv", "solution.npz", "fields/body.pvd"} <= set(after)
    pd.testing.assert_frame_equal(pd.read_csv(out / "history.csv"), run_2d.history, check_exact=True)


@pytest.mark.parametrize("make, words", [
    (lambda out: out.write_text("a file of mine"), ["exists and is not a directory"]),
    (lambda out: (out / "history.csv").mkdir(parents=True), ["history.csv' is a folder", "move it away"]),
    (lambda out: (out.mkdir(), (out / "fields").write_text("mine")), ["fields' is not a folder"]),
])
def test_write_refuses_what_stands_in_the_way_before_writing(run_2d, tmp_path, make, words):
    out = tmp_path / "run"
    make(out)
    before = snapshot_tree(out)
    for overwrite in (False, True):
        with pytest.raises(vpcontact.CaseError) as error:
            vpcontact.write_run(run_2d, out, overwrite=overwrite)
        assert "\n" not in str(error.value)
        for word in words:
            assert word in str(error.value), (word, str(error.value))
        assert snapshot_tree(out) == before


# --- imports ---------------------------------------------------------------------------------------
def test_the_modules_of_the_tables_figures_and_grids_load_pandas_matplotlib_pyvista_only_when_used():
    code = ("import sys, vpcontact.results.tables, vpcontact.results.result_plots, vpcontact.results.pyvista_grid\n"
            "print(sorted({'pandas', 'pyvista', 'matplotlib'} & set(sys.modules)))")
    process = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert process.returncode == 0, process.stderr
    assert process.stdout.splitlines()[-1] == "[]"


def test_a_complete_run_that_kept_no_fields_draws_its_last_step():
    """With output.field_steps = "none" a complete run still has its last step's fields (result.final): the
    deformed body and the pyvista grid use them; a run stopped early, without them, is refused in one line."""
    case = half_disc_case(h=0.25)
    result = vpcontact.solve(case)
    assert result.status == "complete" and not result.fields
    figure = result.plot.deformed(field="sigma_xy")
    (cells,) = [c for c in figure.axes[0].collections if isinstance(c, PolyCollection)]
    np.testing.assert_array_equal(cells.get_array(), result.final.stress[:, 0, 1])
    assert "t = 1.1" in figure.get_suptitle()
    loaded = vpcontact.load_case(case)
    loop = vpcontact.timeloop.loop.TimeLoop(vpcontact.build_problem(loaded), output_options(loaded.output))
    stopped = loop.run(stop=lambda: "stopped" if loop.state.step == 3 else None)
    with pytest.raises(vpcontact.CaseError, match="the run kept no fields"):
        stopped.plot.deformed()
