"""The MPI ranks a case wants for its memory (vpcontact.solvers.ranks_wanted): each rank holds the rest of the problem
whole and its share of the stiffness and of the solver, so M machines of A bytes hold a run when
replicated + shared / M <= A."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from vpcontact.solvers.ranks_wanted import ranks_wanted

GIB = 2**30


@pytest.mark.parametrize("replicated, shared, available, wanted", [
    (1 * GIB, 5 * GIB, 8 * GIB, 1),       # fits in one process
    (2 * GIB, 20 * GIB, 12 * GIB, 2),     # 2 + 20 / 2 = 12 fits on two machines, 2 + 20 / 1 does not
    (2 * GIB, 21 * GIB, 12 * GIB, 3),     # 2 + 21 / 2 = 12.5 does not; 2 + 7 does
    (4 * GIB, 100 * GIB, 8 * GIB, 25),    # 4 + 100 / 25 = 8
])
def test_the_fewest_machines_whose_memory_holds_the_run(replicated, shared, available, wanted):
    found = ranks_wanted(replicated, shared, available, cores=2)
    assert found.ranks == wanted
    assert replicated + shared / found.ranks <= available
    if found.ranks > 1:
        assert replicated + shared / (found.ranks - 1) > available


def test_a_problem_larger_than_a_machine_fits_on_no_number_of_ranks():
    found = ranks_wanted(9 * GIB, 1 * GIB, 8 * GIB, cores=2)
    assert found.ranks is None and "what every rank holds whole exceeds" in found.reason


def test_one_process_that_fits_is_told_how_many_ranks_this_machine_holds():
    assert "mpiexec -n 2" in ranks_wanted(1 * GIB, 1 * GIB, 8 * GIB, cores=2).reason
    assert "mpiexec" not in ranks_wanted(3 * GIB, 1 * GIB, 6 * GIB, cores=2).reason  # 2 × 3 + 1 > 6


def test_check_says_how_many_ranks(tmp_path):
    case = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"
    done = subprocess.run([sys.executable, "-m", "vpcontact", "check", str(case), "--set", "mesh.h=0.2", "--json"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    checked = json.loads(done.stdout)
    assert checked["ranks_wanted"] == 1 and checked["ranks_reason"].startswith("one process fits")
    text = subprocess.run([sys.executable, "-m", "vpcontact", "check", str(case), "--set", "mesh.h=0.2"],
                          capture_output=True, text=True, timeout=300).stdout
    assert "ranks: one process fits" in text
