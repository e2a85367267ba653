"""Where outputs go, and how they get there safely: only over a regular,
writable file (never a device node, a FIFO or a read-only file); through a
temporary file next to the target, named with the writer's process id, that
replaces the target in one step with the target's own mode; under a lock, so
two runs never write the same output at once; and with the debris of a run
that was killed outright (SIGKILL) removed by the next run. docs/robustness.md."""
from __future__ import annotations

import errno
import fcntl
import os
import re
import secrets
import shutil
import stat
import tempfile
from pathlib import Path


class OutputError(ValueError):
    """An output location that must not or cannot be written (exit code 2 at the command line)."""


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
                       (stat.S_ISDIR, "a directory")):
        if test(mode):
            return name
    return "not a regular file"


def printable(text) -> str:
    """TEXT (a path or a message) as one printable line: control characters
    (a newline, a terminal escape) and other unprintable ones escaped as
    repr does (\\n, \\x1b), so a file name can neither split a one-line
    message nor reach the terminal as a command."""
    text = os.fsdecode(text) if isinstance(text, (bytes, os.PathLike)) else str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def _refusal(path, mode: int) -> str | None:
    """Why an existing entry of MODE (from lstat) at PATH must not be replaced, or None."""
    shown = printable(path)
    if stat.S_ISLNK(mode):
        return (f"{shown}: is a symbolic link; outputs are never written through or over a link "
                "(name the file itself)")
    if not stat.S_ISREG(mode):
        return f"{shown}: is {_kind(mode)}; outputs are written only as regular files (choose a file name)"
    if not mode & 0o222:
        return (f"{shown}: is read-only (mode {stat.S_IMODE(mode):04o}); refusing to replace it "
                "(make it writable or choose another output)")
    return None


def check_replaceable(path) -> None:
    """Refuse PATH when it exists and is anything but a writable regular file:
    a symbolic link (not followed: the link itself would be replaced), a
    device node or a FIFO is never replaced by a file, a read-only file is
    never replaced (its mode says not to, also to root)."""
    if not os.fspath(path):
        raise OutputError("the output path is empty; name a file or folder")
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    except OSError as e:
        raise OutputError(f"{printable(path)}: cannot inspect the output ({e.strerror})") from None
    reason = _refusal(path, st.st_mode)
    if reason is None and not os.access(path, os.W_OK):
        reason = f"{printable(path)}: is not writable; refusing to replace it (choose another output)"
    if reason:
        raise OutputError(reason)


