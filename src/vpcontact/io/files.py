"""Files in an output directory: each written atomically (a temporary file beside it, renamed into place:
a reader never sees half a file, and a write that fails, on a full disk say, leaves the file as it was),
and removed by pattern. Nothing is written, replaced or removed through a symbolic link: every act goes
through :mod:`vpcontact.io.directory`, which never follows one.
"""

from __future__ import annotations

import fnmatch
import os
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from . import directory


def _temporary(path: Path, tag: str) -> Path:
    """The temporary file beside ``path`` written by the process ``tag`` (a process id, or a glob
    pattern for any)."""
    return path.with_name(f".{path.stem}.tmp-{tag}{path.suffix}")


def temporaries(patterns: Iterable[str]) -> tuple[str, ...]:
    """The glob patterns of the temporary files of any process beside the files of ``patterns`` (a killed
    writer leaves its own)."""
    return tuple(str(_temporary(Path(pattern), "[0-9]*")) for pattern in patterns)


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
    removed nor followed: a run refuses to start with one where it writes, see
    :func:`vpcontact.io.run.check_room`)."""
    out = Path(out)
    directory.check(out)
    found = [(index, path) for path, index in matching(out, patterns) if not path.is_symlink()]
    for _, path in sorted((index, path) for index, path in found if index is not None and path.is_file()):
        directory.unlink(path)
    folders = [path for index, path in found if index is None and path.is_dir()]
    for folder in sorted(folders, key=lambda f: len(f.parts), reverse=True):
        if not any(folder.iterdir()):
            directory.rmdir(folder)
