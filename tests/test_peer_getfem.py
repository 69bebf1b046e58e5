"""benchmarks/peer_getfem.py: its JSON at a coarse level, with and without GetFEM (the GetFEM part is
skipped where the system Python cannot import getfem, as in CI)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARK = Path(__file__).resolve().parents[1] / "benchmarks" / "peer_getfem.py"
GETFEM_PYTHON = "/usr/bin/python3"


def has_getfem() -> bool:
    try:
        return subprocess.run([GETFEM_PYTHON, "-c", "import getfem"], capture_output=True).returncode == 0
    except OSError:
        return False


def benchmark(*options: str) -> dict:
    done = subprocess.run([sys.executable, str(BENCHMARK), "--level", "32", "--steps", "11", "--runs", "1", *options],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def check_vpcontact_side(record: dict) -> None:
    # h = 1.408 / 32: Γ3, a quarter circle of length π/2, in facets of about h
    assert record["level"] == "1/32" and record["h"] == pytest.approx(0.044)
    assert 30 <= record["contact_nodes"] <= 45 and 1500 <= record["dofs"] <= 2600 and record["dofs"] % 2 == 0
    assert record["steps"] == 11 and record["T"] == 1.1 and record["runs"] == 1
    assert record["processor"] != "" and len(record["load_average_before"]) == 3
    ours = record["vpcontact"]
    assert len(ours["wall_s"]) == 1 and ours["median_s"] == ours["wall_s"][0]
    assert 0 < ours["timings_s"]["total"] < ours["median_s"]  # the process holds the solve
    assert ours["newton_iterations"] >= record["steps"]


def test_without_getfem_it_times_vpcontact_alone():
    record = benchmark("--getfem-python", str(Path(sys.executable).parent / "no-such-python"), "--mesher", "vpcontact")
    check_vpcontact_side(record)
    assert record["mesher"] == "vpcontact half_disc"
    assert record["getfem"] is None and record["ratio"] is None and record["agreement"] is None


@pytest.mark.skipif(not has_getfem(), reason="GetFEM (python3-getfem) is not installed")
def test_with_getfem_both_codes_solve_the_same_problem():
    record = benchmark("--getfem-python", GETFEM_PYTHON)
    check_vpcontact_side(record)
    peer = record["getfem"]
    assert peer["dofs"] == record["dofs"] and peer["version"]
    assert record["ratio"] == pytest.approx(peer["median_s"] / record["vpcontact"]["median_s"])
    assert [a["step"] for a in record["agreement"]] == [5, 11]  # t = 0.5 and 1.1
    for step in record["agreement"]:
        assert step["probe"]["point"] == [0.0, -1.0]
        assert step["max_displacement_difference_relative"] < 1e-8
        assert step["max_pressure_difference_relative"] < 1e-8
        assert step["max_penetration_difference"] < 1e-10
        ours, theirs = step["probe"]["pressure"]
        assert ours > 0 and abs(ours - theirs) <= 1e-8 * ours
        assert step["nodes_at_limit"][0] == step["nodes_at_limit"][1]
    # the rigid limit is reached at T: the comparison covers both parts of the law
    assert record["agreement"][1]["nodes_at_limit"][0] > 0 and record["agreement"][1]["probe"]["pressure_rigid"][0] > 0