def file_mode(path, default: int | None = None) -> int:
    """The permission bits PATH's replacement gets: PATH's own when it exists,
    else DEFAULT (None: 0o666 less the umask, as for a new file)."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        if default is not None:
            return default
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


# Temporary names carry the writer's pid, so a later run can tell a dead run's debris from a live run's files.
def temp_path(path) -> str:
    """A temporary file name next to PATH: .NAME.PID.HEX.tmp."""
    path = os.fspath(path)
    directory, name = os.path.split(os.path.abspath(path))
    return os.path.join(directory, f".{name}.{os.getpid()}.{secrets.token_hex(6)}.tmp")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def sweep_debris(path) -> list[str]:
    """Remove what a killed run left next to PATH (its temporary files and
    staging folders, whose writer's pid is no longer running); returns them."""
    path = os.path.abspath(os.fspath(path))
    directory, name = os.path.split(path)
    return _sweep(directory, re.compile(rf"\.{re.escape(name)}\.(\d+)\.[0-9a-f]+\.tmp\Z"))


def sweep_temp_dirs(prefix: str, directory: str | None = None) -> list[str]:
    """Remove folders PREFIX-PID-* in DIRECTORY (default: the temporary
    directory) whose pid is no longer running: what a killed run left."""
    directory = directory or tempfile.gettempdir()
    return _sweep(directory, re.compile(rf"{re.escape(prefix)}-(\d+)-"))


def _sweep(directory: str, pattern) -> list[str]:
    """Remove the entries of DIRECTORY that PATTERN matches whose pid (its group 1) is no longer running."""
    removed = []
    try:
        entries = os.listdir(directory)
    except OSError:
        return removed
    for entry in entries:
        m = pattern.match(entry)
        if m and not _alive(int(m.group(1))):
            _remove(os.path.join(directory, entry))
            removed.append(entry)
    return removed


def temp_dir(prefix: str, directory: str | None = None) -> tempfile.TemporaryDirectory:
    """A TemporaryDirectory named PREFIX-PID-..., swept by sweep_temp_dirs once its run is dead."""
    sweep_temp_dirs(prefix, directory)
    return tempfile.TemporaryDirectory(prefix=f"{prefix}-{os.getpid()}-", dir=directory)


def _remove(path: str) -> None:
    try:
        if os.path.isdir(path) and not os.path.islink(path):
            shutil.rmtree(path, ignore_errors=True)
        else:
            os.unlink(path)
    except OSError:
        pass


class _Directory:
    """A directory held open: entries are made, inspected and renamed relative
    to this handle (never through a path resolved twice)."""

    def __init__(self, path):
        self.path = os.path.dirname(os.path.abspath(os.fspath(path))) or "/"
        self.fd = os.open(self.path, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        os.close(self.fd)

    def lstat(self, name: str):
        try:
            return os.stat(name, dir_fd=self.fd, follow_symlinks=False)
        except FileNotFoundError:
            return None


def open_temp(path, binary: bool = False):
    """A new temporary file next to PATH, open for writing: (file, its path).
    Created with O_EXCL and O_NOFOLLOW relative to the folder's handle: it
    never opens an existing file or a link."""
    tmp = temp_path(path)
    with _Directory(tmp) as d:
        fd = os.open(os.path.basename(tmp), os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC,
                     0o666, dir_fd=d.fd)
    try:
        return (open(fd, "wb") if binary else open(fd, "w", newline="", encoding="utf-8")), tmp
    except BaseException:
        os.close(fd)
        raise


_RENAME_NOREPLACE, _RENAME_EXCHANGE = 1, 2


def _renameat2(src: _Directory, old: str, dst: _Directory, new: str, flags: int) -> bool:
    """renameat2(2) with FLAGS; False where the system or the file system lacks it (then the caller renames)."""
    global _renameat2_call
    if _renameat2_call is None:
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            call = libc.renameat2
            call.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint)
            _renameat2_call = (call, ctypes)
        except (OSError, AttributeError):
            _renameat2_call = False
    if not _renameat2_call:
        return False
    call, ctypes = _renameat2_call
    if call(src.fd, os.fsencode(old), dst.fd, os.fsencode(new), flags) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False
    raise OSError(err, os.strerror(err), new)


_renameat2_call = None


def replace_into(tmp, path) -> None:
    """Move the finished TMP over PATH in one step, with PATH's mode when it
    exists (an existing file keeps its permissions). Relative to the folders'
    handles, and never over a link, a device or a read-only file, even one
    put there since PATH was checked: a new PATH is created only if still
    absent (RENAME_NOREPLACE); an existing one is exchanged with TMP and,
    should what comes back not be a writable regular file, exchanged back
    and refused (OutputError)."""
    tname, name = os.path.basename(os.fspath(tmp)), os.path.basename(os.path.abspath(os.fspath(path)))
    with _Directory(tmp) as src, _Directory(path) as dst:
        st = dst.lstat(name)
        if st is not None and (reason := _refusal(path, st.st_mode)):
            raise OutputError(reason)
        os.chmod(tname, stat.S_IMODE(st.st_mode) if st is not None else file_mode(path), dir_fd=src.fd)
        if st is None:
            try:
                if _renameat2(src, tname, dst, name, _RENAME_NOREPLACE):
                    return
            except FileExistsError:  # something appeared there meanwhile: look again
                return replace_into(tmp, path)
        elif _renameat2(src, tname, dst, name, _RENAME_EXCHANGE):
            swapped = src.lstat(tname)  # what was at PATH, now at TMP's name
            reason = _refusal(path, swapped.st_mode) if swapped is not None else None
            if reason:
                _renameat2(src, tname, dst, name, _RENAME_EXCHANGE)
                raise OutputError(reason)
            os.unlink(tname, dir_fd=src.fd)
            return
        os.replace(tname, name, src_dir_fd=src.fd, dst_dir_fd=dst.fd)


def write_whole(path, data: str | bytes) -> None:
    """DATA (text as UTF-8) into PATH in one step through open_temp and
    replace_into: never through or over a link, a device or a read-only
    file; on any failure (OutputError naming PATH) nothing is left."""
    check_replaceable(path)
    tmp = None
    try:
        f, tmp = open_temp(path, binary=isinstance(data, bytes))
        with f:
            f.write(data)
        replace_into(tmp, path)  # an existing file keeps its mode; a new one as the umask says
    except OSError as e:
        raise write_error(path, e) from None
    finally:
        if tmp and os.path.lexists(tmp):
            os.unlink(tmp)


def write_error(path, exc: OSError) -> OutputError:
    """An OSError while writing PATH as one line naming PATH (ENOSPC: the disk is full)."""
    reason = exc.strerror or str(exc)
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        reason += " (the disk is full)"
    return OutputError(f"cannot write {printable(path)}: {reason}; nothing was written")


class OutputLock:
    """An exclusive lock on an output (a file or a folder) for the length of a
    run: a second run on the same output is refused at once, naming the
    first's pid. The lock is a small file .NAME.lock next to the output,
    removed at the end; a killed run's lock file is stale (the kernel released
    its lock) and is taken over."""

    def __init__(self, path):
        self.path = os.path.abspath(os.fspath(path))
        directory, name = os.path.split(self.path)
        while not os.path.isdir(directory):  # an output in folders yet to be made: lock in the first that exists
            directory, parent = os.path.split(directory)
            name = f"{parent}%{name}"
        self.lock_path = os.path.join(directory, f".{name}.lock")
        self._fd = None

    def acquire(self) -> "OutputLock":
        while True:
            try:  # never through a link planted under the lock's name (it is truncated below)
                fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
            except OSError as e:
                raise OutputError(f"{printable(self.path)}: cannot lock the output ({printable(self.lock_path)}: "
                                  f"{'a symbolic link' if e.errno == errno.ELOOP else e.strerror})") from None
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                os.close(fd)
                raise OutputError(f"{printable(self.path)}: cannot lock the output ({printable(self.lock_path)} "
                                  "is not a regular file)")
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.read(fd, 32).decode(errors="replace").strip() or "?"
                os.close(fd)
                raise OutputError(f"{printable(self.path)}: another hdjoint run (pid {holder}) is writing this output; "
                                  "wait for it to finish or choose another output") from None
            # The holder before us may have removed the lock file after we opened it: lock the file on disk.
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.lock_path))
            except FileNotFoundError:
                same = False
            if same:
                os.ftruncate(fd, 0)
                os.write(fd, f"{os.getpid()}\n".encode())
                self._fd = fd
                return self
            os.close(fd)

    def release(self) -> None:
        if self._fd is not None:
            try:
                os.unlink(self.lock_path)
            except OSError:
                pass
            os.close(self._fd)
            self._fd = None

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()


def created_directory(out) -> list[Path]:
    """The folders `Path(out).mkdir(parents=True)` would create, outermost first (to remove them on failure)."""
    missing, p = [], Path(out).absolute()
    while not p.exists():
        missing.append(p)
        p = p.parent
    return missing[::-1]
