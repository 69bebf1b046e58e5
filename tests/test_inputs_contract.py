"""Inputs that cannot give a meaningful run are refused before the first step, on one line that names
them: loads that are not finite where and when they are applied, values too long to echo, outputs that
would not fit in memory; NumPy's floating-point warnings never reach the terminal."""

import time
import tracemalloc

import numpy as np
import pytest
import tomli_w

import vpcontact
from vpcontact.case.translate import output_options
from vpcontact.problem.time_grid import TimeGrid
from vpcontact.results.footprint import memory_needed
from vpcontact.memory import available_memory
from conftest import assert_refused, rectangle_case, run_cli, snapshot_tree

TOP = "boundary.traction[0].value[1]"


def cli(tmp_path, case: dict, *overrides: str):
    """Run the case (written to tmp_path/case.toml) into tmp_path/out: (status, stdout, stderr, out)."""
    path = tmp_path / "case.toml"
    path.write_text(tomli_w.dumps(case))
    out = tmp_path / "out"
    status, stdout, stderr = run_cli("run", path, "--out", out, "--quiet",
                                     *[a for o in overrides for a in ("--set", o)])
    return status, stdout, stderr, out


def refused(tmp_path, case: dict, *overrides: str, words=()):
    """The case is refused (exit 2, one line naming ``words``) and nothing is written."""
    before = snapshot_tree(tmp_path)
    status, _, stderr, out = cli(tmp_path, case, *overrides)
    assert_refused(status, stderr, *words)
    assert not out.exists()
    assert {k: v for k, v in snapshot_tree(tmp_path).items() if k != "case.toml"} == \
           {k: v for k, v in (before or {}).items() if k != "case.toml"}
    return stderr


# --- loads that are not finite where and when they are applied -------------------------------------------
# The block: 11 steps t_n = 0.1 n; its top y = 0.5 is cut into facets of 0.125 whose 3 Gauss points
# include the midpoints x = 0.0625, 0.1875, ... (not the vertices x = 0, 0.125, ...).
NON_FINITE_LOADS = [
    # (expression of fy on the top, words of the message: the key, the value, where, when)
    ("1/(t-t)", ["(inf)", "every point", "t = 0.1 (step 1)"]),
    ("exp(1000*t)", ["(inf)", "t = 0.8 (step 8)"]),  # exp overflows beyond t = 0.7098
    ("sqrt(-t)", ["(nan)", "t = 0.1 (step 1)"]),
    ("-100*t/(x-0.0625)", ["(-inf)", "(x, y) = (0.0625, 0.5)", "t = 0.1 (step 1)"]),
    ("-100*t + 1/(t-0.5)", ["(inf)", "every point", "t = 0.5 (step 5)"]),  # t_5 = 5 * (1.1 / 11) = 0.5
    ("-100 + 1/(x-0.1875)", ["(inf)", "(x, y) = (0.1875, 0.5), every t"]),
    ("-100*t + 1/(x-0.1875)", ["(inf)", "(x, y) = (0.1875, 0.5), t = 0.1 (step 1)"]),
    ("-100*t*sqrt(x-0.7)", ["(nan)", "t = 0.1 (step 1)"]),  # only at some points of the part
    ("1e308*10", ["(inf)", "every point, every t"]),
    ("-100*t*(t-0.5)/(t-0.5)", ["(nan)", "every point", "t = 0.5 (step 5)"]),  # 0/0 at one time only
]


@pytest.mark.parametrize("expression, words", NON_FINITE_LOADS, ids=[e for e, _ in NON_FINITE_LOADS])
def test_a_load_that_is_not_finite_at_a_step_is_refused_before_the_run(tmp_path, expression, words):
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = expression
    stderr = refused(tmp_path, case, words=[f'{TOP} = "{expression}": not finite', *words])
    assert "a load must be finite wherever it is applied" in stderr


def test_the_first_time_and_a_point_where_it_is_not_finite_are_named(tmp_path):
    """sqrt(x - 0.7): nan at the Gauss points left of x = 0.7, the first one of the part in its order."""
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = "-100*t*sqrt(x-0.7)"
    stderr = refused(tmp_path, case)
    x = float(stderr.split("(x, y) = (")[1].split(",")[0])
    assert x < 0.7


def test_a_body_force_is_checked_at_its_points_inside_the_body(tmp_path):
    case = rectangle_case()
    case["boundary"]["body_force"] = [{"value": ["0", "-t*log(y-0.25)"]}]
    stderr = refused(tmp_path, case, words=['boundary.body_force[0].value[1] = "-t*log(y-0.25)": not finite',
                                            "t = 0.1 (step 1)"])
    y = float(stderr.split("(x, y) = (")[1].split(",")[1].split(")")[0])
    assert 0.0 < y <= 0.25  # a quadrature point inside the body, below y = 0.25


