"""Solving the runs of the reproduction: a case in this process or a worker, a study in the workers, and
what reproduce.json keeps of a run."""

from __future__ import annotations

from pathlib import Path

from ..case.load import load_case
from ..progress import SILENT, Progress
from ..results.columns import INTEGER_COLUMNS
from ..io.csv_format import read_table
from .paper import T
from .plan import CaseSpec


class ReproduceError(RuntimeError):
    """A run of the reproduction failed."""


def recorded_case(base: Path, spec: CaseSpec, out: Path) -> dict:
    """``case_record`` of ``solve_case``: what a worker returns of a run."""
    return case_record(spec, solve_case(base, spec, out))


def solve_case(base: Path, spec: CaseSpec, out: Path, progress: Progress = SILENT):
    """Solve one case and write its standard outputs; raises ReproduceError if a step fails. ``progress``
    hears of the run as a phase (its start, life while it runs, its status and wall time)."""
    from .. import solve
    from ..io.run import write_run

    with progress.phase(f"run '{spec.name}'") as phase:
        result = solve(load_case(base, spec.overrides))
        write_run(result, out, overwrite=True)
        phase.done(result.status)
    if result.status != "complete":
        raise ReproduceError(f"run '{spec.name}' failed: {result.message} (outputs in {out})")
    return result


SERIES = (  # the history columns reproduce.json keeps of a case, at the step times t_n
    "t",
    "K_probe",
    "penetration_probe",
    "normal_stress_probe",
    "max_penetration",
    "mean_penetration",
    "nodes_separated",
    "nodes_in_compliance",
    "nodes_at_limit",
    "newton_iterations",
)


def case_record(spec: CaseSpec, result) -> dict:
    """What reproduce.json keeps of a run: its overrides, sizes, time and its series at the step times t_n."""
    steps = len(result.discretization.times)
    record = {
        "label": spec.label,
        "group": spec.group,
        "overrides": spec.overrides,
        "steps": steps,
        "k": T / steps,
        "dofs": result.dofs,
        "elements": result.elements,
        "contact_nodes": result.contact_nodes,
        "wall_time_s": result.wall_time_s,
        "solver_method": result.method,
    }
    for name in SERIES:
        values = result.series(name, substeps=False)
        record[name] = [int(v) for v in values] if name in INTEGER_COLUMNS else [float(v) for v in values]
    return record


def mesh_record(result) -> dict:
    """The figure mesh: elements, DOFs, contact nodes and edges on Γ3."""
    surface = result.discretization.surface
    return {
        "elements": int(result.elements),
        "dofs": int(result.dofs),
        "nodes": int(result.nodes),
        "contact_nodes": int(result.contact_nodes),
        "contact_edges": int(surface.facets.shape[1]),
    }


def run_named_study(out: Path, name: str, text: str, executor, progress: Progress = SILENT) -> list[dict]:
    """Write DIR/studies/NAME.toml, run it into DIR/studies/NAME with ``executor``, return study.csv's rows;
    ``progress`` hears of its runs (``studies.run_study``)."""
    from ..drivers.studies.file import load_study
    from ..drivers.studies.running import run_study

    folder = out / "studies"
    folder.mkdir(exist_ok=True)
    path = folder / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    study = load_study(path, folder / name)
    report = run_study(study, folder / name, executor=executor, progress=progress)
    if report["failed"]:
        raise ReproduceError(
            f"study '{name}': runs {', '.join(report['failed'])} failed (see {folder / name / 'study.csv'})"
        )
    return read_table(folder / name / "study.csv")

