"""The files of a run directory. Each is written atomically (a temporary file beside it, renamed into
place: a reader never sees half a file, and a write that fails, on a full disk say, leaves the file
as it was), ``summary.json`` last: a directory whose summary.json says ``"status": "complete"`` holds
a complete run; without summary.json a run is in progress or was killed (``vpcontact run --resume``
continues it from its checkpoint, see :mod:`vpcontact.drivers.rundir`). Nothing is written, replaced or
removed through a symbolic link: ``check_room`` refuses one where a run writes before it starts, and
``replacing`` and ``remove_files`` act through :mod:`vpcontact.io.directory`, which never follows one.

- ``summary.json``      status, sizes, wall time, the final values, versions;
- ``history.csv``       one row per time step (``Result.columns``);
- ``contact.csv``       one row per contact node and step;
- ``fields/body.pvd``   displacement, stress, von Mises (and the viscoplastic history z when there is
                        one) at the field steps, and each element's material (its index in the case's
                        material list), E and ν (VTU files, ParaView);
- ``fields/contact.pvd``  Γ3 with penetration, ξ, K, pressures, status, normal and contact force, and the
                        local layer parameters (``layer_columns``);
- ``fields/body.xdmf``  with ``output.xdmf``, the same fields as an XDMF time series, the mesh stored once
                        in ``fields/body.h5`` (and ``fields/contact.xdmf``, ``.h5``; see :mod:`vpcontact.io.xdmf`);
- ``solution.npz``      the fields at the field steps as arrays, ξ too (see ``write_solution``): what a
                        restart (``initial.from_run``) starts from;
- ``case.resolved.toml``  every value used, defaults included, with the versions as a header;
- ``figures/*.png``     with ``output.figures``, at the end of a complete or failed run: the contact
                        pressure, the deformed body and the history (see :mod:`vpcontact.results.plots`).
"""

from __future__ import annotations

import csv
import fnmatch
import functools
import io
import itertools
import json
import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np

from . import directory
from ..laws.contact import STATUS_NAMES
from ..errors import CaseError
from ..results.plots import DPI, FIGURES
from ..results.columns import CONTACT_ARRAYS
from ..results.frames import field_frames, field_meshes, layer_columns
from ..results.result import Result
from ..fem.space import CELLS, coordinates
from .vtu import Grid, write_vtu

PACKAGES = ("vpcontact", "numpy", "scipy", "scikit-fem", "meshio", "pydantic")


@functools.lru_cache(maxsize=1)
def _installed_versions() -> tuple:
    found = []
    for name in PACKAGES:
        try:
            found.append((name, metadata.version(name)))
        except metadata.PackageNotFoundError:
            found.append((name, "not installed"))
    return tuple(found)


def versions() -> dict[str, str]:
    """Installed versions of vpcontact and its main dependencies (read once per process)."""
    return dict(_installed_versions())


def _temporary(path: Path, tag: str) -> Path:
    """The temporary file beside ``path`` written by the process ``tag`` (a process id, or a glob
    pattern for any)."""
    return path.with_name(f".{path.stem}.tmp-{tag}{path.suffix}")


#: The files of one run, as glob patterns, summary.json first.
RUN_OUTPUTS = ("summary.json", "history.csv", "contact.csv", "solution.npz", "fields/body.pvd", "fields/contact.pvd",
               "fields/body_*.vtu", "fields/contact_*.vtu", "fields/body.h5", "fields/body.xdmf", "fields/contact.h5",
               "fields/contact.xdmf", *(f"figures/{stem}.png" for stem in FIGURES))
OUTPUTS = (*RUN_OUTPUTS, "case.resolved.toml", "checkpoint/state.npz", "checkpoint/fields_*.npz", "adapt.csv",
           "final_mesh.msh", *(f"cycles/[0-9]*/{name}" for name in RUN_OUTPUTS))
