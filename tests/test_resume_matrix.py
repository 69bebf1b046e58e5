"""Every killed run resumes to the bits of an uninterrupted one, whatever stopped it.

The runs go through the command line in a subprocess, as a user's: 2D and 3D, elastic and
viscoplastic (the history z), with the error estimate, by the condensed method (the default here;
also past the solve after which it changes its factor) and the iterative one (the full method:
tests/test_robustness.py), each ``output.field_steps`` setting ("all", "final", "none", a list),
stopped after a random checkpoint by SIGTERM (the run stops at the end of the step, exit 143), by
SIGKILL (at any moment, a write included) or by a full disk (a real one: a small tmpfs filled while
the run is paused; exit 4, one line), some twice in a row; then
``--resume`` (the last one in this process, through the same entry point). Every file of the resumed
run directory is compared with those of an uninterrupted run of the same case (its fields at every
step, no checkpoints): history.csv and contact.csv (pandas, exactly, and byte for byte), the arrays
of solution.npz, the VTU and PNG files byte for byte, the PVD collections, the XDMF/HDF5 series, the resolved
case and summary.json. summary.json alone differs where it must: the wall times, the steps the run
was resumed at, the memory figure of solver_reason (``SESSION_KEYS``).
"""

import errno
import json
import os
import random
import signal
import subprocess
import sys
import time
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
import tomli_w

from vpcontact.io import checkpoint, directory
from vpcontact.cli import main
from conftest import block_3d_case, half_disc_case, rectangle_case

STEPS = 30


def elastic_2d(steps: int = STEPS) -> dict:
    case = rectangle_case()
    case["time"] = {"T": 1.1, "steps": steps}
    return case


def long_2d() -> dict:
    """The 2D block for 80 steps: past the 50 solves after which the condensed method's PARDISO factor
    changes (from the Schur-mode one to a plain one), which a resumed run must do at the same solve."""
    return elastic_2d(steps=80)


def elastic_3d() -> dict:
    case = block_3d_case()
    case["time"] = {"T": 1.1, "steps": STEPS}
    return case


def viscoplastic_2d() -> dict:
    """The half disc of a Perzyna body (z ≠ 0) on a layer with β = −1 (nodes reach the rigid limit)."""
    case = half_disc_case(h=0.2, stiffness={"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": -1.0})
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    case["time"] = {"T": 1.1, "steps": STEPS}
    return case


def estimated_3d() -> dict:
    """The 3D block of a Perzyna body with the residual error estimate of every step."""
    case = elastic_3d()
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 20.0}
    case["output"]["error_estimate"] = True
    return case


def iterative_3d() -> dict:
    """The 3D block by the iterative method (AMG-preconditioned CG: the hierarchy is built on a Newton
    matrix of some step, which a resumed run must build on the same matrix). With pyamg's multigrid where PETSc
    cannot be bound to its own BLAS (a python executable with libpython linked in): there PETSc takes MKL's BLAS in
    a process that used PARDISO before, as the reference run's test process did, and the resumed run, in a fresh
    process, the reference BLAS (vpcontact.parallel.petsc.deep_binding_is_safe)."""
    case = elastic_3d()
    case["solver"] = {"method": "iterative", **({} if petsc_is_bound_deeply() else {"multigrid": "pyamg"})}
    return case


def petsc_is_bound_deeply() -> bool:
    """Whether PETSc, if installed, is bound to its own BLAS whatever the process loaded before."""
    from vpcontact.parallel.petsc import deep_binding_is_safe

    return deep_binding_is_safe()


