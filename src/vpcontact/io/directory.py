"""An output directory held by this process while it writes into it (a run directory, a study
directory, a directory of ``write_run``).

``acquire(path)`` refuses, with a one-line CaseError naming the path and the reason, a path that
cannot be a directory to write in (:func:`vpcontact.io.paths.usable`: a symbolic link loop, a dangling
link, a file in the way; a file system that refuses: read-only, /proc, no permission); otherwise it creates the directory (and its
missing parents), takes an exclusive lock on it (``.vpcontact.lock``, ``flock``: two processes never
write into one directory; the kernel releases it when a process dies), and opens it: its identity
(device and inode) is remembered. All of this happens before any computation.

The writers create, rename and remove files and folders in a held directory through ``create``,
``replace``, ``unlink``, ``mkdir`` and ``rmdir`` below: each first checks that the path still leads
to the directory that was locked (else :class:`DirectoryReplaced`: the run stops) and then acts
relative to the open directory itself, so that even a directory swapped between the check and the
act is never written into: a process writes only into the directory it locked. (A temporary file is
written by path before its rename; in that instant's window it can land in the new directory, where
the failed rename leaves it to be removed again.) A worker process of a study ``watch``-es the study
directory its parent holds: its writes below it are checked the same way.

Symbolic links inside a held directory are never followed for writing or removing: the folders on
the way from the held directory to a file (``fields/``, ``checkpoint/``, ``cycles/<n>/``, ...) are
opened one by one without following a link (``O_NOFOLLOW``), and a file or folder that is a link is
neither replaced, nor removed, nor created through: :class:`SymbolicLink` names it (vpcontact never
makes links, so a link there is the user's, and so is what it leads to). The runs refuse such a link
before they start (``io.run.check_room``); this is the guard of every single write. The held
directory itself may be reached through a link (``--out`` a link to a folder on another disk).
"""

from __future__ import annotations

import errno
import itertools
import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

try:
    import fcntl
except ImportError:  # not POSIX: no lock, and no operations relative to a directory
    fcntl = None

from ..errors import CaseError
from .paths import reason, usable

LOCK = ".vpcontact.lock"


class DirectoryReplaced(OSError):
    """A held directory was removed or replaced while this process was writing into it."""


class SymbolicLink(OSError):
    """A symbolic link where vpcontact was to write or remove a file or folder inside a held directory:
    nothing was written through it, nothing removed (one line naming the link, see ``refuse_link``)."""


