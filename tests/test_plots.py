"""The figures of a run (vpcontact.results.plots) in 2D and 3D, and output.figures in a run directory."""

import io
import json
import subprocess
import sys

import numpy as np
import pytest
import tomli_w
from matplotlib.collections import PathCollection, PolyCollection, TriMesh
from matplotlib.colors import to_hex
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

import vpcontact
from vpcontact.io import checkpoint
from vpcontact.results import plots
from vpcontact.cli import main
from vpcontact.laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED
from vpcontact.errors import CaseError
from vpcontact.io.outputs import write_outputs
from conftest import assert_refused, block_3d_case, half_disc_case, run_cli, snapshot_tree

PNG = b"\x89PNG\r\n\x1a\n"
FIGURE_FILES = ["contact_pressure.png", "deformed.png", "time_series.png"]


def flat_2d_case():
    """The half disc on a flat foundation (gap y, normal [0, -1]): nodes in all three states at the end."""
    case = half_disc_case(h=0.2, load=20.0, g=0.05, gap="y", normal=[0.0, -1.0],
                          stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["output"]["field_steps"] = [5, 11]
    return case



@pytest.fixture(scope="module")
def run_2d():
    return vpcontact.solve(flat_2d_case())


@pytest.fixture(scope="module")
def run_3d():
    return vpcontact.solve(block_3d_case())


def pressures(result):
    return result.contact_history("pressure_compliance") + result.contact_history("pressure_rigid")


def step_row(result, step):
    return int(np.flatnonzero(result.ends_step() & (result.series("step") == step))[0])


def state_counts(ax):
    """{state: number of points} of the node-state scatters of a panel, told apart by their colour."""
    colors = {to_hex(color): state for state, color in plots.STATE_COLORS.items()}
    counts = dict.fromkeys(plots.STATE_COLORS, 0)
    for collection in ax.collections:
        if isinstance(collection, PathCollection) and len(collection.get_offsets()):
            for color in {to_hex(c) for c in collection.get_facecolor()}:
                counts[colors[color]] += len(collection.get_offsets())
    return counts


@pytest.mark.parametrize("fixture", ["run_2d", "run_3d"])
def test_every_state_occurs_in_the_runs_drawn(fixture, request):
    """The test runs have nodes in all three states at the end (else the state tests below prove little)."""
    status = request.getfixturevalue(fixture).contact_history("status")[-1]
    assert set(status) == {SEPARATED, IN_COMPLIANCE, AT_LIMIT}


def test_default_steps_spread_over_the_run_end_with_the_last():
    class Done:
        def __init__(self, steps):
            self.completed_steps = steps

    assert plots.default_steps(Done(11)) == [2, 5, 8, 11]  # the paper's t = 0.2, 0.5, 0.8, 1.1
    assert plots.default_steps(Done(100)) == [25, 50, 75, 100]
    assert plots.default_steps(Done(3)) == [1, 2, 3]
    assert plots.default_steps(Done(1)) == [1]
    assert plots.default_steps(Done(0)) == []


def test_contact_patch_3d(run_3d):
    figure = plots.contact_pressure(run_3d)
    assert isinstance(figure, Figure)
    panels = figure.axes[:4]
    assert len(figure.axes) == 4  # the colour bar is an inset of the last panel
    steps = [2, 5, 8, 11]
    rows = [step_row(run_3d, n) for n in steps]
    assert [ax.get_title().splitlines()[0] for ax in panels] == [f"t = {run_3d.times[r]:g}" for r in rows]
    pressure, status = pressures(run_3d)[rows], run_3d.contact_history("status")[rows]
    x, y = run_3d.discretization.surface.coordinates[:2]
    for ax, p, s in zip(panels, pressure, status):
        (patch,) = [c for c in ax.collections if isinstance(c, TriMesh)]
        np.testing.assert_array_equal(patch.get_array(), p)
        assert patch.norm.vmin == pressure.min() and patch.norm.vmax == pressure.max()  # one shared scale
        assert state_counts(ax) == {state: int(np.sum(s == state)) for state in plots.STATE_COLORS}
        assert ax.get_aspect() == 1.0 and ax.get_xlabel() == "x"
    # zoomed: every node with pressure at the last time is inside, and the view is smaller than Γ3
    (x0, x1), (y0, y1) = panels[-1].get_xlim(), panels[-1].get_ylim()
    pressed = pressure[-1] > 0
    assert pressed.any()
    assert np.all((x[pressed] >= x0) & (x[pressed] <= x1) & (y[pressed] >= y0) & (y[pressed] <= y1))
    assert (x1 - x0) * (y1 - y0) < 0.8 * np.ptp(x) * np.ptp(y)
    legend = [text.get_text() for text in figure.legends[0].get_texts()]
    assert legend == [f"node {plots.STATE_LABELS[s]}" for s in plots.STATE_COLORS]


def test_a_contact_patch_is_seen_along_the_axis_of_its_normal():
    """Γ3 on the face x = 0 of a block pushed sideways: seen along x, on the (y, z) plane."""
    case = block_3d_case()
    case["boundary"] = {"dirichlet": [{"part": "front", "components": ["y"]}, {"part": "bottom", "components": ["z"]}],
                        "traction": [{"part": "right", "value": ["-30*t", "0", "0"]}]}
    case["contact"].update(part="left", normal=[-1, 0, 0], gap="y*y + z*z", probe=[0, 0, 0])
    result = vpcontact.solve(case)
    figure = plots.contact_pressure(result, steps=[11])
    (ax,) = figure.axes
    assert "seen along x, on the (y, z) plane" in figure.get_suptitle()
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("y", "z")
    y, z = result.discretization.surface.coordinates[1:]
    pressed = pressures(result)[-1] > 0
    (y0, y1), (z0, z1) = ax.get_xlim(), ax.get_ylim()
    assert pressed.any() and np.all((y[pressed] >= y0) & (y[pressed] <= y1) & (z[pressed] >= z0) & (z[pressed] <= z1))


def test_contact_profile_2d(run_2d):
    figure = plots.contact_pressure(run_2d, steps=[11, 3])
    panels = figure.axes
    assert len(panels) == 2
    rows = [step_row(run_2d, 3), step_row(run_2d, 11)]
    surface = run_2d.discretization.surface
    for ax, row in zip(panels, rows):
        (line,) = ax.get_lines()
        s, p = line.get_xdata(), line.get_ydata()
        # along Γ3 from its end of least x (the bottom point of the half disc): s grows by the segments' lengths
        order = np.argsort(surface.coordinates[0])  # the bottom arc is a graph over x
        np.testing.assert_allclose(p, pressures(run_2d)[row][order], rtol=0, atol=0)
        steps = np.linalg.norm(np.diff(surface.coordinates[:, order], axis=1), axis=0)
        np.testing.assert_allclose(s, np.concatenate([[0.0], np.cumsum(steps)]), rtol=1e-14)
        status = run_2d.contact_history("status")[row]
        assert state_counts(ax) == {state: int(np.sum(status == state)) for state in plots.STATE_COLORS}
        assert ax.get_title(loc="left").startswith(f"t = {run_2d.times[row]:g}")
    low, high = panels[0].get_ylim()
    assert low <= pressures(run_2d)[rows].min() and high >= pressures(run_2d)[rows].max()


def test_arc_length_of_a_curve_in_pieces():
    """Pieces one after another: s goes on without a jump between them, and the line breaks there."""
    coordinates = np.array([[3.0, 4.0, 0.0, 1.0, 5.0], [0.0, 0.0, 0.0, 0.0, 0.0]])
    segments = np.array([[0, 2], [1, 3]])  # the pieces 0–1 and 2–3, and the lone node 4
    order, s, breaks = plots.arc_length(coordinates, segments)
    assert order.tolist() == [0, 1, 2, 3, 4]
    assert s.tolist() == [0.0, 1.0, 1.0, 2.0, 2.0] and breaks.tolist() == [2, 4]
    # one open piece runs from its end of least x
    order, s, breaks = plots.arc_length(np.array([[2.0, 0.0, 1.0], [0.0, 0.0, 0.0]]), np.array([[0, 2], [2, 1]]))
    assert order.tolist() == [1, 2, 0] and s.tolist() == [0.0, 1.0, 2.0] and breaks.size == 0


def test_deformed_body_3d(run_3d):
    figure = plots.deformed_body(run_3d, scale=3.0)  # the last field step: 11
    figure.savefig(io.BytesIO(), format="png")  # the facets are projected when drawn
    body, bar = figure.axes
    (surface,) = [c for c in body.collections if isinstance(c, Poly3DCollection)]
    mesh, fields = run_3d.discretization.mesh.mesh, run_3d.fields[11]
    boundary = mesh.boundary_facets()
    assert len(surface.get_paths()) == boundary.size
    assert bar.get_ylim() == (fields.von_mises.min(), fields.von_mises.max())
    # each boundary facet has the colour of the von Mises stress of its element (drawn in depth order)
    expected = plots_colors(fields.von_mises[mesh.f2t[0, boundary]], fields.von_mises)
    np.testing.assert_allclose(np.unique(surface.get_facecolor(), axis=0), np.unique(expected, axis=0), atol=1e-12)
    # the box is the body moved by three times its displacement
    moved = mesh.p + 3.0 * fields.displacement.T
    for limits, coordinate in zip((body.get_xlim(), body.get_ylim(), body.get_zlim()), moved):
        np.testing.assert_allclose(limits, (coordinate.min(), coordinate.max()), rtol=1e-14)
    largest = np.linalg.norm(fields.displacement, axis=1).max()
    assert "× 3" in figure.get_suptitle() and f"{largest:.3g}" in figure.get_suptitle()
    assert "t = 1.1" in figure.get_suptitle()


def plots_colors(values, everything):
    """The colours of ``values`` on the stress map scaled from the least to the largest of ``everything``."""
    from matplotlib import colormaps
    from matplotlib.colors import Normalize

    return colormaps[plots.STRESS_MAP](Normalize(everything.min(), everything.max())(values))


def test_deformed_body_2d_is_the_mesh_moved_by_the_magnified_displacement(run_2d):
    figure = plots.deformed_body(run_2d, step=5, scale=7.0)
    body = figure.axes[0]
    (cells,) = [c for c in body.collections if isinstance(c, PolyCollection)]
    mesh, fields = run_2d.discretization.mesh.mesh, run_2d.fields[5]
    moved = mesh.p.T + 7.0 * fields.displacement
    np.testing.assert_allclose(np.array([path.vertices[:3] for path in cells.get_paths()]), moved[mesh.t.T],
                               rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(cells.get_array(), fields.von_mises)
    assert cells.norm.vmin == fields.von_mises.min() and cells.norm.vmax == fields.von_mises.max()
    assert "× 7" in figure.get_suptitle() and "t = 0.5" in figure.get_suptitle()


def test_default_magnification_draws_the_largest_displacement_at_about_a_tenth_of_the_body():
    for largest in (1e-6, 3.3e-4, 0.01, 0.07):
        scale = plots.magnification(largest, 2.0)
        assert 0.04 < scale * largest / 2.0 <= 0.1, (largest, scale)
        assert f"{scale:g}"[0] in "125"
    assert plots.magnification(0.5, 2.0) == 1.0  # never below true scale
    assert plots.magnification(0.0, 2.0) == 1.0  # nothing moves


def test_time_series_draws_the_history(run_3d):
    columns = ["K_probe", "penetration_probe", "residual"]
    figure = plots.time_series(run_3d, columns)
    assert len(figure.axes) == 3
    for ax, column in zip(figure.axes, columns):
        (line,) = ax.get_lines()
        np.testing.assert_array_equal(line.get_xdata(), run_3d.times)
        np.testing.assert_array_equal(line.get_ydata(), run_3d.series(column))
        assert ax.get_ylabel() == column
    assert figure.axes[2].get_yscale() == "log"
    low, high = figure.axes[1].get_ylim()  # the probe stays at the limit: a readable range, not rounding noise
    assert high - low > 1e-3
    with pytest.raises(KeyError, match="did you mean 'K_probe'"):
        plots.time_series(run_3d, ["K_prob"])


def test_what_cannot_be_drawn_is_a_one_line_error(run_2d):
    free = dict(flat_2d_case())
    free.pop("contact")
    free["boundary"] = {"dirichlet": [{"part": "axis"}], "traction": [{"part": "top_arc", "value": ["0", "-t"]}]}
    without_contact = vpcontact.solve(free)
    with pytest.raises(CaseError, match="no contact"):
        plots.contact_pressure(without_contact)
    assert list(plots.run_figures(without_contact)) == ["deformed"]
    with pytest.raises(CaseError, match=r"step 12 is not a step the run has done \(steps 1 to 11\)"):
        plots.contact_pressure(run_2d, steps=[3, 12])
    with pytest.raises(CaseError, match=r"step 4 has no fields: the run kept them at steps \[5, 11\]"):
        plots.deformed_body(run_2d, step=4)
    with pytest.raises(CaseError, match="scale"):
        plots.deformed_body(run_2d, scale=0.0)


def test_along_contact_draws_each_run_at_its_nodes(run_2d, run_3d):
    """One curve per run and panel, its points the contact nodes (2D: ordered by arc length, 3D: by the
    distance from the probe node) and their values at the step asked for."""
    figure = plots.along_contact({"a": run_2d, "b": run_2d}, ("pressure", "xi"), step=5)
    pressure, xi = (ax.get_lines()[0].get_ydata() for ax in figure.axes)
    row = step_row(run_2d, 5)
    assert np.allclose(np.sort(pressure[np.isfinite(pressure)]), np.sort(pressures(run_2d)[row]))
    assert np.allclose(np.sort(xi[np.isfinite(xi)]), np.sort(run_2d.contact_history("xi")[row]))
    assert [len(ax.get_lines()) for ax in figure.axes] == [2, 2]
    figure = plots.along_contact({"3D": run_3d}, "K")
    line = figure.axes[0].get_lines()[0]
    surface = run_3d.discretization.surface
    distance = np.linalg.norm(surface.coordinates - surface.coordinates[:, [run_3d.discretization.probe]], axis=0)
    assert np.allclose(line.get_xdata(), np.sort(distance))
    assert np.allclose(np.sort(line.get_ydata()), np.sort(run_3d.contact_history("K")[-1]))


def test_along_contact_refuses_what_it_cannot_draw(run_2d, run_3d):
    with pytest.raises(CaseError, match="mix 2D and 3D"):
        plots.along_contact({"a": run_2d, "b": run_3d})
    with pytest.raises(CaseError, match="give at least one run"):
        plots.along_contact({})
    with pytest.raises(KeyError, match="pressur"):
        plots.along_contact({"a": run_2d}, "pressur")


def test_importing_vpcontact_does_not_load_matplotlib():
    code = ("import sys, vpcontact, vpcontact.results.plots, vpcontact.io.run, vpcontact.drivers.rundir; "
            "assert 'matplotlib' not in sys.modules, 'matplotlib loaded'")
    subprocess.run([sys.executable, "-c", code], check=True)


# --- output.figures ----------------------------------------------------------------------------
def write_case(folder, case):
    path = folder / "case.toml"
    path.write_text(tomli_w.dumps(case))
    return path


def assert_pngs(folder, names):
    assert sorted(p.name for p in folder.iterdir()) == sorted(names)
    for name in names:
        data = (folder / name).read_bytes()
        assert data.startswith(PNG) and len(data) > 10_000, name


def test_output_figures_writes_three_pngs_and_overwrite_removes_only_them(tmp_path):
    case = flat_2d_case()
    case["output"]["figures"] = True
    path = write_case(tmp_path, case)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    assert_pngs(out / "figures", FIGURE_FILES)
    assert json.loads((out / "summary.json").read_text())["status"] == "complete"
    # summary.json is written after the figures
    assert (out / "summary.json").stat().st_mtime_ns >= max((out / "figures" / n).stat().st_mtime_ns
                                                            for n in FIGURE_FILES)

    (out / "figures" / "notes.txt").write_text("mine")
    assert main(["run", str(path), "--out", str(out), "--quiet", "--overwrite", "--set", "output.figures=false"]) == 0
    assert sorted(p.name for p in (out / "figures").iterdir()) == ["notes.txt"]
    (out / "figures" / "notes.txt").unlink()
    assert main(["run", str(path), "--out", str(out), "--quiet", "--overwrite"]) == 0  # figures/ left empty: removed
    assert_pngs(out / "figures", FIGURE_FILES)
    assert main(["run", str(path), "--out", str(out), "--quiet", "--overwrite", "--set", "output.figures=false"]) == 0
    assert not (out / "figures").exists()


def test_a_file_where_the_figures_go_is_refused_before_the_run(tmp_path):
    case = flat_2d_case()
    case["output"]["figures"] = True
    path = write_case(tmp_path, case)
    out = tmp_path / "run"
    out.mkdir()
    (out / "figures").write_text("a file of mine")
    before = snapshot_tree(out)
    status, _, stderr = run_cli("run", path, "--out", out, "--quiet")
    assert_refused(status, stderr, "figures", "is not a folder", untouched=[(out, before)])


def test_output_figures_false_writes_none(tmp_path):
    path = write_case(tmp_path, flat_2d_case())
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    assert not (tmp_path / "run" / "figures").exists()


def test_output_figures_of_a_3d_run(tmp_path):
    case = block_3d_case()
    case["output"]["figures"] = True
    path = write_case(tmp_path, case)
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"]) == 0
    assert_pngs(tmp_path / "run" / "figures", FIGURE_FILES)


def test_figures_only_at_the_end_of_a_complete_or_failed_run(tmp_path, run_2d):
    """Not for an interrupted run (it goes on with --resume), not at checkpoints (history only)."""
    case = vpcontact.load_case(flat_2d_case(), {"output.figures": True})
    result = vpcontact.solve(case)
    result.status = "interrupted"
    write_outputs(result, tmp_path, history_only=True)
    write_outputs(result, tmp_path)
    assert not (tmp_path / "figures").exists() and (tmp_path / "summary.json").exists()
    result.status = "failed"
    write_outputs(result, tmp_path)
    assert_pngs(tmp_path / "figures", FIGURE_FILES)


def test_output_figures_may_change_on_resume():
    """It does not change the numbers: a run may be resumed with figures turned on or off."""
    on = vpcontact.load_case(flat_2d_case(), {"output.figures": True}).resolved()
    off = vpcontact.load_case(flat_2d_case()).resolved()
    assert on != off and checkpoint.comparable(on) == checkpoint.comparable(off)


def test_output_figures_must_be_a_boolean(tmp_path):
    case = flat_2d_case()
    case["output"]["figures"] = "yes"
    with pytest.raises(CaseError, match="output.figures"):
        vpcontact.load_case(case)
