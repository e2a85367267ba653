"""Pieces side by side in forked processes: the same results as one after
the other, errors passed on, and no fork where it is not safe."""
import multiprocessing
import os
import threading

from hdjoint.diagnosis import forked


def _pid_and_square(i):
    return os.getpid(), i * i


def _in_single_threaded_process(job):
    """job() in a forked process, where only one thread runs (the test
    session's Dask cluster keeps threads in this one): its result or error."""
    context = multiprocessing.get_context("fork")
    queue = context.Queue()

    def run():
        try:
            queue.put(("ok", os.getpid(), job()))
        except Exception as e:  # noqa: BLE001 (handed to the test)
            queue.put(("error", os.getpid(), repr(e)))
    child = context.Process(target=run)
    child.start()
    out = queue.get(timeout=120)
    child.join()
    return out


def test_results_in_order_and_from_other_processes():
    status, caller, out = _in_single_threaded_process(lambda: forked.map_forked(_pid_and_square, 6, workers=2))
    assert status == "ok"
    assert [v for _, v in out] == [i * i for i in range(6)]
    assert {pid for pid, _ in out} - {caller}, "no piece ran in a child"


def test_closures_over_unpicklable_state_run_in_children():
    # The diagnosis's pieces close over the prepared recording (never pickled).
    state = {"lock": threading.Lock(), "values": [3, 1, 4, 1, 5]}
    job = lambda: forked.map_forked(lambda i: (os.getpid(), state["values"][i] * 2), 5, workers=2)  # noqa: E731
    status, caller, out = _in_single_threaded_process(job)
    assert status == "ok" and [v for _, v in out] == [6, 2, 8, 2, 10]
    assert {pid for pid, _ in out} - {caller}


def test_an_error_in_a_piece_reaches_the_caller():
    def piece(i):
        if i == 3:
            raise ValueError("piece 3 failed")
        return i
    status, _, error = _in_single_threaded_process(lambda: forked.map_forked(piece, 5, workers=2))
    assert status == "error" and "piece 3 failed" in error


def test_no_fork_while_other_threads_run():
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        assert not forked.can_fork()
        out = forked.map_forked(_pid_and_square, 4, workers=2)
        assert {pid for pid, _ in out} == {os.getpid()}
    finally:
        stop.set()
        other.join()


def _inside_daemon(queue):
    queue.put((forked.can_fork(), forked.map_forked(lambda i: i + 1, 3, workers=2)))


def test_a_daemonic_process_runs_its_pieces_itself():
    # A Dask worker is daemonic: it may not have children.
    queue = multiprocessing.get_context("fork").Queue()
    child = multiprocessing.get_context("fork").Process(target=_inside_daemon, args=(queue,), daemon=True)
    child.start()
    can, out = queue.get(timeout=60)
    child.join()
    assert can is False and out == [1, 2, 3]


def _lent_jacobian(seconds_per_call: float = 0.03):
    """A least-squares fit whose residual function closes over unpicklable
    state (and takes `seconds_per_call`), with its Jacobian's columns by forked children and one after the
    other: for each, (solution, Jacobian, the other processes that evaluated it)."""
    import time
    import numpy as np
    from scipy.optimize import least_squares
    state = {"lock": threading.Lock(), "t": np.linspace(0.0, 1.0, 200)}
    evaluated_by = multiprocessing.get_context("fork").SimpleQueue()

    def residuals(z):
        evaluated_by.put(os.getpid())
        time.sleep(seconds_per_call)
        t = state["t"]
        return z[0] * np.exp(-z[1] * t) + z[2] * t - (2.0 * np.exp(-3.0 * t) + 0.5 * t)

    solutions = []
    for workers in (2, 1):
        with forked.forked_map(residuals, workers) as (function, columns):
            sol = least_squares(function, [1.0, 1.0, 0.0], diff_step=1e-6, x_scale="jac", workers=columns)
        pids = set()
        while not evaluated_by.empty():
            pids.add(evaluated_by.get())
        solutions.append((sol.x.tolist(), sol.jac.tolist(), sorted(pids - {os.getpid()})))
    return solutions


def test_a_fits_jacobian_by_forked_children_is_the_one_after_the_other():
    status, _, out = _in_single_threaded_process(_lent_jacobian)
    assert status == "ok"
    (x_side, jac_side, children), (x_serial, jac_serial, none) = out
    assert len(children) == 2 and not none
    assert x_side == x_serial and jac_side == jac_serial  # bit for bit


def test_a_quick_jacobian_is_not_worth_forking_for():
    # Three columns of a millisecond: a pool would cost more than it saves.
    status, _, out = _in_single_threaded_process(lambda: _lent_jacobian(seconds_per_call=0.001))
    assert status == "ok"
    (_, _, children), _ = out
    assert children == []


