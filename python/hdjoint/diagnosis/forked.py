"""Independent pieces of one computation, side by side in forked processes.

The diagnosis tries every hypothesis of a round on the same recording: each
fit is independent and CPU-bound (the GIL would serialise threads). Forked
children inherit the prepared recording and its caches without copying or
pickling them; only each piece's result comes back. Where forking is not
safe (a daemonic process such as a Dask worker, which may not have
children, or a process running other threads, whose locks a child could
inherit held) the pieces run one after the other, with the same results.

A fit's finite-difference Jacobian is such a computation too: one residual
evaluation per parameter (forked_map lends a least-squares solver a
map-like over forked children).

A Helper is forked ahead of its pieces: it prepares (imports matplotlib)
on the core the diagnosis's serial stages leave idle, then maps pieces
sent to it from that prepared state."""
from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from contextlib import contextmanager
from typing import Callable, Iterator, TypeVar

T = TypeVar("T")
_piece: Callable[[int], object] | None = None  # what the forked children run, inherited
_function: Callable | None = None  # what forked_map's children evaluate, inherited


def available_cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def can_fork() -> bool:
    return (hasattr(os, "fork") and not multiprocessing.current_process().daemon
            and threading.active_count() == 1)


_in_piece = False  # set in a forked child: the cores are its pool's, one process each


def threads_here() -> int:
    """Threads a computation here may split itself over: every core in the
    process that runs the diagnosis's serial stages, one in a forked piece
    (its pool already fills the cores) or where this process may not fork
    (a Dask worker, one of several sharing the cores)."""
    return 1 if _in_piece or not can_fork() else available_cores()


def _run(index: int):
    return _piece(index)


def _start_piece() -> None:
    """A pool's child: one core's worth of work, and Ctrl-C the parent's to handle."""
    global _in_piece
    _in_piece = True
    _die_with_parent()
    _quiet_on_ctrl_c()


def _die_with_parent() -> None:
    """In a child: killed when its parent ends, also by SIGKILL (Linux's
    PR_SET_PDEATHSIG), so no orphan computes on holding the run's output lock."""
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)  # 1: PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: the helper still ends at the end of its pipe
        return
    parent = multiprocessing.parent_process()
    if parent is not None and os.getppid() != parent.pid:  # the parent ended before the line above
        os._exit(1)