class Held:
    """A directory this process holds: its path as given, its descriptor (None where the system has
    no operations relative to a directory), its identity and lock (None: watched only, see
    ``watch``), and what ``acquire`` changed to get it (to leave no trace when the run is refused: see
    ``release``)."""

    def __init__(self, path: Path, descriptor: int | None, identity: tuple[int, int], lock: int | None,
                 created: list[Path], lock_existed: bool, changed: tuple[Path, os.stat_result]):
        self.path, self.descriptor, self.identity, self.lock = path, descriptor, identity, lock
        self.created, self.lock_existed, self.changed = created, lock_existed, changed
        self.key = os.path.abspath(path)

    def check(self) -> None:
        """Raise DirectoryReplaced unless ``path`` still is the directory that was locked."""
        try:
            now = os.stat(self.path)
        except OSError:
            now = None
        if now is None or _identity(now) != self.identity:
            what = "removed" if now is None else "replaced by another directory"
            raise DirectoryReplaced(f"the directory '{self.path}' was {what} while vpcontact was writing to it: "
                                    f"vpcontact stopped and wrote nothing into what is now at that path")

    def at(self, path: Path) -> tuple[str | Path, int | None]:
        """``path`` for an os function: (the path relative to the open directory, its descriptor), or
        (the path as it is, None)."""
        if self.descriptor is None:
            return path, None
        return os.path.relpath(os.path.abspath(path), self.key), self.descriptor

    @contextmanager
    def folder_of(self, path: Path) -> Iterator[tuple[str | Path, int | None]]:
        """(the name of ``path`` in its folder, that folder's descriptor) for an os function, the folders
        from the held directory down opened one by one without following a symbolic link
        (SymbolicLink: one is a link); (the path as it is, None) where the system has no operations
        relative to a directory."""
        if self.descriptor is None:
            yield path, None
            return
        *folders, name = Path(os.path.relpath(os.path.abspath(path), self.key)).parts
        opened = []
        try:
            descriptor = self.descriptor
            for depth, folder in enumerate(folders, start=1):
                try:
                    descriptor = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | NOFOLLOW, dir_fd=descriptor)
                except OSError:
                    refuse_link(self.path.joinpath(*folders[:depth]), folder, descriptor)
                    raise
                opened.append(descriptor)
            yield name, descriptor
        finally:
            for descriptor in reversed(opened):
                os.close(descriptor)

    def release(self, *, undo: bool = False) -> None:
        """Unlock and remove the lock file (in the directory locked, wherever it is now). ``undo``
        (nothing was written: the run was refused): remove only what ``acquire`` created (the lock
        file, folders) and restore the times of the folder whose entries that changed."""
        _HELD.pop(self.key, None)
        try:
            self.check()
            same = True
        except DirectoryReplaced:
            same = False  # what is at the path now is not ours: touch nothing there
        if not (undo and self.lock_existed) and (same or self.descriptor is not None):
            name, descriptor = self.at(self.path / LOCK)
            _quietly(os.unlink, name, dir_fd=descriptor)
        os.close(self.lock)
        if self.descriptor is not None:
            os.close(self.descriptor)
        if undo and same:
            _undo(self.created, self.changed)


_HELD: dict[str, Held] = {}
"""The directories this process holds, by absolute path."""


def holds_files(path: Path, label: str = "--out") -> bool:
    """Does the directory ``path`` exist and hold anything besides a lock file?"""
    try:
        return any(entry.name != LOCK for entry in Path(path).iterdir())
    except FileNotFoundError:
        return False
    except OSError as error:
        raise CaseError(f"{label} '{path}': cannot read the directory ({reason(error)})") from None


def acquire(path: Path, label: str = "--out") -> Held:
    """Create the directory ``path`` if needed, lock it and open it (see the module's docstring);
    CaseError when it cannot be used, or when another vpcontact process holds it."""
    path = Path(path)
    usable(path, label)
    check(path)  # inside a directory held (or watched) by this process: still that one
    missing = list(itertools.takewhile(lambda p: not os.path.lexists(p), (path, *path.parents)))
    parent = missing[-1].parent if missing else path  # the folder whose entries acquire changes
    changed = (parent, os.stat(parent))
    lock_existed = os.path.lexists(path / LOCK)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        _undo(missing, changed)
        raise CaseError(f"{label} '{path}': cannot create the directory ({reason(error)})") from None
    descriptor = None
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_DIRECTORY) if fcntl is not None else None
        lock = os.open(LOCK if descriptor is not None else path / LOCK, os.O_RDWR | os.O_CREAT | NOFOLLOW, 0o644,
                       dir_fd=descriptor)
    except OSError as error:
        if descriptor is not None:
            os.close(descriptor)
        _undo(missing, changed)
        if os.path.islink(path / LOCK):
            raise CaseError(f"{label} '{path}': '{path / LOCK}' is a symbolic link, and vpcontact writes its lock "
                            f"file there and never through a link: remove the link") from None
        raise CaseError(f"{label} '{path}': cannot write in the directory ({reason(error)})") from None
    if fcntl is not None:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            if _identity(os.stat(LOCK, dir_fd=descriptor)) != _identity(os.fstat(lock)):
                raise OSError(errno.EAGAIN, "the lock file was just replaced")  # by a process releasing it
        except OSError:
            os.close(lock)
            os.close(descriptor)
            raise CaseError(f"{label} '{path}': another vpcontact run is writing to it") from None
    identity = _identity(os.fstat(descriptor) if descriptor is not None else os.stat(path))
    held = Held(path, descriptor, identity, lock, missing, lock_existed, changed)
    _HELD[held.key] = held
    return held


