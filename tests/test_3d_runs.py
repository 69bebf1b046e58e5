"""A 3D case runs exactly like a 2D one: the command line, its outputs, checkpoints and --resume,
step cuts, a viscoplastic body, a user's tetrahedral gmsh mesh; and the case's vectors must have the
mesh's dimension (exit 2, one line)."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import meshio
import numpy as np
import pytest

import vpcontact
from conftest import assert_refused, run_cli, snapshot_tree
from test_robustness import read_csv, write

MESHES = Path(__file__).parent / "meshes" / "3d"


def ball_case(h=0.4, beta=-1.0, steps=11, **solver) -> dict:
    """The quarter ball of examples/quarter_ball.toml on a coarse mesh, softening (nodes reach the limit)."""
    return {
        "mesh": {"shape": "quarter_ball", "h": h},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "sym_x", "components": ["x"]}, {"part": "sym_y", "components": ["y"]}],
                     "traction": [{"part": "top", "value": ["0", "0", "-11.4443*t"]}]},
        "contact": {"part": "bottom", "g": 0.2, "probe": [0.0, 0.0, 0.0],
                    "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": beta}},
        "time": {"T": 1.1, "steps": steps},
        "solver": {"tolerance": 1e-11, **solver},
        "output": {"field_steps": "all"},
    }


def test_the_outputs_of_a_3d_run(tmp_path):
    path = write(tmp_path, ball_case())
    status, out, err = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert status == 0, err
    run = tmp_path / "out"
    summary = json.loads((run / "summary.json").read_text())
    assert summary["status"] == "complete" and len(summary["final"]["contact_force"]) == 3
    header, rows = read_csv(run / "history.csv")
    assert {"contact_force_x", "contact_force_y", "contact_force_z"} <= set(header)
    force = np.array([float(r[header.index("contact_force_z")]) for r in rows])
    # the foundation carries the vertical load: 11.4443 t per unit area of the top, πR²/2 (the
    # inscribed mesh's area, 0.8 % less at h = 0.4)
    np.testing.assert_allclose(force, 11.4443 * np.pi / 2 * 0.1 * np.arange(1, 12), rtol=0.02)
    header, rows = read_csv(run / "contact.csv")
    assert header[:9] == ["step", "t", "node", "x", "y", "z", "normal_x", "normal_y", "normal_z"]
    assert {"at_limit", "in_compliance"} <= {r[header.index("status")] for r in rows}
    body = meshio.read(run / "fields" / "body_00011.vtu")
    assert [c.type for c in body.cells] == ["tetra"] and body.cell_data["stress"][0].shape[1] == 9
    contact = meshio.read(run / "fields" / "contact_00011.vtu")
    assert [c.type for c in contact.cells] == ["triangle"]
    with np.load(run / "solution.npz") as solution:
        assert solution["points"].shape[0] == 3 and solution["tetrahedra"].shape[0] == 4
        assert solution["displacement"].shape[1:] == (solution["points"].shape[1], 3)
        assert solution["stress"].shape[2:] == (3, 3) and "triangles" not in solution.files
    # stress symmetric and the displacement of the bottom point downwards
    stress = np.load(run / "solution.npz")["stress"]
    np.testing.assert_allclose(stress, stress.transpose(0, 1, 3, 2), atol=1e-12 * np.abs(stress).max())


def test_a_3d_run_resumed_after_a_kill_equals_an_uninterrupted_one(tmp_path):
    case = ball_case(steps=60, method="full")
    case["output"] = {"field_steps": [30, 60], "checkpoint_every_steps": 1}
    path = write(tmp_path, case)
    reference = tmp_path / "reference"
    assert run_cli("run", path, "--out", reference, "--quiet")[0] == 0
    out = tmp_path / "killed"
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "run", str(path), "--out", str(out), "--quiet"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 120
    while not (out / "checkpoint" / "state.npz").exists():
        assert process.poll() is None and time.time() < deadline
        time.sleep(0.01)
    time.sleep(0.3)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    assert not (out / "summary.json").exists()
    status, _, err = run_cli("run", path, "--out", out, "--resume", "--quiet")
    assert status == 0, err
    for name in ("history.csv", "contact.csv"):
        mine, theirs = read_csv(out / name), read_csv(reference / name)
        assert mine[0] == theirs[0] and len(mine[1]) == len(theirs[1])
        assert mine[1] == theirs[1], name  # the full method resumes bitwise
    with np.load(out / "solution.npz") as a, np.load(reference / "solution.npz") as b:
        for key in b.files:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_a_3d_step_is_cut_when_newton_cannot_do_it_whole():
    whole = vpcontact.solve(ball_case())
    cut = vpcontact.solve(ball_case(max_iterations=4, max_step_cuts=8))
    assert whole.status == cut.status == "complete" and whole.step_cuts == 0 and cut.step_cuts > 0
    assert len(cut.rows) > len(whole.rows) and cut.steps == whole.steps == 11
    # a cut step is the same scheme on a finer grid: close to the uncut run, not equal
    np.testing.assert_allclose(cut.series("K_probe", substeps=False), whole.series("K_probe"), rtol=2e-2)


def test_a_viscoplastic_3d_body_creeps_under_a_held_load():
    """A constant layer (α = 0) and a load held from t = 0.5: the elastic body stays put, the Perzyna
    body keeps moving (monotonically) as its deviatoric stress relaxes above the yield stress."""
    case = ball_case(beta=1.0, steps=40)
    case["contact"]["stiffness"]["alpha"] = 0.0
    case["boundary"]["traction"][0]["value"] = ["0", "0", "-11.4443*min(t, 0.5)"]
    elastic = vpcontact.solve(case)
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    creeping = vpcontact.solve(case)
    assert elastic.status == creeping.status == "complete"
    held = elastic.times >= 0.5
    still = elastic.series("penetration_probe")[held]
    assert np.abs(still - still[0]).max() <= 1e-10 * still[0]
    moving = np.diff(creeping.series("penetration_probe")[held])
    assert np.abs(moving).sum() > 1e-3 * still[0] and (np.all(moving > 0) or np.all(moving < 0))
    z = creeping.final.z
    assert z.shape == (creeping.elements, 3, 3) and np.abs(z).max() > 0
    np.testing.assert_allclose(z, z.transpose(0, 2, 1), atol=1e-12 * np.abs(z).max())


def test_a_users_tetrahedral_gmsh_mesh_runs(tmp_path):
    """The quarter ball written by gmsh (tests/meshes/3d/quarter_ball.msh): no exact normals, the same
    problem: close to the built-in mesh's solution."""
    case = ball_case(h=0.25, beta=1.0)
    mesh = meshio.read(MESHES / "quarter_ball.msh")
    names = {name for name, (tag, dim) in mesh.field_data.items() if dim == 2}
    assert {"sym_x", "sym_y", "top", "bottom"} <= names
    from_file = {**case, "mesh": {"file": str(MESHES / "quarter_ball.msh")}}
    path = write(tmp_path, from_file)
    status, _, err = run_cli("run", path, "--out", tmp_path / "out", "--quiet")
    assert status == 0, err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    built_in = vpcontact.solve(case)
    assert summary["final"]["K_probe"] == pytest.approx(built_in.series("K_probe")[-1], rel=0.05)