def _quiet_on_ctrl_c() -> None:
    """In a child: Ctrl-C (SIGINT to the whole process group) is the parent's to handle; the pool then
    ends its children (without this, each printed a KeyboardInterrupt traceback). SIGTERM, which the
    pool ends its children with, kills at once: a handler inherited from the parent (the command
    line's) runs only between bytecodes, and a child blocked in C never reached one."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _exit_on_sigterm(signum, frame):
    raise SystemExit(128 + signum)


def _pool(workers: int):
    return multiprocessing.get_context("fork").Pool(workers, initializer=_start_piece)


class Deferred:
    """A computation that needs nothing a map computes: run as one more piece
    of the first map_forked it is handed to, on a core that map's pieces would
    leave idle at their end, instead of alone beside an idle core; else
    where its result is first asked for. The same result either way."""

    def __init__(self, compute: Callable[[], T]):
        self.compute, self.value, self.done = compute, None, False

    def result(self):
        if not self.done:
            self.settle(self.compute())
        return self.value

    def settle(self, value) -> None:
        self.value, self.done = value, True


def map_forked(piece: Callable[[int], T], count: int, workers: int | None = None,
               beside: Deferred | None = None) -> list[T]:
    """[piece(0), ..., piece(count - 1)], computed by up to `workers` forked
    processes (None: one per available core). Results come back pickled.
    `beside`, if not yet done, is computed with them, handed out first
    (the pool hands pieces out in order: a piece started last ends the map late)."""
    global _piece
    if beside is not None and not beside.done:
        out = map_forked(lambda i: beside.compute() if i == 0 else piece(i - 1), count + 1, workers)
        beside.settle(out[0])
        return out[1:]
    workers = min(count, available_cores() if workers is None else workers)
    if workers <= 1 or not can_fork():
        return [piece(i) for i in range(count)]
    _piece = piece
    try:
        with _pool(workers) as pool:
            return pool.map(_run, range(count), chunksize=1)
    finally:
        _piece = None


class Inherited:
    """Stands for the function forked_map's children inherited: it pickles
    as nothing, so a solver can hand it to the map with each argument."""

    def __call__(self, *args):
        return _function(*args)


# A map that took this long one after the other is worth forking children for
# (a pool starts in tens of milliseconds; a fit's Jacobian on a recording
# against a torque sensor takes about 20 ms, without one over 100 ms).
WORTH_FORKING_S = 0.05


class _ForkedWhenWorthIt:
    """A map-like that runs its first map one after the other and, if that
    took WORTH_FORKING_S or longer, every later one in forked children."""

    def __init__(self, workers: int):
        self.workers, self.pool, self.first_took = workers, None, None

    def __call__(self, f: Callable, arguments) -> list:
        if self.first_took is None:
            started = time.perf_counter()
            out = [f(a) for a in arguments]
            self.first_took = time.perf_counter() - started
            return out
        if self.first_took < WORTH_FORKING_S:
            return [f(a) for a in arguments]
        if self.pool is None:
            self.pool = _pool(self.workers)
        return self.pool.map(f, list(arguments), chunksize=1)

    def close(self) -> None:
        if self.pool is not None:
            self.pool.terminate()
            self.pool.join()


@contextmanager
def forked_map(function: Callable, workers: int | None = None) -> Iterator[tuple[Callable, Callable | None]]:
    """(f, map): f evaluates `function` and pickles, map(f, arguments) is a
    map-like over up to `workers` forked children that inherited `function`
    (None: one per available core) once a map proves worth it. Where forking
    is not safe, or already lent (one at a time), f is `function` and map is
    None: one after the other."""
    global _function
    workers = available_cores() if workers is None else workers
    if workers <= 1 or not can_fork() or _function is not None:
        yield function, None
        return
    _function = function
    columns = _ForkedWhenWorthIt(workers)
    try:
        yield Inherited(), columns
    finally:
        columns.close()
        _function = None


# A helper's priority below the work it runs beside (nice increment): what
# it draws fills the cores the diagnosis leaves idle and takes a quarter of a
# busy core from the diagnosis's own pieces (the kernel's weights at +5);
# lower still, it would wait long for a core on a machine others load, while
# the diagnosis, finished, waits for its figures.
HELPER_NICENESS = 5


class Helper:
    """A process forked ahead of its work: it runs `prepare` while this one
    computes, then maps a function over pieces on request (map_forked, from
    its prepared state, at HELPER_NICENESS); pieces, function and results
    cross pickled. One request at a time: submit, then collect."""

    def __init__(self, process, connection):
        self.process, self.connection = process, connection
        self.request: tuple | None = None
        self.sent = False

    def submit(self, function: Callable[[T], object], pieces: list[T]) -> None:
        """Start [function(piece) for piece in pieces] in the helper; collect() returns it."""
        self.request = (function, pieces)
        try:
            self.connection.send(self.request)
            self.sent = True
        except OSError:  # it has ended: collect() maps them here
            self.sent = False

    def collect(self) -> list:
        """The submitted request's results (mapped here, should the helper have ended)."""
        function, pieces = self.request
        self.request = None
        try:
            if not self.sent:
                raise EOFError
            ok, value = self.connection.recv()
        except (EOFError, OSError):
            return map_forked(lambda i: function(pieces[i]), len(pieces))
        if not ok:
            raise RuntimeError(value)
        return value

    def map(self, function: Callable[[T], object], pieces: list[T]) -> list:
        """[function(piece) for piece in pieces], by the helper (from here, should it have ended)."""
        self.submit(function, pieces)
        return self.collect()

    @staticmethod
    def _serve(connection, prepare: Callable[[], None]) -> None:
        _die_with_parent()
        _quiet_on_ctrl_c()
        signal.signal(signal.SIGTERM, _exit_on_sigterm)  # its own children are ended on the way out
        os.nice(HELPER_NICENESS)
        prepare()
        while True:
            try:
                request = connection.recv()
            except EOFError:  # the parent is gone
                return
            if request is None:
                return
            function, pieces = request
            try:
                connection.send((True, map_forked(lambda i: function(pieces[i]), len(pieces))))
            except Exception as e:  # told to the parent, which raises it
                connection.send((False, f"{type(e).__name__}: {e}"))


@contextmanager
def helper(prepare: Callable[[], None]) -> Iterator[Helper | None]:
    """A Helper for the length of the block (None where forking is not
    safe); ended when the block ends, at once if it raised."""
    if not can_fork():
        yield None
        return
    context = multiprocessing.get_context("fork")
    ours, theirs = context.Pipe()
    process = context.Process(target=Helper._serve, args=(theirs, prepare), name="hdjoint helper")
    process.start()
    theirs.close()  # so the helper reads the end of the pipe once this process is gone
    try:
        yield Helper(process, ours)
    except BaseException:
        process.terminate()
        raise
    finally:
        try:
            ours.send(None)
        except OSError:  # it has already ended
            pass
        ours.close()
        process.join()