@pytest.mark.parametrize("expression", ["100*log(t/2)", "-100*t - t/(x-0.5)"])
def test_a_load_finite_wherever_it_is_evaluated_is_accepted(tmp_path, expression):
    """log(t) is never evaluated at t = 0 (the loads enter at t_n = n k > 0); 1/(x - 0.5) is infinite at a
    vertex of the top, which is not a quadrature point (with a net push down: alone, that load has no
    resultant, so nothing would press the block on the foundation, see test_floating_body)."""
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = expression
    status, stdout, stderr, out = cli(tmp_path, case)
    assert status == 0 and stdout.startswith("complete: 11 steps"), stderr
    assert stderr == ""


def test_a_load_not_finite_at_a_sub_step_time_stops_the_run_with_the_same_message(tmp_path):
    """Finite at every t_n, infinite at t = 0.05, the middle of step 1, which only a cut step reaches
    (one Newton iteration is too few: the step is cut). The load presses the block down at t_n (a load that
    pulls it off the foundation there fails before any cut: test_resting_body)."""
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = "-100*t - 1/(t-0.05)**2"
    case["solver"]["max_iterations"] = 1
    status, _, stderr, out = cli(tmp_path, case)
    assert status == 3, stderr
    assert stderr.count("\n") == 1 and "Warning" not in stderr and "Traceback" not in stderr
    assert "step 1 (t = 0.1) failed at a sub-step" in stderr
    assert f'{TOP} = "-100*t - 1/(t-0.05)**2": not finite (-inf) at every point, t = 0.05;' in stderr
    assert "iterates are not finite" not in stderr
    assert (out / "summary.json").is_file()


def test_the_api_checks_a_python_load_at_every_step_time():
    case = rectangle_case()
    case["boundary"]["traction"] = []
    with pytest.raises(vpcontact.CaseError, match=r"tractions\['top'\] \(fy\): not finite \(nan\) at \(x, y\) = "
                                                  r"\(.*\), t = 0\.7 \(step 7\)"):
        vpcontact.solve(case, tractions={"top": lambda x, y, t: (0.0 * x, -100 * t + (np.sqrt(x - 0.5) if t > 0.65
                                                                                      else 0.0))})


@pytest.mark.parametrize("gap, words", [
    ("log(x-0.5)", ["(nan)", "(x, y) = (0, 0)"]),
    ("0.01/(x-0.25)", ["(inf)", "(x, y) = (0.25, 0)"]),
])
def test_a_gap_that_is_not_finite_at_a_contact_node_is_refused(tmp_path, gap, words):
    refused(tmp_path, rectangle_case(gap=gap), words=[f'contact.gap = "{gap}": not finite', "contact node", *words])


def test_an_initial_stress_whose_forces_overflow_is_refused(tmp_path):
    refused(tmp_path, rectangle_case(), "initial.stress=[[1e308, 0], [0, 1e308]]",
            words=["initial.stress = [[1e+308, 0.0], [0.0, 1e+308]]", "not finite"])


@pytest.mark.parametrize("eta, T, words", [
    (1e-308, 1.1, ["material.viscoplastic: G(initial.stress, 0) is not finite (-inf)"]),
    (1e-298, 1100.0, ["material.viscoplastic: the history after the first step", "is the time step k = 100 small"]),
])
def test_a_viscoplastic_history_that_cannot_start_finite_is_refused(tmp_path, eta, T, words):
    """Perzyna with η tiny against the initial stress: 𝒢(σ_0, 0) = −(σ_0 − Pσ_0)/η, or z_1 = σ_0 + k 𝒢, overflows:
    refused before the first step (not four step cuts and "iterates are not finite")."""
    case = rectangle_case()
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": eta, "yield_stress": 0.0}
    case["initial"] = {"stress": [[1e10, 0.0], [0.0, -1e10]]}
    case["time"]["T"] = T
    refused(tmp_path, case, words=words)


# --- no NumPy warnings on the terminal -------------------------------------------------------------------
@pytest.mark.parametrize("overrides, words", [
    (["material.E=1e308"], ["material.E = 1e+308", "stiffness matrix is not finite"]),
    (["time.T=1e308"], [TOP, "not finite (-inf)"]),
    (["mesh.width=1e-300", "mesh.height=1e-300", "mesh.h=1e-300"], ["stiffness matrix is not finite",
                                                                    "sizes of the triangles"]),
])
def test_an_overflow_before_the_run_is_refused_without_warnings(tmp_path, overrides, words):
    refused(tmp_path, rectangle_case(), *overrides, words=words)


