"""A run directory during and after a run: ``vpcontact run CASE --out DIR [--resume | --overwrite]``.

The directory exists from the start: ``case.resolved.toml`` first, then a checkpoint (see
:mod:`vpcontact.io.checkpoint`) every ``output.checkpoint_every_steps`` steps and/or every
``output.checkpoint_every_seconds`` seconds, with ``history.csv`` refreshed at each; at the end every
output, each written atomically, ``summary.json`` last. The checkpoint is removed once the run is
complete or has failed; an interrupted or killed run keeps it, and ``--resume`` continues from it.

Status (summary.json) and exit status of the command line:

    complete      0    every step done
    failed        3    a step did not converge even after ``solver.max_step_cuts`` halvings; the
                       converged steps (and sub-steps) are written
    interrupted   130  SIGINT (Ctrl-C) / 143 SIGTERM: the run stopped at the end of the current
                       step, wrote what exists and its checkpoint; ``--resume`` continues it
    (bad input)   2    one line on stderr; nothing computed, nothing written (an unusable ``--out`` too)
    (no summary)  4    the run directory was removed or replaced during the run (the run stopped
                       and wrote nothing into what is now at that path), or a write failed
                       (disk full, ...; :class:`RunStopped`): one line on stderr naming the file,
                       the step of the checkpoint left and what to do (make room, then --resume)

A write that fails leaves the file it replaces as it was (every file is written atomically), so a
full disk leaves the previous complete checkpoint: ``--resume`` continues from it once there is
room, to the same numbers as an uninterrupted run.

The directory is held while the run writes (see :mod:`vpcontact.io.directory`); ``--overwrite`` removes
the outputs of an earlier run (``io.run.OUTPUTS``) and nothing else. A symbolic link where a run writes
(``fields/``, ``checkpoint/``, ``history.csv``, ...) is the user's: the run refuses to start (exit 2,
one line naming the link), with or without ``--overwrite`` and ``--resume``, and no write ever goes
through one (see :mod:`vpcontact.io.directory`). ``--out`` itself may be a link to a folder.

A case with ``[adapt]`` runs its adaptive cycles (:mod:`vpcontact.adaptivity.cycles`): ``case.resolved.toml`` first,
each cycle's run in ``cycles/<n>/`` (its outputs as above, summary.json last) with ``adapt.csv``
refreshed after each cycle, then the last cycle's mesh ``final_mesh.msh`` and ``summary.json`` (the
status, why the cycles stopped, the rows of adapt.csv). It writes no checkpoints: ``--resume`` is refused; the
status and exit status are those of the last cycle's run ("failed" too when a refinement fails). With
``adapt.mode = "run"`` (:mod:`vpcontact.adaptivity.during_run`) it is one run: its outputs as above, on its last
mesh, with ``adapt.csv`` (one row per estimated level, rewritten after each step that adds rows) and
``final_mesh.msh``; no checkpoints either.
"""

from __future__ import annotations

import csv
import errno
import json
import sys
import time as clock
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..case.load import read_case
from ..case.model import Case
from ..case.translate import CaseOptions, translate
from ..errors import CaseError
from ..io import checkpoint, directory, paths
from ..io.files import remove_files, replacing, write_text
from ..io.outputs import write_outputs
from ..io.run import check_room, remove_outputs, remove_temporaries, write_resolved_case
from ..io.summary import json_safe, read_summary
from ..io.versions import versions
from ..mesh.gmsh import write_mesh
from ..parallel.ranks import ALONE, Ranks
from ..problem.build import Problem, build_problem
from ..progress import Progress, reporting
from ..results.result import Result
from ..timeloop.loop import TimeLoop
from .signals import StopOnSignals

if TYPE_CHECKING:
    from ..adaptivity.cycles import Adaptation, Cycle
    from ..adaptivity.during_run import RunAdaptation


class RunStopped(OSError):
    """A run stopped because a write into its directory failed (a full disk, a symbolic link put there
    during the run, ...): one line, what failed and how to continue; ``errno`` is the failed write's."""


@dataclass
class Outcome:
    """What ``run`` did: the result (None when a resumed run had nothing left to do), the status, a
    message, and the signal that stopped it (if any)."""

    result: Result | None
    status: str
    message: str = ""
    signal: int | None = None