def check(path: Path) -> None:
    """Before writing at ``path``: every held directory that contains it is still the one locked (else
    DirectoryReplaced)."""
    for held in _holders(path):
        held.check()


#: Open flags that refuse a symbolic link as the last component (none where the system has no such flag).
NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


def refuse_link(path: Path, name: str | Path, descriptor: int | None = None) -> None:
    """SymbolicLink if ``name`` (in the folder ``descriptor``, or a path) is a symbolic link; ``path``
    is how it is named to the user."""
    if _is_link(name, descriptor):
        raise SymbolicLink(f"'{path}' is a symbolic link (to '{os.readlink(name, dir_fd=descriptor)}'), and vpcontact "
                           f"never writes or removes through a link in its output directory")


def create(path: Path, replaces: Path) -> tuple[int, int]:
    """Create the empty file ``path`` exclusively (a writer's temporary, to be renamed to ``replaces``
    beside it once written), never through a symbolic link, in its held directory, and return its
    identity (see ``written``); SymbolicLink if ``replaces`` or a folder on the way is a link (and
    nothing is created). A file of that name left by a killed process (whose id this one now has) is
    replaced."""
    held = _checked(path)
    made = []
    with _folder_of(held, path) as (name, descriptor):
        refuse_link(replaces, Path(name).with_name(Path(replaces).name), descriptor)

        def make():
            flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | NOFOLLOW
            try:
                handle = os.open(name, flags, 0o644, dir_fd=descriptor)
            except FileExistsError:
                refuse_link(path, name, descriptor)
                os.unlink(name, dir_fd=descriptor)
                handle = os.open(name, flags, 0o644, dir_fd=descriptor)
            made.append(_identity(os.fstat(handle)))
            os.close(handle)

        _act(held, make)
    return made[0]


def written(handle: int, path: Path, identity: tuple[int, int]) -> None:
    """After a writer wrote the temporary ``path`` by its path: DirectoryReplaced unless the file open as
    ``handle`` (opened at that path) is the one ``create`` made (``identity``), i.e. the write went
    into the held directory and not into what replaced it (or where a link led) meanwhile."""
    if _identity(os.fstat(handle)) != identity:
        raise DirectoryReplaced(f"'{path}' is not the file vpcontact created there: what holds it was replaced "
                                f"while vpcontact was writing it, and vpcontact stopped")


def replace(source: Path, target: Path) -> None:
    """``os.replace(source, target)``, both in one folder of a held directory (see the module's
    docstring); SymbolicLink if ``target`` is a link (it is not replaced)."""
    held = _checked(target)
    with _folder_of(held, target) as (name, descriptor):
        refuse_link(target, name, descriptor)
        source = Path(name).with_name(Path(source).name)
        _act(held, lambda: os.replace(source, name, src_dir_fd=descriptor, dst_dir_fd=descriptor))


def unlink(path: Path) -> None:
    """Remove the file ``path`` (if it is there) in its held directory; SymbolicLink if it is a link
    (it is not removed)."""
    held = _checked(path)
    with _folder_of(held, path) as (name, descriptor):
        refuse_link(path, name, descriptor)
        _act(held, lambda: _quietly(os.unlink, name, dir_fd=descriptor))


def mkdir(path: Path) -> None:
    """Create the folder ``path`` (if it is not there) in its held directory; SymbolicLink if it is a
    link, even to a folder (what is written in ``path`` would land where it leads)."""
    held = _checked(path)
    with _folder_of(held, path) as (name, descriptor):

        def make():
            try:
                os.mkdir(name, dir_fd=descriptor)
            except FileExistsError:
                refuse_link(path, name, descriptor)
                if not stat.S_ISDIR(os.stat(name, dir_fd=descriptor).st_mode):
                    raise

        _act(held, make)


