"""benchmarks/startup.py runs and its JSON holds what docs/performance.md ("Start-up and outputs")
reads from it."""

import json
import subprocess
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
OUTPUTS = ("case.resolved.toml", "history.csv", "contact.csv", "fields", "solution.npz", "summary.json")


def test_the_startup_benchmark_times_the_commands_and_each_phase_of_a_run():
    done = subprocess.run([sys.executable, str(BENCHMARKS / "startup.py"), "--quick"], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    assert record["processor"] and record["cores"] >= 1 and len(record["load_average_before"]) == 3
    for command in (record["python_pass_s"], record["help_s"], record["tiny_run"]):
        assert 0 < command["min_s"] <= command["median_s"] <= command["max_s"] and command["runs"] == 1
    assert record["python_pass_s"]["median_s"] < record["tiny_run"]["median_s"]
    built_in, from_file = record["built_in_mesh"], record["gmsh_file"]
    assert "mesh.h" in built_in["overrides"] and "mesh.h" not in from_file["overrides"]  # the file's mesh
    for run in (built_in, from_file):
        assert run["dofs"] == built_in["dofs"] > 0 and run["contact_nodes"] == built_in["contact_nodes"] > 0
        assert run["steps"] == 11 and run["field_steps"] == 4
        phases = run["phases_s"]
        assert all(phases[name] > 0 for name in ("import", "mesh", "assembly", "time_loop", *OUTPUTS)), phases
        assert abs(phases["outputs"] - sum(phases[name] for name in OUTPUTS)) < 1e-9
        assert phases["figures (if asked for)"] > 0 and phases["checkpoint (if due)"] > 0
        assert run["whole_run"]["median_s"] > phases["time_loop"]
