"""A study file (TOML) read into its runs: the base case, the overrides of every run, the grid of the [[vary]]
axes, the runs' ids (their directories) and the compared times (see :mod:`vpcontact.drivers.studies`)."""

from __future__ import annotations

import itertools
import math
import os
import re
import tomllib
import unicodedata
from dataclasses import dataclass, field
from pathlib import Path

from ...case.load import load_case
from ...errors import CaseError, brief
from ...inputs import MAX_TOML_BYTES, check_regular_file

STUDY_KEYS = {"base", "set", "vary", "runs", "compare"}
MAX_ID = 100
"""The longest run id (characters): an id names a directory, DIR/runs/<id>."""


@dataclass
class RunSpec:
    """One run of a study: its id, overrides (dotted key -> value) and output directory."""

    id: str
    overrides: dict
    out: Path
    base: Path
    ranks: int = 1  # MPI ranks that solve it (mpiexec -n ranks: :mod:`.members`)


@dataclass
class Study:
    """A study file, expanded into its runs."""

    path: Path
    base: Path
    runs: list[RunSpec]
    reference: str | None = None
    times: list[float] = field(default_factory=list)


def load_study(path: str | os.PathLike, out: str | os.PathLike, ranks: int = 1) -> Study:
    """Read a study file and validate every run's case (one-line CaseError naming the run); each run is to be solved
    on ``ranks`` MPI ranks."""
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
            raise CaseError(f"study runs[{where[_folded(given)]}] and runs[{i}] have the same id {brief(given)} "
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
        runs.append(RunSpec(run_id, overrides, Path(out) / "runs" / run_id, base, ranks))
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
        raise CaseError(f"study {where}: id = {brief(value)} must be a string")
    if not re.fullmatch(r"[\w=.,+\-]+", value) or value.startswith(".") or len(value) > MAX_ID:
        raise CaseError(f"study {where}: id = {brief(value)} cannot name a run directory: use 1 to {MAX_ID} letters, "
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
