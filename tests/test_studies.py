"""Parameter studies: the same table from a local pool and from a real Dask cluster, difference
norms, resuming after a kill, retrying failed runs, run ids that are safe directory names, unusable
study directories, and SIGTERM/SIGINT stopping a study and its workers."""

import csv
import ctypes
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import tomli_w

import vpcontact
from vpcontact.drivers.studies import load_study, run_study
from conftest import assert_refused, half_disc_case, rectangle_case, run_cli, snapshot_tree

NOT_COMPARED = {"wall_time_s", "peak_memory_bytes"}


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
    assert float(table["signorini"]["norm_energy_t1.1"]) == 0.0 and float(table["rho=1"]["norm_energy_t1.1"]) > 0.0
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


# --- run ids: a single safe path component, unique; every run directory inside DIR/runs -------------
def write_id_study(folder, ids, vary=None):
    """A study of the fast rectangle case: one [[runs]] per entry of ``ids`` (None: no id; a run's
    contact.g differs from the others'), and an optional [[vary]] axis."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "base.toml").write_text(tomli_w.dumps(rectangle_case()))
    study = {"base": "base.toml", "runs": []}
    for i, run_id in enumerate(ids):
        run = {"contact.g": 0.1 + 0.01 * i}
        if run_id is not None:
            run["id"] = run_id
        study["runs"].append(run)
    if vary:
        study["vary"] = [vary]
    (folder / "study.toml").write_text(tomli_w.dumps(study))
    return folder / "study.toml"


def put_user_files(folder):
    (folder / "notes.txt").write_text("mine")
    (folder / "runs" / "mine").mkdir(parents=True)
    (folder / "runs" / "mine" / "summary.json").write_text('{"status": "complete"}')


BAD_IDS = {
    "parent": "..", "itself": ".", "empty": "", "a separator": "a/b", "a backslash": "a\\b", "absolute": "/etc",
    "escaping": "../escape", "hidden": ".hidden", "a newline": "a\nb", "a NUL": "a\x00b", "a space": "a b",
    "too long": "x" * 101, "a number": 3, "a list": ["x"],
}


@pytest.mark.parametrize("kind", sorted(BAD_IDS))
def test_a_run_id_that_is_not_a_safe_directory_name_is_refused(tmp_path, kind):
    path = write_id_study(tmp_path, ["fine", BAD_IDS[kind]])
    out = tmp_path / "study"
    out.mkdir()
    put_user_files(out)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("study", path, "--out", out, "--quiet")
    assert_refused(status, stderr, "runs[1]", "id = ", untouched=[(tmp_path, before)])


@pytest.mark.parametrize("ids, named", [(["x-2", "x", "x"], "runs[1] and runs[2] have the same id 'x'"),
                                        (["Run", "run"], "runs[0] and runs[1] have the same id 'run'")])
def test_two_runs_with_one_id_are_refused(tmp_path, ids, named):
    path = write_id_study(tmp_path, ids)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("study", path, "--out", tmp_path / "study", "--quiet")
    assert_refused(status, stderr, named, untouched=[(tmp_path, before)])


def test_generated_ids_never_collide_with_given_ones(tmp_path):
    """Ids made from the varied values get a suffix against every id, given or made: each run writes
    its own directory and study.csv shows each run's own numbers."""
    path = write_id_study(tmp_path, ["g=0.1", None, "g=0.1-2", None, None],
                          vary={"contact.g": [0.1, 0.1]})
    # the runs without an id vary contact.g: 0.11 ("g=0.11"), 0.13 and 0.14; the grid gives g=0.1 twice
    study = load_study(path, tmp_path / "study")
    ids = [spec.id for spec in study.runs]
    assert ids == ["g=0.1-3", "g=0.1-4", "g=0.1", "g=0.11", "g=0.1-2", "g=0.13", "g=0.14"]
    status, _, stderr = run_cli("study", path, "--out", tmp_path / "study", "--workers", "2", "--quiet")
    assert status == 0, stderr
    rows = read_table(tmp_path / "study" / "study.csv")
    assert sorted(p.name for p in (tmp_path / "study" / "runs").iterdir()) == sorted(ids)
    for spec in study.runs:
        resolved = vpcontact.load_case(spec.out / "case.resolved.toml")
        assert resolved.contact.g == spec.overrides["contact.g"] == float(rows[spec.id]["contact.g"])
        summary = json.loads((spec.out / "summary.json").read_text())
        assert float(rows[spec.id]["max_penetration"]) == summary["final"]["max_penetration"]
    assert len({rows[i]["max_penetration"] for i in ids if i not in ("g=0.1-3", "g=0.1-4")}) == 5
    assert sorted(p.name for p in (tmp_path / "study").iterdir()) == ["runs", "study.csv"]


