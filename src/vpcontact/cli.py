"""The command line:

    vpcontact run CASE.toml [--set key=value ...] --out DIR
    vpcontact study STUDY.toml --out DIR [--workers N | --scheduler tcp://HOST:PORT]

Exit status: 0 complete; 2 bad input (one line on stderr, nothing written); 3 a step failed
(the converged steps are written, summary.json has "status": "failed") or, for a study, a run failed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import __version__
from .case import load_case
from .errors import CaseError
from .problem import build_problem
from .stepping import solve_problem
from .writers import write_run

EXIT_BAD_INPUT, EXIT_FAILED = 2, 3


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="vpcontact", description=(
        "Quasistatic contact of viscoplastic bodies with a foundation whose soft layer hardens or "
        "softens with the history of penetration (Barboteu, Han, Sofonea)."))
    parser.add_argument("--version", action="version", version=f"vpcontact {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="solve a case and write its results")
    run.add_argument("case", type=Path, help="case file (TOML)")
    run.add_argument("--out", type=Path, required=True, help="output directory")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a case value, e.g. --set contact.stiffness.beta=-1 (repeatable)")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--overwrite", action="store_true", help="replace a non-empty output directory")
    study = commands.add_parser("study", help="run a parameter study (rerun to resume)")
    study.add_argument("study", type=Path, help="study file (TOML)")
    study.add_argument("--out", type=Path, required=True, help="study directory")
    where = study.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, help="local worker processes (default: cores)")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS", help="a Dask scheduler, e.g. tcp://host:8786")
    study.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    return _study(args) if args.command == "study" else _run(args)


def _run(args) -> int:
    try:
        case = load_case(args.case, args.overrides)
        if args.out.exists() and not args.out.is_dir():
            raise CaseError(f"--out '{args.out}' exists and is not a directory")
        if args.out.exists() and any(args.out.iterdir()) and not args.overwrite:
            raise CaseError(f"--out '{args.out}' is not empty (use --overwrite to replace it)")
        problem = build_problem(case)
        progress = case.output.progress and not args.quiet and sys.stderr.isatty()
        result = solve_problem(problem, progress=progress)
    except CaseError as error:
        print(f"vpcontact: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    write_run(result, args.out, overwrite=args.overwrite)
    summary = result.summary()
    if result.status != "complete":
        print(f"vpcontact: {result.message}", file=sys.stderr)
        return EXIT_FAILED
    final = summary["final"]
    print(f"complete: {summary['steps']} steps, {summary['dofs']} dofs, {summary['contact_nodes']} contact nodes, "
          f"{summary['newton_iterations']} Newton iterations, {summary['wall_time_s']:.1f} s -> {args.out}")
    if final.get("K_probe") is not None and summary["contact_nodes"]:
        print(f"final t = {final['t']:g}: K_probe = {final['K_probe']:.6g}, penetration_probe = "
              f"{final['penetration_probe']:.6g}, nodes separated/compliance/limit = {final['nodes_separated']}/"
              f"{final['nodes_in_compliance']}/{final['nodes_at_limit']}")
    return 0




def _study(args) -> int:
    from .studies import load_study, run_study

    try:
        study = load_study(args.study, args.out)
        if args.workers is not None and args.workers < 1:
            raise CaseError(f"--workers {args.workers}: must be at least 1")
        executor = client = None
        if args.scheduler is not None:
            from distributed import Client

            try:
                client = Client(args.scheduler, timeout="10s")
            except OSError as error:
                raise CaseError(f"--scheduler {args.scheduler}: cannot connect ({error})") from None
            executor = client.get_executor()
    except CaseError as error:
        print(f"vpcontact: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        report = run_study(study, args.out, executor=executor, workers=args.workers,
                           progress=not args.quiet and sys.stderr.isatty())
    finally:
        if client is not None:
            client.close()
    print(f"study: {len(study.runs)} runs: {len(report['completed'])} run, {len(report['skipped'])} already complete, "
          f"{len(report['retried'])} retried, {len(report['failed'])} failed -> {args.out / 'study.csv'}")
    for run_id in report["failed"]:
        print(f"vpcontact: run '{run_id}' failed (see {args.out / 'runs' / run_id})", file=sys.stderr)
    return EXIT_FAILED if report["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