DIMENSION_MISTAKES = [
    ({"boundary.traction[0].value": ["0", "-t"]}, ["boundary.traction[0].value has 2 components", "mesh is 3D",
                                                   "give 3 (x, y, z)"]),
    ({"contact.probe": [0.0, 0.0]}, ["contact.probe has 2 components"]),
    ({"contact.normal": [0.0, -1.0]}, ["contact.normal has 2 components"]),
    ({"material.hypothesis": "plane_strain"}, ["material.hypothesis = \"plane_strain\"", "remove material.hypothesis"]),
    ({"initial.stress": [[1.0, 0.0], [0.0, 1.0]]}, ["initial.stress is 2 x 2", "give a 3 x 3 table"]),
]
PLANE_MISTAKES = [
    ({"boundary.traction[0].value": ["0", "0", "-t"]}, ["boundary.traction[0].value has 3 components",
                                                        "mesh is 2D"]),
    ({"boundary.traction[0].value": ["0", "-z*t"]}, ["boundary.traction[0].value[1]", "uses z", "mesh is 2D"]),
    ({"contact.gap": "z"}, ["contact.gap", "uses z"]),
    ({"boundary.dirichlet[0].components": ["z"]}, ["boundary.dirichlet[0].components names \"z\"", "mesh is 2D"]),
    ({"contact.normal": [0.0, 0.0, -1.0]}, ["contact.normal has 3 components"]),
]


@pytest.mark.parametrize("override, words", DIMENSION_MISTAKES + PLANE_MISTAKES,
                         ids=[f"3d-{i}" for i in range(len(DIMENSION_MISTAKES))]
                         + [f"2d-{i}" for i in range(len(PLANE_MISTAKES))])
def test_vectors_of_the_wrong_dimension_are_refused(tmp_path, override, words):
    from conftest import half_disc_case

    case = ball_case() if (override, words) in DIMENSION_MISTAKES else half_disc_case(h=0.25)
    path = write(tmp_path, case)
    before = snapshot_tree(tmp_path)
    args = [a for key, value in override.items() for a in ("--set", f"{key}={json.dumps(value)}")]
    status, _, err = run_cli("run", path, "--out", tmp_path / "out", *args)
    assert_refused(status, err, *words, untouched=[(tmp_path, before)])


def test_a_clamped_3d_contact_part_is_refused(tmp_path):
    """Every component of every contact node fixed (components omitted: all three) leaves the contact force
    independent of the load: refused, naming the entry with its three components."""
    case = ball_case()
    case["boundary"]["dirichlet"].append({"part": "bottom"})
    path = write(tmp_path, case)
    before = snapshot_tree(tmp_path)
    status, _, err = run_cli("run", path, "--out", tmp_path / "out")
    assert_refused(status, err, "contact part 'bottom' is clamped", "boundary.dirichlet[2] (part 'bottom', "
                   "components x, y, z)", untouched=[(tmp_path, before)])