def test_a_rerun_keeps_the_users_files_in_a_run_directory(tmp_path):
    path = write_id_study(tmp_path, ["a", "b"])
    out = tmp_path / "study"
    assert run_cli("study", path, "--out", out, "--workers", "1", "--quiet")[0] == 0
    (out / "runs" / "a" / "notes.txt").write_text("mine")
    (out / "runs" / "a" / "fields").mkdir()
    (out / "runs" / "a" / "fields" / "view.pvsm").write_text("mine too")
    path.write_text(path.read_text().replace("0.1", "0.12"))  # run "a" changes: it runs again
    assert run_cli("study", path, "--out", out, "--workers", "1", "--quiet")[0] == 0
    assert (out / "runs" / "a" / "notes.txt").read_text() == "mine"
    assert (out / "runs" / "a" / "fields" / "view.pvsm").read_text() == "mine too"
    assert vpcontact.load_case(out / "runs" / "a" / "case.resolved.toml").contact.g == 0.12


# --- an unusable study directory ---------------------------------------------------------------------
def _file(out):
    out.write_text("a user's file")


def _runs_file(out):
    out.mkdir()
    (out / "runs").write_text("a user's file")


def _run_link(out):
    (out / "runs").mkdir(parents=True)
    (out.parent / "elsewhere").mkdir()
    (out / "runs" / "a").symlink_to(out.parent / "elsewhere")


def _loop(out):
    os.symlink(out.name, out.parent / "other")
    os.symlink("other", out)


def _table_folder(out):
    (out / "study.csv").mkdir(parents=True)


def _summary_folder(out):
    (out / "runs" / "b" / "summary.json").mkdir(parents=True)


STUDY_OUT = {
    "study.csv a folder": (_table_folder, "study.csv' is a folder"),
    "a folder where a run writes summary.json": (_summary_folder, "summary.json' is a folder"),
    "a file": (_file, "exists and is not a directory"),
    "a symbolic link loop": (_loop, "symbolic link loop"),
    "runs/ a file": (_runs_file, "runs' is not a directory"),
    "a run directory that is a symbolic link": (_run_link, "a' is a symbolic link"),
}


@pytest.mark.parametrize("kind", sorted(STUDY_OUT))
def test_an_unusable_study_directory_is_refused(tmp_path, kind):
    path = write_id_study(tmp_path / "input", ["a", "b"])
    out = tmp_path / "study"
    make, words = STUDY_OUT[kind]
    make(out)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("study", path, "--out", out, "--quiet")
    assert_refused(status, stderr, str(out), words, untouched=[(tmp_path, before)])


def test_a_study_under_proc_is_refused(tmp_path):
    path = write_id_study(tmp_path, ["a"])
    status, _, stderr = run_cli("study", path, "--out", "/proc/vpcontact-study", "--quiet")
    assert_refused(status, stderr, "/proc/vpcontact-study", "cannot create the directory")


def test_scheduler_without_the_cluster_extra_names_the_fix(tmp_path):
    """`distributed` not importable (as without the cluster extra): exit 2 and the pip command."""
    fake = tmp_path / "no_distributed"
    fake.mkdir()
    (fake / "distributed.py").write_text('raise ImportError("No module named \'distributed\'")\n')
    path = write_id_study(tmp_path, ["a"])
    before = snapshot_tree(tmp_path)
    python_path = os.pathsep.join([str(fake), *filter(None, [os.environ.get("PYTHONPATH")])])
    status, _, stderr = run_cli("study", path, "--out", tmp_path / "study", "--scheduler", "tcp://127.0.0.1:8786",
                                "--quiet", env={"PYTHONPATH": python_path, "PYTHONDONTWRITEBYTECODE": "1"})
    assert_refused(status, stderr, "--scheduler", 'pip install "vpcontact[cluster]"', untouched=[(tmp_path, before)])


