"""Parameter studies: the same table from a local pool and from a real Dask cluster, difference
norms, resuming after a kill, and retrying failed runs."""

import csv
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import tomli_w

from vpcontact.studies import load_study, run_study
from conftest import half_disc_case

NOT_COMPARED = {"wall_time_s"}


def write_study(tmp_path, runs_extra="", steps=11, h=0.2):
    case = half_disc_case(h=h, load=20.0)
    case["time"]["steps"] = steps
    (tmp_path / "base.toml").write_text(tomli_w.dumps(case))
    (tmp_path / "study.toml").write_text(f'''base = "base.toml"
[[vary]]
"contact.rho" = [1.0, 0.1, 0.01]
[[runs]]
id = "signorini"
"contact.stiffness" = {{ law = "constant", value = 0.0 }}
{runs_extra}
[compare]
reference = "signorini"
times = [1.1]
''')
    return tmp_path / "study.toml"


def read_table(path):
    with open(path) as handle:
        return {row["id"]: {k: v for k, v in row.items() if k not in NOT_COMPARED} for row in csv.DictReader(handle)}


def test_local_pool_and_dask_cluster_give_the_same_table(tmp_path):
    distributed = pytest.importorskip("distributed")
    path = write_study(tmp_path)
    local = run_study(load_study(path, tmp_path / "local"), tmp_path / "local", workers=2)
    assert sorted(local["completed"]) == ["rho=0.01", "rho=0.1", "rho=1", "signorini"]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster.scheduler_address) as client:
            report = run_study(load_study(path, tmp_path / "dask"), tmp_path / "dask", executor=client.get_executor())
    assert sorted(report["completed"]) == sorted(local["completed"])
    table, other = read_table(tmp_path / "local" / "study.csv"), read_table(tmp_path / "dask" / "study.csv")
    assert table == other
    # Fig. 8: the distance to the Signorini solution shrinks with rho; the reference to itself is 0
    assert float(table["signorini"]["norm_V_t1.1"]) == 0.0 and float(table["signorini"]["norm_Q_t1.1"]) == 0.0
    distance = [float(table[f"rho={r}"]["norm_V_t1.1"]) + float(table[f"rho={r}"]["norm_Q_t1.1"]) for r in ("1", "0.1", "0.01")]
    assert distance[0] > distance[1] > distance[2] > 0


def test_a_killed_study_resumes_without_redoing_finished_runs(tmp_path):
    path = write_study(tmp_path, steps=150, h=0.1)
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "study", str(path), "--out", str(out),
                                "--workers", "1", "--quiet"], start_new_session=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while time.time() < deadline and not list(out.glob("runs/*/summary.json")):
        time.sleep(0.02)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    finished = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")}
    assert 1 <= len(finished) < 4, finished
    report = run_study(load_study(path, out), out, workers=2)
    assert sorted(report["skipped"]) == sorted(finished)
    assert len(report["completed"]) == 4 - len(finished) and not report["failed"]
    assert {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json") if p.parent.name in finished} == finished
    assert {row["status"] for row in read_table(out / "study.csv").values()} == {"complete"}


def test_a_failing_run_is_retried_once_and_reported(tmp_path):
    extra = '[[runs]]\nid = "too-few-iterations"\n"solver.max_iterations" = 1\n"solver.method" = "full"\n'
    path = write_study(tmp_path, runs_extra=extra)
    out = tmp_path / "out"
    report = run_study(load_study(path, out), out, workers=2)
    assert report["failed"] == ["too-few-iterations"] and report["retried"] == ["too-few-iterations"]
    table = read_table(out / "study.csv")
    assert table["too-few-iterations"]["status"] == "failed"
    assert "no convergence" in table["too-few-iterations"]["message"]
    assert np.isnan(float(table["too-few-iterations"]["norm_V_t1.1"]))
    again = run_study(load_study(path, out), out, workers=2)
    assert sorted(again["skipped"]) == ["rho=0.01", "rho=0.1", "rho=1", "signorini"]
    assert again["failed"] == ["too-few-iterations"]
