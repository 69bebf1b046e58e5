"""Checkpoints of a run in progress: the time loop's snapshot (:meth:`~vpcontact.timeloop.loop.TimeLoop.snapshot`,
everything it needs to continue as if it had never stopped) in files, and back (``TimeLoop.restore``).

Layout, inside the run directory:

    checkpoint/state.npz           the loop state at the end of a time step and the results so far
    checkpoint/fields_NNNNN.npz    the fields of field step NNNNN (written once, before the state
                                   that includes that step)

Every file is written atomically (a temporary file renamed into place), so a run killed at any
moment, or stopped by a write that fails (a full disk), leaves the previous complete checkpoint. A
fields file is written once, before the state that lists its step; one that no state lists (its
session was killed in between) is removed when a session starts (``remove_unrecorded``). A field
that a run has not (σ33 in 3D, z without viscoplastic history, η_K without the error estimate) is
not stored, and None again on restore. state.npz holds

- ``case``: the resolved case (TOML) the run was started with, and ``mesh_digest``: a hash of the
  mesh, the free dofs and the contact nodes, both checked on resume;
- the arrays of the :class:`~vpcontact.timeloop.snapshot.LoopSnapshot`: the loop state
  (:class:`~vpcontact.timeloop.state.LoopState`: the step reached, ξ, z and 𝒢 there (viscoplastic
  history), and the last StepSolution (u at the free dofs for the full solver, λ, d, the active set,
  its report) and its trend (how u, λ and d changed since the level before): the next Newton
  iteration starts from the same prediction as in an uninterrupted run; ``rigid``, the body's
  position on the rigid motions only the contact holds (where a level that nothing presses leaves it,
  :mod:`vpcontact.timeloop.resting`)); the history rows (one array per column) and the per-node
  contact arrays so far (rows × m); ``solver_method`` and ``solver_*``, what the step solver carries
  from step to step (its ``kept()``: the condensed method's solved span, kept inverse and choice of
  factor; the iterative method's Newton matrix its AMG hierarchy was built on);
- ``meta`` (JSON): the snapshot's (the field steps saved, step cuts, wall time and the solver's counters
  so far, the steps where the run was resumed before) and the versions.

The step solver itself is rebuilt on resume (the condensed solver refactors A0 and rebuilds S) and
given that state (``restore``): every method then continues exactly as an uninterrupted run, and
the numbers are its bits (tests/test_resume_matrix.py).
"""

from __future__ import annotations

import hashlib
import json
import tomllib
import zipfile
from collections.abc import Callable, Collection
from pathlib import Path

import numpy as np

from . import directory
from ..errors import CaseError, brief
from ..timeloop.loop import TimeLoop
from ..timeloop.snapshot import LoopSnapshot
from .files import matching, remove_files, replacing
from .versions import versions

FOLDER = "checkpoint"
STATE = "state.npz"
FILES = (f"{FOLDER}/{STATE}", f"{FOLDER}/fields_*.npz")
"""The files of a checkpoint in a run directory: state.npz and fields_NNNNN.npz."""
FORMAT = 1
#: Output keys that do not change the numbers: they may differ between a run and its resumption.
FREE_KEYS = ("progress", "checkpoint_every_steps", "checkpoint_every_seconds", "figures")


class ResumeError(CaseError):
    """A checkpoint that does not belong to the case given (or cannot be read): a one-line message."""


def folder(out: Path) -> Path:
    return Path(out) / FOLDER


def exists(out: Path) -> bool:
    return (folder(out) / STATE).is_file()


def remove(out: Path) -> None:
    """Delete the checkpoint's files (and checkpoint/, if that leaves it empty)."""
    remove_files(out, FILES)


def saved_step(out: Path) -> int | None:
    """The step the checkpoint in ``out`` continues after; None when there is none (or it is damaged)."""
    return _saved(out, "step", int)


def saved_method(out: Path) -> str | None:
    """The step method of the run the checkpoint in ``out`` saved; None when there is none (or it is damaged)."""
    return _saved(out, "solver_method", str)


def _saved(out: Path, name: str, kind):
    """The array ``name`` of the checkpoint's state in ``out`` as ``kind``; None when there is none (or it is
    damaged)."""
    try:
        with np.load(folder(out) / STATE, allow_pickle=False) as data:
            return kind(data[name])
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile):
        return None


def remove_unrecorded(out: Path, recorded: Collection[int]) -> None:
    """Delete the fields files of checkpoint/ whose step is not in ``recorded`` (the field steps of the
    state restored; none for a run that starts): a session that stopped before it saved the state
    listing them wrote them, and their steps are computed again (``save`` writes a fields file once)."""
    pattern = f"{FOLDER}/fields_*.npz"
    found = [path.relative_to(out) for path, whole in matching(out, (pattern,)) if whole is not None]
    remove_files(out, tuple(str(path) for path in found if path.name[7:-4] not in {f"{n:05d}" for n in recorded}))


def comparable(case_dict: dict) -> dict:
    """A resolved case without the keys that do not change the numbers."""
    output = {k: v for k, v in case_dict.get("output", {}).items() if k not in FREE_KEYS}
    return {**case_dict, "output": output}


