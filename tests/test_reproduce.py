"""`vpcontact reproduce --quick`, end to end once: the paper's numbers, the figures and the report."""

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from matplotlib.colors import to_hex
from matplotlib.quiver import Quiver

from vpcontact import build_problem, load_case
from vpcontact.cli import main
from vpcontact.laws.contact import AT_LIMIT, IN_COMPLIANCE, SEPARATED
from vpcontact.results.plots import STATE_COLORS, along_curve
from vpcontact.reproduction.figures import MESH_DRAWN_UP_TO, deformed_panels
from vpcontact.reproduction.frames import ARROWS, Frame
from vpcontact.reproduction.paper import PAPER_CASE
from vpcontact.reproduction.plan import make_plan

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FIGURES = [f"fig{n:02d}" for n in range(2, 12)]


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce") / "quick"
    assert main(["reproduce", "--out", str(out), "--quick", "--workers", "2", "--quiet"]) == 0
    return out, json.loads((out / "reproduce.json").read_text())


def test_the_packaged_case_is_the_example():
    assert load_case(tomllib.loads(PAPER_CASE)).resolved() == load_case(EXAMPLES / "paper_ball.toml").resolved()


def test_stiffness_at_the_bottom_point_matches_the_paper(quick):
    _, data = quick
    K = data["K_bottom_final"]["k0.1"]
    assert K["beta=1"] == pytest.approx(323.0, rel=0.01)
    assert K["beta=-1"] == pytest.approx(21.0, rel=0.05)
    # the series start near c_v = 100 and end at those values
    assert data["cases"]["beta+1_k0.1"]["K_probe"][-1] == K["beta=1"]
    assert data["cases"]["beta-1_k1_128"]["steps"] == 141


def test_rho_distance_decreases_to_zero(quick):
    _, data = quick
    rho = data["rho_study"]
    assert rho["rho"] == sorted(rho["rho"], reverse=True) and len(rho["rho"]) >= 4
    difference = rho["difference"]
    assert all(b < a for a, b in zip(difference, difference[1:]))
    assert rho["decreasing"] and difference[-1] < 1e-3 * difference[0]


def test_hk_slope_is_linear(quick):
    _, data = quick
    hk = data["hk_study"]
    assert hk["slope"] >= 0.8
    assert hk["levels"] == [4, 8, 16, 32] and hk["reference"]["level"] == 64
    assert all(b < a for a, b in zip(hk["error_V"], hk["error_V"][1:]))


def test_the_rates_in_h_and_in_k_are_first_order_each(quick):
    """Beyond the paper: h with k held (measured slopes 1.01 in V, 0.89 in Q) and k with h held (1.12 in
    both), each error decreasing at every refinement; the report has the table."""
    out, data = quick
    for name in ("h", "k"):
        rates = data["rates"][name]
        for norm in ("V", "Q"):
            error = rates[f"error_{norm}"]
            assert all(b < a for a, b in zip(error, error[1:])), (name, norm, error)
            assert 0.75 <= rates[f"slope_{norm}"] <= 1.4, (name, norm, rates[f"slope_{norm}"])
    assert len(set(data["rates"]["h"]["steps"])) == 1 and len(set(data["rates"]["k"]["dofs"])) == 1
    assert "The rates in h and in k separately" in (out / "report.md").read_text()


def test_the_error_estimate_bounds_the_error_by_a_steady_factor(quick):
    """η(1.1) of the residual estimator against ‖u − u_ref‖_E on the rate-in-h runs (the same time grid as
    the reference): measured 3.26, 3.58, 3.91 (quick)."""
    out, data = quick
    rates = data["rates"]["h"]
    effectivity = np.array(rates["effectivity"])
    assert np.all((effectivity > 2.0) & (effectivity < 6.0)) and effectivity.max() / effectivity.min() < 1.5
    assert all(b < a for a, b in zip(rates["error_energy"], rates["error_energy"][1:]))
    assert "The a posteriori error estimate and its effectivity" in (out / "report.md").read_text()


def test_the_adaptive_meshes_are_measured_against_the_uniform_ones(quick):
    """[adapt] from h = 1/4 in the quick run: DOFs 48 → 1,042 in 6 cycles, the error and the estimate falling
    at every cycle; the uniform 1/16 error (532 DOFs) is reached at about 592 DOFs (coarse meshes: no gain
    yet)."""
    out, data = quick
    adaptive = data["adaptive"]
    assert adaptive["dofs"][0] == data["rates"]["h"]["dofs"][0] and len(adaptive["dofs"]) == 6
    for name in ("dofs",):
        assert all(b > a for a, b in zip(adaptive[name], adaptive[name][1:]))
    for name in ("error_energy", "estimate"):
        assert all(b < a for a, b in zip(adaptive[name], adaptive[name][1:])), name
    assert adaptive["error_energy"][0] == pytest.approx(data["rates"]["h"]["error_energy"][0], rel=1e-12)
    ratio = adaptive["dofs_at_uniform_error"] / adaptive["uniform_finest"]["dofs"]
    assert 0.5 < ratio < 2.0
    assert (out / "cases" / "adaptive" / "adapt.csv").is_file() and (out / "figures" / "fig11.png").is_file()