"""Every file vpcontact writes in a run directory, as glob patterns (those in checkpoint/ are the files of
:mod:`vpcontact.io.checkpoint`; an adaptive run, ``[adapt]``, writes adapt.csv, the final_mesh.msh and each
cycle's run in cycles/<n>/), summary.json first: ``--overwrite`` removes these, their temporaries, and
the folders that this leaves empty; nothing else."""
TEMPORARIES = tuple(str(_temporary(Path(pattern), "[0-9]*")) for pattern in OUTPUTS)
"""The temporary files of the OUTPUTS (of any process: a killed writer leaves its own)."""


@contextmanager
def replacing(path: Path):
    """Yield a temporary path beside ``path`` (same suffix), created empty; once the caller has written
    it, flush it to disk and rename it to ``path`` (atomic: ``path`` is the old file or the new one,
    never a part). In a held directory nothing is written once it was removed or replaced
    (DirectoryReplaced, see :mod:`vpcontact.io.directory`; an error of the write caused by that is
    reported so too), nor through a symbolic link (SymbolicLink: ``path`` or a folder on its way is
    one). A write that fails (a full disk: ENOSPC) leaves ``path`` as it was, removes the temporary
    and raises the OSError naming ``path``."""
    path = Path(path)
    temporary = _temporary(path, str(os.getpid()))
    try:
        created = directory.create(temporary, path)
        yield temporary
        with open(temporary, "rb+") as handle:
            directory.written(handle.fileno(), temporary, created)
            os.fsync(handle.fileno())
        directory.replace(temporary, path)
    except OSError as error:
        directory.check(path)
        raise _naming(error, path, temporary) from None
    finally:
        directory.discard(temporary)


def _naming(error: OSError, path: Path, temporary: Path) -> OSError:
    """The OSError of a write into ``temporary`` (or of no file: a write, a flush) as one about ``path``,
    the file the user knows: "No space left on device: 'out/solution.npz'"."""
    if error.errno is None or error.filename not in (None, str(temporary)):
        return error
    return OSError(error.errno, error.strerror, str(path))


def write_text(path: Path, text: str) -> None:
    """Write a text file atomically."""
    with replacing(path) as temporary:
        temporary.write_text(text, encoding="utf-8")


def matching(out: Path, patterns: Iterable[str]) -> Iterator[tuple[Path, int | None]]:
    """The entries below ``out`` that match a leading part of one of the glob ``patterns`` (relative
    paths, matched part by part), with the index of the first pattern each matches whole (None: a
    folder on the way only), in name order, never entering a symbolic link (one that matches is
    given, not followed)."""
    yield from _matching(Path(out), [(index, Path(pattern).parts) for index, pattern in enumerate(patterns)])


def _matching(folder: Path, patterns: list[tuple[int, tuple[str, ...]]]) -> Iterator[tuple[Path, int | None]]:
    try:
        with os.scandir(folder) as found:
            entries = sorted(found, key=lambda entry: entry.name)
    except OSError:  # not there, not a folder, not readable: nothing in it is matched (as by Path.glob)
        return
    for entry in entries:
        matched = [(index, parts) for index, parts in patterns if fnmatch.fnmatchcase(entry.name, parts[0])]
        if not matched:
            continue
        path = folder / entry.name
        yield path, min((index for index, parts in matched if len(parts) == 1), default=None)
        deeper = [(index, parts[1:]) for index, parts in matched if len(parts) > 1]
        if deeper and entry.is_dir(follow_symlinks=False):
            yield from _matching(path, deeper)


def remove_files(out: Path, patterns: tuple[str, ...]) -> None:
    """Delete the files in ``out`` that match ``patterns`` (glob patterns, in their order), then the
    folders of the patterns (and their parents below ``out``) that this leaves empty, deepest first.
    Nothing else is touched: no other file, no folder that holds anything, no symbolic link (neither
    removed nor followed: see ``check_room``)."""
    out = Path(out)
    directory.check(out)
    found = [(index, path) for path, index in matching(out, patterns) if not path.is_symlink()]
    for _, path in sorted((index, path) for index, path in found if index is not None and path.is_file()):
        directory.unlink(path)
    folders = [path for index, path in found if index is None and path.is_dir()]
    for folder in sorted(folders, key=lambda f: len(f.parts), reverse=True):
        if not any(folder.iterdir()):
            directory.rmdir(folder)


