"""One solve on two MPI ranks (``mpiexec -n 2 vpcontact run``, docs/mpi.md) against the same run in one process.

The run on two ranks shares the iterative method's Newton iteration and its CG + GAMG among them; its numbers must
be the one-process iterative method's to 1e-8 (relative to each column's largest value) in every column of
history.csv and contact.csv (the node states at the last step), in 2D and 3D, for a layer that hardens and one that
softens onto the rigid base, with a viscoplastic body and data that vary in space. Also: the run directory is
rank 0's alone and summary.json says how many ranks solved; a checkpoint of a run on two ranks, stopped by SIGTERM
to the launcher, resumes in one process (and one of one process on two ranks) to the uninterrupted numbers; a rank
that fails stops every rank in one line, never a hang; a launch on two ranks without mpi4py is refused in one line;
a study solves each of its runs on two ranks; the scaling benchmark reports each rank.

Skipped where mpiexec, mpi4py, petsc4py or pymetis is missing (the README's test command installs them).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import tomli_w
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

from test_displacement_control import W, assert_the_history_is_the_closed_form, w
from test_uniaxial_reference import DEPTH, HEIGHT, LAYERS, STEPS, WIDTH, E, G, NU, T, block, power_layer
from uniaxial import under_displacement

for module in ("mpi4py", "petsc4py", "pymetis"):
    pytest.importorskip(module)
MPIEXEC = shutil.which("mpiexec")
if MPIEXEC is None:
    pytest.skip("no mpiexec here", allow_module_level=True)

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: The viscoplastic half disc of the gallery on a coarse mesh, its layer's thickness, its stiffness and the body's
#: modulus varying in space, to t = 1 (the load held from 0.5 on: the body creeps), solved to a tolerance that
#: leaves the two runs' Newton iterations 1e-10 apart.
VISCOPLASTIC = [str(EXAMPLES / "viscoplastic_ball.toml"), "--set", "mesh.h=0.05", "--set", 'contact.g="0.03 + 0.02*x"',
                "--set", 'contact.stiffness.c_v="100 + 50*x"', "--set", 'material.E="1000*(1 + 0.3*y)"',
                "--set", "time.T=1.0", "--set", "time.steps=10", "--set", 'output.field_steps="final"',
                "--set", "solver.tolerance=1e-11"]
QUARTER_BALL = [str(EXAMPLES / "quarter_ball.toml"), "--set", "mesh.h=0.2", "--set", "solver.tolerance=1e-11",
                "--set", 'output.field_steps="final"']


def coated_viscoplastic(folder: Path) -> list[str]:
    """The arguments of the gallery's coated half disc (examples/coated_ball.toml) made viscoplastic by region: a
    relaxing core, a Perzyna coating whose modulus varies in space, the layer's stiffness varying along the arc;
    the load ramped to t = 0.5 and held (the body creeps), fields at a middle step and the last."""
    case = tomllib.loads((EXAMPLES / "coated_ball.toml").read_text())
    core, coating = case["material"]
    core["viscoplastic"] = {"law": "relaxation", "mu": 2.0, "E_inf": 600.0, "nu_inf": 0.3}
    coating.update(E="100*(1 + 0.5*y)", viscoplastic={"law": "perzyna", "eta": 0.5, "yield_stress": 0.5})
    case["mesh"]["h"] = 0.05
    case["boundary"]["traction"][0]["value"] = ["0", "-17.977*min(t, 0.5)"]
    case["time"] = {"T": 1.0, "steps": 10}
    case["output"] = {"field_steps": [5, 10]}
    case["solver"] = {"tolerance": 1e-11}
    path = folder / "coated.toml"
    path.write_text(tomli_w.dumps(case))
    return [str(path)]


def environment() -> dict:
    """The environment of a launch: Open MPI allowed to run as root (CI's containers), its ranks yielding the core
    while they wait (two test workers share two cores)."""
    return {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
            "OMPI_MCA_mpi_yield_when_idle": "1", "OMPI_MCA_rmaps_base_oversubscribe": "1"}


def launch(ranks: int, arguments: list[str], **kwargs) -> subprocess.Popen:
    """``mpiexec -n ranks python -m vpcontact run ...`` (one process without mpiexec for ``ranks`` = 0)."""
    command = [sys.executable, "-m", "vpcontact", "run", "--quiet", *arguments]
    if ranks:
        command = [MPIEXEC, "-n", str(ranks), *command]
    return subprocess.Popen(command, env=environment(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            **kwargs)


def run(ranks: int, arguments: list[str], out: Path) -> subprocess.CompletedProcess:
    process = launch(ranks, [*arguments, "--out", str(out)])
    stdout, stderr = process.communicate(timeout=600)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def assert_same_numbers(one: Path, two: Path, tolerance: float = 1e-8) -> None:
    """Every numeric column of history.csv and contact.csv equal to ``tolerance`` times the column's largest value
    (the solver's own counters and the residuals aside), and every array of the body's fields as VTK reads them
    (the displacement at the nodes; σ, von Mises and z on the elements) equal to ``tolerance`` times its largest
    value."""
    for name in ("history.csv", "contact.csv"):
        a, b = pd.read_csv(one / name, comment="#"), pd.read_csv(two / name, comment="#")
        assert list(a.columns) == list(b.columns) and len(a) == len(b)
        for column in a.select_dtypes("number").columns:
            if column in ("newton_iterations", "residual", "complementarity"):
                continue
            scale = max(float(np.abs(a[column]).max()), 1e-300)
            difference = float(np.abs(a[column] - b[column]).max()) / scale
            assert difference <= tolerance, f"{name}: {column} differs by {difference:.1e}"
        for column in a.select_dtypes(exclude="number").columns:
            assert (a[column] == b[column]).all(), f"{name}: {column}"
    files = sorted(path.name for path in (one / "fields").glob("body_*.vtu"))
    assert files == sorted(path.name for path in (two / "fields").glob("body_*.vtu"))
    for name in files:
        a, b = body_arrays(one / "fields" / name), body_arrays(two / "fields" / name)
        assert a.keys() == b.keys() and {"displacement", "stress"} <= a.keys()
        for key in a:
            difference = float(np.abs(a[key] - b[key]).max()) / max(float(np.abs(a[key]).max()), 1e-300)
            assert difference <= tolerance, f"{name}: {key} differs by {difference:.1e}"


def body_arrays(path: Path) -> dict[str, np.ndarray]:
    """The point and cell arrays of a body's VTU file, as VTK's reader (ParaView's) gives them."""
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    arrays = {}
    for data in (grid.GetPointData(), grid.GetCellData()):
        for i in range(data.GetNumberOfArrays()):
            arrays[data.GetArrayName(i)] = vtk_to_numpy(data.GetArray(i))
    return arrays


@pytest.mark.parametrize("arguments", [coated_viscoplastic, VISCOPLASTIC + ["--set", "contact.stiffness.beta=-1"],
                                       QUARTER_BALL, VISCOPLASTIC + ["--set", "time.adaptive=true"]],
                         ids=["2d-hardening-coated-by-region", "2d-softening-to-the-base", "3d-quarter-ball",
                              "2d-adaptive-time-steps"])
def test_two_ranks_give_the_numbers_of_one_process(arguments, tmp_path):
    """... and each rank keeps the history z of its own elements: every element's once, whole in the fields."""
    arguments = arguments(tmp_path) if callable(arguments) else arguments
    one = run(0, [*arguments, "--set", 'solver.method="iterative"'], tmp_path / "one")
    two = run(2, arguments, tmp_path / "two")
    assert one.returncode == 0, one.stderr
    assert two.returncode == 0, two.stderr
    assert_same_numbers(tmp_path / "one", tmp_path / "two")
    summary = json.loads((tmp_path / "two" / "summary.json").read_text())
    assert summary["ranks"] == 2 and summary["solver_method"] == "iterative"
    assert "on 2 MPI ranks" in summary["solver_reason"]
    elements = summary["ranks_detail"]["elements"]
    assert len(elements) == 2 and min(elements) > 0 and sum(elements) == summary["elements"]
    entries = summary["ranks_detail"]["stiffness_entries"]  # each rank assembles its rows alone
    assert len(entries) == 2 and max(entries) < 0.7 * sum(entries)
    assert json.loads((tmp_path / "one" / "summary.json").read_text())["ranks"] == 1
    assert two.stdout.count("complete:") == 1  # rank 0 alone speaks
    if "contact.stiffness.beta=-1" in arguments:  # the softening layer is crushed: the active set is tested
        assert pd.read_csv(tmp_path / "two" / "history.csv", comment="#")["nodes_at_limit"].iloc[-1] > 0


def test_a_moved_block_on_two_ranks_is_the_closed_form(tmp_path):
    """3D displacement control (tests/test_displacement_control.py) by mpiexec: the top pressed to the rigid limit,
    lifted off and pressed again, the layer hardening with ξ. The prescribed displacement's coupling with the free
    dofs and the reactions' rows of A come from both ranks' rows of the stiffness: history.csv, read by pandas, is
    the closed form."""
    layer = LAYERS[3, 1.0]
    case = {"mesh": {"shape": "block", "width": WIDTH, "depth": DEPTH, "height": HEIGHT, "h": 0.125},
            "material": {"E": E, "nu": NU},
            "boundary": {"dirichlet": [*({"part": part, "components": [component]} for part, component in
                                         (("left", "x"), ("right", "x"), ("front", "y"), ("back", "y"))),
                                       {"part": "top", "components": ["z"], "value": [W]}]},
            "contact": {"part": "bottom", "g": G, "rho": layer["rho"], "p": "power", "exponent": layer["exponent"],
                        "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
            "time": {"T": T, "steps": STEPS}, "solver": {"tolerance": 1e-12}, "output": {"field_steps": "none"}}
    (tmp_path / "block.toml").write_text(tomli_w.dumps(case))
    two = run(2, [str(tmp_path / "block.toml")], tmp_path / "two")
    assert two.returncode == 0, two.stderr
    assert json.loads((tmp_path / "two" / "summary.json").read_text())["ranks"] == 2
    reference = under_displacement(block(3), power_layer(1.0, layer["exponent"], layer["rho"]),
                                   np.linspace(0.0, T, STEPS + 1), w)
    assert_the_history_is_the_closed_form(pd.read_csv(tmp_path / "two" / "history.csv"), reference, 3)


def stopped_by_sigterm(ranks: int, arguments: list[str], out: Path) -> subprocess.CompletedProcess:
    """A run stopped by SIGTERM to its launcher once its second step is done (a checkpoint at every step)."""
    process = launch(ranks, [*arguments, "--set", "output.checkpoint_every_steps=1", "--set", "output.progress=true",
                             "--out", str(out)], start_new_session=True)
    deadline = time.monotonic() + 300
    while not (out / "checkpoint").exists() and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.05)
    process.send_signal(signal.SIGTERM)
    stdout, stderr = process.communicate(timeout=120)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


@pytest.mark.parametrize("first, second", [(2, 0), (0, 2)], ids=["two-ranks-then-one", "one-then-two-ranks"])
def test_a_checkpoint_resumes_on_another_number_of_ranks(first, second, tmp_path):
    arguments = [*VISCOPLASTIC, "--set", 'solver.method="iterative"', "--set", "time.steps=40"]  # SIGTERM in time
    whole = run(0, arguments, tmp_path / "whole")
    assert whole.returncode == 0, whole.stderr
    stopped = stopped_by_sigterm(first, arguments, tmp_path / "resumed")
    # one process exits 143; mpiexec, itself stopped by the signal it passes on, has a status of its own
    assert stopped.returncode == 143 if not first else stopped.returncode != 0, stopped.stderr
    assert stopped.stderr.count("vpcontact: stopped by SIGTERM") == 1
    summary = json.loads((tmp_path / "resumed" / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    resumed = subprocess.run([*(([MPIEXEC, "-n", str(second)]) if second else []), sys.executable, "-m", "vpcontact",
                              "run", "--quiet", *arguments, "--out", str(tmp_path / "resumed"), "--resume"],
                             env=environment(), capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    summary = json.loads((tmp_path / "resumed" / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["resumed_at_steps"]
    assert_same_numbers(tmp_path / "whole", tmp_path / "resumed")


def test_a_rank_that_fails_stops_every_rank_in_one_line(tmp_path):
    """Rank 1 fails while building the problem (an error of that rank's own, as a lost file system or a memory
    error would be): the run ends with exit status 3 and one line naming the rank, within a minute, not a hang."""
    script = ("import sys, vpcontact.drivers.rundir as rundir\n"
              "from vpcontact.parallel.ranks import launched\n"
              "from vpcontact.cli import main\n"
              "build = rundir.build_problem\n"
              "def failing(*args, **kwargs):\n"
              "    if launched()[0] == 1:\n"
              "        raise MemoryError('rank 1 cannot allocate')\n"
              "    return build(*args, **kwargs)\n"
              "rundir.build_problem = failing\n"
              "sys.exit(main(sys.argv[1:]))\n")
    started = time.monotonic()
    done = subprocess.run([MPIEXEC, "-n", "2", sys.executable, "-c", script, "run", "--quiet", *VISCOPLASTIC,
                           "--out", str(tmp_path / "run")], env=environment(), capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 3, done.stderr
    ours = [line for line in done.stderr.splitlines() if line.startswith("vpcontact:")]
    assert ours == ["vpcontact: rank 1 of 2 failed (MemoryError: rank 1 cannot allocate): every rank is stopped"]
    assert time.monotonic() - started < 60


def test_two_ranks_without_mpi4py_are_refused_in_one_line(tmp_path):
    """As the launcher's environment says to a process when mpi4py cannot be imported there."""
    script = ("import sys\nsys.modules['mpi4py'] = None\nfrom vpcontact.cli import main\n"
              "sys.exit(main(sys.argv[1:]))\n")
    done = subprocess.run([sys.executable, "-c", script, "run", *VISCOPLASTIC, "--out", str(tmp_path / "run")],
                          env={**environment(), "OMPI_COMM_WORLD_SIZE": "2", "OMPI_COMM_WORLD_RANK": "0"},
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "launched on 2 MPI ranks, but mpi4py is not installed" in done.stderr
    assert "vpcontact[mpi]" in done.stderr
    assert not (tmp_path / "run").exists()


def test_a_method_of_one_process_is_refused_on_two_ranks(tmp_path):
    done = run(2, [*VISCOPLASTIC, "--set", 'solver.method="condensed"'], tmp_path / "run")
    assert done.returncode == 2
    assert done.stderr.count("vpcontact: error:") == 1
    assert 'solver.method = "condensed" runs in one process' in done.stderr
    assert not any((tmp_path / "run").iterdir()) if (tmp_path / "run").exists() else True


def test_the_scaling_benchmark_reports_each_rank(tmp_path):
    """benchmarks/ranks.py --quick: one process and two ranks on the quarter ball; the ranks' shares partition the
    free dofs and the contact nodes, each rank's memory is reported, and both solve with the same iterations."""
    done = subprocess.run([sys.executable, str(EXAMPLES.parent / "benchmarks" / "ranks.py"), "--quick"],
                          env=environment(), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    one, two = json.loads(done.stdout)["runs"]
    assert one["status"] == two["status"] == "complete"
    assert one["shares"] is None and len(one["peak_memory_bytes"]) == 1
    shares = two["shares"]
    assert len(two["peak_memory_bytes"]) == 2 and min(two["peak_memory_bytes"]) > 0
    assert sum(shares["contact_nodes"]) == one["contact_nodes"]
    assert 0 < sum(shares["free_dofs"]) < one["dofs"] and all(ghosts > 0 for ghosts in shares["ghost_dofs"])
    assert one["newton_iterations"] == two["newton_iterations"] and two["cg_iterations"] > 0
    assert two["speedup"] > 0 and "partition" in two["timings_s"]


def test_a_study_solves_each_run_on_two_ranks(tmp_path):
    """``vpcontact study --ranks 2``: each run launched on two MPI ranks gives the numbers of the study's runs in one
    process, its summary says so, and a rerun finds them complete (their resolved case is the study's)."""
    study = tmp_path / "study.toml"
    study.write_text(f'base = "{EXAMPLES / "viscoplastic_ball.toml"}"\n'
                     '[set]\n"mesh.h" = 0.05\n"solver.tolerance" = 1e-11\n"solver.method" = "iterative"\n'
                     '"contact.g" = "0.03 + 0.02*x"\n"output.field_steps" = "none"\n'
                     '"time.T" = 1.0\n"time.steps" = 10\n'
                     '[[runs]]\nid = "hardening"\n[[runs]]\nid = "constant"\n'
                     '"contact.stiffness" = {law = "constant", value = 300.0}\n')
    results = {}
    for ranks in (1, 2):
        done = subprocess.run([sys.executable, "-m", "vpcontact", "study", str(study), "--out", str(tmp_path / str(ranks)),
                               "--ranks", str(ranks), "--quiet"], env=environment(), capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr
        results[ranks] = pd.read_csv(tmp_path / str(ranks) / "study.csv")
        assert (results[ranks]["status"] == "complete").all() and len(results[ranks]) == 2
    for run_id in results[2]["id"]:
        summary = json.loads((tmp_path / "2" / "runs" / run_id / "summary.json").read_text())
        assert summary["ranks"] == 2
        assert_same_numbers(tmp_path / "1" / "runs" / run_id, tmp_path / "2" / "runs" / run_id)
    again = subprocess.run([sys.executable, "-m", "vpcontact", "study", str(study), "--out", str(tmp_path / "2"),
                            "--ranks", "2"], env=environment(), capture_output=True, text=True, timeout=600)
    assert again.returncode == 0 and "2 already complete" in again.stdout + again.stderr