def mesh_digest(problem) -> str:
    """A hash of what the numbers depend on beyond the case file: the mesh (a mesh file may change),
    the free dofs and the contact nodes."""
    digest = hashlib.sha256()
    for array in (problem.mesh.mesh.p, problem.mesh.mesh.t, problem.free, problem.surface.nodes):
        digest.update(np.ascontiguousarray(array).tobytes())
    return digest.hexdigest()


def save(loop: TimeLoop, out: Path) -> None:
    """Write the checkpoint of ``loop`` (its snapshot at the end of its last completed step) into ``out``:
    the fields files it has not written yet, then state.npz."""
    target = folder(out)
    directory.mkdir(target)
    snapshot = loop.snapshot()
    for n, arrays in snapshot.fields.items():
        path = target / f"fields_{n:05d}.npz"
        if not path.exists():
            with replacing(path) as temporary:
                np.savez(temporary, **arrays)
    problem = loop.problem
    arrays = {"format": np.array(FORMAT), "case": np.array(problem.source or ""),
              "mesh_digest": np.array(mesh_digest(problem)), **snapshot.arrays,
              "meta": np.array(json.dumps({**snapshot.meta, "versions": versions()}))}
    with replacing(target / STATE) as temporary:
        np.savez(temporary, **arrays)


def restore(loop: TimeLoop, out: Path, as_now: Callable[[dict], dict] = lambda case: case) -> int:
    """Load the checkpoint in ``out`` into a fresh ``loop`` (same case, same mesh: else ResumeError; the
    snapshot's arrays and the fields files it lists, handed to ``loop.restore``); returns the step it
    continues after. ``as_now``: the resolved case the checkpoint holds as this version resolves it (the keys added
    since it was written at their defaults), compared with the case now."""
    path = folder(out) / STATE
    arrays = _read(path)
    try:
        return _restore(loop, out, path, arrays, as_now)
    except (KeyError, IndexError, TypeError, json.JSONDecodeError, tomllib.TOMLDecodeError) as error:
        raise ResumeError(f"cannot resume from '{path}': unreadable checkpoint ({type(error).__name__}: {error}); "
                          f"{RESTART}") from None


def _restore(loop: TimeLoop, out: Path, path: Path, arrays: dict[str, np.ndarray],
             as_now: Callable[[dict], dict]) -> int:
    """``restore`` once state.npz (at ``path``) is read into ``arrays``."""
    meta = json.loads(str(arrays["meta"]))
    stored_case = tomllib.loads(str(arrays["case"]))
    if int(arrays["format"]) != FORMAT:
        raise ResumeError(f"cannot resume from '{path}': checkpoint format {int(arrays['format'])}, expected {FORMAT}")
    problem = loop.problem
    case_now = tomllib.loads(problem.source or "")
    stored_case = as_now(stored_case)
    if comparable(stored_case) != comparable(case_now):
        raise ResumeError(f"cannot resume: the run in '{out}' was started with a different case "
                          f"({first_difference(stored_case, case_now)})")
    if str(arrays["mesh_digest"]) != mesh_digest(problem):
        raise ResumeError(f"cannot resume: the mesh of the run in '{out}' differs from the mesh of the case now")

    fields = {n: _read(folder(out) / f"fields_{n:05d}.npz") for n in meta["field_steps"]}
    try:
        loop.restore(LoopSnapshot(arrays, meta, fields))
    except KeyError as error:  # a checkpoint of this case and mesh, without what this version keeps
        raise ResumeError(f"cannot resume from '{path}': the checkpoint has no {error}, which this version of "
                          f"vpcontact needs (it was written by an earlier one); {RESTART}") from None
    return loop.state.step


def saved_versions(out: Path) -> dict[str, str]:
    """The versions the checkpoint in ``out`` was written with (empty when it does not say or cannot be
    read): a resumed run warns when they differ from those installed."""
    try:
        with np.load(folder(out) / STATE, allow_pickle=False) as data:
            versions = json.loads(str(data["meta"])).get("versions", {})
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile):
        return {}
    return versions if isinstance(versions, dict) else {}


RESTART = "the checkpoint cannot be used: start the run again with --overwrite"


def _read(path: Path) -> dict[str, np.ndarray]:
    """Every array of a checkpoint file; ResumeError naming the file when it is missing, empty,
    truncated or damaged."""
    if path.exists() and not path.is_file():
        raise ResumeError(f"cannot resume: the checkpoint file '{path}' is not a regular file; {RESTART}")
    try:
        with np.load(path, allow_pickle=False) as data:
            return {key: data[key] for key in data.files}
    except FileNotFoundError:
        raise ResumeError(f"cannot resume: the checkpoint file '{path}' is missing; {RESTART}") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        what = "empty" if path.stat().st_size == 0 else f"truncated or damaged ({error})"
        raise ResumeError(f"cannot resume: the checkpoint file '{path}' is {what}; {RESTART}") from None


def first_difference(a, b, where: str = "") -> str:
    """The first key where two nested tables differ, as 'key: old -> new'."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b), key=str):
            if a.get(key) != b.get(key):
                return first_difference(a.get(key), b.get(key), f"{where}.{key}" if where else str(key))
        return where or "?"
    return f"{where} = {brief(a)} in the run, {brief(b)} now"
