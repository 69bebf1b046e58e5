"""Initial fields (issue 12): u_0, σ_0 and ξ_0 as expressions or arrays, (2.28) as written, a restart
from another run's state (initial.from_run) and a start time (time.start), in 2D and 3D; and their
refusals (exit 2, one line, nothing written)."""

import copy
import csv

import numpy as np
import pytest

import vpcontact
from conftest import assert_refused, half_disc_case, rectangle_case, resumed_after, run_cli, snapshot_tree, solved
from test_3d_runs import ball_case
from test_robustness import write
from vpcontact.fem.assembly import element_strain
from vpcontact.case.load import load_case
from vpcontact.case.translate import output_options
from vpcontact import build_problem
from vpcontact.drivers.rundir import run
from vpcontact.timeloop.loop import TimeLoop, solve_problem

#: History columns of the solution (not the solver's reports: iterations, residuals, sub-steps).
PHYSICAL = ("t", "max_penetration", "mean_penetration", "K_min", "K_max", "K_probe", "penetration_probe",
            "normal_stress_probe", "nodes_separated", "nodes_in_compliance", "nodes_at_limit", "contact_force_x",
            "contact_force_y", "contact_force_z")
RELAXATION = {"law": "relaxation", "mu": 2.0, "E_inf": 500.0, "nu_inf": 0.3}


def history(path) -> dict[str, np.ndarray]:
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    return {column: np.array([float(row[column]) for row in rows]) for column in rows[0]}


def softening_case(dim: int) -> dict:
    """A viscoplastic body (z matters) on a softening layer (β ≠ 0: ξ matters), some nodes at the limit."""
    stiffness = {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0}
    case = (half_disc_case(h=0.15, stiffness=stiffness, load=40.0) if dim == 2 else ball_case(h=0.4, beta=-1.0))
    case["material"]["viscoplastic"] = dict(RELAXATION)
    case["time"] = {"T": 1.2, "steps": 12}
    case["output"] = {"field_steps": "final", "progress": False}
    return case


def largest_difference(a: np.ndarray, b: np.ndarray) -> float:
    """max |a − b| relative to max |a|."""
    return float(np.abs(a - b).max() / np.abs(a).max())


# --- a restart continues the run ------------------------------------------------------------------
@pytest.mark.parametrize("dim", [2, 3])
def test_a_run_restarted_from_its_own_state_continues_as_the_uninterrupted_run(tmp_path, dim):
    """u_0, σ_0 and ξ_0 at t_6 from the run's solution.npz, t_0 = t_6 (time.start omitted): the six
    later steps agree with the uninterrupted run to rounding (measured: 1e-14 in 2D, 1e-12 in 3D)."""
    case = softening_case(dim)
    case["output"]["field_steps"] = [6, 12]
    assert run(load_case(case), tmp_path / "full").status == "complete"
    restart = copy.deepcopy(case)
    restart["initial"] = {"from_run": str(tmp_path / "full"), "step": 6}
    restart["time"]["steps"] = 6
    restart["output"]["field_steps"] = "final"
    assert run(load_case(restart), tmp_path / "restart").status == "complete"

    full, again = history(tmp_path / "full" / "history.csv"), history(tmp_path / "restart" / "history.csv")
    assert again["step"].tolist() == [1, 2, 3, 4, 5, 6]
    assert full["nodes_at_limit"][5] > 0 and np.all(again["nodes_in_compliance"] > 0)
    np.testing.assert_allclose(again["t"], full["t"][6:], rtol=1e-15, atol=0)  # t_0 = t_6, k = (T - t_0)/6
    for column in PHYSICAL:
        if column in full:
            scale = np.abs(full[column]).max()
            assert np.abs(again[column] - full[column][6:]).max() <= 1e-11 * scale, column
    with np.load(tmp_path / "full" / "solution.npz") as a, np.load(tmp_path / "restart" / "solution.npz") as b:
        assert a["times"][-1] == b["times"][-1] == 1.2 and a["xi"].shape == (2, a["contact_nodes"].size)
        for name in ("displacement", "stress", "z", "xi"):
            assert largest_difference(a[name][-1], b[name][-1]) <= 1e-11, name
        assert np.abs(a["z"][-1] - a["z"][0]).max() > 0.1 * np.abs(a["z"][0]).max()  # z changes after t_6
        assert np.ptp(a["xi"][0]) > 0  # and ξ at t_6 varies along Γ3: K(ξ) differs from node to node


