"""The command line: ``vpcontact run CASE.toml [--set key=value ...] --out DIR``.

Exit status: 0 complete; 2 bad input (one line on stderr, nothing written); 3 a step failed
(the converged steps are written, summary.json has "status": "failed").
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
    return parser


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
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


if __name__ == "__main__":
    sys.exit(main())
