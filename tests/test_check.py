"""``vpcontact check``: the description's numbers against counts made independently on structured meshes
(2D and 3D), the method "auto" chooses against the one a run then uses, the same refusals as ``run``
(exit 2, the same line), and nothing written."""

import json
import math
import re
import subprocess
import sys

import numpy as np
import pytest

import vpcontact
from conftest import assert_refused, half_disc_case, rectangle_case, snapshot_tree
from test_robustness import write
from vpcontact.drivers.check import check_case
from vpcontact.cli import main
from vpcontact.solvers import condensed


def block_case() -> dict:
    """A block 1 × 1 × 0.5 of cubes of edge 0.25 (4 × 4 × 2, six tetrahedra each) on rollers at its four
    sides, pushed down onto the foundation under its bottom."""
    return {
        "mesh": {"shape": "block", "width": 1.0, "depth": 1.0, "height": 0.5, "h": 0.25},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}, {"part": "right", "components": ["x"]},
                                   {"part": "front", "components": ["y"]}, {"part": "back", "components": ["y"]}],
                     "traction": [{"part": "top", "value": ["0", "0", "-100*t"]}]},
        "contact": {"part": "bottom", "g": 0.2,
                    "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
        "time": {"T": 1.0, "steps": 8},
        "output": {"field_steps": [4, 8]},
    }


def test_a_rectangle_of_square_cells():
    """[0, 1] × [0, 0.5] with h = 0.125: 8 × 4 squares of edge a = 0.125, each two right isosceles triangles
    (mean ratio 4√3 (a²/2) / (4a²) = √3/2, smallest angle 45°, longest edge a√2)."""
    checked = check_case(vpcontact.load_case(rectangle_case()))
    nx, ny, a = 8, 4, 0.125
    assert checked.dim == 2
    assert (checked.nodes, checked.elements) == ((nx + 1) * (ny + 1), 2 * nx * ny)
    assert checked.dofs == 2 * checked.nodes
    assert checked.free_dofs == checked.dofs - 2 * (ny + 1)  # u_x = 0 on the left and right sides
    assert {(p.name, p.facets, p.nodes) for p in checked.parts} == {
        ("bottom", nx, nx + 1), ("top", nx, nx + 1), ("left", ny, ny + 1), ("right", ny, ny + 1)}
    np.testing.assert_allclose([checked.quality_min, checked.quality_median], math.sqrt(3) / 2, rtol=1e-12)
    np.testing.assert_allclose(checked.smallest_angle_degrees, 45.0, rtol=1e-12)
    np.testing.assert_allclose([checked.h_min, checked.h_max], a * math.sqrt(2), rtol=1e-12)
    assert checked.contact_nodes == nx + 1 and checked.contact_nodes_by_part == {"bottom": nx + 1}
    assert (checked.start, checked.T, checked.steps, checked.field_steps) == (0.0, 1.1, 11, 0)
    np.testing.assert_allclose(checked.k, 0.1, rtol=1e-15)
    assert [(m.key, m.regions, m.elements, m.E, m.nu, m.viscoplastic) for m in checked.materials] == [
        ("material", [], 2 * nx * ny, 1000.0, 0.3, None)]
    assert checked.regions == []


def test_a_block_of_cubes():
    """The block of ``block_case``: 5 × 5 × 3 nodes, 6 · 32 tetrahedra of the cube's Kuhn split (edges a, a, a,
    a√2, a√2, a√3, volume a³/6: mean ratio 12 (a³/2)^(2/3) / (10 a²) = 1.2 / 2^(2/3), longest edge a√3)."""
    checked = check_case(vpcontact.load_case(block_case()))
    a = 0.25
    assert checked.dim == 3 and checked.smallest_angle_degrees is None
    assert (checked.nodes, checked.elements, checked.dofs) == (75, 6 * 32, 3 * 75)
    assert checked.free_dofs == 3 * 75 - 4 * 15  # one component fixed on each side of 5 × 3 nodes
    assert {(p.name, p.facets, p.nodes) for p in checked.parts} == {
        ("bottom", 32, 25), ("top", 32, 25), ("left", 16, 15), ("right", 16, 15), ("front", 16, 15), ("back", 16, 15)}
    np.testing.assert_allclose([checked.quality_min, checked.quality_median], 1.2 / 2 ** (2 / 3), rtol=1e-12)
    np.testing.assert_allclose([checked.h_min, checked.h_max], a * math.sqrt(3), rtol=1e-12)
    assert checked.contact_nodes == 25 and checked.field_steps == 2 and checked.steps == 8