def test_a_restart_from_a_run_without_xi_needs_initial_xi(tmp_path):
    """A solution.npz of an earlier version has no ξ: the restart asks for initial.xi (then takes it)."""
    case = softening_case(2)
    case["output"]["field_steps"] = [6, 12]
    run(load_case(case), tmp_path / "full")
    with np.load(tmp_path / "full" / "solution.npz") as data:
        older = {key: data[key] for key in data.files if key not in ("xi", "contact_nodes")}
    (tmp_path / "older").mkdir()
    np.savez_compressed(tmp_path / "older" / "solution.npz", **older)
    restart = copy.deepcopy(case)
    restart["time"]["steps"] = 6
    restart["output"]["field_steps"] = "final"
    restart["initial"] = {"from_run": str(tmp_path / "older"), "step": 6}
    with pytest.raises(vpcontact.CaseError, match="holds no xi .* give the layer's history initial.xi"):
        build_problem(load_case(restart))
    restart["initial"]["xi"] = "0.01*x*x"
    problem = build_problem(load_case(restart))
    x = problem.surface.coordinates[0]
    np.testing.assert_array_equal(problem.initial.xi, 0.01 * x * x)
    restart["initial"]["from_run"] = str(tmp_path / "full")
    with pytest.raises(vpcontact.CaseError, match="holds xi, which the restart takes; remove initial.xi"):
        build_problem(load_case(restart))


def test_a_restart_is_resumed_from_its_checkpoint_as_if_never_stopped(tmp_path):
    """A restarted run (t_0 from the run) stopped after its second step and resumed from its checkpoint
    ends as the same restart done at once: time.start and the initial state survive a checkpoint."""
    case = softening_case(2)
    case["solver"]["method"] = "full"
    case["output"]["field_steps"] = [6, 12]
    run(load_case(case), tmp_path / "full")
    restart = copy.deepcopy(case)
    restart["initial"] = {"from_run": str(tmp_path / "full"), "step": 6}
    restart["time"]["steps"] = 6
    restart["output"]["field_steps"] = "final"
    restart = load_case(restart)
    whole = TimeLoop(build_problem(restart), output_options(restart.output)).run()
    resumed = resumed_after(restart, 2, tmp_path / "stopped").run()
    assert resumed.status == whole.status == "complete"
    np.testing.assert_array_equal(resumed.times, whole.times)
    assert resumed.times[0] == pytest.approx(0.7, rel=1e-15)
    np.testing.assert_array_equal(resumed.final.displacement, whole.final.displacement)
    np.testing.assert_array_equal(resumed.contact_history("xi"), whole.contact_history("xi"))


def test_time_start_shifts_the_step_times(tmp_path):
    """t_n = t_0 + n k, k = (T − t_0)/steps, bitwise linspace(t_0, T, steps + 1)[1:]; on an elastic body
    with a layer without history the state at t depends on the load at t only: the run on [0.5, 1.6]
    meets the run on [0, 1.6] at its steps 6 to 16."""
    case = rectangle_case(stiffness={"law": "constant", "value": 300.0})
    case["time"] = {"T": 1.6, "steps": 16}
    later = copy.deepcopy(case)
    later["time"] = {"T": 1.6, "steps": 11, "start": 0.5}
    whole, shifted = vpcontact.solve(load_case(case)), vpcontact.solve(load_case(later))
    np.testing.assert_array_equal(shifted.times, np.linspace(0.5, 1.6, 12)[1:])
    assert shifted.discretization.times.k == (1.6 - 0.5) / 11
    np.testing.assert_allclose(shifted.times, whole.times[5:], rtol=1e-15)
    for column in ("max_penetration", "contact_force_y", "nodes_at_limit"):
        np.testing.assert_allclose(shifted.series(column), whole.series(column)[5:], rtol=1e-12, atol=0)
    assert whole.series("nodes_at_limit")[-1] > 0


