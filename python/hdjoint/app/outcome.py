"""The one exit-code layer every `hdjoint` command shares: what a failure
is told as (one line on stderr, names escaped) and its exit code. 2: bad
input or an output that must not or cannot be written (a missing,
unreadable or unwritable path, a read-only file system, a full disk);
1: a failure while running (out of memory included). docs/robustness.md."""
from __future__ import annotations

import errno
import sys

from hdjoint.io.outputs import OutputError, printable
from hdjoint.jobs.inputs import UserError

# An OSError with one of these is the user's path, not the program: exit 2.
PATH_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM, errno.ENOENT,
                         errno.ENOTDIR, errno.EISDIR, errno.EEXIST, errno.ENAMETOOLONG, errno.ELOOP,
                         errno.ENXIO, errno.EFBIG})
FULL = frozenset({errno.ENOSPC, errno.EDQUOT})
TOLD = (UserError, OutputError, OSError, RuntimeError, ValueError, MemoryError)


def exit_code(exc: BaseException) -> int:
    if isinstance(exc, (UserError, OutputError)):
        return 2
    if isinstance(exc, OSError) and exc.errno in PATH_ERRNOS:
        return 2
    return 1


def message(exc: BaseException) -> str:
    """EXC as one line, its path escaped; never a raw `[Errno N]`."""
    if isinstance(exc, MemoryError):
        return ("out of memory (a limit on this process's memory, or the machine's); nothing was written "
                "and the temporary files are removed")
    if isinstance(exc, OSError) and exc.errno is not None:
        reason = exc.strerror or str(exc)
        if exc.errno in FULL and "full" not in reason:
            reason += " (the disk is full)"
        if exc.filename is not None:
            target = f" -> {printable(exc.filename2)}" if exc.filename2 is not None else ""
            return f"{printable(exc.filename)}{target}: {reason}"
        return reason
    return printable(str(exc) or type(exc).__name__)


def told(command: str, exc: BaseException) -> int | None:
    """Print EXC as the command's one-line failure and return its exit code;
    None for an exception that is no failure of the user's run (a bug: its
    traceback is kept)."""
    if not isinstance(exc, TOLD):
        return None
    print(f"hdjoint {command}: {printable(message(exc))}", file=sys.stderr)
    return exit_code(exc)
