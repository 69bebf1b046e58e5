"""Run directories that never lose a user's file: --overwrite removes only vpcontact's outputs, an
unusable --out, a damaged checkpoint or a symbolic link where a run writes is refused with one line
(exit 2) before anything is computed or written, and a run whose directory is removed or replaced
under it, or where a link appears, stops writing (exit 4); nothing is ever written through a link."""

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import tomli_w

import vpcontact
import vpcontact.io.solution
from vpcontact.io import checkpoint, directory
from vpcontact.io.files import write_text
from vpcontact.io.outputs import write_outputs
from vpcontact.io.run import remove_outputs, write_resolved_case, write_run
from vpcontact.cli import main
from vpcontact import build_problem
from vpcontact.case.translate import output_options
from vpcontact.timeloop.loop import TimeLoop
from conftest import assert_refused, half_disc_case, rectangle_case, run_cli, snapshot_tree


def write_case(folder, name="case.toml", **output):
    """A fast case (11 steps, 0.1 s) writing the fields of every step (fields/ is used)."""
    case = rectangle_case()
    case["output"] = {"field_steps": "all", **output}
    path = Path(folder) / name
    path.write_text(tomli_w.dumps(case))
    return path


def contents(folder):
    """{relative path: bytes} of every file under ``folder``."""
    folder = Path(folder)
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def put_user_files(out):
    """What a user keeps in a run directory: the case and mesh, notes, a folder with files named like
    outputs, a file in fields/ and in checkpoint/, hidden files; returns them ({path: bytes})."""
    out.mkdir(parents=True, exist_ok=True)
    before = contents(out)
    write_case(out, "my_case.toml")
    (out / "mesh.msh").write_bytes(b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
    (out / "notes.txt").write_text("calibration notes")
    (out / "old").mkdir(exist_ok=True)
    (out / "old" / "summary.json").write_text('{"status": "complete", "mine": true}')
    (out / "old" / "history.csv").write_text("mine\n")
    (out / "fields").mkdir(exist_ok=True)
    (out / "fields" / "my_view.pvsm").write_text("<ParaView/>")
    (out / "checkpoint").mkdir(exist_ok=True)
    (out / "checkpoint" / "README").write_text("do not delete")
    (out / ".hidden").write_text("mine")
    (out / ".history.tmp-notes.csv").write_text("named like a temporary, but not one")
    return {name: data for name, data in contents(out).items() if name not in before}


def assert_user_files_intact(out, before):
    after = contents(out)
    for name, data in before.items():
        assert after.get(name) == data, f"{name} changed or deleted"


# --- 1. --overwrite removes only vpcontact's outputs -------------------------------------------------
def test_overwrite_keeps_every_file_vpcontact_did_not_write(tmp_path):
    out = tmp_path / "run"
    case = write_case(tmp_path)
    assert run_cli("run", case, "--out", out, "--quiet")[0] == 0
    mine = put_user_files(out)
    vtu_before = sorted(p.name for p in (out / "fields").glob("*.vtu"))
    assert len(vtu_before) == 22

    # the new run writes no fields: the old ones go, fields/ stays for the user's file in it
    status, stdout, stderr = run_cli("run", case, "--out", out, "--quiet", "--overwrite",
                                     "--set", 'output.field_steps="none"', "--set", "contact.g=0.15")
    assert status == 0, stderr
    assert_user_files_intact(out, mine)
    assert sorted(p.name for p in (out / "fields").iterdir()) == ["my_view.pvsm"]
    assert sorted(p.name for p in (out / "checkpoint").iterdir()) == ["README"]
    assert not (out / "solution.npz").exists() and not (out / directory.LOCK).exists()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "complete" and vpcontact.load_case(out / "case.resolved.toml").contact.g == 0.15


def test_overwrite_removes_fields_and_checkpoint_folders_it_empties(tmp_path):
    out = tmp_path / "run"
    case = write_case(tmp_path)
    assert run_cli("run", case, "--out", out, "--quiet")[0] == 0
    (out / "notes.txt").write_text("mine")
    assert run_cli("run", case, "--out", out, "--quiet", "--overwrite", "--set", 'output.field_steps="none"')[0] == 0
    assert sorted(p.name for p in out.iterdir()) == ["case.resolved.toml", "contact.csv", "history.csv", "notes.txt",
                                                     "summary.json"]


def test_the_list_of_outputs_names_every_file_a_run_writes(tmp_path):
    """A run directory holding everything a run writes (outputs, fields, a checkpoint with fields,
    temporaries of every kind) is empty after remove_outputs: the list misses nothing."""
    case = rectangle_case()
    case["output"]["field_steps"] = "all"
    case = vpcontact.load_case(case)
    loop = TimeLoop(build_problem(case), output_options(case.output))
    result = loop.run(stop=lambda: "stopped" if loop.state.step >= 5 else None)
    out = tmp_path / "run"
    out.mkdir()
    checkpoint.save(loop, out)
    write_resolved_case(case.to_toml(), out)
    write_outputs(result, out)
    for path in list(out.rglob("*")):
        if path.is_file():
            (path.parent / f".{path.stem}.tmp-12345{path.suffix}").write_text("half a file")
    assert {p.parent.name for p in out.rglob("*.npz")} == {"run", "checkpoint"} and len(list(out.rglob("*"))) > 40
    remove_outputs(out)
    assert list(out.iterdir()) == []


def test_write_run_with_overwrite_keeps_the_users_files(tmp_path):
    result = vpcontact.solve(rectangle_case())
    out = tmp_path / "run"
    write_run(result, out)
    mine = put_user_files(out)
    write_run(result, out, overwrite=True)
    assert_user_files_intact(out, mine)
    assert json.loads((out / "summary.json").read_text())["status"] == "complete"
    with pytest.raises(FileExistsError):
        write_run(result, out)


# --- 4. an unusable --out: exit 2, one line, nothing written, nothing computed ------------------------
def _file(tmp):
    (tmp / "file").write_text("a user's file")
    return tmp / "file"


def _loop(tmp):
    os.symlink("b", tmp / "a")
    os.symlink("a", tmp / "b")
    return tmp / "a"


def _dangling(tmp):
    os.symlink("missing", tmp / "link")
    return tmp / "link"


def _fifo(tmp):
    os.mkfifo(tmp / "fifo")
    return tmp / "fifo"


UNUSABLE = {
    "a regular file": (lambda tmp: _file(tmp), "exists and is not a directory"),
    "below a regular file": (lambda tmp: _file(tmp) / "run", "is not a directory"),
    "deep below a regular file": (lambda tmp: _file(tmp) / "a" / "b", "is not a directory"),
    "a FIFO": (lambda tmp: _fifo(tmp), "exists and is not a directory"),
    "/dev/null": (lambda tmp: Path("/dev/null"), "exists and is not a directory"),
    "a symbolic link loop": (lambda tmp: _loop(tmp), "symbolic link loop"),
    "below a symbolic link loop": (lambda tmp: _loop(tmp) / "run", "symbolic link loop"),
    "a dangling symbolic link": (lambda tmp: _dangling(tmp), "which does not exist"),
    "below a dangling symbolic link": (lambda tmp: _dangling(tmp) / "run", "which does not exist"),
    "a new folder under /proc": (lambda tmp: Path("/proc/vpcontact-test/run"), "cannot create the directory"),
    "a folder of /proc": (lambda tmp: Path("/proc/self/fdinfo/run"), "cannot create the directory"),
    "under /sys": (lambda tmp: Path("/sys/vpcontact-test"), "cannot create the directory"),
}


@pytest.mark.parametrize("kind, flag", [(kind, "") for kind in sorted(UNUSABLE)] + [
    (kind, flag) for kind in ("a regular file", "a symbolic link loop", "a dangling symbolic link",
                              "a new folder under /proc") for flag in ("--overwrite", "--resume")])
def test_an_unusable_out_is_refused_with_one_line(tmp_path, kind, flag):
    make, words = UNUSABLE[kind]
    case = write_case(tmp_path)
    out = make(tmp_path)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", *([flag] if flag else []))
    assert_refused(status, stderr, str(out), words, untouched=[(tmp_path, before)])


@pytest.mark.parametrize("flag", ["", "--overwrite", "--resume"])
@pytest.mark.parametrize("name, words", [("n" * 300, "has 300 bytes, more than the 255 the file system allows: give a "
                                                      "shorter name"),
                                         ("n/" * 3000, "bytes of a path the file system allows: give a shorter path")])
def test_an_out_longer_than_the_file_system_allows_is_refused(tmp_path, name, words, flag):
    case = write_case(tmp_path)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", tmp_path / name, "--quiet", *([flag] if flag else []))
    assert_refused(status, stderr, "--out", words, untouched=[(tmp_path, before)])


IN_THE_WAY = {
    "a folder named summary.json": (lambda out: (out / "summary.json").mkdir(), "summary.json' is a folder"),
    "a folder named case.resolved.toml": (lambda out: (out / "case.resolved.toml").mkdir(), "is a folder"),
    "a file named fields": (lambda out: (out / "fields").write_text("mine"), "fields' is not a folder"),
    "a file named checkpoint": (lambda out: (out / "checkpoint").write_text("mine"), "checkpoint' is not a folder"),
}


@pytest.mark.parametrize("flag", ["--overwrite", "--resume"])
@pytest.mark.parametrize("kind", sorted(IN_THE_WAY))
def test_a_user_file_where_a_run_writes_is_refused_before_the_run(tmp_path, kind, flag):
    """What stands where an output goes is the user's: refused at once (not after the computation),
    and left alone."""
    make, words = IN_THE_WAY[kind]
    case = write_case(tmp_path)
    out = tmp_path / "run"
    out.mkdir()
    make(out)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", flag)
    assert_refused(status, stderr, words, "move it away", untouched=[(tmp_path, before)])


@pytest.mark.parametrize("out, flag", [("/proc/self", "--overwrite"), ("/proc", "--resume")])
def test_an_existing_directory_on_a_read_only_file_system_is_refused(tmp_path, out, flag):
    case = write_case(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", flag)
    assert_refused(status, stderr, out, "cannot write in the directory")


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_a_read_only_directory_is_refused(tmp_path):
    case = write_case(tmp_path)
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        status, _, stderr = run_cli("run", case, "--out", folder / "run", "--quiet")
        assert_refused(status, stderr, "cannot create the directory", "Permission denied")
    finally:
        folder.chmod(0o755)


def test_out_is_checked_before_the_case_is_built(tmp_path):
    """An unusable --out is refused before any computation: before the mesh and its parts are built."""
    case = write_case(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", "/proc/vpcontact-test", "--quiet",
                                "--set", 'contact.part="nonexistent"')
    assert_refused(status, stderr, "/proc/vpcontact-test", "cannot create the directory")


@pytest.mark.parametrize("depth", [1, 3])
def test_a_case_refused_after_out_was_created_leaves_nothing(tmp_path, depth):
    """The directory (and parents) created for the run are removed again when the case is refused."""
    case = write_case(tmp_path)
    out = tmp_path.joinpath(*[f"level{i}" for i in range(depth)])
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", "--set", 'contact.part="nonexistent"')
    assert_refused(status, stderr, "nonexistent", untouched=[(tmp_path, before)])


def test_a_case_refused_in_a_used_directory_changes_nothing_in_it(tmp_path):
    out = tmp_path / "run"
    case = write_case(tmp_path)
    assert run_cli("run", case, "--out", out, "--quiet")[0] == 0
    put_user_files(out)
    (out / directory.LOCK).write_text("")  # a killed run's lock file stays too
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", "--overwrite", "--set", 'contact.part="nope"')
    assert_refused(status, stderr, "nope", untouched=[(tmp_path, before)])


def test_a_used_directory_is_refused_without_overwrite_or_resume(tmp_path):
    out = tmp_path / "run"
    case = write_case(tmp_path)
    mine = put_user_files(out)
    before = snapshot_tree(out)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet")
    assert_refused(status, stderr, "is not empty", "--overwrite", untouched=[(out, before)])
    assert contents(out) == mine


# --- 4. --resume from a damaged checkpoint: exit 2, one line naming the file and what to do ----------
def killed_run(folder, steps_done=5):
    """A run directory as a run killed after its checkpoint at step ``steps_done`` leaves it (fields
    saved at steps 2 and 4)."""
    case = rectangle_case()
    case["output"] = {"field_steps": [2, 4, 11], "checkpoint_every_steps": 1}
    path = Path(folder) / "case.toml"
    path.write_text(tomli_w.dumps(case))
    loaded = vpcontact.load_case(path)
    loop = TimeLoop(build_problem(loaded), output_options(loaded.output))
    loop.run(stop=lambda: "killed" if loop.state.step >= steps_done else None)
    out = Path(folder) / "run"
    out.mkdir()
    write_resolved_case(loaded.to_toml(), out)
    checkpoint.save(loop, out)
    write_outputs(loop.result, out, history_only=True)
    return path, out


def _truncate(fraction, name="state.npz"):
    def damage(out):
        path = out / "checkpoint" / name
        data = path.read_bytes()
        path.write_bytes(data[: int(len(data) * fraction)])
        return path, "empty" if fraction == 0 else "truncated or damaged"
    return damage


def _remove(name):
    def damage(out):
        (out / "checkpoint" / name).unlink()
        return out / "checkpoint" / name, "is missing"
    return damage


def _garbage(out):
    path = out / "checkpoint" / "state.npz"
    path.write_bytes(os.urandom(5000))
    return path, "truncated or damaged"


def _folder(out):
    path = out / "checkpoint" / "fields_00004.npz"
    path.unlink()
    path.mkdir()
    return path, "not a regular file"


def _not_ours(out):
    path = out / "checkpoint" / "state.npz"
    np.savez(path, something=np.arange(3))
    return path, "unreadable checkpoint"


DAMAGE = {
    "empty state.npz": _truncate(0.0),
    "state.npz cut to 1%": _truncate(0.01),
    "state.npz cut in half": _truncate(0.5),
    "state.npz without its last byte": _truncate(0.9999),
    "a fields file cut in half": _truncate(0.5, "fields_00002.npz"),
    "an empty fields file": _truncate(0.0, "fields_00004.npz"),
    "a missing fields file": _remove("fields_00002.npz"),
    "state.npz of random bytes": _garbage,
    "a fields file that is a folder": _folder,
    "an .npz that is not a checkpoint": _not_ours,
}


@pytest.mark.parametrize("kind", sorted(DAMAGE))
def test_resume_from_a_damaged_checkpoint_is_refused(tmp_path, kind):
    case, out = killed_run(tmp_path)
    path, words = DAMAGE[kind](out)
    before = snapshot_tree(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", "--resume")
    assert_refused(status, stderr, str(path), words, "--overwrite", untouched=[(tmp_path, before)])


def test_after_a_damaged_checkpoint_overwrite_starts_again(tmp_path):
    case, out = killed_run(tmp_path)
    _truncate(0.5)(out)
    assert run_cli("run", case, "--out", out, "--quiet", "--resume")[0] == 2
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", "--overwrite")
    assert status == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["resumed_at_steps"] == [] and not (out / "checkpoint").exists()


def test_resume_from_an_intact_checkpoint_still_works(tmp_path):
    case, out = killed_run(tmp_path)
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", "--resume")
    assert status == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["resumed_at_steps"] == [5] and summary["steps"] == 11 and not (out / "checkpoint").exists()


# --- 3. a run writes only into the directory it locked ----------------------------------------------
def slow_case(folder):
    """The half disc with a creeping body: 400 steps, a checkpoint after each (several seconds)."""
    case = half_disc_case(h=0.1, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["boundary"]["traction"][0]["value"] = ["0", "-20*min(t, 0.5)"]
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    case["time"] = {"T": 2.0, "steps": 400}
    case["output"] = {"field_steps": [100, 200, 400], "checkpoint_every_steps": 1}
    path = Path(folder) / "slow.toml"
    path.write_text(tomli_w.dumps(case))
    return path


def start_run(case, out):
    return subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "run", str(case), "--out", str(out), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)


def wait_for(condition, process, timeout=60.0):
    deadline = time.time() + timeout
    while not condition():
        assert process.poll() is None, f"the run ended too early: {process.communicate()}"
        assert time.time() < deadline, "timed out"
        time.sleep(0.005)


@pytest.mark.parametrize("replace", [True, False], ids=["replaced", "removed"])
def test_a_run_whose_directory_is_replaced_stops_writing(tmp_path, replace):
    out = tmp_path / "run"
    process = start_run(slow_case(tmp_path), out)
    try:
        wait_for(lambda: (out / "checkpoint" / "state.npz").exists(), process)
        os.kill(process.pid, signal.SIGSTOP)  # the swap is two steps: the run must not look in between
        out.rename(tmp_path / "moved")
        if replace:
            out.mkdir()
            (out / "notes.txt").write_text("a new directory of the user")
        before = snapshot_tree(tmp_path / "run")
        os.kill(process.pid, signal.SIGCONT)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 4, stderr
    assert stderr.count("\n") == 1 and "Traceback" not in stderr, stderr
    assert f"the directory '{out}' was {'replaced by another directory' if replace else 'removed'}" in stderr
    time.sleep(0.5)
    assert snapshot_tree(out) == before  # nothing written into the new directory, nothing recreated
    # the run's own directory, where it was moved, holds the run so far (and perhaps the temporary file
    # of the write the swap interrupted, as a killed run does; --resume removes it)
    moved = tmp_path / "moved"
    assert not (moved / "summary.json").exists() and (moved / "checkpoint" / "state.npz").exists()
    assert {p.name for p in moved.iterdir() if not p.match(".history.tmp-*.csv")} <= {
        "case.resolved.toml", "history.csv", "checkpoint", directory.LOCK}


def test_a_run_resumes_in_its_moved_directory(tmp_path):
    """The run stopped by a replaced directory left a valid checkpoint in the directory it wrote to."""
    out = tmp_path / "run"
    case = slow_case(tmp_path)
    process = start_run(case, out)
    try:
        wait_for(lambda: (out / "checkpoint" / "state.npz").exists(), process)
        out.rename(tmp_path / "moved")
        out.mkdir()
        process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 4
    status, _, stderr = run_cli("run", case, "--out", tmp_path / "moved", "--quiet", "--resume",
                                "--set", "output.checkpoint_every_steps=0", timeout=300)
    assert status == 0, stderr
    summary = json.loads((tmp_path / "moved" / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["resumed_at_steps"][0] >= 1
    assert list(out.iterdir()) == []


def test_the_held_directory_is_checked_before_each_write(tmp_path):
    """In-process: once the held directory is replaced, every write raises DirectoryReplaced and the
    new directory stays as it is (its lock file too); the lock file goes from the directory locked."""
    out = tmp_path / "run"
    held = directory.acquire(out)
    write_text(out / "history.csv", "step\n")
    out.rename(tmp_path / "moved")
    out.mkdir()
    (out / directory.LOCK).write_text("")  # a lock file of another run now there
    for write in (lambda: write_text(out / "summary.json", "{}"),
                  lambda: directory.mkdir(out / "fields"),
                  lambda: write_text(out / "fields" / "body.pvd", ""),
                  lambda: remove_outputs(out)):
        with pytest.raises(directory.DirectoryReplaced, match="replaced by another directory"):
            write()
    held.release()
    assert sorted(p.name for p in out.iterdir()) == [directory.LOCK]
    assert sorted(p.name for p in (tmp_path / "moved").iterdir()) == ["history.csv"]


def test_a_swap_between_the_check_and_the_write_still_misses_the_new_directory(tmp_path, monkeypatch):
    """Files and folders are created, renamed and removed relative to the directory locked: even a
    swap the check does not see (the check disabled here) leaves the new directory untouched."""
    out = tmp_path / "run"
    held = directory.acquire(out)
    write_text(out / "summary.json", "{}")
    out.rename(tmp_path / "moved")
    out.mkdir()
    (out / "summary.json").write_text("the user's")
    monkeypatch.setattr(directory.Held, "check", lambda self: None)
    directory.unlink(out / "summary.json")
    directory.mkdir(out / "fields")
    with pytest.raises(directory.DirectoryReplaced, match="is not the file vpcontact created"):
        write_text(out / "history.csv", "step\n")  # the temporary was written in the new directory
    held.release()
    assert contents(out) == {"summary.json": b"the user's"} and [p.name for p in out.iterdir()] == ["summary.json"]
    assert sorted(p.name for p in (tmp_path / "moved").iterdir()) == ["fields"]


def test_a_write_that_fails_ends_the_run_with_one_line(tmp_path, monkeypatch, capsys):
    """A full disk (say) during the run: exit 4 and one line naming the file and the reason."""
    def disk_full(result, out):
        raise OSError(errno.ENOSPC, "No space left on device", str(out / "solution.npz"))

    monkeypatch.setattr(vpcontact.io.solution, "write", disk_full)
    out = tmp_path / "run"
    assert main(["run", str(write_case(tmp_path)), "--out", str(out), "--quiet"]) == 4
    stderr = capsys.readouterr().err
    assert stderr == (f"vpcontact: stopped: No space left on device: '{out / 'solution.npz'}'; no checkpoint was "
                      f"written yet: make room, then run it again with --resume (it starts over)\n")
    assert not (out / "summary.json").exists() and not (out / directory.LOCK).exists()


def test_two_processes_never_hold_one_directory(tmp_path):
    out = tmp_path / "run"
    held = directory.acquire(out)
    try:
        status, _, stderr = run_cli("run", write_case(tmp_path), "--out", out, "--quiet", "--overwrite")
        assert_refused(status, stderr, "another vpcontact run is writing to it")
    finally:
        held.release()
    assert list(out.iterdir()) == []


# --- 5. a symbolic link inside a run directory is the user's: never written through, never removed ---
def user_folder(tmp_path):
    """A user's folder with files named like a run's (fields, checkpoint files): the target of links."""
    folder = tmp_path / "users_folder"
    folder.mkdir()
    for name in ("body.h5", "body.pvd", "body_00001.vtu", "contact_00002.vtu", "state.npz", "fields_00002.npz",
                 "notes.txt"):
        (folder / name).write_bytes(os.urandom(64))
    return folder


def user_file(tmp_path):
    path = tmp_path / "users_table.csv"
    path.write_text("the user's own table\n")
    return path


#: What is made a link in the run directory, and to what (a folder or a file of the user).
LINKS = {"fields": user_folder, "checkpoint": user_folder, "figures": user_folder, "cycles": user_folder,
         "history.csv": user_file, "summary.json": user_file, directory.LOCK: user_file}


def link_in(out, name, tmp_path):
    """Replace ``out/name`` (if there) by a symbolic link to a user's folder or file; returns the link."""
    target = LINKS[name](tmp_path)
    link = out / name
    if link.is_dir() and not link.is_symlink():
        link.rename(tmp_path / f"{name}.moved")
    elif os.path.lexists(link):
        link.unlink()
    link.symlink_to(target, target_is_directory=target.is_dir())
    return link


def everything(folder):
    """{relative path: bytes, or the target of a link} of every entry under ``folder``, links not followed."""
    found = {}
    for root, folders, files in os.walk(folder):
        for name in folders + files:
            path = Path(root) / name
            found[str(path.relative_to(folder))] = (os.readlink(path) if path.is_symlink() else
                                                     path.read_bytes() if path.is_file() else "folder")
    return found


@pytest.mark.parametrize("flag", ["", "--overwrite", "--resume"])
@pytest.mark.parametrize("name", sorted(LINKS))
def test_a_link_in_the_run_directory_is_refused_before_anything_is_written(tmp_path, name, flag, capsys):
    """A plain run (into a directory that holds only the link), --overwrite (over a complete run) and
    --resume (of a killed run with its checkpoint): one line naming the link and what to do, exit 2,
    and nothing changed, neither in the run directory nor where the link leads."""
    case, out = killed_run(tmp_path)
    if flag == "--overwrite":
        assert main(["run", str(case), "--out", str(out), "--quiet", "--resume"]) == 0
    elif flag == "":
        shutil.rmtree(out)
        out.mkdir()
    link = link_in(out, name, tmp_path)
    capsys.readouterr()
    before = everything(tmp_path)
    status = main(["run", str(case), "--out", str(out), "--quiet", *([flag] if flag else [])])
    assert_refused(status, capsys.readouterr().err, f"'{link}' is a symbolic link", "remove the link")
    assert everything(tmp_path) == before


def test_the_refusal_of_a_link_through_the_command_line(tmp_path):
    """The same through the command line (a process): a user's body.h5 behind a linked fields/ stays."""
    case, out = killed_run(tmp_path)
    link = link_in(out, "fields", tmp_path)
    before = everything(tmp_path)
    for flag in ("--overwrite", "--resume"):
        status, _, stderr = run_cli("run", case, "--out", out, "--quiet", flag)
        assert_refused(status, stderr, f"'{link}' is a symbolic link (to '{tmp_path / 'users_folder'}')")
    assert everything(tmp_path) == before


@pytest.mark.parametrize("name", ["fields/body_00003.vtu", "checkpoint/state.npz", "checkpoint/fields_00004.npz",
                                  ".history.tmp-12345.csv", "fields/.body.tmp-12345.pvd"])
def test_a_link_named_like_an_output_inside_the_folders_is_refused_too(tmp_path, name, capsys):
    case, out = killed_run(tmp_path)
    (out / "fields").mkdir(exist_ok=True)
    target = user_file(tmp_path)
    link = out / name
    link.unlink(missing_ok=True)
    link.symlink_to(target)
    before = everything(tmp_path)
    status = main(["run", str(case), "--out", str(out), "--quiet", "--overwrite"])
    assert_refused(status, capsys.readouterr().err, f"'{link}' is a symbolic link")
    assert everything(tmp_path) == before


def test_result_write_refuses_a_link_in_its_directory(tmp_path):
    """The Python API's Result.write (write_run) as the command line: CaseError, nothing changed."""
    result = vpcontact.solve(rectangle_case())
    out = tmp_path / "run"
    vpcontact.write_run(result, out)
    link = link_in(out, "fields", tmp_path)
    before = everything(tmp_path)
    with pytest.raises(vpcontact.CaseError, match=f"'{link}' is a symbolic link"):
        vpcontact.write_run(result, out, overwrite=True)
    assert everything(tmp_path) == before


def test_out_itself_may_be_a_link_to_a_folder(tmp_path):
    """--out a link to a folder elsewhere (another disk): the run, --resume and --overwrite write there."""
    case, real = killed_run(tmp_path)
    out = tmp_path / "shortcut"
    out.symlink_to(real, target_is_directory=True)
    assert main(["run", str(case), "--out", str(out), "--quiet", "--resume"]) == 0
    assert json.loads((real / "summary.json").read_text())["resumed_at_steps"] == [5]
    assert main(["run", str(case), "--out", str(out), "--quiet", "--overwrite"]) == 0
    assert json.loads((real / "summary.json").read_text())["resumed_at_steps"] == []
    assert out.is_symlink() and not (real / directory.LOCK).exists()


def test_no_single_write_goes_through_a_link_made_after_the_start(tmp_path):
    """In-process, a held directory where links appear after the run's check: every write, folder and
    removal refuses them (SymbolicLink naming the link) and the user's files stay as they were."""
    out = tmp_path / "run"
    held = directory.acquire(out)
    try:
        write_text(out / "history.csv", "mine\n")
        folder, table = user_folder(tmp_path), user_file(tmp_path)
        (out / "fields").symlink_to(folder, target_is_directory=True)
        (out / "summary.json").symlink_to(table)
        before = everything(tmp_path)
        for attempt, link in [
            (lambda: write_text(out / "fields" / "body.pvd", "<VTKFile/>"), out / "fields"),
            (lambda: write_text(out / "fields" / "body.h5", "data"), out / "fields"),
            (lambda: directory.mkdir(out / "fields"), out / "fields"),
            (lambda: directory.mkdir(out / "fields" / "deeper"), out / "fields"),
            (lambda: directory.unlink(out / "fields" / "body.h5"), out / "fields"),
            (lambda: directory.rmdir(out / "fields"), out / "fields"),
            (lambda: write_text(out / "summary.json", "{}"), out / "summary.json"),
            (lambda: directory.unlink(out / "summary.json"), out / "summary.json"),
            (lambda: directory.create(out / "summary.json", out / "x.npz"), out / "summary.json"),  # as a temporary
        ]:
            with pytest.raises(directory.SymbolicLink, match=f"'{link}' is a symbolic link"):
                attempt()
            assert everything(tmp_path) == before
        remove_outputs(out)  # removes the run's files, passes the links by
        assert sorted(p.name for p in out.iterdir()) == [directory.LOCK, "fields", "summary.json"]
        assert everything(folder) == {k[len("users_folder/"):]: v for k, v in before.items()
                                      if k.startswith("users_folder/")}
        assert table.read_text() == "the user's own table\n"
    finally:
        held.release()


def test_a_link_made_during_a_run_stops_it_and_the_run_resumes_once_it_is_gone(tmp_path):
    """A link put in place of history.csv while the run goes: exit 4, one line naming the link, the
    checkpoint and the user's file intact; --resume once the link is removed completes the run."""
    out = tmp_path / "run"
    case = slow_case(tmp_path)
    table = user_file(tmp_path)
    process = start_run(case, out)
    try:
        wait_for(lambda: (out / "checkpoint" / "state.npz").exists(), process)
        os.kill(process.pid, signal.SIGSTOP)
        (out / "history.csv").unlink(missing_ok=True)
        (out / "history.csv").symlink_to(table)
        os.kill(process.pid, signal.SIGCONT)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    step = checkpoint.saved_step(out)
    assert process.returncode == 4, stderr
    assert stderr == (f"vpcontact: stopped: '{out / 'history.csv'}' is a symbolic link (to '{table}'), and vpcontact "
                      f"never writes or removes through a link in its output directory; the "
                      f"checkpoint of step {step} is intact: remove the link (what it leads to is kept), then continue "
                      f"with --resume\n")
    assert table.read_text() == "the user's own table\n" and (out / "history.csv").is_symlink()
    (out / "history.csv").unlink()
    status, _, stderr = run_cli("run", case, "--out", out, "--quiet", "--resume", "--set",
                                "output.checkpoint_every_steps=0", timeout=300)
    assert status == 0, stderr
    assert json.loads((out / "summary.json").read_text())["resumed_at_steps"] == [step]


def test_a_study_refuses_links_in_its_directory(tmp_path, capsys):
    """study.csv, a run's fields/ inside runs/<id>/, or the lock file a link: refused before any run."""
    base = rectangle_case()
    (tmp_path / "base.toml").write_text(tomli_w.dumps(base))
    study = tmp_path / "study.toml"
    study.write_text('base = "base.toml"\n[[vary]]\n"contact.g" = [0.1, 0.2]\n')
    out = tmp_path / "study"
    status, _, stderr = run_cli("study", study, "--out", out, "--quiet", "--workers", "1")
    assert status == 0, stderr
    runs = sorted((out / "runs").iterdir())
    for link, target in [(out / "study.csv", user_file(tmp_path)), (runs[0] / "history.csv", user_file(tmp_path)),
                         (runs[1] / "fields", user_folder(tmp_path))]:
        if link.is_file():
            link.unlink()
        link.symlink_to(target)
        (runs[0] / "summary.json").unlink(missing_ok=True)  # a run to do again
        before = everything(tmp_path)
        capsys.readouterr()
        status = main(["study", str(study), "--out", str(out), "--quiet", "--workers", "1"])
        assert_refused(status, capsys.readouterr().err, f"'{link}' is a symbolic link")
        assert everything(tmp_path) == before
        link.unlink()


def test_an_adaptive_run_refuses_a_linked_cycle_folder(tmp_path):
    case = half_disc_case(h=0.25)
    case["adapt"] = {"cycles": 2, "theta": 0.5}
    path = tmp_path / "adaptive.toml"
    path.write_text(tomli_w.dumps(case))
    out = tmp_path / "run"
    (out / "cycles").mkdir(parents=True)
    (out / "cycles" / "1").symlink_to(user_folder(tmp_path), target_is_directory=True)
    before = everything(tmp_path)
    status, _, stderr = run_cli("run", path, "--out", out, "--quiet", "--overwrite")
    assert_refused(status, stderr, f"'{out / 'cycles' / '1'}' is a symbolic link")
    assert everything(tmp_path) == before