# --- σ_0 and u_0 as the case gives them -----------------------------------------------------------
@pytest.mark.parametrize("dim", [2, 3])
def test_a_uniform_initial_stress_as_expressions_is_bitwise_the_number_form(dim):
    case = softening_case(dim)
    case["time"]["steps"] = 4
    numbers = [[2.0, 0.5], [0.5, -3.0]] if dim == 2 else [[2.0, 0.5, 0.0], [0.5, -3.0, 1.0], [0.0, 1.0, 4.0]]
    case["initial"] = {"stress": numbers}
    numbers_problem, by_numbers = solved(load_case(case))
    case["initial"] = {"stress": [[f"{v!r}" if (i + j) % 2 else f"4*{v / 4!r}" for j, v in enumerate(row)]
                                  for i, row in enumerate(numbers)]}
    expressions_problem, by_expressions = solved(load_case(case))
    assert isinstance(load_case(case).initial.stress[0][0], str)
    np.testing.assert_array_equal(expressions_problem.initial.stress, numbers_problem.initial.stress)
    assert by_expressions.rows == by_numbers.rows
    for name in ("displacement", "stress", "z"):
        np.testing.assert_array_equal(getattr(by_expressions.final, name), getattr(by_numbers.final, name))


@pytest.mark.parametrize("dim", [2, 3])
def test_an_initial_stress_varies_over_the_elements(dim):
    """σ_0 of an expression is its value at each element's centroid."""
    case = softening_case(dim)
    zero = ["0"] * dim
    table = [list(zero) for _ in range(dim)]
    table[0][0], table[1][1] = "10*x + y", "-x*x"
    table[0][1] = table[1][0] = " 2 * y"  # symmetric as written, whitespace aside
    case["initial"] = {"stress": table}
    problem = build_problem(load_case(case))
    centroids = problem.mesh.mesh.p[:, problem.mesh.mesh.t].mean(axis=1)
    x, y = centroids[0], centroids[1]
    np.testing.assert_array_equal(problem.initial.stress[0, 0], 10 * x + y)
    np.testing.assert_array_equal(problem.initial.stress[1, 1], -x * x)
    np.testing.assert_array_equal(problem.initial.stress[0, 1], 2 * y)


@pytest.mark.parametrize("dim", [2, 3])
def test_2_28_an_initial_stress_equal_to_the_elastic_one_of_u0_is_the_run_from_zero_data(dim):
    """Elastic body, u_0 ≠ 0 (zero on the Dirichlet components, admissible), σ_0 = ℰε(u_0): z_0 = 0, the
    run is the one from zero data; with σ_0 = 0 instead it is not (z_0 = −ℰε(u_0), a prestress)."""
    case = softening_case(dim)
    del case["material"]["viscoplastic"]
    case["time"]["steps"] = 6
    case["output"] = {"field_steps": "final", "progress": False}
    from_zero = vpcontact.solve(load_case(case))
    case["initial"] = {"displacement": (["0.01*x*y", "0.02*x*x - 0.01*y"] if dim == 2 else
                                        ["0.01*x*z", "0.02*y*x", "0.01*x*x - 0.02*z"])}
    moved = load_case(case)
    problem = build_problem(moved)
    u0 = problem.initial.dofs(problem.basis)
    assert np.abs(u0).max() > 1e-3
    sigma0 = np.moveaxis(problem.elasticity.stress(element_strain(problem.basis, u0)), -1, 0)
    same = vpcontact.solve(moved, initial_stress=sigma0)
    for column in PHYSICAL:
        if column in same.columns:
            a, b = from_zero.series(column), same.series(column)
            assert np.abs(a - b).max() <= 1e-11 * np.abs(a).max(), column
    assert largest_difference(from_zero.final.displacement, same.final.displacement) <= 1e-11
    assert largest_difference(from_zero.final.stress, same.final.stress) <= 1e-11
    prestressed = solve_problem(problem)
    assert largest_difference(from_zero.final.displacement, prestressed.final.displacement) > 0.01