def run(case: Case, out: str | Path, *, resume: bool = False, overwrite: bool = False,
        progress: bool | Progress = False, ranks: Ranks = ALONE) -> Outcome:
    """Solve ``case`` into the run directory ``out`` (see the module's docstring). Bad input, an
    unusable ``out`` or a checkpoint of another case raise CaseError before anything is written; a
    run directory removed or replaced during the run raises DirectoryReplaced (an OSError) and a
    write that fails raises RunStopped (an OSError), and nothing more is written. ``progress``: True for the
    set-up phases, the steps and the outputs reported on stderr (:mod:`vpcontact.progress`), or a reporter.

    On several MPI ranks (``ranks``, :mod:`vpcontact.parallel`) every rank runs this with the same arguments: rank 0
    checks and holds the directory and writes into it, the others solve with it (the checkpoint they resume
    from is read by every rank: ``out`` must be on a file system they all see), and they stop together."""
    out = Path(out)
    if ranks.size > 1 and case.adapt is not None:
        raise CaseError(f"an adaptive run ([adapt]) runs in one process, not on {ranks.size} MPI ranks")
    used, done = ranks.decided(lambda: _checked_directory(case, out, resume, overwrite))
    if done is not None:
        return done
    options = translate(case)
    held = _NotHeld()

    def acquire():
        nonlocal held
        held = directory.acquire(out)  # before any computation: an unusable directory is refused at once

    ranks.decided(acquire)
    started = False
    try:
        with StopOnSignals() as stopper, reporting(progress) as progress:
            problem = build_problem(options.problem, progress=progress, ranks=ranks)
            if case.adapt is not None:
                from ..adaptivity.cycles import check_start  # an adaptive run only (as _adapt_locked)

                check_start(problem, options.adapt)
                started = True  # from here on the directory is written to: nothing above wrote to it
                if options.adapt.mode == "run":
                    during = _adapt_during_run_locked(problem, case, options, held, clear=overwrite and used,
                                                      stopper=stopper, progress=progress)
                    return Outcome(during.result, during.status, during.message, stopper.signal)
                adaptation = _adapt_locked(problem, case, options, held, clear=overwrite and used, stopper=stopper,
                                           progress=progress)
                return Outcome(adaptation.last.result, adaptation.status, adaptation.message, stopper.signal)
            resuming = resume and ranks.first(checkpoint.exists(out))
            # a resumed run keeps the method of the run it continues ("auto" would weigh this session's speed)
            loop = TimeLoop(problem, options.output, progress,
                            resumed_method=ranks.first(checkpoint.saved_method(out)) if resuming else None)
            if resuming:
                with progress.phase("checkpoint", f"restoring {checkpoint.folder(out)}") as phase:
                    checkpoint.restore(loop, out, as_now=with_new_defaults)
                    phase.done(f"{loop.state.step:,} of {len(problem.times):,} steps done")
                if ranks.root:
                    _warn_versions(out)
            elif resume and used:
                ranks.decided(lambda: _check_same_case(case, out))
            started = True  # from here on the directory is written to: nothing above wrote to it

            def stop() -> str | None:
                return ranks.agreed(stopper.reason())

            if ranks.root:
                result = _run_locked(loop, case, held, clear=overwrite and used, stop=stop, progress=progress,
                                     ranks=ranks)
            else:
                result = _follow(loop, stop, ranks)
    except OSError as error:
        if not started or isinstance(error, directory.DirectoryReplaced):
            raise
        raise _stopped(error, case, out) from None
    finally:
        held.release(undo=not started)
    return Outcome(result, result.status, result.message, ranks.first(stopper.signal))


def _checked_directory(case: Case, out: Path, resume: bool, overwrite: bool) -> tuple[bool, Outcome | None]:
    """Whether ``out`` holds files already, and the outcome of a resumed run that had nothing left to do (None:
    run); CaseError for arguments or a directory that cannot be used (see :func:`run`)."""
    if resume and overwrite:
        raise CaseError("--resume and --overwrite exclude each other")
    if resume and case.adapt is not None:
        raise CaseError("--resume of an adaptive run ([adapt]) is not supported: it keeps no checkpoints; run it "
                        "again with --overwrite")
    paths.usable(out)
    check_room(out)
    if case.adapt is not None and (out / "cycles").exists() and not (out / "cycles").is_dir():
        raise CaseError(f"--out '{out}': '{out / 'cycles'}' is not a folder, and an adaptive run writes its cycles/ "
                        f"there: move it away")
    used = directory.holds_files(out)
    if used and not (resume or overwrite):
        raise CaseError(f"--out '{out}' is not empty (use --overwrite to replace the outputs of a run in it, or "
                        f"--resume to continue the run in it)")
    return used, _finished(case, out) if resume and used else None


class _NotHeld:
    """The run directory as the MPI ranks other than rank 0 see it: held and written by rank 0 alone."""

    def check(self) -> None:
        """Nothing to check here."""

    def release(self, undo: bool = False) -> None:
        """Nothing to release here."""