def test_regions_and_their_materials():
    """A coated half disc with a material per region: each region's elements (as the mesh groups them) and its
    material, each material's elements, its law."""
    case = half_disc_case(h=0.2)
    case["mesh"]["coating"] = 0.3
    case["material"] = [{"E": 1000.0, "nu": 0.3, "region": "core"},
                        {"E": "500 + 100*x", "nu": 0.3, "region": "coating",
                         "viscoplastic": {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}}]
    checked = check_case(vpcontact.load_case(case))
    mesh = vpcontact.build_problem(vpcontact.load_case(case)).mesh
    assert [(r.name, r.elements, r.material) for r in checked.regions] == [
        ("coating", mesh.regions["coating"].size, "material[1]"), ("core", mesh.regions["core"].size, "material[0]")]
    assert [(m.key, m.regions, m.elements, m.E, m.viscoplastic) for m in checked.materials] == [
        ("material[0]", ["core"], mesh.regions["core"].size, 1000.0, None),
        ("material[1]", ["coating"], mesh.regions["coating"].size, "500 + 100*x", "perzyna")]
    assert mesh.regions["core"].size + mesh.regions["coating"].size == checked.elements


@pytest.mark.parametrize("available", [8 * 2**30, 1000])
@pytest.mark.parametrize("make", [rectangle_case, block_case])
def test_the_method_auto_chooses_is_the_one_that_runs(monkeypatch, make, available):
    """The method and reason of check are those of the run: the condensed method, and with too little memory
    for its dense algebra the fastest of the others that the cost model predicts (the full one on these small
    bodies)."""
    monkeypatch.setattr(condensed, "available_memory", lambda: available)
    case = vpcontact.load_case(make())
    checked, result = check_case(case), vpcontact.solve(case)
    assert (checked.method, checked.method_reason) == (result.method, result.method_reason)
    assert checked.method == ("condensed" if available > 1000 else "full")
    assert (checked.dofs, checked.contact_nodes) == (result.dofs, result.contact_nodes)


def test_the_command_line(tmp_path, capsys):
    """Text and --json describe the same case, with --set applied; ``python -m vpcontact check`` is the same
    command; nothing is written beside the case."""
    path = write(tmp_path, rectangle_case())
    before = snapshot_tree(tmp_path)
    process = subprocess.run([sys.executable, "-m", "vpcontact", "check", str(path), "--set", "mesh.h=0.25"],
                             capture_output=True, text=True, timeout=120)
    assert process.returncode == 0 and process.stderr == "", process.stderr
    assert process.stdout.startswith("2D body: 15 nodes, 16 triangles, 30 dofs (24 free)\n")
    assert "smallest angle 45.0°" in process.stdout
    assert "method: condensed (solver.method = \"auto\": " in process.stdout
    assert main(["check", str(path), "--set", "mesh.h=0.25", "--json"]) == 0
    described = json.loads(capsys.readouterr().out)
    assert (described["nodes"], described["elements"], described["free_dofs"]) == (15, 16, 24)
    assert described["parts"][0] == {"name": "bottom", "facets": 4, "nodes": 5}
    assert set(described["time_seconds"]) == {"build", "solver setup", "time loop", "total"}
    assert snapshot_tree(tmp_path) == before


BAD = [
    ({"contact.part": "floor"}, "unknown part 'floor'"),  # found on the mesh: while building the problem
    ({"time.steps": 100_000_000}, "time.steps = 100000000"),  # the outputs would not fit in memory
    ({"solver.augmentation": 1e-30}, "solver.augmentation"),  # found when the solver would be made
    ({"mesh.h": -1}, "mesh.h"),  # found by the schema
    ({"adapt.cycles": 2, "adapt.max_dofs": 10}, "adapt.max_dofs = 10"),  # an adaptive run's first mesh
]


@pytest.mark.parametrize("overrides, words", BAD)
def test_a_bad_case_is_refused_as_run_refuses_it(tmp_path, capsys, overrides, words):
    """Exit 2 with one line, the line of ``vpcontact run`` (but for the memory available, which changes from
    one moment to the next), and nothing written (run writes nothing either)."""
    path = write(tmp_path, rectangle_case())
    sets = [item for key, value in overrides.items() for item in ("--set", f"{key}={value}")]
    before = snapshot_tree(tmp_path)
    status = main(["check", str(path), *sets])
    checked = capsys.readouterr().err
    assert_refused(status, checked, words, untouched=[(tmp_path, before)])
    status = main(["run", str(path), *sets, "--out", str(tmp_path / "out")])
    ran = capsys.readouterr().err.splitlines()[-1] + "\n"  # a set-up longer than the hold shows its phases before
    available = re.compile(r"[0-9.]+ GiB available")
    assert status == 2 and available.sub("", ran) == available.sub("", checked)
    assert snapshot_tree(tmp_path) == before
