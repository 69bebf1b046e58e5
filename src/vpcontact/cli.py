"""The command line:

    vpcontact run CASE.toml [--set key=value ...] --out DIR [--resume | --overwrite]
    mpiexec -n N vpcontact run ...     (one solve on N MPI ranks: docs/mpi.md)
    vpcontact check CASE.toml [--set key=value ...] [--json]
    vpcontact study STUDY.toml --out DIR [--workers N | --scheduler tcp://HOST:PORT] [--ranks N]

Only what a command uses is imported when it runs (``--help`` imports no numerics).

Exit status: 0 complete; 2 bad input or an unusable --out (one line on stderr, nothing written); 3 a
step failed even after its cuts (the converged steps are written, summary.json has "status":
"failed") or, for a study, a run failed; 4 the run directory was removed or replaced during the run,
or a write failed (one line; nothing more written); 130 / 143 a run stopped by SIGINT / SIGTERM at
the end of a step (outputs and a checkpoint written, "status": "interrupted"; ``--resume`` continues
it), a study stopped by them (its workers stopped, study.csv written; rerun to continue).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import __version__
from .errors import CaseError, one_line

EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OUTPUT = 2, 3, 4


class _Parser(argparse.ArgumentParser):
    """argparse with the refusal of every other bad input: one line, exit status 2 (not the usage)."""

    def error(self, message: str):
        print(f"vpcontact: error: {one_line(message)} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="vpcontact", description=(
        "Quasistatic contact of viscoplastic bodies with a foundation whose soft layer hardens or "
        "softens with the history of penetration (Barboteu, Han, Sofonea)."))
    parser.add_argument("--version", action="version", version=f"vpcontact {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="solve a case and write its results")
    run.add_argument("case", type=Path, help="case file (TOML)")
    run.add_argument("--out", type=Path, required=True, help="output directory")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a case value, e.g. --set contact.stiffness.beta=-1 (repeatable)")
    run.add_argument("--quiet", action="store_true", help="no progress lines or bar")
    replace = run.add_mutually_exclusive_group()
    replace.add_argument("--overwrite", action="store_true", help="replace a non-empty output directory")
    replace.add_argument("--resume", action="store_true",
                         help="continue the run in --out from its checkpoint (a killed or interrupted run)")
    check = commands.add_parser("check", help="validate a case without solving it and describe what would run")
    check.add_argument("case", type=Path, help="case file (TOML)")
    check.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                       help="override a case value, as for run (repeatable)")
    check.add_argument("--json", action="store_true", help="the description as JSON")
    study = commands.add_parser("study", help="run a parameter study (rerun to resume)")
    study.add_argument("study", type=Path, help="study file (TOML)")
    study.add_argument("--out", type=Path, required=True, help="study directory")
    where = study.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, help="local worker processes (default: cores)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS", help="a Dask scheduler, e.g. tcp://host:8786")
    study.add_argument("--ranks", type=int, default=1, metavar="N",
                       help="solve each run on N MPI ranks (mpiexec -n N; docs/mpi.md)")
    study.add_argument("--quiet", action="store_true", help="no progress lines or bar")
    reproduce = commands.add_parser("reproduce", help="regenerate every result of Sect. 4 of the paper, with a report")
    reproduce.add_argument("--out", type=Path, required=True, help="output directory (report.md, report.html, ...)")
    reproduce.add_argument("--quick", action="store_true", help="a coarse version (under 2 minutes)")
    reproduce.add_argument("--workers", type=int, default=None, help="worker processes of the studies (default: cores)")
    reproduce.add_argument("--overwrite", action="store_true", help="replace an earlier reproduction in --out")
    reproduce.add_argument("--quiet", action="store_true",
                           help="no progress lines (on stdout: the parts; on stderr: the runs)")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "reproduce":
        return _reproduce(args)
    if args.command == "check":
        return _check(args)
    return _study(args) if args.command == "study" else _run(args)


def _refuse(error) -> int:
    """Bad input: one line on stderr (however long or multi-line the message), exit status 2."""
    print(f"vpcontact: error: {one_line(str(error))}", file=sys.stderr)
    return EXIT_BAD_INPUT


def _run(args) -> int:
    from .parallel.ranks import ALONE, launched

    return _run_case(args, ALONE) if launched()[1] == 1 else _run_on_ranks(args)


def _run_on_ranks(args) -> int:
    """``vpcontact run`` on the MPI ranks of ``mpiexec -n N``: every rank runs the case, rank 0 alone writes and
    speaks (the others' output is discarded); a launch without mpi4py or petsc4py is refused in one line. A rank that
    fails (an error of its own, not the case's) stops every rank, MPI_Abort with EXIT_FAILED, after one line naming
    it, and a write that failed on rank 0 (EXIT_OUTPUT) stops the others, which would wait for it."""
    import os

    from .parallel.ranks import launched, world

    rank, size = launched()
    try:
        ranks = world()
    except CaseError as error:
        return _refuse(error) if rank == 0 else EXIT_BAD_INPUT
    stderr = sys.stderr
    if not ranks.root:
        sys.stdout = sys.stderr = open(os.devnull, "w")
    try:
        status = _run_case(args, ranks)
    except BaseException as error:  # noqa: B036 (any failure of one rank ends all of them, never a hang)
        print(f"vpcontact: rank {rank} of {size} failed ({type(error).__name__}: {one_line(str(error))}): every rank "
              f"is stopped", file=stderr, flush=True)
        ranks.comm.Abort(EXIT_FAILED)
    if status == EXIT_OUTPUT:
        ranks.comm.Abort(EXIT_OUTPUT)
    return status


def _run_case(args, ranks) -> int:
    """``vpcontact run`` on the ``ranks`` of this process (:mod:`vpcontact.parallel.ranks`)."""
    from .case.load import load_case
    from .progress import SILENT, Log
    from .drivers.rundir import run
    from .drivers.signals import EXIT_SIGNAL

    try:
        case = load_case(args.case, args.overrides)
        with (Log() if case.output.progress and not args.quiet and ranks.root else SILENT) as progress:  # stderr
            outcome = run(case, args.out, resume=args.resume, overwrite=args.overwrite, progress=progress, ranks=ranks)
    except CaseError as error:
        return _refuse(error)
    except OSError as error:  # the run directory was replaced, or a write failed: the run stopped
        print(f"vpcontact: {_describe(error)}", file=sys.stderr)
        return EXIT_OUTPUT
    if outcome.status == "interrupted":
        print(f"vpcontact: {outcome.message}", file=sys.stderr)
        return EXIT_SIGNAL[outcome.signal]
    if outcome.status != "complete":
        print(f"vpcontact: {outcome.message}", file=sys.stderr)
        return EXIT_FAILED
    if outcome.result is None:
        print(f"vpcontact: {outcome.message}")
        return 0
    if case.adapt is not None:
        written = "adapt.csv, cycles/" if case.adapt.mode == "cycles" else "adapt.csv, the run's outputs"
        print(f"adaptive: {outcome.message}; {written} and the final_mesh.msh -> {args.out}")
    summary = outcome.result.summary()
    final = summary["final"]
    cuts = f", {summary['step_cuts']} step cuts" if summary["step_cuts"] else ""
    cuts += f" in {summary['history_rows']} levels" if summary["history_rows"] > summary["steps"] else ""
    print(f"complete: {summary['steps']} steps{cuts}, {summary['dofs']} dofs, {summary['contact_nodes']} contact nodes, "
          f"{summary['newton_iterations']} Newton iterations, {summary['wall_time_s']:.1f} s -> {args.out}")
    if final.get("K_probe") is not None and summary["contact_nodes"]:
        print(f"final t = {final['t']:g}: K_probe = {final['K_probe']:.6g}, penetration_probe = "
              f"{final['penetration_probe']:.6g}, nodes separated/compliance/limit = {final['nodes_separated']}/"
              f"{final['nodes_in_compliance']}/{final['nodes_at_limit']}")
    if "time_estimate" in final:
        print(f"error estimates at t = {final['t']:g}: in space {final['error_estimate']:.4g}, in time "
              f"{final['time_estimate']:.4g} (energy norm)")
    return 0


def _check(args) -> int:
    import json

    from .case.load import load_case
    from .drivers.check import check_case

    try:
        checked = check_case(load_case(args.case, args.overrides))
    except CaseError as error:
        return _refuse(error)
    if args.json:
        print(json.dumps(checked.as_dict(), indent=2))
    else:
        print("\n".join(checked.lines()))
    return 0


def _describe(error: OSError) -> str:
    """One line for an OSError: its message, or its reason and the file."""
    if error.strerror is None:
        return str(error)
    where = f": '{error.filename}'" if error.filename else ""
    return f"stopped: {error.strerror}{where}"


def _study(args) -> int:
    import os

    from .progress import SILENT, Log
    from .drivers.signals import EXIT_SIGNAL, StopOnSignals
    from .drivers.studies.file import load_study
    from .drivers.studies.running import connect, run_study

    client = None
    try:
        if args.workers is not None and args.workers < 1:
            raise CaseError(f"--workers {args.workers}: must be at least 1")
        if args.ranks < 1:
            raise CaseError(f"--ranks {args.ranks}: must be at least 1")
        study = load_study(args.study, args.out, args.ranks)
        if args.ranks > 1 and args.workers is None and args.scheduler is None:  # the cores shared by the ranks
            args.workers = max(1, (os.cpu_count() or 1) // args.ranks)
        if args.scheduler is not None:
            client = connect(args.scheduler)
        with StopOnSignals() as stopper, (Log(hold=0.0, watch=False) if not args.quiet else SILENT) as progress:
            report = run_study(study, args.out, executor=client.get_executor() if client else None,
                               workers=args.workers, progress=progress, stop=stopper.reason)
    except CaseError as error:
        return _refuse(error)
    except OSError as error:  # the study directory was replaced, or a write failed: the study stopped
        print(f"vpcontact: {_describe(error)}", file=sys.stderr)
        return EXIT_OUTPUT
    finally:
        if client is not None:
            client.close()
    table = args.out / "study.csv"
    if report["stopped"]:
        complete = len(report["skipped"]) + len(report["completed"])
        print(f"vpcontact: study {report['stopped']}: {complete} of {len(study.runs)} runs complete, "
              f"{len(report['interrupted'])} not finished -> {table} (rerun the study to continue)", file=sys.stderr)
        return EXIT_SIGNAL.get(stopper.signal, EXIT_FAILED)
    print(f"study: {len(study.runs)} runs: {len(report['completed'])} run, {len(report['skipped'])} already complete, "
          f"{len(report['retried'])} retried, {len(report['failed'])} failed -> {table}")
    for run_id in report["failed"]:
        print(f"vpcontact: run '{run_id}' failed (see {args.out / 'runs' / run_id})", file=sys.stderr)
    return EXIT_FAILED if report["failed"] else 0


def _reproduce(args) -> int:
    from .progress import SILENT, Log
    from .reproduction.reproduce import OutputError, ReproduceError, run

    if args.workers is not None and args.workers < 1:
        return _refuse(f"--workers {args.workers}: must be at least 1")
    log = (lambda line: None) if args.quiet else (lambda line: print(line, flush=True))
    try:
        with (SILENT if args.quiet else Log(hold=0.0)) as progress:  # its workers are spawned: a thread is safe
            run(args.out, quick=args.quick, workers=args.workers, overwrite=args.overwrite, log=log, progress=progress)
    except OutputError as error:  # --out unusable: nothing was run
        return _refuse(error)
    except ReproduceError as error:
        print(f"vpcontact: {error}", file=sys.stderr)
        return EXIT_FAILED
    return 0


if __name__ == "__main__":
    sys.exit(main())