def _warn_versions(out: Path) -> None:
    """A warning on stderr when the checkpoint in ``out`` was written with other versions than this process's."""
    now, stored = versions(), checkpoint.saved_versions(out)
    changed = [f"{name} {stored.get(name)} -> {version}" for name, version in now.items()
               if stored.get(name) != version]
    if changed:
        print(f"vpcontact: warning: resuming with other versions ({', '.join(changed)}): the numbers may differ in the "
              f"last digits from an uninterrupted run", file=sys.stderr)


def _stopped(error: OSError, case: Case, out: Path) -> RunStopped:
    """RunStopped for a write into ``out`` that failed with ``error``: what failed, what is left to
    continue from, and what to do."""
    if isinstance(error, directory.SymbolicLink):
        what, fix = f"stopped: {error}", "remove the link (what it leads to is kept), then"
    else:
        where = f": '{error.filename}'" if error.filename else ""
        what = f"stopped: {error.strerror or error}{where}"
        fix = "make room, then" if error.errno == errno.ENOSPC else "once that is fixed,"
    if case.adapt is not None:
        left = f"{fix} run it again with --overwrite (an adaptive run keeps no checkpoint)"
    else:
        step = checkpoint.saved_step(out)
        left = (f"the checkpoint of step {step} is intact: {fix} continue with --resume" if step is not None else
                f"no checkpoint was written yet: {fix} run it again with --resume (it starts over)")
    stopped = RunStopped(f"{what}; {left}")
    stopped.errno = error.errno
    return stopped


def _run_locked(loop: TimeLoop, case: Case, held: directory.Held, *, clear: bool, stop,
                progress: Progress, ranks: Ranks) -> Result:
    """The run proper, in a directory this process holds: prepare it, loop with checkpoints, write.
    Every step and every write first checks that the directory is still the one locked. On several MPI ranks this
    is rank 0's part: it tells the others when it checkpoints (:func:`_follow`)."""
    out = held.path
    if clear:
        remove_outputs(out)
    remove_temporaries(out)
    checkpoint.remove_unrecorded(out, loop.result.fields)
    remove_files(out, ("summary.json",))
    write_resolved_case(case.to_toml(), out)
    cadence = _Cadence(case.output.checkpoint_every_steps, case.output.checkpoint_every_seconds, loop.state.step)

    def after_step(loop: TimeLoop) -> None:
        held.check()
        if ranks.first(cadence.due(loop.state.step)):
            checkpoint.save(loop, out)
            write_outputs(loop.result, out, history_only=True)
            cadence.saved(loop.state.step)

    result = loop.run(after_step=after_step, stop=stop)
    if result.status == "interrupted":
        if ranks.first(cadence.last_step != loop.state.step or not checkpoint.exists(out)):
            checkpoint.save(loop, out)
        result.message += f"; continue with --resume (checkpoint in {checkpoint.folder(out)})"
    with progress.phase("outputs", f"writing into {out}"):
        write_outputs(result, out)
    if result.status != "interrupted":
        checkpoint.remove(out)
    return result


def _follow(loop: TimeLoop, stop, ranks: Ranks) -> Result:
    """The run on an MPI rank other than 0 (:func:`_run_locked` is rank 0's): the steps, and this rank's part of
    the loop's snapshot (its elements' history) whenever rank 0 checkpoints."""

    def after_step(loop: TimeLoop) -> None:
        if ranks.first(None):
            loop.snapshot()

    result = loop.run(after_step=after_step, stop=stop)
    if result.status == "interrupted" and ranks.first(None):
        loop.snapshot()
    return result


def _prepare(case: Case, out: Path, clear: bool) -> None:
    """The run directory ``out`` of an adaptive run made ready: the outputs of an earlier run removed (``clear``),
    temporaries and summary.json too, the resolved case written."""
    if clear:
        remove_outputs(out)
    remove_temporaries(out)
    remove_files(out, ("summary.json",))
    write_resolved_case(case.to_toml(), out)


def _write_adapt_csv(out: Path, columns: tuple[str, ...], rows: list[dict]) -> None:
    """adapt.csv: ``rows`` under ``columns`` (floats as repr: every digit)."""
    with replacing(out / "adapt.csv") as temporary, temporary.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        writer.writerows({k: repr(float(v)) if isinstance(v, float) else v for k, v in row.items()} for row in rows)


