"""Paths given as output directories (``--out``, a study's DIR, ``write_run``'s ``out``), checked before
anything is computed or written: a folder's name (a string or a path without NUL), a name the file
system takes (no component longer than NAME_MAX, room below it for the names a run writes within
PATH_MAX), and an existing folder on its way (a symbolic link followed; a loop or a dangling one is
named). Each refusal is one line, a CaseError naming the path and the reason.
"""

from __future__ import annotations

import errno
import math
import os
import stat
from pathlib import Path

from ..errors import CaseError, shown


def folder_path(value, label: str = "--out") -> Path:
    """``value`` (a folder's name given from Python) as a Path; CaseError for another object, or a name with a
    NUL character (which no file system holds)."""
    if not isinstance(value, (str, os.PathLike)) or not isinstance(os.fspath(value), str) or "\0" in os.fspath(value):
        name = os.fspath(value) if isinstance(value, os.PathLike) else value
        raise CaseError(f"{label} = {shown(repr(name))}: expected a folder's name (a string or a path, without NUL "
                        f"characters)")
    return Path(value)


def usable(path: Path, label: str = "--out") -> None:
    """Refuse (CaseError) a path that cannot be a directory to write in, without writing anything: its
    name must fit the file system (see ``_check_length``) and its nearest existing component must be a
    directory (after following symbolic links)."""
    path = folder_path(path, label)
    existing = next(p for p in (path, *path.parents) if os.path.lexists(p))
    _check_length(path, existing, label)
    subject = f"{label} '{path}'" if existing == path else f"{label} '{path}': '{existing}'"
    try:
        mode = os.stat(existing).st_mode
    except OSError as error:
        if os.path.islink(existing) and error.errno == errno.ELOOP:
            raise CaseError(f"{subject} is a symbolic link loop (it leads back to itself); remove it or give "
                            f"another path") from None
        if os.path.islink(existing) and error.errno == errno.ENOENT:
            raise CaseError(f"{subject} is a symbolic link to '{os.readlink(existing)}', which does not exist; "
                            f"create that directory or give another path") from None
        raise CaseError(f"{subject}: cannot use it ({reason(error)})") from None
    if not stat.S_ISDIR(mode):
        raise CaseError(f"{subject} exists and is not a directory")


#: Room kept in a path for the names a run writes below its directory (fields/contact_00000011.vtu and
#: the temporary files beside it, checkpoint/..., runs/<id>/... of a study).
ROOM = 96


def _check_length(path: Path, existing: Path, label: str) -> None:
    """Refuse a path with a component longer than the file system's NAME_MAX (255 bytes on most), or too
    long, with the names a run writes below it (ROOM), for its PATH_MAX (4096 bytes on Linux): the file
    system would refuse the run's first write, after its computation."""
    name_max, path_max = _limit(existing, "PC_NAME_MAX", 255), _limit(existing, "PC_PATH_MAX", 4096)
    for part in path.parts:
        size = len(os.fsencode(part))
        if size > name_max:
            raise CaseError(f"{label} '{shown(str(path))}': the name '{shown(part)}' has {size} bytes, more than "
                            f"the {name_max} the file system allows: give a shorter name")
    size = len(os.fsencode(path))
    if size + ROOM > path_max:
        raise CaseError(f"{label} '{shown(str(path))}' has {size} bytes and the names a run writes below it make "
                        f"more than the {path_max} bytes of a path the file system allows: give a shorter path")


def _limit(folder: Path, name: str, default: int) -> float:
    """The file system's limit ``name`` at ``folder`` (os.pathconf); ``default`` where the system does not
    tell, inf where it has none (-1)."""
    try:
        value = os.pathconf(folder, name)
    except (OSError, ValueError, AttributeError):  # not POSIX, or not told
        return default
    return math.inf if value is None or value < 0 else value


def reason(error: OSError) -> str:
    """The OS's reason; ENOENT where the folders exist means the file system refuses (/proc, ...)."""
    if error.errno == errno.ENOENT:
        return f"the file system refuses: {error.strerror}"
    return error.strerror or str(error)
