"""A run directory: the files vpcontact writes there, the refusals before a run writes into one, and a
result written into one (:func:`write_run`, the API's ``vpcontact.write_run``).

Each file is written atomically (:mod:`vpcontact.io.files`), ``summary.json`` last: a directory whose
summary.json says ``"status": "complete"`` holds a complete run; without summary.json a run is in
progress or was killed (``vpcontact run --resume`` continues it from its checkpoint, see
:mod:`vpcontact.drivers.rundir`). Nothing is written, replaced or removed through a symbolic link:
``check_room`` refuses one where a run writes before it starts, and every write and removal acts
through :mod:`vpcontact.io.directory`, which never follows one. The files, each written by the module
of its format (the plug-ins of :mod:`vpcontact.io.outputs`):

- ``summary.json``      status, sizes, wall time, the final values, versions (:mod:`~vpcontact.io.summary`);
- ``history.csv``       one row per time step (``Result.columns``; :mod:`~vpcontact.io.history_csv`);
- ``contact.csv``       one row per contact node and step (:mod:`~vpcontact.io.contact_csv`);
- ``fields/body.pvd``   displacement, stress, von Mises (and the viscoplastic history z when there is
                        one) at the field steps, and each element's material (its index in the case's
                        material list), E and ν (VTU files, ParaView; :mod:`~vpcontact.io.vtu`);
- ``fields/contact.pvd``  Γ3 with penetration, ξ, K, pressures, status, normal and contact force, and the
                        local layer parameters (:func:`~vpcontact.results.frames.layer_columns`);
- ``fields/body.xdmf``  with ``output.xdmf``, the same fields as an XDMF time series, the mesh stored once
                        in ``fields/body.h5`` (and ``fields/contact.xdmf``, ``.h5``; :mod:`~vpcontact.io.xdmf`);
- ``solution.npz``      the fields at the field steps as arrays, ξ too (:mod:`~vpcontact.io.solution`):
                        what a restart (``initial.from_run``) starts from;
- ``case.resolved.toml``  every value used, defaults included, with the versions as a header;
- ``figures/*.png``     with ``output.figures``, at the end of a complete or failed run: the contact
                        pressure, the deformed body and the history (:mod:`~vpcontact.io.figures`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from ..errors import CaseError, flag
from . import checkpoint, directory, paths
from .files import matching, remove_files, temporaries, write_text
from .outputs import FILES, write_outputs
from .versions import versions

RESOLVED_CASE = "case.resolved.toml"
OUTPUTS = (*FILES, RESOLVED_CASE, *checkpoint.FILES, "adapt.csv", "final_mesh.msh",
           *(f"cycles/[0-9]*/{name}" for name in FILES))
"""Every file vpcontact writes in a run directory, as glob patterns (those in checkpoint/ are the files of
:mod:`vpcontact.io.checkpoint`; an adaptive run, ``[adapt]``, writes adapt.csv, the final_mesh.msh and each
cycle's run in cycles/<n>/), summary.json first: ``--overwrite`` removes these, their temporaries, and
the folders that this leaves empty; nothing else."""
TEMPORARIES = temporaries(OUTPUTS)
"""The temporary files of the OUTPUTS (of any process: a killed writer leaves its own)."""


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


def write_run(result, out: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Write the files of a run directory (README, "Outputs") of ``result`` into ``out``, as ``vpcontact
    run`` does: created if missing, each file atomically and summary.json last, while holding the directory
    (see :mod:`vpcontact.io.directory`); with ``overwrite`` the outputs of an earlier run there are removed
    first, and nothing else. Refused as ``vpcontact run`` refuses its ``--out``, before anything is written:
    CaseError for a path that cannot be a directory or with a file or folder standing where an output goes,
    NotEmpty (a CaseError, and a FileExistsError) for a directory that is not empty without ``overwrite``.
    Returns ``out`` as a Path."""
    out, overwrite = paths.folder_path(out, "output directory"), flag("overwrite", overwrite)
    paths.usable(out, "output directory")
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
    (:meth:`~vpcontact.case.model.Case.to_toml`), the versions in its header. A run directory's case reads
    back with ``vpcontact.load_case(DIR / "case.resolved.toml")``."""
    header = "".join(f"# {name} {version}\n" for name, version in versions().items())
    write_text(Path(out) / RESOLVED_CASE, header + resolved)