def check_room(out: Path, label: str = "--out") -> None:
    """CaseError naming what stands where a run writes in ``out`` (a symbolic link, a folder named like
    an output file, a file named fields or checkpoint), before anything is computed. A symbolic link
    where a run writes or removes (``fields/``, ``checkpoint/``, ``history.csv``, the lock file, ...)
    is the user's, and so is what it leads to: a run neither follows nor removes it, and refuses to
    start (the link itself is reported, not where it leads)."""
    out = Path(out)
    refuse_links(out, (*OUTPUTS, *TEMPORARIES, directory.LOCK), label)
    for name in OUTPUTS:
        path = out / name
        if path.parent != out and os.path.lexists(path.parent) and not path.parent.is_dir():
            raise CaseError(f"{label} '{out}': '{path.parent}' is not a folder, and a run writes its "
                            f"{path.parent.name}/ there: move it away")
        if "*" not in name and path.is_dir():
            raise CaseError(f"{label} '{out}': '{path}' is a folder, and a run writes a file there: move it away")


def refuse_links(out: Path, patterns: Iterable[str], label: str = "--out") -> None:
    """CaseError naming the first symbolic link in ``out`` that matches ``patterns`` or a leading part of
    one (a folder on the way), if there is one."""
    for path, _ in matching(out, patterns):
        if path.is_symlink():
            raise CaseError(f"{label} '{out}': '{path}' is a symbolic link (to '{os.readlink(path)}'), and a run "
                            f"writes there but never through a link: remove the link (what it leads to is kept) "
                            f"or give another {label}")


def remove_outputs(out: Path) -> None:
    """Delete what a run wrote in ``out`` (OUTPUTS and TEMPORARIES, see there), summary.json first: it
    must never describe files that are gone."""
    remove_files(out, OUTPUTS + TEMPORARIES)


def remove_temporaries(out: Path) -> None:
    """Delete the temporary files that a killed writer left beside the OUTPUTS in ``out``."""
    remove_files(out, TEMPORARIES)


class NotEmpty(CaseError, FileExistsError):
    """A directory that is not empty, written to without ``overwrite``: a CaseError (one line) and a
    FileExistsError."""


def write_run(result: Result, out: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Write every output of ``result`` to ``out`` (created; with ``overwrite`` the outputs of an earlier
    run there are removed first, and nothing else), each file atomically and summary.json last, while
    holding the directory (see :mod:`vpcontact.io.directory`). Refused as ``vpcontact run`` refuses its
    ``--out``, before anything is written: CaseError for a path that cannot be a directory or with a file
    or folder standing where an output goes, NotEmpty for a directory that is not empty without
    ``overwrite``."""
    out = Path(out)
    directory.usable(out, "output directory")
    check_room(out, "output directory")
    if directory.holds_files(out, "output directory") and not overwrite:
        raise NotEmpty(f"output directory '{out}' is not empty: overwrite=True replaces the outputs of a run in it "
                       f"(and nothing else)")
    held = directory.acquire(out, "output directory")
    try:
        remove_outputs(out)
        if result.discretization.source is not None:
            write_resolved_case(result.discretization.source, out)
        write_outputs(result, out)
    finally:
        held.release()
    return out


def write_resolved_case(resolved: str, out: Path) -> None:
    """case.resolved.toml: ``resolved``, the case with every value used and defaults included
    (:meth:`~vpcontact.case.schema.Case.to_toml`), the versions in its header."""
    header = "".join(f"# {name} {version}\n" for name, version in versions().items())
    write_text(Path(out) / "case.resolved.toml", header + resolved)


def write_outputs(result: Result, out: Path, *, history_only: bool = False) -> None:
    """history.csv, contact.csv, fields/ and solution.npz, figures/ (``output.figures``, once the run is
    complete or has failed), then summary.json (the last file written). ``history_only``: history.csv
    alone (refreshed at the checkpoints of a run in progress)."""
    out = Path(out)
    _write_history(result, out / "history.csv")
    if history_only:
        return
    _write_contact(result, out / "contact.csv")
    _write_fields(result, out / "fields")
    if result.output.xdmf:
        from .xdmf import write_xdmf  # h5py: imported by the runs that write XDMF only

        write_xdmf(result, out / "fields")
    if result.output.figures and result.status in ("complete", "failed"):
        _write_figures(result, out / "figures")
    summary = {**result.summary(), "versions": versions()}
    write_text(out / "summary.json", json.dumps(json_safe(summary), indent=2) + "\n")


def json_safe(value):
    """Plain JSON values: NumPy scalars as Python ones, NaN and inf as null, keys as strings."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def _write_history(result: Result, path: Path) -> None:
    with replacing(path) as temporary, temporary.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=result.columns)
        writer.writeheader()
        for row in result.rows:
            writer.writerow({k: (repr(float(v)) if isinstance(v, (float, np.floating)) else v) for k, v in row.items()})