def rmdir(path: Path) -> None:
    """Remove the empty folder ``path`` in its held directory; SymbolicLink if it is a link."""
    held = _checked(path)
    with _folder_of(held, path) as (name, descriptor):
        refuse_link(path, name, descriptor)
        _act(held, lambda: os.rmdir(name, dir_fd=descriptor))


def discard(path: Path) -> None:
    """Remove this process's own temporary file ``path`` wherever it is, never raising and never
    through a symbolic link: in its held directory (which may have been moved) and at the path (where
    a write racing a swap of the directory may have put it)."""
    holders = _holders(path)
    try:
        with _folder_of(holders[-1] if holders else None, path) as (name, descriptor):
            if not _is_link(name, descriptor):
                _quietly(os.unlink, name, dir_fd=descriptor)
    except OSError:
        pass
    if holders and not any(map(_is_link, _below(holders[-1].path, Path(path)))):
        _quietly(os.unlink, path)


def forget_inherited() -> None:
    """In a process forked from one that holds directories: let go of the copies of their locks (the
    parent holds them; a worker process writes only into the directories it acquires itself)."""
    for held in _HELD.values():
        for descriptor in (held.lock, held.descriptor):
            if descriptor is not None:
                os.close(descriptor)
    _HELD.clear()


def watch(path: Path, identity: tuple[int, int]) -> None:
    """In a worker process: check every write below ``path`` (a directory its parent process holds,
    with this ``identity``) as if this process held it: nothing is written below a replacement."""
    held = Held(Path(path), None, identity, None, [], False, None)
    _HELD[held.key] = held


def _holders(path: Path) -> list[Held]:
    """The held directories that contain ``path``, innermost last."""
    target = os.path.abspath(path)
    found = [held for held in list(_HELD.values())
             if target == held.key or target.startswith(held.key.rstrip(os.sep) + os.sep)]
    return sorted(found, key=lambda held: len(held.key))


@contextmanager
def _folder_of(held: Held | None, path: Path) -> Iterator[tuple[str | Path, int | None]]:
    """``held.folder_of(path)``; (the path as it is, None) outside a held directory."""
    if held is None:
        yield path, None
    else:
        with held.folder_of(path) as found:
            yield found


def _below(top: Path, path: Path) -> list[Path]:
    """The paths from the entry of ``top`` down to ``path`` (a path inside the folder ``top``)."""
    parts = Path(os.path.relpath(os.path.abspath(path), os.path.abspath(top))).parts
    return [Path(top).joinpath(*parts[:depth]) for depth in range(1, len(parts) + 1)]


def _is_link(name: str | Path, descriptor: int | None = None) -> bool:
    """Is ``name`` (in the folder ``descriptor``, or a path) a symbolic link?"""
    try:
        return stat.S_ISLNK(os.lstat(name, dir_fd=descriptor).st_mode)
    except OSError:
        return False


def _checked(path: Path) -> Held | None:
    """Check the held directories that contain ``path``; the innermost (None: not in one)."""
    holders = _holders(path)
    for held in holders:
        held.check()
    return holders[-1] if holders else None


def _act(held: Held | None, action) -> None:
    """Do ``action``; an OSError it raises because the held directory was removed or replaced meanwhile
    becomes DirectoryReplaced."""
    try:
        action()
    except OSError:
        if held is not None:
            held.check()
        raise


def _quietly(function, *arguments, **keywords) -> None:
    """``function(*arguments, **keywords)``, a missing file being no error."""
    try:
        function(*arguments, **keywords)
    except FileNotFoundError:
        pass


def _identity(status: os.stat_result) -> tuple[int, int]:
    return status.st_dev, status.st_ino


def _undo(created: list[Path], changed: tuple[Path, os.stat_result]) -> None:
    """Remove the folders ``acquire`` created (deepest first, if empty) and restore the times of the
    folder whose entries that changed: a refused run leaves no trace."""
    for folder in created:
        try:
            folder.rmdir()
        except OSError:
            break
    folder, before = changed
    try:
        os.utime(folder, ns=(before.st_atime_ns, before.st_mtime_ns))
    except OSError:
        pass  # a folder we cannot write in: it did not change
