"""Parameter studies: many runs of one base case, on a local process pool or a Dask cluster.

A study file (TOML) names a base case and its runs:

    base = "../paper_ball.toml"            # relative to the study file
    [set]                                  # overrides applied to every run
    "output.field_steps" = "none"
    [[vary]]                               # one axis of the grid; keys in one axis vary together
    "mesh.h" = [0.1, 0.05, 0.025]
    "time.steps" = [11, 22, 44]
    [[vary]]                               # the grid is the Cartesian product of the axes
    "contact.stiffness.beta" = [1.0, -1.0]
    [[runs]]                               # runs listed one by one, added to the grid
    id = "signorini"
    "contact.stiffness" = {law = "constant", value = 0.0}
    [compare]                              # difference norms against a run of the study
    reference = "signorini"
    times = [1.1]

Each run writes the standard outputs to DIR/runs/<id>/ (an explicit id is a single path component:
letters, digits and ``= . , + - _``, not starting with "."; ids are unique, letter case aside; the
ids made from the varied values get a suffix -2, -3, ... where they would collide); DIR/study.csv has
a row per run. A run whose directory holds a complete result of the same resolved case is not run
again; a run that fails is retried once; a stopped study (``stop``, SIGINT/SIGTERM on the command
line) writes study.csv with its unfinished runs "interrupted", and a rerun does them. Runs execute
through a ``concurrent.futures`` executor: a local process pool, or the executor of a
``distributed.Client`` (a shared file system is assumed). The numbers do not depend on the executor.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import os
import re
import signal
import time
import tomllib
import unicodedata
from collections import deque
from collections.abc import Callable, Collection
from concurrent.futures import FIRST_COMPLETED, Executor, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path

from ..io import directory, paths
from ..case.schema import _brief, load_case
from ..errors import CaseError
from ..case.inputs import MAX_TOML_BYTES, check_regular_file
from ..results.norms import Snapshot, differences
from ..progress import Progress, duration, reporting
from ..io.solution import snapshots_at
from ..io.summary import read_summary
from ..fem.space import COORDINATES
from ..io.files import replacing
from ..io.run import RESOLVED_CASE, check_room, refuse_links

STUDY_KEYS = {"base", "set", "vary", "runs", "compare"}
COMPARED = ("V", "Q", "U", "energy")
"""The difference norms (:func:`vpcontact.results.norms.differences`) study.csv has at each compared time t, in
the columns ``norm_column(norm, t)`` (NaN where a run has no fields at t; "energy" needs the
reference's Lamé parameters)."""
MAX_ID = 100
"""The longest run id (characters): an id names a directory, DIR/runs/<id>."""


@dataclass
class RunSpec:
    """One run of a study: its id, overrides (dotted key -> value) and output directory."""

    id: str
    overrides: dict
    out: Path
    base: Path


@dataclass
class Study:
    """A study file, expanded into its runs."""

    path: Path
    base: Path
    runs: list[RunSpec]
    reference: str | None = None
    times: list[float] = field(default_factory=list)


# --- reading a study -----------------------------------------------------------------------------
def load_study(path: str | os.PathLike, out: str | os.PathLike) -> Study:
    """Read a study file and validate every run's case (one-line CaseError naming the run)."""
    path = Path(path)
    check_regular_file(path, "study file", MAX_TOML_BYTES)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise CaseError(f"study file '{path}' not found") from None
    except tomllib.TOMLDecodeError as error:
        raise CaseError(f"study file '{path}' is not valid TOML: {error}") from None
    except (OSError, UnicodeDecodeError) as error:
        raise CaseError(f"study file '{path}' cannot be read: {error}") from None
    unknown = set(data) - STUDY_KEYS
    if unknown:
        raise CaseError(f"unknown key '{sorted(unknown)[0]}' in study file (valid keys: {', '.join(sorted(STUDY_KEYS))})")
    if not isinstance(data.get("base"), str):
        raise CaseError("missing required value 'base' (the case file the runs start from)")
    base = path.parent / data["base"]
    common = _table(data.get("set", {}), "set")
    override_sets = [{**common, **combo} for combo in _grid(data.get("vary", []))] if data.get("vary") else []
    explicit_ids, where = [], {}
    for i, run in enumerate(data.get("runs", [])):
        run = dict(_table(run, f"runs[{i}]"))
        given = _explicit_id(run.pop("id"), f"runs[{i}]") if "id" in run else None
        if given is not None and _folded(given) in where:
            raise CaseError(f"study runs[{where[_folded(given)]}] and runs[{i}] have the same id {_brief(given)} "
                            f"(ids name directories: they must differ in more than letter case)")
        if given is not None:
            where[_folded(given)] = i
        explicit_ids.append(given)
        override_sets.append({**common, **run})
    explicit_ids = [None] * (len(override_sets) - len(explicit_ids)) + explicit_ids
    if not override_sets:
        raise CaseError("the study has no runs: give [[vary]] axes or [[runs]]")

    compare = _table(data.get("compare", {}), "compare")
    times = [float(t) for t in compare.get("times", [])]
    reference = compare.get("reference")
    ids = _run_ids(override_sets, common, explicit_ids)
    if reference is not None and reference not in ids:
        raise CaseError(f"compare.reference = \"{reference}\": no run has that id (runs: {', '.join(ids)})")
    if reference is not None and not times:
        raise CaseError("compare.times is required with compare.reference")
    runs = []
    for run_id, overrides in zip(ids, override_sets):
        overrides = _with_field_times(base, overrides, times, run_id)
        runs.append(RunSpec(run_id, overrides, Path(out) / "runs" / run_id, base))
    return Study(path, base, runs, reference, times)


def _table(value, where: str) -> dict:
    if not isinstance(value, dict):
        raise CaseError(f"study '{where}' must be a table of dotted keys")
    return value


def _grid(axes: list) -> list[dict]:
    """The Cartesian product of the axes; the keys of one axis vary together."""
    columns = []
    for i, axis in enumerate(axes):
        axis = _table(axis, f"vary[{i}]")
        lengths = {len(v) if isinstance(v, list) else -1 for v in axis.values()}
        if len(lengths) != 1 or -1 in lengths or not axis:
            raise CaseError(f"study vary[{i}]: every key needs a list of values, all of the same length")
        count = lengths.pop()
        columns.append([{key: values[j] for key, values in axis.items()} for j in range(count)])
    return [{k: v for part in combo for k, v in part.items()} for combo in itertools.product(*columns)]


def _explicit_id(value, where: str) -> str:
    """A run id given in the study file: a single, visible path component (DIR/runs/<id> is its
    directory), else CaseError."""
    if not isinstance(value, str):
        raise CaseError(f"study {where}: id = {_brief(value)} must be a string")
    if not re.fullmatch(r"[\w=.,+\-]+", value) or value.startswith(".") or len(value) > MAX_ID:
        raise CaseError(f"study {where}: id = {_brief(value)} cannot name a run directory: use 1 to {MAX_ID} letters, "
                        f"digits and = . , + - _, not starting with '.'")
    return value


def _run_ids(override_sets: list[dict], common: dict, explicit: list) -> list[str]:
    """The explicit ids as given (no two alike, see load_study), and readable ids from the varied
    values ("h=0.05,steps=22") for the other runs, made unique against all ids by a suffix -2, -3, ...
    (letter case aside: one directory on a case-insensitive file system)."""
    taken = {_folded(given) for given in explicit if given is not None}
    ids = []
    for overrides, given in zip(override_sets, explicit):
        if given is None:
            varied = {k: v for k, v in overrides.items() if k not in common or common[k] != v}
            text = ",".join(f"{k.split('.')[-1]}={_short(v)}" for k, v in varied.items()) or "base"
            text = re.sub(r"[^A-Za-z0-9=.,+\-_]", "_", text)[:MAX_ID]
            candidates = itertools.chain([text], (f"{text}-{n}" for n in itertools.count(2)))
            given = next(candidate for candidate in candidates if _folded(candidate) not in taken)
            taken.add(_folded(given))
        ids.append(given)
    return ids


def _folded(run_id: str) -> str:
    """The id as a case-insensitive, normalizing file system sees it."""
    return unicodedata.normalize("NFC", run_id).casefold()


def _short(value) -> str:
    if isinstance(value, dict):
        return "-".join(_short(v) for v in value.values())
    return f"{value:g}" if isinstance(value, float) else str(value)


def _with_field_times(base: Path, overrides: dict, times: list[float], run_id: str) -> dict:
    """Validate the run's case and make its field steps include the compared times."""
    try:
        case = load_case(base, overrides)
    except CaseError as error:
        raise CaseError(f"run '{run_id}': {error}") from None
    if case.adapt is not None:
        raise CaseError(f"run '{run_id}': its case has [adapt], and a study solves each run once on its mesh; "
                        f"remove [adapt] from the study's case (run adaptive cases with vpcontact run)")
    if not times:
        return overrides
    start = case.time.start or 0.0  # t_n = t_0 + n k
    k = (case.time.T - start) / case.time.steps
    steps = []
    for t in times:
        n = round((t - start) / k)
        if not (1 <= n <= case.time.steps and math.isclose(start + n * k, t, rel_tol=1e-9, abs_tol=1e-12)):
            raise CaseError(f"run '{run_id}': compare time {t:g} is not a time step (k = {k:g}, T = {case.time.T:g})")
        steps.append(n)
    fields = case.output.field_steps
    have = {"all": list(range(1, case.time.steps + 1)), "final": [case.time.steps], "none": []}.get(fields, fields)
    return {**overrides, "output.field_steps": sorted(set(have) | set(steps))}


# --- running -------------------------------------------------------------------------------------
def execute_run(spec: RunSpec) -> dict:
    """Solve one run and write its directory; returns its summary (status "error" on an exception)."""
    from ..problem.build import build_problem
    from ..timeloop.loop import solve_problem
    from ..io.run import write_run

    try:
        case = load_case(spec.base, spec.overrides)
        result = solve_problem(build_problem(case), output=case.output)
        write_run(result, spec.out, overwrite=True)
        return result.summary()
    except Exception as error:  # a failed run is reported in study.csv, never stops the study
        return {"status": "error", "message": f"{type(error).__name__}: {error}"}


def is_complete(spec: RunSpec) -> bool:
    """Does spec.out hold a complete result of exactly this run's resolved case?"""
    summary = read_summary(spec.out)
    if summary is None or summary.get("status") != "complete":
        return False
    try:
        done = load_case(Path(spec.out) / RESOLVED_CASE).resolved()
    except CaseError:
        return False
    return done == load_case(spec.base, spec.overrides).resolved()


def run_study(study: Study, out: str | os.PathLike, *, executor: Executor | None = None, workers: int | None = None,
              progress: bool | Progress = False, stop: Callable[[], str | None] | None = None) -> dict:
    """Run every incomplete run (each failed one retried once), then write DIR/study.csv.

    DIR is held while the study runs (see :mod:`vpcontact.io.directory`: CaseError before any run if it
    cannot be used or another vpcontact process holds it). ``stop()`` is asked while the runs go (a
    signal, see :mod:`vpcontact.drivers.cli`); once it gives a reason, the runs not finished are abandoned (the
    workers of the local pool are killed and waited for: nothing is written after run_study returns;
    on a Dask cluster, runs already started finish there), study.csv marks them "interrupted", and a
    rerun of the study does them.

    ``progress`` (True: lines on stderr, :mod:`vpcontact.progress`; or a reporter, which should run no watcher
    thread: the workers of the local pool are forked) hears of each run as it starts and ends (its id,
    status and wall time) and, while runs go on, of which ones (a line after 10 s of silence, and so on).

    Returns a report: {"skipped", "completed", "failed", "retried", "interrupted": [ids], "stopped":
    the reason or None}.
    """
    out = Path(out)
    paths.usable(out)
    _check_run_directories(study, out)
    held = directory.acquire(out)
    try:
        pending = [spec for spec in study.runs if not is_complete(spec)]
        report = {"skipped": [s.id for s in study.runs if s not in pending], "completed": [], "failed": [],
                  "retried": [], "interrupted": [], "stopped": None}
        with reporting(progress, hold=0.0, watch=False) as reporter:
            errors = _run_pending(pending, report, held, executor, workers, reporter, stop)
        write_study_table(study, out, errors, report["interrupted"])
    finally:
        held.release()
    return report


POLL_SECONDS = 0.1
"""How often run_study asks ``stop()`` while it waits for runs."""


def _run_pending(pending: list[RunSpec], report: dict, held: directory.Held, executor: Executor | None,
                 workers: int | None, progress: Progress, stop) -> dict[str, str]:
    """Run ``pending`` (filling ``report``) until done or ``stop()``; returns {id: message} of the runs
    that ended with an exception (they wrote nothing). The study directory ``held`` removed or
    replaced meanwhile stops the study too (DirectoryReplaced). The local pool is given as many runs at a
    time as it has workers, so that a run reported as started is one that runs; the executor of a cluster
    is given them all (its scheduler decides: they are reported as submitted)."""
    errors = {}
    owned = executor is None
    if owned:
        workers = workers or os.cpu_count() or 1
        executor = ProcessPoolExecutor(max_workers=workers, initializer=_start_worker,
                                       initargs=(held.path, held.identity))
    capacity, started_words = (workers, "started") if owned else (len(pending), "submitted")
    queue, futures, started = deque(pending), {}, {}  # started: id -> when its run was given to the executor
    total = len(pending)
    ended = lambda: len(report["completed"]) + len(report["failed"])  # noqa: E731
    failed = lambda: f", {len(report['failed'])} failed" if report["failed"] else ""  # noqa: E731

    def submit() -> None:
        while queue and len(futures) < capacity:
            spec = queue.popleft()
            futures[executor.submit(execute_run, spec)] = spec
            started[spec.id] = time.monotonic()
            again = " again" if spec.id in report["retried"] else ""
            progress.note(f"run '{spec.id}' {started_words}{again}")

    def describe() -> str:
        now = time.monotonic()
        going = ", ".join(f"'{run_id}' for {duration(now - since)}" for run_id, since in list(started.items()))
        return f"study: {ended()} of {total} runs done{failed()}; running: {going}"

    if pending:
        where = f"on {workers} worker process{'es' if workers != 1 else ''}" if owned else "given to the executor"
        skipped = f" ({len(report['skipped'])} already complete)" if report["skipped"] else ""
        progress.note(f"study: {total} run{'s' if total != 1 else ''} to do{skipped}, {where}")
    try:
        with progress.runs(total, describe) as runs:
            submit()
            while futures:
                done, _ = wait(futures, timeout=POLL_SECONDS, return_when=FIRST_COMPLETED)
                progress.tick()
                if stop is not None and (reason := stop()):  # before the results: a signal sent to the
                    report["stopped"] = reason              # whole process group has ended the workers too
                    break
                held.check()
                for future in done:
                    spec = futures.pop(future)
                    try:
                        summary = future.result()
                    except BrokenProcessPool:  # killed by a signal or the out-of-memory killer: so are its runs
                        futures[future] = spec
                        report["stopped"] = (f"stopped: a worker process died (killed, or out of memory) while "
                                             f"running '{spec.id}' or a run beside it")
                        break
                    status, took = summary.get("status"), duration(time.monotonic() - started.pop(spec.id))
                    why = f": {summary.get('message')}" if status != "complete" and summary.get("message") else ""
                    if status == "complete":
                        report["completed"].append(spec.id)
                    elif spec.id not in report["retried"]:
                        report["retried"].append(spec.id)
                        queue.appendleft(spec)
                        progress.note(f"run '{spec.id}' {status} ({took}), to be tried again{why}")
                        continue
                    else:
                        report["failed"].append(spec.id)
                        if status == "error":
                            errors[spec.id] = summary.get("message", "")
                    progress.note(f"run '{spec.id}' {status} ({took}); {ended()} of {total} runs done{failed()}{why}")
                    runs.advance(done=len(report["completed"]), failed=len(report["failed"]),
                                 left=len(futures) + len(queue))
                if report["stopped"]:
                    break
                submit()
    finally:
        if futures or queue:  # stopped (or an exception): abandon the runs not finished
            for future in futures:
                future.cancel()
            if owned:
                _stop_workers(executor)
            for spec in [*futures.values(), *queue]:  # one may have completed just before
                report["completed" if is_complete(spec) else "interrupted"].append(spec.id)
        if owned:
            executor.shutdown(cancel_futures=True)
    return errors


def _start_worker(out: Path, identity: tuple[int, int]) -> None:
    """In a worker of the local pool: Ctrl-C (sent to the whole process group) is for the study
    process, which stops the workers; SIGTERM has its default action (not the handler inherited from
    the study process); the study directory stays held by the study process alone, and the worker
    writes nothing below it once it was replaced (``directory.watch``)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    directory.forget_inherited()
    directory.watch(out, identity)


def _stop_workers(executor: ProcessPoolExecutor) -> None:
    """Kill the pool's worker processes and wait until they are gone: the runs they were doing are
    lost (their directories hold no summary.json of them) and nothing is written after this."""
    processes = list((executor._processes or {}).values())  # no public way before Python 3.14's kill_workers()
    for process in processes:
        process.kill()
    for process in processes:
        process.join()
    # Only then shut the pool down, waiting for its management thread: shut down first, without waiting,
    # the thread could still be reading from a worker's pipe the shutdown closes, and print
    # "OSError: [Errno 9] Bad file descriptor" on the study's stderr.
    executor.shutdown(wait=True, cancel_futures=True)


def _check_run_directories(study: Study, out: Path) -> None:
    """Every run writes into DIR/runs/<id> and nowhere else: refuse a run directory elsewhere (a study
    loaded for another DIR), a runs/ or runs/<id> that is a symbolic link or not a directory, a
    study.csv that is a link, and anything standing where a run or the table is written (see
    ``io.run.check_room``: a symbolic link too)."""
    runs = out / "runs"
    for spec in study.runs:
        if spec.out != runs / spec.id:
            raise CaseError(f"run '{spec.id}': its directory '{spec.out}' is not in '{runs}' (load the study with "
                            f"the same output directory)")
    for path in (runs, *(spec.out for spec in study.runs)):
        if path.is_symlink() or (path.exists() and not path.is_dir()):
            what = "a symbolic link" if path.is_symlink() else "not a directory"
            raise CaseError(f"--out '{out}': '{path}' is {what}; runs write only into directories inside '{runs}'")
        if path != runs and path.is_dir():
            check_room(path)
    refuse_links(out, ("study.csv", ".study.tmp-[0-9]*.csv", directory.LOCK))
    if (out / "study.csv").is_dir():
        raise CaseError(f"--out '{out}': '{out / 'study.csv'}' is a folder, and the study writes its table there: "
                        f"move it away")


# --- the table -----------------------------------------------------------------------------------
def write_study_table(study: Study, out: Path, errors: dict[str, str] | None = None,
                      interrupted: Collection[str] = ()) -> list[dict]:
    """DIR/study.csv: per run its overrides, status, wall time, summary values and difference norms
    (``errors``: why runs that wrote nothing failed; ``interrupted``: runs a stopped study did not
    finish)."""
    rows = []
    reference = _snapshots(study, study.reference) if study.reference else {}
    for spec in study.runs:
        row = {"id": spec.id, **{k: _cell(v) for k, v in spec.overrides.items() if k != "output.field_steps"}}
        summary = _summary(spec, (errors or {}).get(spec.id), spec.id in interrupted)
        row.update({"status": summary.get("status"), "message": summary.get("message", ""),
                    "wall_time_s": summary.get("wall_time_s"), "dofs": summary.get("dofs"),
                    "contact_nodes": summary.get("contact_nodes"), "steps": summary.get("steps"),
                    "newton_iterations": summary.get("newton_iterations")})
        final = dict(summary.get("final") or {})
        force = final.pop("contact_force", [None, None])
        row.update(final)
        row.update({f"contact_force_{c}": value for c, value in zip(COORDINATES, force)})
        if reference:
            mine = _snapshots(study, spec.id) if summary.get("status") == "complete" else {}
            for t in study.times:
                norms = differences(mine[t], reference[t]) if t in mine and t in reference else {}
                row.update({norm_column(norm, t): norms.get(norm, math.nan) for norm in COMPARED})
        rows.append(row)
    columns = list(dict.fromkeys(key for row in rows for key in row))
    with replacing(out / "study.csv") as temporary, temporary.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    return rows


def norm_column(norm: str, t: float) -> str:
    """The column of study.csv with the difference norm ``norm`` (one of COMPARED) at time t."""
    return f"norm_{norm}_t{t:g}"


def _summary(spec: RunSpec, error: str | None, interrupted: bool) -> dict:
    """The run's summary.json; for a run that ended with an exception, or that a stopped study did not
    finish, what happened instead (a summary.json there is an earlier run's)."""
    if error is not None:
        return {"status": "error", "message": error}
    if interrupted:
        return {"status": "interrupted", "message": "the study was stopped before this run finished; rerun the "
                                                    "study to do it"}
    return read_summary(spec.out) or {"status": "missing", "message": ""}


def _cell(value):
    return json.dumps(value) if isinstance(value, (dict, list)) else value


def _snapshots(study: Study, run_id: str) -> dict[float, Snapshot]:
    """The run's fields at the compared times, from its solution.npz."""
    spec = next(s for s in study.runs if s.id == run_id)
    return snapshots_at(spec.out, study.times)