@pytest.mark.parametrize("overrides", [
    ["contact.stiffness.c_v=1e308"],
    ["contact.stiffness.alpha=1e308"],
    ["contact.stiffness.beta=1e308"],
    ["contact.stiffness.beta=-1e308"],
    ["contact.rho=1e308"],
    ["material.E=1e-308"],
    ['contact.gap="1e300"'],
    ['contact.p="power"', "contact.exponent=1e300"],
    [f'{TOP}="-1e200*t"'],
])
def test_nonsense_physics_fails_with_a_message_and_no_warning(tmp_path, overrides):
    """Values each within its range whose combination overflows float64: the run fails (exit 3) with one
    line saying what is not finite; no NumPy RuntimeWarning, no "complete"."""
    status, _, stderr, out = cli(tmp_path, rectangle_case(), *overrides)
    assert status == 3, (status, stderr)
    assert stderr.count("\n") == 1 and "not finite" in stderr, stderr
    assert "Warning" not in stderr and "Traceback" not in stderr


def test_a_probe_far_away_is_accepted_without_overflow_warnings(tmp_path):
    """contact.probe = (1e308, -1e308): a finite point whose squared distances to the nodes would overflow."""
    status, stdout, stderr, out = cli(tmp_path, rectangle_case(probe=[1e308, -1e308]))
    assert status == 0 and stdout.startswith("complete") and stderr == "", stderr


def test_a_viscoplastic_history_that_blows_up_says_why_without_warnings(tmp_path):
    case = rectangle_case()
    case["material"]["viscoplastic"] = {"law": "relaxation", "mu": 1e308, "E_inf": 1e300, "nu_inf": 0.3}
    case["initial"] = {"stress": [[1.0, 0.0], [0.0, 1.0]]}
    status, _, stderr, _ = cli(tmp_path, case)
    assert status == 3 and "viscoplastic history" in stderr and "Warning" not in stderr, stderr


# --- long values: the echo is cut, the reason is kept -----------------------------------------------------
MEGABYTE = 2**20


@pytest.mark.parametrize("expression, reason", [
    ("-100*t + 0." + "0" * MEGABYTE + "1*", "not a valid expression"),
    ("x" * MEGABYTE, "unknown name 'xxxxxxxx"),
    ("1+" * MEGABYTE + "1", "nested too deeply"),
    ("-100*t + 0." + "0" * MEGABYTE + "1", None),  # valid: accepted
    ("1/(t-t) + 0." + "0" * MEGABYTE + "1", "not finite (inf) at every point, t = 0.1 (step 1)"),
])
def test_a_megabyte_expression_is_cut_in_the_message_and_the_reason_kept(tmp_path, expression, reason):
    case = rectangle_case()
    case["boundary"]["traction"][0]["value"][1] = expression
    if reason is None:
        status, stdout, stderr, _ = cli(tmp_path, case)
        assert status == 0 and stdout.startswith("complete: 11 steps") and stderr == "", stderr
        return
    stderr = refused(tmp_path, case, words=[TOP, reason, f"({len(expression)} characters)"])
    assert len(stderr) < 500, len(stderr)


def test_a_long_string_for_a_choice_is_cut_and_the_choices_kept(tmp_path):
    stderr = refused(tmp_path, rectangle_case(), 'material.hypothesis="' + "p" * 100000 + '"',
                     words=["material.hypothesis", "(100000 characters)", "plane_strain", "plane_stress"])
    assert len(stderr) < 400


@pytest.mark.parametrize("override, words", [
    ('contact.part="' + "q" * 100000 + '"', ["unknown part 'qqqq", "(100000 characters)'",
                                             "the mesh has parts: bottom, left, right, top"]),
    ("mesh." + "q" * 100000 + "=1", ["unknown key 'mesh.qqqq", "(100005 characters)'",
                                     "valid keys: coating, depth, file, h, h_bottom, height, radius, shape, width"]),
    ("output.field_steps=[" + "1," * 50000 + "0]", ["output.field_steps = [1, 1,", "(150003 characters)",
                                                    'expected "all", "final", "none" or a list of step numbers']),
])
def test_a_long_name_or_value_in_a_case_is_cut_and_the_reason_kept(tmp_path, override, words):
    stderr = refused(tmp_path, rectangle_case(), override, words=words)
    assert len(stderr) < 300


def test_a_long_part_name_in_the_api_is_cut():
    with pytest.raises(vpcontact.CaseError) as error:
        vpcontact.solve(rectangle_case(), tractions={"q" * 10**6: lambda x, y, t: (0, 0)})
    assert "unknown part" in str(error.value) and "bottom, left, right, top" in str(error.value)
    assert len(str(error.value)) < 300