#: Values of each column of contact.csv turned into text at once: the memory the writer adds to the run's
#: stays the same however many rows the run has.
CONTACT_BLOCK = 2**14


def _write_contact(result: Result, path: Path) -> None:
    """contact.csv, in blocks of rows: each number turned into text once (the columns of a node, such as its
    coordinates, once for all the steps; those of a row, such as t, once for all its nodes), as csv.writer
    writes it (floats as repr, an empty cell for None or a NaN layer parameter, text quoted if need be)."""
    surface = result.discretization.surface
    rows, m = len(result.rows), surface.size
    steps, substeps, times = result.series("step").astype(int), result.series("substep").astype(int), result.times
    axes = coordinates(result.dim)
    layer = layer_columns(result.discretization)
    names = ["step", "t", "node", *axes, *(f"normal_{c}" for c in axes), "weight", *CONTACT_ARRAYS, "substep",
             *layer]
    node_cells = _joined(surface.nodes, *surface.coordinates, *surface.normals, surface.weights)
    layer_cells = _joined(*layer.values(), nan="") if layer else None  # a parameter a node's law has not: empty
    status_names = np.asarray(STATUS_NAMES)
    block = max(1, CONTACT_BLOCK // max(m, 1))
    with replacing(path) as temporary, temporary.open("w", newline="") as handle:
        csv.writer(handle).writerow(names)
        for start in range(0, rows, block):
            chosen = slice(start, min(rows, start + block))
            count = chosen.stop - start
            row_cells = _joined(steps[chosen], times[chosen])  # step and t
            columns = [itertools.chain.from_iterable(itertools.repeat(cells, m) for cells in row_cells),
                       node_cells * count]
            columns += [_texts(np.array(result.contact[name][chosen]).ravel()) for name in CONTACT_ARRAYS[:-1]]
            columns.append(status_names[np.array(result.contact["status"][chosen]).ravel().astype(int)].tolist())
            columns.append(_texts(np.repeat(substeps[chosen], m)))
            if layer_cells is not None:
                columns.append(layer_cells * count)
            handle.writelines(",".join(cells) + "\r\n" for cells in zip(*columns))


def _joined(*columns: np.ndarray, nan: str = "nan") -> list[str]:
    """The cells of ``columns`` (arrays of one length) as the text of each row, comma-separated."""
    return [",".join(cells) for cells in zip(*(_texts(column, nan) for column in columns))]


def _texts(values: np.ndarray, nan: str = "nan") -> list[str]:
    """The cells of a CSV column as csv.writer writes them: integers as str, floats as repr (NaN as ``nan``),
    text quoted where it holds a comma, a quote or a line break."""
    if values.dtype.kind == "f":
        texts = list(map(repr, values.tolist()))
        return texts if nan == "nan" else [nan if text == "nan" else text for text in texts]
    if values.dtype.kind in "iub":
        return list(map(str, values.tolist()))
    quoted = {text: _quoted(text) for text in set(values.tolist())}
    return [quoted[text] for text in values.tolist()]


def _quoted(text: str) -> str:
    """One text cell as csv.writer writes it."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="").writerow([text])
    return buffer.getvalue()


def _write_fields(result: Result, folder: Path) -> None:
    """fields/: body_NNNNN.vtu and contact_NNNNN.vtu at each field step, their PVD collections, and
    solution.npz beside fields/."""
    if not result.fields:
        return
    directory.mkdir(folder)
    body_mesh, contact_mesh = field_meshes(result.discretization)
    body_grid = Grid(*body_mesh)
    contact_grid = Grid(*contact_mesh) if contact_mesh is not None else None
    body, contact = [], []
    for frame in field_frames(result):
        name = f"body_{frame.step:05d}.vtu"
        with replacing(folder / name) as temporary:
            write_vtu(temporary, body_grid, frame.body_points, frame.body_cells)
        body.append((frame.t, name))
        if frame.contact_points is not None:
            name = f"contact_{frame.step:05d}.vtu"
            with replacing(folder / name) as temporary:
                write_vtu(temporary, contact_grid, frame.contact_points)
            contact.append((frame.t, name))
    _write_pvd(folder / "body.pvd", body)
    if contact:
        _write_pvd(folder / "contact.pvd", contact)
    write_solution(result, folder.parent / "solution.npz")




def write_solution(result: Result, path: Path) -> None:
    """solution.npz: ``points`` (d, nnodes), the elements by their type, ``triangles`` (3, nelements) in
    2D or ``tetrahedra`` (4, nelements) in 3D, ``steps`` (s,), ``times`` (s,), ``displacement``
    (s, nnodes, d), ``stress`` (s, nelements, d, d) at the s field steps, ``lame`` (2, nelements) the
    Lamé parameters (λ, μ) of each element (for energy norms); with a viscoplastic law or an
    initial stress also ``z`` (s, nelements, d, d), the history of (2.28): stress = ℰε(u) + z; with a
    contact part also ``contact_nodes`` (m,), the node indices of Γ3, and ``xi`` (s, m), the layer's
    history ξ there. A run restarts from one of these steps with ``initial.from_run``."""
    steps = sorted(result.fields)
    mesh = result.discretization.mesh.mesh
    arrays = dict(points=mesh.p, steps=np.array(steps), **{CELLS[result.dim][2]: mesh.t},
                  times=np.array([result.discretization.times[s - 1] for s in steps]),
                  displacement=np.array([result.fields[s].displacement for s in steps]),
                  stress=np.array([result.fields[s].stress for s in steps]),
                  lame=np.array([np.broadcast_to(np.asarray(value, dtype=float), mesh.t.shape[1:])
                                 for value in result.discretization.elasticity.lame]))
    if steps and result.fields[steps[0]].z is not None:
        arrays["z"] = np.array([result.fields[s].z for s in steps])
    surface = result.discretization.surface
    if surface.size:
        end_rows = result.end_of_step_rows()
        arrays["contact_nodes"] = surface.nodes
        arrays["xi"] = np.array([result.contact["xi"][end_rows[s]] for s in steps]).reshape(len(steps), surface.size)
    with replacing(path) as temporary:
        np.savez(temporary, **arrays)


def _write_figures(result: Result, folder: Path) -> None:
    """The PNG files of :func:`vpcontact.results.plots.run_figures` (those the run has data for)."""
    from ..results.plots import run_figures

    figures = run_figures(result)
    if figures:
        directory.mkdir(folder)
    for stem, figure in figures.items():
        with replacing(folder / f"{stem}.png") as temporary:
            figure.savefig(temporary, dpi=DPI)


def _write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """A ParaView collection: one dataset per time."""
    root = ET.Element("VTKFile", type="Collection", version="0.1")
    collection = ET.SubElement(root, "Collection")
    for t, name in entries:
        ET.SubElement(collection, "DataSet", timestep=repr(float(t)), part="0", file=name)
    with replacing(path) as temporary:
        ET.ElementTree(root).write(temporary, xml_declaration=True, encoding="utf-8")