# --- stopping a study: SIGTERM / SIGINT ---------------------------------------------------------------
def children(pid):
    """The ids of the processes whose parent is ``pid`` (from /proc)."""
    found = set()
    for status in Path("/proc").glob("[0-9]*/status"):
        try:
            fields = dict(line.split(":\t", 1) for line in status.read_text().splitlines() if ":\t" in line)
        except OSError:
            continue
        if fields.get("PPid", "").strip() == str(pid):
            found.add(int(status.parent.name))
    return found


def running(pid):
    """Is the process alive (not gone, not a zombie)?"""
    try:
        state = (Path("/proc") / str(pid) / "status").read_text().split("State:")[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
@pytest.mark.parametrize("number, code, group", [(signal.SIGTERM, 143, False), (signal.SIGINT, 130, False),
                                                 (signal.SIGTERM, 143, True)],
                         ids=["SIGTERM", "SIGINT", "SIGTERM to the process group"])
def test_a_signal_stops_the_study_its_workers_and_writes_the_table(tmp_path, number, code, group):
    path = write_study(tmp_path, steps=600, h=0.1)
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "study", str(path), "--out", str(out),
                                "--workers", "2", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    workers = set()
    try:
        deadline = time.time() + 180
        while not list(out.glob("runs/*/summary.json")):
            assert process.poll() is None and time.time() < deadline, process.communicate()
            workers |= children(process.pid)
            time.sleep(0.02)
        workers |= children(process.pid)
        if group:  # as a service manager or `kill -TERM -PGID` does: the workers get it too
            os.killpg(process.pid, number)
        else:
            process.send_signal(number)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == code, stderr
    assert len(workers) >= 2 and not [pid for pid in workers if running(pid)]
    name = signal.Signals(number).name
    assert stderr.count("\n") == 1 and f"vpcontact: study stopped by {name}: " in stderr and "Traceback" not in stderr
    table = read_table(out / "study.csv")
    statuses = {row["status"] for row in table.values()}
    assert len(table) == 4 and statuses <= {"complete", "interrupted"} and "interrupted" in statuses
    complete = {run_id for run_id, row in table.items() if row["status"] == "complete"}
    assert complete == {p.parent.name for p in out.glob("runs/*/summary.json")}
    assert f"{len(complete)} of 4 runs complete, {4 - len(complete)} not finished" in stderr
    assert not list(out.glob(".*tmp*")) and not (out / ".vpcontact.lock").exists()
    before = snapshot_tree(out)
    time.sleep(2.0)
    assert snapshot_tree(out) == before, "written after the study exited"
    if number == signal.SIGTERM and not group:  # a rerun does what is left
        finished = {run_id: (out / "runs" / run_id / "summary.json").stat().st_mtime_ns for run_id in complete}
        status, stdout, stderr = run_cli("study", path, "--out", out, "--workers", "2", "--quiet", timeout=300)
        assert status == 0, stderr
        assert f"{len(complete)} already complete" in stdout
        assert {row["status"] for row in read_table(out / "study.csv").values()} == {"complete"}
        assert {r: (out / "runs" / r / "summary.json").stat().st_mtime_ns for r in complete} == finished


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
def test_a_worker_killed_by_the_system_stops_the_study_cleanly(tmp_path):
    """A worker killed from outside (the out-of-memory killer, say) breaks the local pool: the study
    stops with one line and exit 3, writes the table of what finished, and leaves no process behind."""
    path = write_study(tmp_path, steps=600, h=0.1)
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "study", str(path), "--out", str(out),
                                "--workers", "2", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    try:
        deadline = time.time() + 180
        while len(workers := children(process.pid)) < 2 or not list(out.glob("runs/*/history.csv")):
            assert process.poll() is None and time.time() < deadline, process.communicate()
            time.sleep(0.02)
        os.kill(min(workers), signal.SIGKILL)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 3, stderr
    assert stderr.count("\n") == 1 and "a worker process died" in stderr and "Traceback" not in stderr, stderr
    assert not [pid for pid in workers if running(pid)]
    table = read_table(out / "study.csv")
    assert len(table) == 4 and "interrupted" in {row["status"] for row in table.values()}


def test_a_second_study_into_a_directory_in_use_is_refused(tmp_path):
    path = write_study(tmp_path, steps=6000, h=0.1)  # still running when the second study starts, on a busy machine
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "study", str(path), "--out", str(out),
                                "--workers", "1", "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               start_new_session=True)
    try:
        deadline = time.time() + 120
        while not list(out.glob("runs/*/.vpcontact.lock")):
            assert process.poll() is None and time.time() < deadline
            time.sleep(0.02)
        status, _, stderr = run_cli("study", path, "--out", out, "--quiet")
        assert_refused(status, stderr, str(out), "another vpcontact run is writing to it")
    finally:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def exchange(first, second):
    """Swap two directories in one step (Linux renameat2 with RENAME_EXCHANGE): a rename away and a mkdir leave a
    moment with no directory, which the study may see first and report as removed."""
    libc = ctypes.CDLL(None, use_errno=True)
    if not hasattr(libc, "renameat2"):
        pytest.skip("this C library has no renameat2")
    at_current_directory, rename_exchange = -100, 2
    if libc.renameat2(at_current_directory, os.fsencode(first), at_current_directory, os.fsencode(second),
                      rename_exchange) != 0:
        pytest.skip(f"renameat2 cannot exchange here: {os.strerror(ctypes.get_errno())}")


def test_a_study_whose_directory_is_replaced_stops_and_writes_nothing_there(tmp_path):
    path = write_study(tmp_path, steps=600, h=0.1)
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "study", str(path), "--out", str(out),
                                "--workers", "2", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True)
    workers = set()
    try:
        deadline = time.time() + 180
        while not list(out.glob("runs/*/summary.json")):
            assert process.poll() is None and time.time() < deadline, process.communicate()
            workers |= children(process.pid)
            time.sleep(0.02)
        replacement = tmp_path / "moved"
        replacement.mkdir()
        (replacement / "notes.txt").write_text("a new directory of the user")
        exchange(out, replacement)
        before = snapshot_tree(out)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 4, stderr
    assert stderr.count("\n") == 1 and f"the directory '{out}' was replaced by another directory" in stderr
    assert not [pid for pid in workers if running(pid)]
    time.sleep(1.0)
    assert snapshot_tree(out) == before
    assert not (tmp_path / "moved" / ".vpcontact.lock").exists()