def _adapt_during_run_locked(problem: Problem, case: Case, options: CaseOptions, held: directory.Held, *,
                             clear: bool, stopper, progress: Progress) -> RunAdaptation:
    """One run of ``case`` that adapts its mesh between steps (``adapt.mode = "run"``) from ``problem`` in a directory
    this process holds: its outputs as a run's (on its last mesh), adapt.csv (one row per estimated level) rewritten
    after each step that adds rows, final_mesh.msh, summary.json last (with the adaptation's refinements and
    message)."""
    from ..adaptivity.during_run import COLUMNS, adapt_during_run

    out = held.path
    _prepare(case, out, clear)
    rows: list[dict] = []
    written = [0]  # the rows in adapt.csv

    def after_step(loop: TimeLoop) -> None:
        held.check()
        if len(rows) > written[0]:  # a level was estimated: adapt.csv again, not at every step
            _write_adapt_csv(out, COLUMNS, rows)
            written[0] = len(rows)

    adaptation = adapt_during_run(problem, options.adapt, options.output, stop=stopper.reason, progress=progress,
                                  after_step=after_step, rows=rows)
    _write_adapt_csv(out, COLUMNS, adaptation.rows)
    with replacing(out / "final_mesh.msh") as temporary:
        write_mesh(adaptation.mesh, temporary)
    result = adaptation.result
    result.status, result.message = adaptation.status, adaptation.message
    result.adaptation = {"mode": "run", "tolerance": options.adapt.tolerance, "refinements": adaptation.refinements,
                         "estimated_levels": len(adaptation.rows), "message": adaptation.message}
    with progress.phase("outputs", f"writing into {out}"):
        write_outputs(result, out)
    return adaptation


def _adapt_locked(problem: Problem, case: Case, options: CaseOptions, held: directory.Held, *, clear: bool, stopper,
                  progress: Progress) -> Adaptation:
    """The adaptive cycles of ``case.adapt`` (translated: ``options``) from ``problem`` (the case's) in a directory
    this process holds (see the module docstring)."""
    from ..adaptivity.cycles import COLUMNS, adapt

    out = held.path
    _prepare(case, out, clear)
    rows = []

    def after_cycle(cycle: Cycle) -> None:
        held.check()
        directory.mkdir(out / "cycles")
        folder = out / "cycles" / str(cycle.number)
        directory.mkdir(folder)
        with progress.phase("outputs", f"writing cycle {cycle.number} into {folder}"):
            write_outputs(cycle.result, folder)
        rows.append(cycle.row)
        _write_adapt_csv(out, COLUMNS, rows)

    adaptation = adapt(problem, options.adapt, options.output, after_cycle=after_cycle, stop=stopper.reason,
                       progress=progress,
                       after_step=lambda loop: held.check())
    with replacing(out / "final_mesh.msh") as temporary:
        write_mesh(adaptation.mesh, temporary)
    summary = {"status": adaptation.status, "message": adaptation.message, "cycles": adaptation.rows,
               "versions": versions()}
    write_text(out / "summary.json", json.dumps(json_safe(summary), indent=2) + "\n")
    return adaptation


def _finished(case: Case, out: Path) -> Outcome | None:
    """A run directory that holds a finished run of this case and no checkpoint: nothing to resume."""
    summary = None if checkpoint.exists(out) else read_summary(out)
    if summary is None or summary.get("status") not in ("complete", "failed"):
        return None
    _check_same_case(case, out)
    message = summary.get("message", "") or f"the run in '{out}' is already complete; nothing to resume"
    return Outcome(None, summary["status"], message)


def with_new_defaults(stored: dict) -> dict:
    """A resolved case as this version of vpcontact resolves it: the keys added since it was written (by an earlier
    version, in a checkpoint) at their defaults, which keep what the run did then; as it is when this version refuses
    it."""
    try:
        return Case.model_validate(stored).resolved()
    except ValueError:
        return stored


def _check_same_case(case: Case, out: Path) -> None:
    """--resume in a directory without a checkpoint: it must hold a run of this same case."""
    try:
        before = read_case(out)
    except CaseError:
        raise CaseError(f"cannot resume: '{out}' holds no run of vpcontact (no readable case.resolved.toml)") from None
    if checkpoint.comparable(before.resolved()) != checkpoint.comparable(case.resolved()):
        raise checkpoint.ResumeError(f"cannot resume: the run in '{out}' was started with a different case "
                                     f"({checkpoint.first_difference(before.resolved(), case.resolved())})")


class _Cadence:
    """When to checkpoint: every ``steps`` steps and/or every ``seconds`` seconds (0: not by that)."""

    def __init__(self, steps: int, seconds: float, start: int):
        self.steps, self.seconds = steps, seconds
        self.last_step, self.last_time = start, clock.monotonic()

    def due(self, step: int) -> bool:
        by_steps = self.steps > 0 and step - self.last_step >= self.steps
        by_time = self.seconds > 0 and clock.monotonic() - self.last_time >= self.seconds
        return by_steps or by_time

    def saved(self, step: int) -> None:
        self.last_step, self.last_time = step, clock.monotonic()