def displaced_3d() -> dict:
    """The 3D block of a Perzyna body pressed by a prescribed top displacement that reverses (u_D(t) at the held
    dofs, recomputed by the resumed loop from t), its back face held at a node set."""
    case = elastic_3d()
    case["boundary"]["traction"] = []
    case["boundary"]["dirichlet"] += [{"part": "top", "components": ["z"], "value": ["-0.02*sin(3*t)"]},
                                      {"where": "abs(y - 1) < 1e-9", "components": ["y"], "name": "back"}]
    case["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 5.0}
    return case


CASES = {"2d": elastic_2d, "3d": elastic_3d, "viscoplastic": viscoplastic_2d, "estimate": estimated_3d,
         "long": long_2d, "iterative": iterative_3d, "displacement": displaced_3d}
#: The cases whose runs with every field step also write the figures of a complete run (PNG files: the
#: same bytes however the run went).
FIGURES = ("2d",)
#: The step after which a run of the case is stopped at the earliest (default: the first).
EARLIEST = {"long": 52}

#: summary.json's values that belong to the sessions of a run, not to its numbers: the wall times, the
#: steps it was resumed at, the methods' costs predicted at the machine's speed of the session (in
#: predicted_costs and solver_reason; the method chosen, solver_method, is compared: a resumed run keeps it) and
#: the session's peak memory; every other value is the uninterrupted run's, the counts of solves and iterations
#: included.
SESSION_KEYS = ("wall_time_s", "timings_s", "resumed_at_steps", "solver_reason", "predicted_costs", "peak_memory_bytes")
#: ... but for linear_solves, which depends on the field steps (the condensed method recovers u where
#: it is written): compared when the run writes the reference's fields.
WRITTEN_FIELDS_KEYS = ("linear_solves",)


def write(folder: Path, name: str, case: dict) -> Path:
    path = folder / f"{name}.toml"
    path.write_text(tomli_w.dumps(case))
    return path


@pytest.fixture(scope="module")
def references(tmp_path_factory):
    """{case name: the run directory of its uninterrupted run}, its fields at every step (and as XDMF),
    no checkpoints; made once, on first use."""
    folder = tmp_path_factory.mktemp("references")
    made = {}

    def reference(name: str) -> Path:
        if name not in made:
            case = CASES[name]()
            case["output"].update(field_steps="all", xdmf=True, figures=name in FIGURES, checkpoint_every_steps=0,
                                  checkpoint_every_seconds=0)
            out = folder / name
            assert main(["run", str(write(folder, name, case)), "--out", str(out), "--quiet"]) == 0
            made[name] = out
        return made[name]

    return reference


@pytest.fixture
def small_disk(tmp_path):
    """A folder on a 32 MiB tmpfs of its own, to fill (root only: skipped elsewhere)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=32m", "tmpfs", str(disk)], capture_output=True,
                             text=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.strip()}")
    try:
        yield disk
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=True)


def fill(disk: Path) -> Path:
    """Write zeros on ``disk`` until it is full (ENOSPC); returns the file that holds them."""
    filler = disk / "filler"
    with open(filler, "wb", buffering=0) as handle:
        for size in (2**20, 2**12):
            with pytest.raises(OSError) as full:
                while True:
                    handle.write(bytes(size))
            assert full.value.errno == errno.ENOSPC
    return filler


def start(path: Path, out: Path, *flags: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "vpcontact.cli", "run", str(path), "--out", str(out), "--quiet",
                             *flags], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL, start_new_session=True)


def wait_for_checkpoint(process: subprocess.Popen, out: Path, step: int, timeout: float = 120.0) -> None:
    """Until the run's checkpoint is of ``step`` or later (the run must still go on). The run is paused (SIGSTOP)
    while its checkpoint is looked at: a run of short steps on a busy machine could otherwise pass from the
    step before to its end between two looks."""
    deadline = time.monotonic() + timeout
    while True:
        os.killpg(process.pid, signal.SIGSTOP)
        try:
            reached = (checkpoint.saved_step(out) or 0) >= step
            ended = process.poll() is not None
        finally:
            os.killpg(process.pid, signal.SIGCONT)
        if reached:
            return
        assert not ended, f"the run ended before its checkpoint of step {step}: {process.communicate()}"
        assert time.monotonic() < deadline, f"no checkpoint of step {step} in {timeout} s"
        time.sleep(0.002)


def interrupt(how: str, path: Path, out: Path, disk: Path | None, rng: random.Random, resume: bool,
              earliest: int = 0) -> int:
    """Run ``path`` into ``out`` (``resume``: with --resume) and stop it by ``how`` after a random
    checkpoint, after step ``earliest`` at least; check how it ended; returns the step of the
    checkpoint it left."""
    done = max(checkpoint.saved_step(out) or 0, earliest)
    target = rng.randint(done + 1, done + 6)
    process = start(path, out, *(["--resume"] if resume else []))
    try:
        wait_for_checkpoint(process, out, target)
        if how == "SIGTERM":
            process.send_signal(signal.SIGTERM)
        elif how == "SIGKILL":
            time.sleep(rng.uniform(0.0, 0.01))  # at any moment: perhaps in the middle of a write
            os.killpg(process.pid, signal.SIGKILL)
        else:
            os.killpg(process.pid, signal.SIGSTOP)  # the disk fills while the run is paused
            fill(disk)
            os.killpg(process.pid, signal.SIGCONT)
        _, stderr = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    step = checkpoint.saved_step(out)
    assert step is not None and step >= target, (how, step, target)
    if how == "SIGKILL":
        assert process.returncode == -signal.SIGKILL and not (out / "summary.json").exists()
    elif how == "SIGTERM":
        assert process.returncode == 143, stderr
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "interrupted" and summary["steps"] == step
        assert stderr == f"vpcontact: {summary['message']}\n" and "continue with --resume" in stderr
    else:
        assert process.returncode == 4, stderr
        assert stderr.startswith("vpcontact: stopped: No space left on device: '") and stderr.count("\n") == 1, stderr
        assert stderr.endswith(f"the checkpoint of step {step} is intact: make room, then continue with --resume\n")
        assert not (out / "summary.json").exists() and not list(out.rglob(".*.tmp-*")), "half-written files left"
        (disk / "filler").unlink()
    return step


def read_pvd(path: Path) -> list[tuple[str, str]]:
    return [(d.get("timestep"), d.get("file")) for d in ET.parse(path).getroot().iter("DataSet")]


#: The arrays of solution.npz with one entry per field step (the others are the mesh's).
PER_FIELD_STEP = ("steps", "times", "displacement", "stress", "z", "xi")


def assert_same_outputs(out: Path, reference: Path, steps: list[int], xdmf: bool, resumed_at: list[int]) -> None:
    """The run directory ``out`` holds exactly what an uninterrupted run with the field ``steps`` writes, and
    its numbers are those of ``reference`` (fields at every step) bit for bit."""
    fields = [f"fields/{part}_{n:05d}.vtu" for n in steps for part in ("body", "contact")]
    series = ["fields/body.pvd", "fields/contact.pvd", "solution.npz"] if steps else []
    hdf = [f"fields/{part}.{suffix}" for part in ("body", "contact") for suffix in ("h5", "xdmf")] \
        if xdmf and steps else []
    all_steps = len(steps) == len(read_pvd(reference / "fields/body.pvd"))
    figures = sorted(str(p.relative_to(reference)) for p in reference.glob("figures/*.png")) if all_steps else []
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert written == sorted(["case.resolved.toml", "summary.json", "history.csv", "contact.csv", *fields, *series,
                              *hdf, *figures]), "a missing or left-over file (a checkpoint, a temporary, the lock)"
    for name in ("history.csv", "contact.csv"):
        mine, theirs = (pd.read_csv(folder / name) for folder in (out, reference))
        pd.testing.assert_frame_equal(mine, theirs, check_exact=True, obj=name)
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name
    for name in fields + figures:
        assert (out / name).read_bytes() == (reference / name).read_bytes(), name
    if steps:
        at = [n - 1 for n in steps]
        with np.load(out / "solution.npz") as mine, np.load(reference / "solution.npz") as theirs:
            assert sorted(mine.files) == sorted(theirs.files)
            for key in theirs.files:
                expected = theirs[key][at] if key in PER_FIELD_STEP else theirs[key]
                np.testing.assert_array_equal(mine[key], expected, err_msg=key, strict=True)
        for part in ("body", "contact"):
            expected = [entry for entry in read_pvd(reference / f"fields/{part}.pvd")
                        if int(entry[1][-9:-4]) in steps]
            assert read_pvd(out / f"fields/{part}.pvd") == expected
    if hdf:
        for part in ("body", "contact"):
            with h5py.File(out / f"fields/{part}.h5") as mine, h5py.File(reference / f"fields/{part}.h5") as theirs:
                names = []
                mine.visit(lambda name: names.append(name) if isinstance(mine[name], h5py.Dataset) else None)
                assert names, part
                for name in names:
                    np.testing.assert_array_equal(mine[name][()], theirs[name][()], err_msg=f"{part}.h5 {name}")
    mine, theirs = (json.loads((folder / "summary.json").read_text()) for folder in (out, reference))
    assert mine["status"] == "complete" and mine["resumed_at_steps"] == resumed_at
    ignored = SESSION_KEYS if all_steps else SESSION_KEYS + WRITTEN_FIELDS_KEYS
    assert {k: v for k, v in mine.items() if k not in ignored} == {k: v for k, v in theirs.items() if k not in ignored}
    mine, theirs = (checkpoint.comparable(tomllib.loads((folder / "case.resolved.toml").read_text()))
                    for folder in (out, reference))
    for case in (mine, theirs):
        case["output"] = {k: v for k, v in case["output"].items() if k not in ("field_steps", "xdmf")}
    assert mine == theirs


#: (case, output.field_steps, what stops the run: one or two interruptions, resumed after each): each
#: case with each setting of the fields and each way of stopping, none of them with every other. (A run
#: of the long case is compared with a reference of the same field steps: the fields written decide
#: how many solves the condensed method does, and so when its factor changes.)
MATRIX = [
    ("2d", "all", ("SIGTERM",)),
    ("2d", "final", ("SIGKILL", "ENOSPC")),
    ("2d", [3, 10, 17, 30], ("ENOSPC",)),
    ("2d", "none", ("SIGKILL",)),
    ("3d", "all", ("SIGKILL",)),
    ("3d", "final", ("ENOSPC",)),
    ("3d", [1, 8, 16], ("SIGTERM", "SIGKILL")),
    ("3d", "none", ("SIGTERM",)),
    ("viscoplastic", [2, 9, 20, 30], ("SIGKILL", "ENOSPC")),
    ("estimate", "all", ("SIGTERM",)),
    ("long", "all", ("SIGKILL",)),
    ("iterative", [4, 15, 30], ("SIGKILL",)),
    ("displacement", [5, 12, 30], ("SIGKILL", "SIGTERM")),
]


def steps_of(field_steps, steps: int) -> list[int]:
    return {"all": list(range(1, steps + 1)), "final": [steps], "none": []}.get(str(field_steps), field_steps)


@pytest.mark.parametrize("name, field_steps, stops", MATRIX,
                         ids=[f"{name}-{str(fields).replace(' ', '')}-{'+'.join(stops)}"
                              for name, fields, stops in MATRIX])
def test_a_resumed_run_is_the_uninterrupted_one(tmp_path, references, request, name, field_steps, stops):
    seed = int.from_bytes(os.urandom(4), "little")
    rng = random.Random(seed)
    disk = request.getfixturevalue("small_disk") if "ENOSPC" in stops else None
    case = CASES[name]()
    xdmf = field_steps == "all"  # and the figures, as the reference
    case["output"].update(field_steps=field_steps, xdmf=xdmf, figures=xdmf and name in FIGURES,
                          checkpoint_every_steps=1)
    path = write(tmp_path, "case", case)
    out = (disk or tmp_path) / "run"
    resumed_at = []
    for how in stops:
        try:
            resumed_at.append(interrupt(how, path, out, disk, rng, resume=bool(resumed_at),
                                        earliest=EARLIEST.get(name, 0)))
        except AssertionError as error:
            raise AssertionError(f"seed {seed}: {error}") from None
    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 0, f"seed {seed}"
    assert_same_outputs(out, references(name), steps_of(field_steps, case["time"]["steps"]), xdmf, resumed_at)
    assert not (out / directory.LOCK).exists()


def older(out: Path, case_keys: dict[str, tuple[str, ...]], meta_keys: tuple[str, ...],
          array_prefixes: tuple[str, ...] = ()) -> None:
    """Make the checkpoint in ``out`` look written by an earlier vpcontact: without the case keys (section: names),
    meta values and arrays (by prefix) added since."""
    path = checkpoint.folder(out) / checkpoint.STATE
    with np.load(path) as stored:
        arrays = {key: stored[key] for key in stored.files if not key.startswith(array_prefixes or ("\0",))}
    case = tomllib.loads(str(arrays["case"]))
    for section, names in case_keys.items():
        assert any(name in case[section] for name in names), case[section]
        case[section] = {k: v for k, v in case[section].items() if k not in names}
    meta = json.loads(str(arrays["meta"]))
    assert all(key in meta for key in meta_keys)
    arrays["case"] = np.array(tomli_w.dumps(case))
    arrays["meta"] = np.array(json.dumps({k: v for k, v in meta.items() if k not in meta_keys}))
    np.savez(path, **arrays)


#: What checkpoints of vpcontact before the estimate in time (time.adaptive) lack.
BEFORE_TIME_ADAPTIVE = {"case_keys": {"time": ("adaptive", "balance", "max_halvings")},
                        "meta_keys": ("time_cuts", "halvings", "time_over_share", "time_largest")}


def test_a_checkpoint_of_an_earlier_version_resumes_with_the_new_keys_at_their_defaults(tmp_path, references):
    """A run stopped by an earlier vpcontact, whose case had no time.adaptive (a key added since, whose default
    keeps what that run did) and whose checkpoint has no time control: it resumes, and is the uninterrupted run
    bit for bit."""
    case = CASES["viscoplastic"]()
    case["output"].update(field_steps="all", xdmf=True, figures="viscoplastic" in FIGURES, checkpoint_every_steps=1)
    path = write(tmp_path, "case", case)
    out = tmp_path / "run"
    step = interrupt("SIGTERM", path, out, None, random.Random(5), resume=False)
    older(out, **BEFORE_TIME_ADAPTIVE)
    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 0
    assert_same_outputs(out, references("viscoplastic"), steps_of("all", case["time"]["steps"]), True, [step])


def test_a_checkpoint_of_an_earlier_version_without_what_the_case_needs_is_refused(tmp_path, capsys):
    """The error estimate in time needs the companion's level and the history's columns of it, which a checkpoint
    of an earlier version has not: exit 2, one line naming what is missing; the checkpoint stays."""
    case = elastic_2d(steps=12)
    case["output"].update(error_estimate=True, checkpoint_every_steps=1)
    path = write(tmp_path, "case", case)
    out = tmp_path / "run"
    interrupt("SIGTERM", path, out, None, random.Random(6), resume=False)
    older(out, **BEFORE_TIME_ADAPTIVE, array_prefixes=("companion_", "row_time_estimate"))
    kept = (checkpoint.folder(out) / checkpoint.STATE).read_bytes()
    capsys.readouterr()
    assert main(["run", str(path), "--out", str(out), "--quiet", "--resume"]) == 2
    stderr = capsys.readouterr().err
    assert stderr.count("\n") == 1 and "the checkpoint has no 'row_time_estimate" in stderr, stderr
    assert "written by an earlier one" in stderr and "--overwrite" in stderr
    assert (checkpoint.folder(out) / checkpoint.STATE).read_bytes() == kept
