"""The runs of a study, on a local process pool or on a Dask cluster: each run solved and written into its
directory, a failed run retried once, a stopped study's runs abandoned (see :mod:`vpcontact.drivers.studies`)."""

from __future__ import annotations

import os
import signal
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Executor, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from ...case.load import load_case, read_case
from ...errors import CaseError
from ...io import directory, paths
from ...io.run import check_room, refuse_links
from ...io.summary import read_summary
from ...progress import Progress, duration, reporting
from ...solvers.pardiso import use_one_thread
from .file import RunSpec, Study
from .table import write_study_table


def execute_run(spec: RunSpec) -> dict:
    """Solve one run and write its directory; returns its summary (status "error" on an exception). A run on several
    MPI ranks is launched by :func:`.members.execute_on_ranks`."""
    if spec.ranks > 1:
        from .members import execute_on_ranks

        return execute_on_ranks(spec)
    from ...case.translate import translate
    from ...io.run import write_run
    from ...problem.build import build_problem
    from ...timeloop.loop import solve_problem

    try:
        options = translate(load_case(spec.base, spec.overrides))
        result = solve_problem(build_problem(options.problem), output=options.output)
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
        done = read_case(spec.out).resolved()
    except CaseError:
        return False
    return done == load_case(spec.base, spec.overrides).resolved()


def run_study(study: Study, out: str | os.PathLike, *, executor: Executor | None = None, workers: int | None = None,
              progress: bool | Progress = False, stop: Callable[[], str | None] | None = None) -> dict:
    """Run every incomplete run (each failed one retried once), then write DIR/study.csv.

    DIR is held while the study runs (see :mod:`vpcontact.io.directory`: CaseError before any run if it
    cannot be used or another vpcontact process holds it). ``stop()`` is asked while the runs go (a
    signal, see :mod:`vpcontact.cli`); once it gives a reason, the runs not finished are abandoned (the
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
    writes nothing below it once it was replaced (``directory.watch``); MKL runs on one thread
    (:func:`vpcontact.solvers.pardiso.use_one_thread`: the workers share the cores, and a forked MKL may hang)."""
    use_one_thread()
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


def connect(address: str):
    """A client of the Dask scheduler at ``address`` (CaseError without the cluster extra, or when it
    cannot be reached): its ``get_executor()`` is the executor of :func:`run_study`."""
    try:
        from distributed import Client
    except ImportError:
        raise CaseError(f'--scheduler {address}: the Dask client is not installed; install it with: '
                        f'pip install "vpcontact[cluster]"') from None
    try:
        return Client(address, timeout="10s")
    except (OSError, ValueError, TypeError) as error:
        raise CaseError(f"--scheduler {address}: cannot connect ({error})") from None