def test_no_lending_while_lent_nor_where_forking_is_unsafe():
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        with forked.forked_map(abs, 2) as (function, columns):
            assert function is abs and columns is None
    finally:
        stop.set()
        other.join()

    def nested():
        with forked.forked_map(abs, 2) as (_, outer):
            with forked.forked_map(abs, 2) as (inner_function, inner):
                return outer is not None, inner is None and inner_function is abs
    status, _, out = _in_single_threaded_process(nested)
    assert status == "ok" and out == (True, True)


_PREPARED = []  # what a helper's prepare leaves behind, read by its pieces


def _prepare():
    _PREPARED.append(os.getpid())


def _prepared_by_and_square(i):
    return _PREPARED[:], os.getpid(), i * i


def _helper_maps():
    with forked.helper(_prepare) as helper:
        out = helper.map(_prepared_by_and_square, [1, 2, 3, 4])
        helper_pid = helper.process.pid
        alive = helper.process.is_alive()
    return out, helper_pid, alive, helper.process.exitcode


def test_a_helper_prepares_once_then_maps_from_its_prepared_state():
    status, caller, (out, helper_pid, alive, exitcode) = _in_single_threaded_process(_helper_maps)
    assert status == "ok"
    assert [v for _, _, v in out] == [1, 4, 9, 16]
    assert all(prepared == [helper_pid] for prepared, _, _ in out)  # prepared in the helper, inherited
    assert {pid for _, pid, _ in out} - {caller, helper_pid}, "no piece ran in the helper's children"
    assert _PREPARED == [] and alive and exitcode == 0  # never prepared here; ended with the block


def _helper_that_failed():
    def fails():
        raise ImportError("no matplotlib here")
    with forked.helper(fails) as helper:
        helper.process.join()
        return helper.map(_pid_and_square, [1, 2])


def test_pieces_are_mapped_here_when_the_helper_has_ended():
    status, caller, out = _in_single_threaded_process(_helper_that_failed)
    assert status == "ok" and [v for _, v in out] == [1, 4]


def _helper_ended_by_an_error():
    try:
        with forked.helper(_prepare) as helper:
            raise KeyboardInterrupt
    except KeyboardInterrupt:
        return helper.process.exitcode


def test_a_block_that_raises_ends_its_helper_at_once():
    status, _, exitcode = _in_single_threaded_process(_helper_ended_by_an_error)
    assert status == "ok" and exitcode is not None and exitcode != 0


def test_no_helper_where_forking_is_unsafe():
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        with forked.helper(_prepare) as helper:
            assert helper is None
    finally:
        stop.set()
        other.join()


def _pid_then_sleep(path):
    with open(path, "a") as f:
        f.write(f"{os.getpid()}\n")
    import time
    time.sleep(60)


def _helper_interrupted_while_mapping(folder):
    import time
    try:
        with forked.helper(_prepare) as helper:
            helper.submit(_pid_then_sleep, [folder / "a", folder / "b"])
            while not ((folder / "a").exists() and (folder / "b").exists()):
                time.sleep(0.05)
            raise KeyboardInterrupt
    except KeyboardInterrupt:
        return [int(p.read_text()) for p in (folder / "a", folder / "b")]


def test_a_helper_ended_while_mapping_ends_its_children_too(tmp_path):
    import time
    status, _, pids = _in_single_threaded_process(lambda: _helper_interrupted_while_mapping(tmp_path))
    assert status == "ok"
    deadline = time.monotonic() + 10
    alive = pids
    while alive and time.monotonic() < deadline:
        time.sleep(0.1)
        alive = [pid for pid in alive if _alive(pid)]
    assert not alive, "the helper's children outlived it"


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"  # a zombie has ended
    except FileNotFoundError:
        return False


def test_a_deferred_computation_runs_as_the_first_piece_of_a_map_and_only_once():
    """forked.Deferred: handed to a map, it runs there (in a child, first) and
    its result comes back with the map's; asked for again, it is not rerun."""
    def job():
        runs = []
        deferred = forked.Deferred(lambda: runs.append(1) or (os.getpid(), "located"))
        out = forked.map_forked(_pid_and_square, 4, workers=2, beside=deferred)
        again = forked.map_forked(_pid_and_square, 2, workers=2, beside=deferred)  # done: not a piece again
        return out, again, deferred.result(), runs
    status, caller, (out, again, (pid, value), runs) = _in_single_threaded_process(job)
    assert status == "ok"
    assert [v for _, v in out] == [0, 1, 4, 9] and [v for _, v in again] == [0, 1]
    assert value == "located" and pid != caller, "the deferred computation did not run in a child"
    assert runs == [], "it ran in the caller as well"


def test_a_deferred_computation_no_map_took_runs_where_it_is_asked_for():
    deferred = forked.Deferred(lambda: os.getpid())
    assert deferred.result() == os.getpid() and deferred.done


def test_only_the_process_of_the_serial_stages_splits_a_run_over_threads():
    """forked.threads_here: a forked piece's pool already fills the cores."""
    def job():
        return forked.threads_here(), forked.map_forked(lambda i: forked.threads_here(), 2, workers=2)
    status, _, (here, pieces) = _in_single_threaded_process(job)
    assert status == "ok" and here == forked.available_cores() and pieces == [1, 1]