def test_an_admissible_u0_is_compared_node_by_node_with_a_varying_thickness():
    """u_0·ν − gap ≤ g(x) at each contact node: u_0 = −(0.05 + 0.2 x) e_y is admissible under
    g = 0.1 + 0.2 x and not under g = 0.1 (then the worst node, x = 1, is named)."""
    case = rectangle_case()
    case["initial"] = {"displacement": ["0", "-(0.05 + 0.2*x)"]}
    case["contact"]["g"] = "0.1 + 0.2*x"
    problem = build_problem(load_case(case))
    assert solve_problem(problem).status == "complete"
    case["contact"]["g"] = 0.1
    with pytest.raises(vpcontact.CaseError, match=r"u_0.nu - gap = 0\.25 > g = 0\.1 at the contact node \(1, 0\)"):
        build_problem(load_case(case))


# --- the arrays of the Python API ------------------------------------------------------------------
def test_the_initial_arrays_of_the_api_replace_the_case_and_are_checked():
    case = load_case(rectangle_case())
    problem = build_problem(case)
    nodes, elements, m = problem.mesh.mesh.p.shape[1], problem.mesh.mesh.t.shape[1], problem.surface.size
    uniform = build_problem(case, initial_stress=[[1.0, 2.0], [2.0, -1.0]])
    by_case = build_problem(load_case(rectangle_case(), {"initial.stress": [[1.0, 2.0], [2.0, -1.0]]}))
    np.testing.assert_array_equal(uniform.initial.stress, by_case.initial.stress)
    xi = np.linspace(0.0, 0.01, m)
    np.testing.assert_array_equal(build_problem(case, initial_xi=xi).initial.xi, xi)
    bad = [
        ({"initial_displacement": np.zeros((nodes, 3))}, f"initial_displacement: an array of shape ({nodes}, 3)"),
        ({"initial_displacement": "up"}, "initial_displacement = 'up': expected an array of numbers"),
        ({"initial_stress": np.zeros((elements, 2))}, f"expected (elements, d, d) or (d, d) = ({elements}, 2, 2)"),
        ({"initial_stress": [[0.0, np.nan], [np.nan, 0.0]]}, "initial_stress is not finite (nan)"),
        ({"initial_stress": [[0.0, 1.0], [0.0, 0.0]]}, "initial_stress is not symmetric"),
        ({"initial_xi": np.zeros(m + 1)}, f"initial_xi: an array of shape ({m + 1},)"),
        ({"initial_xi": -0.01 * problem.surface.coordinates[0]}, "initial_xi = -0.01 at the contact node (1, 0)"),
        ({"initial_displacement": np.full((nodes, 2), np.inf)}, "initial_displacement is not finite (inf)"),
    ]
    for arguments, words in bad:
        with pytest.raises(vpcontact.CaseError) as caught:
            build_problem(case, **arguments)
        assert words in str(caught.value) and "\n" not in str(caught.value), (words, str(caught.value))


# --- refusals on the command line ------------------------------------------------------------------
@pytest.fixture(scope="module")
def earlier_run(tmp_path_factory):
    """A 2D run directory with fields at steps 6 and 12 (the state a restart starts from)."""
    folder = tmp_path_factory.mktemp("earlier")
    case = rectangle_case()
    case["time"] = {"T": 1.2, "steps": 12}
    case["output"] = {"field_steps": [6, 12], "progress": False}
    assert run(load_case(case), folder / "run").status == "complete"
    return folder / "run", case