# --- memory: the time grid costs nothing, outputs that cannot fit are refused ----------------------------
@pytest.mark.parametrize("T, steps", [(1.1, 11), (1.1, 563), (0.3, 7), (1e-7, 1000), (7.77, 99991), (1e300, 3)])
def test_the_time_grid_is_bitwise_the_linspace_it_replaces(T, steps):
    grid = TimeGrid(T, steps)
    expected = np.linspace(0.0, T, steps + 1)[1:]
    assert len(grid) == steps
    np.testing.assert_array_equal(np.asarray(grid), expected)
    np.testing.assert_array_equal(np.fromiter(grid, float), expected)
    np.testing.assert_array_equal(grid[2:5], expected[2:5])
    np.testing.assert_array_equal(grid.at(np.arange(1, steps + 1)), expected)
    assert grid[-1] == T and grid[0] == expected[0] and grid[np.int64(steps - 1)] == T
    with pytest.raises(IndexError):
        grid[steps]


def test_a_grid_of_1e8_steps_is_built_at_once():
    started = time.perf_counter()
    grid = TimeGrid(1.1, 10**8)
    assert grid[10**8 - 1] == 1.1 and grid[-2] == (10**8 - 1) * (1.1 / 10**8)
    assert time.perf_counter() - started < 0.1


@pytest.mark.parametrize("field_steps, words", [
    ("none", ["time.steps = 100000000: the run's outputs need about", "history rows", "contact rows of 9 nodes",
              "use fewer steps"]),
    ("all", ['time.steps = 100000000 with output.field_steps = "all"', "fields at 100000000 steps",
             "keep the fields at fewer steps"]),
])
def test_1e8_steps_are_refused_before_anything_is_allocated(tmp_path, field_steps, words):
    case = rectangle_case()
    case["time"]["steps"] = 10**8
    case["output"]["field_steps"] = field_steps
    started = time.perf_counter()
    refused(tmp_path, case, words=[*words, "GiB available"])
    assert time.perf_counter() - started < 60


def test_fields_at_every_step_are_refused_naming_field_steps(tmp_path):
    """10⁵ steps of 10⁴ triangles with the fields at every step: about 90 GiB of fields."""
    case = rectangle_case()
    case["time"]["steps"] = 10**5
    case["mesh"]["h"] = 0.01
    case["output"]["field_steps"] = "all"
    refused(tmp_path, case, words=['time.steps = 100000 with output.field_steps = "all"', "fields at 100000 steps",
                                   "keep the fields at fewer steps"])


def test_the_estimate_covers_what_a_run_holds_and_writes(tmp_path):
    """What a run of the block (fields at every step) holds at its end, and its peak while it writes a
    checkpoint or its outputs, measured, against the estimate: its parts per step cover what is held
    (and are not more than twice that), the whole covers the peak."""
    case = rectangle_case()
    case["time"]["steps"] = steps = 400
    case["output"] = {"field_steps": "all"}
    loaded = vpcontact.load_case(case)
    loop = vpcontact.timeloop.loop.TimeLoop(vpcontact.build_problem(loaded), output_options(loaded.output))
    tracemalloc.start()
    try:
        result = loop.run()
        held, _ = tracemalloc.get_traced_memory()
        peaks = []
        for write in (lambda: vpcontact.io.checkpoint.save(loop, tmp_path), lambda: vpcontact.write_run(result, tmp_path / "out")):
            tracemalloc.reset_peak()
            write()
            peaks.append(tracemalloc.get_traced_memory()[1])
    finally:
        tracemalloc.stop()
    assert result.status == "complete"
    parts = memory_needed(steps, steps, result.nodes, result.elements, result.contact_nodes, False, held_parts=2)
    per_step = parts["history rows"] + parts["contact rows"] + parts["fields"]
    assert held <= per_step <= 2 * held, (held, parts)
    assert max(peaks) <= sum(parts.values()), (peaks, parts)


def test_a_million_steps_of_a_small_case_are_accepted_and_start_at_once():
    """1e6 steps of the block need about 3.7 GiB for their rows (with the reactions and mean displacements of its two
    rollers): accepted when that much memory is free; building the problem and the loop does not depend on the
    number of steps."""
    needed = sum(memory_needed(10**6, 1, 45, 64, 9, False, held_parts=2).values())
    assert needed < 4 * 2**30, needed
    if available_memory() < 1.2 * needed:
        pytest.skip(f"needs {needed / 2**30:.1f} GiB free")
    case = rectangle_case()
    case["time"] = {"T": 1.1e5, "steps": 10**6}
    case["output"]["field_steps"] = [1, 2, 3, 10**6]
    started = time.perf_counter()
    loaded = vpcontact.load_case(case)
    problem = vpcontact.build_problem(loaded)
    loop = vpcontact.timeloop.loop.TimeLoop(problem, output_options(loaded.output))
    assert time.perf_counter() - started < 20
    result = loop.run(stop=lambda: "enough" if loop.state.step >= 3 else None)
    assert result.status == "interrupted" and result.steps == 3
    np.testing.assert_array_equal(result.times, problem.times[:3])
    assert sorted(result.fields) == [1, 2, 3]
