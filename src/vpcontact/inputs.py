"""Input files (case, study and mesh files) are checked before they are opened.

Only a regular file is read: a FIFO would hang the reader, a device such as /dev/zero would feed it
until memory is gone, a directory cannot be read at all. A case or study file is a few kilobytes of
TOML; one larger than ``MAX_TOML_BYTES`` is refused with its size instead of being read whole.
"""

from __future__ import annotations

import os
import stat

from .errors import CaseError

#: Largest case or study file read (bytes).
MAX_TOML_BYTES = 16 * 2**20

_KINDS = [(stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")]


def check_regular_file(path: str | os.PathLike, kind: str, max_bytes: int | None = None) -> None:
    """Raise CaseError unless `path` (symbolic links followed) is a regular file of at most
    `max_bytes` bytes; `kind` ("case file", ...) starts the message, which names the path."""
    try:
        status = os.stat(path)
    except FileNotFoundError:
        raise CaseError(f"{kind} '{os.fspath(path)}' not found") from None
    except (OSError, ValueError) as error:  # ValueError: a NUL in the name
        reason = getattr(error, "strerror", None) or str(error)
        raise CaseError(f"{kind} '{os.fspath(path)}' cannot be read: {reason}") from None
    if not stat.S_ISREG(status.st_mode):
        what = next((name for test, name in _KINDS if test(status.st_mode)), "a special file")
        raise CaseError(f"{kind} '{os.fspath(path)}' is {what}, not a regular file: give the path of a file")
    if max_bytes is not None and status.st_size > max_bytes:
        raise CaseError(f"{kind} '{os.fspath(path)}' is {status.st_size} bytes, more than the {max_bytes} bytes a "
                        f"{kind} can have: is it the right file?")