REFUSED = [
    ({"initial": {"displacement": ["0", "-0.5"]}},
     ["initial.displacement penetrates the foundation", "u_0.nu - gap = 0.5 > g = 0.2 at the contact node (0, 0)",
      "(9 of 9 nodes)"]),
    ({"initial": {"displacement": ["0.01*y", "0"]}},
     ["initial.displacement: u_x = 0.005 at the node (0, 0.5) held by boundary.dirichlet[0] (part 'left',",
      "u_0 must be 0 there"]),
    ({"initial": {"xi": "x - 0.5"}}, ["initial.xi = -0.5 at the contact node (0, 0)", "must be >= 0"]),
    ({"initial": {"stress": [["t", "0"], ["0", "0"]]}}, ["initial.stress[0][0] = \"t\": unknown name 't'"]),
    ({"initial": {"stress": [["1", "x"], ["y", "1"]]}}, ["must be symmetric (stress[0][1] = 'x', stress[1][0] = 'y')"]),
    ({"initial": {"displacement": ["0", "0", "0"]}}, ["initial.displacement has 3 components and the mesh is 2D"]),
    ({"initial": {"step": 6}}, ["initial.step needs initial.from_run"]),
    ({"time": {"T": 1.0, "steps": 4, "start": 1.0}}, ["time.T = 1.0 must be > time.start = 1.0"]),
]


@pytest.mark.parametrize("change, words", REFUSED, ids=[w[0].split(" ")[0] + str(i) for i, (_, w) in enumerate(REFUSED)])
def test_bad_initial_data_are_refused(tmp_path, change, words):
    case = rectangle_case()
    for section, values in change.items():
        case[section] = {**case.get(section, {}), **values}
    out = tmp_path / "out"
    status, _, stderr = run_cli("run", write(tmp_path, case), "--out", out, "--quiet")
    assert_refused(status, stderr, *words, untouched=[(out, None)])


def restart_of(earlier_run, tmp_path, **initial):
    folder, case = earlier_run
    case = copy.deepcopy(case)
    case["initial"] = {"from_run": str(folder), **initial}
    case["time"]["steps"] = 6
    case["output"]["field_steps"] = "final"
    return case


@pytest.mark.parametrize("change, words", [
    ({"step": 3}, ["initial.step = 3", "wrote its fields at the steps 6, 12 (its output.field_steps)"]),
    ({"step": 6, "mesh.h": 0.25}, ["the run's mesh has 45 nodes and 64 triangles, the case's", "needs the same mesh"]),
    ({"step": 6, "mesh.width": 0.99}, ["the run's mesh has the case's node and element counts but nodes moved"]),
    ({"step": 12}, ["time.T = 1.2 must be > the time of step 12 of initial.from_run = 1.2"]),
    ({"step": 6, "initial.displacement": ["0", "0"]}, ["initial.displacement and initial.from_run exclude each other"]),
    ({"step": 6, "from_run": "nowhere"}, ["initial.from_run = \"nowhere\"", "is not a run directory"]),
])
def test_a_bad_restart_is_refused(earlier_run, tmp_path, change, words):
    initial = {key: value for key, value in change.items() if "." not in key}
    case = restart_of(earlier_run, tmp_path, **initial)
    for key, value in change.items():
        if "." in key:
            section, name = key.split(".")
            case[section][name] = value
    before = snapshot_tree(earlier_run[0])
    out = tmp_path / "out"
    status, _, stderr = run_cli("run", write(tmp_path, case), "--out", out, "--quiet")
    assert_refused(status, stderr, *words, untouched=[(out, None), (earlier_run[0], before)])


def test_a_restart_on_the_command_line_takes_the_time_of_its_step(earlier_run, tmp_path):
    """The resolved case names the run directory by its absolute path; the history starts at t_7 = 0.7."""
    case = restart_of(earlier_run, tmp_path, step=6)
    out = tmp_path / "out"
    status, _, stderr = run_cli("run", write(tmp_path, case), "--out", out, "--quiet")
    assert status == 0, stderr
    assert history(out / "history.csv")["t"][0] == pytest.approx(0.7, rel=1e-15)
    assert f'from_run = "{earlier_run[0]}"' in (out / "case.resolved.toml").read_text()


def test_an_inadmissible_u0_is_refused_in_3d(tmp_path):
    case = ball_case()
    case["initial"] = {"displacement": ["0", "0", "-0.3"]}
    out = tmp_path / "out"
    status, _, stderr = run_cli("run", write(tmp_path, case), "--out", out, "--quiet")
    assert_refused(status, stderr, "u_0.nu - gap = 0.3 > g = 0.2 at the contact node (0, 0, 0)",
                   untouched=[(out, None)])