def test_a_study_after_gmsh_and_a_pardiso_solve_in_the_same_process_does_not_hang(tmp_path):
    """A script that imported gmsh (its library brings GNU OpenMP), solved a problem by PARDISO, then runs a study
    on a local pool: the forked workers' MKL hung in its first parallel region before they were put on one thread
    (the study never ended). In a process of its own, with a deadline."""
    try:
        import gmsh  # noqa: F401
    except (ImportError, OSError) as error:
        pytest.skip(f"gmsh does not load: {error}")
    from vpcontact.solvers.factorization import installed_backends

    if "pardiso" not in installed_backends():
        pytest.skip("MKL PARDISO is not installed")
    path = write_study(tmp_path, steps=3)
    script = f"""
import gmsh, vpcontact
from vpcontact import mesh
from vpcontact.drivers.studies import load_study, run_study
problem = vpcontact.compose(mesh.rectangle(1, 0.5, 0.25), {{"E": 1000.0, "nu": 0.3}}, dirichlet={{"left": "x"}},
                            traction={{"top": ["0", "-100*t"]}}, time={{"T": 1.0, "steps": 2}},
                            contact={{"part": "bottom", "g": 0.2, "stiffness": {{"law": "constant", "value": 100.0}}}},
                            solver={{"factorization": "pardiso"}})
assert vpcontact.solve(problem).status == "complete"
report = run_study(load_study({str(path)!r}, {str(tmp_path / 'out')!r}), {str(tmp_path / 'out')!r}, workers=2)
print(len(report["completed"]))
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-1] == "4"