def test_claims_and_the_ordering_of_penetrations(quick):
    _, data = quick
    verdicts = {c["claim"]: c["verdict"] for c in data["claims"]}
    assert any("all contact nodes in normal compliance" in c and v == "holds" for c, v in verdicts.items())
    order = data["penetration_ordering"]["k0.1"]
    # the paper's ordering fails against the uncapped case once β = −1 sits on the rigid base
    assert order["hardening_below_constant_all_steps"]
    assert order["softening_below_uncapped_from_t"] == pytest.approx(0.6)
    assert order["final"]["alpha0_g2000"] > order["final"]["beta-1"] == pytest.approx(0.2)
    states = data["node_states"]
    assert all(r["at_limit"] == 0 for r in states["beta+1"]) and states["beta-1"][-1]["at_limit"] > 0


def test_every_figure_is_written_and_mentioned(quick):
    out, data = quick
    markdown = (out / "report.md").read_text()
    page = (out / "report.html").read_text()
    assert sorted(data["figures"]) == FIGURES
    for key in FIGURES:
        for kind in ("png", "pdf"):
            path = out / "figures" / f"{key}.{kind}"
            assert path.is_file() and path.stat().st_size > 1000, path
        number = f"Fig. {int(key[3:])}"
        assert f"figures/{key}.png" in markdown and number in markdown
        assert f'id="{key}"' in page and "data:image/png;base64," in page and number in page
    assert (out / "figures" / "fig02.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "figures" / "fig02.pdf").read_bytes()[:5] == b"%PDF-"


def test_report_states_the_deviations_and_the_machine(quick):
    out, data = quick
    markdown = (out / "report.md").read_text()
    for text in ("17.977", "1000", "k = 0.1", "1/128", "plane strain", "does not hold", "Wall time and machine"):
        assert text in markdown, text
    assert data["machine"]["cores"] >= 1 and data["wall_time_s"]["total"] > 0
    assert all(math.isfinite(v) for v in data["wall_time_s"].values())
    assert all(math.isfinite(v) and v >= 0 for v in data["cpu_time_s"].values())
    assert data["cpu_time_s"]["total"] < 120  # --quick: under 2 minutes of CPU time (wall time depends on the load)


def test_runs_are_written_as_ordinary_outputs(quick):
    out, _ = quick
    assert (out / "cases" / "beta+1_k0.1" / "summary.json").is_file()
    assert (out / "studies" / "rho_sweep" / "study.csv").is_file()
    assert (out / "studies" / "hk_convergence.toml").is_file()


def test_refuses_a_non_empty_directory(quick, capsys):
    out, _ = quick
    assert main(["reproduce", "--out", str(out), "--quick", "--quiet"]) == 2
    assert "not empty" in capsys.readouterr().err


def test_quick_plan_is_coarse():
    plan = make_plan(True)
    assert plan.figure_h == 0.05 and plan.reference_level == 64 and max(plan.levels) == 32
    full = make_plan(False)
    assert full.reference_level == 512 and full.levels[-1] == 256 and full.rho[-1] == 1e-6


# --- what the deformed-configuration panels (Figs. 2, 3, 5, 9) draw -------------------------------
def paper_frame(h: float) -> Frame:
    """The paper's body at element size h, undeformed, with Γ3 in three zones from the bottom point:
    at the limit g, in normal compliance, separated; the pressure falls along Γ3."""
    problem = build_problem(load_case(tomllib.loads(PAPER_CASE), {"mesh.h": h}))
    surface, mesh = problem.surface, problem.mesh.mesh
    angle = np.arctan2(surface.coordinates[0], 1.0 - surface.coordinates[1])  # 0 at (0, 0), π/2 at (1, 1)
    status = np.select([angle < 0.4, angle < 1.2], [AT_LIMIT, IN_COMPLIANCE], SEPARATED)
    pressure = np.where(status == SEPARATED, 0.0, 10.0 * np.cos(angle))
    return Frame("test", mesh.p, mesh.t, np.zeros((mesh.p.shape[1], 2)), surface.nodes, surface.normals, pressure,
                 status, 0.2, 1.1)


def drawn_lines(ax) -> list[np.ndarray]:
    """The vertices (k, 2) of each line drawn in ax."""
    return [np.asarray(line.get_xydata()) for line in ax.lines]


def test_full_resolution_panels_draw_the_outline_and_a_readable_subset_of_arrows():
    frame = paper_frame(0.0125)
    elements, m = frame.triangles.shape[1], frame.nodes.size
    assert elements == 23_204 and m == 127  # the figure mesh of the full reproduction
    figure = deformed_panels([frame, frame], "test")
    for ax in figure.axes[:2]:
        # no line traces the mesh's 35,000 edges: the longest is the outline (about 410 edges, 1,240 vertices)
        assert max(len(xy) for xy in drawn_lines(ax)) < 2_000
        # nor a collection its 23,204 triangles: the body is filled as one polygon
        for collection in ax.collections:
            assert sum(len(path.vertices) for path in collection.get_paths()) < 2_000
        # one quiver with 20 to ARROWS arrows, spread along Γ3 (distinct, none closer than half the even spacing)
        (arrows,) = [c for c in ax.collections if isinstance(c, Quiver)]
        assert 20 <= arrows.N <= ARROWS
        tips = arrows.XY
        gaps = np.linalg.norm(tips[:, None, :] - tips[None, :, :], axis=2) + np.eye(arrows.N)
        assert gaps.min() > 0.5 * (np.pi / 2) / (arrows.N - 1)
        assert np.ptp(np.arctan2(tips[:, 0], 1.0 - tips[:, 1])) > 0.95 * np.pi / 2  # from the bottom to the equator
        # Γ3 in the three colours of the node states
        contact = [line for line in ax.lines if line.get_linewidth() == 3.0 and len(line.get_xydata())]
        colors = {to_hex(line.get_color()) for line in contact}
        assert colors == {to_hex(STATE_COLORS[s]) for s in (SEPARATED, IN_COMPLIANCE, AT_LIMIT)}


def test_coarse_mesh_is_drawn_with_an_arrow_at_every_contact_node():
    frame = paper_frame(0.05)
    assert frame.triangles.shape[1] <= MESH_DRAWN_UP_TO and frame.nodes.size <= ARROWS
    ax = deformed_panels([frame], "test").axes[0]
    edges = np.unique(np.sort(np.hstack([frame.triangles[[0, 1]], frame.triangles[[1, 2]], frame.triangles[[2, 0]]]),
                              axis=0), axis=1).shape[1]
    assert 3 * edges in [len(xy) for xy in drawn_lines(ax)]  # every edge: two ends and a break
    (arrows,) = [c for c in ax.collections if isinstance(c, Quiver)]
    assert arrows.N == frame.nodes.size


def test_along_curve_orders_shuffled_segments():
    rng = np.random.default_rng(3)
    path = rng.permutation(12)  # an open piece of 12 nodes and a closed one of 5
    segments = np.hstack([np.vstack([path[:-1], path[1:]]), np.array([[12, 13, 14, 15, 16], [13, 14, 15, 16, 12]])])
    segments = segments[:, rng.permutation(segments.shape[1])]
    segments[:, ::2] = segments[::-1, ::2]  # either direction
    order = along_curve(segments, 17)
    assert sorted(order) == list(range(17))
    pieces = (order[:12], order[12:]) if order[0] < 12 else (order[5:], order[:5])
    assert list(pieces[0]) in (list(path), list(path[::-1]))
    assert all(abs(int(a) - int(b)) in (1, 4) for a, b in zip(pieces[1], pieces[1][1:]))


def test_overwrite_removes_the_reproduction_and_nothing_else(quick, tmp_path):
    """--overwrite deletes what a reproduction wrote, and keeps every file of the user's, also inside
    the reproduction's folders (cases/, studies/, a run directory, figures/)."""
    import shutil

    from vpcontact.reproduction.reproduce import prepare

    source, _ = quick
    out = tmp_path / "paper"
    shutil.copytree(source, out)
    mine = {"notes.txt": "mine", "cases/my_case.toml": "x", "cases/beta+1_k0.1/notes.md": "y",
            "studies/rho_sweep/runs/rho=1/fields/view.pvsm": "z", "figures/fig02_annotated.png": "w",
            "figures/drafts/a.txt": "v"}
    for name, text in mine.items():
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        (out / name).write_text(text)
    prepare(out, overwrite=True)
    left = {str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()}
    assert left == set(mine)
    assert all((out / name).read_text() == text for name, text in mine.items())
    assert not (out / "studies" / "hk_convergence").exists()  # emptied folders go


def test_dofs_reaching_interpolates_log_log_between_the_meshes_around_the_target():
    """On errors that fall as a power of the DOFs the interpolation is exact; a first mesh already below
    the target gives its own DOFs; no mesh reaching it, NaN."""
    from vpcontact.reproduction.records import dofs_reaching

    dofs = [100, 400, 1600, 6400]
    errors = [3.0 * n**-0.6 for n in dofs]
    target = 3.0 * 1000**-0.6
    assert math.isclose(dofs_reaching(dofs, errors, target), 1000.0, rel_tol=1e-12)
    assert dofs_reaching(dofs, errors, errors[0]) == 100.0
    assert math.isnan(dofs_reaching(dofs, errors, 0.5 * errors[-1]))
