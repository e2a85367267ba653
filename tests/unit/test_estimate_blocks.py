"""`hdjoint estimate` a block at a time (issue 12: memory <= 2x the file for
every path): the core's EstimatorStream carries the estimator across blocks,
the RTS smoother's backward pass reads its records back in reverse blocks.
Blocks must not change a single number."""
from __future__ import annotations

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.jobs.estimate import Options, estimate_to_file
from hdjoint.io.recording import read_recording, write_recording

from cli_helpers import rec_csv, simulated  # noqa: F401 (fixtures)

BLOCK_SIZES = (1, 2, 7, 300, 1000)  # uneven, down to one row a block


@pytest.fixture(scope="module")
def rows(simulated):
    rec = read_recording(simulated)
    return rec, parameters.for_estimator({**parameters.defaults(), "Ts": 1e-3})


def in_blocks(rec, sizes):
    """(start, stop) of consecutive blocks of the given sizes, cycling, over the whole recording."""
    start, k = 0, 0
    while start < len(rec):
        stop = min(start + sizes[k % len(sizes)], len(rec))
        yield start, stop
        start, k = stop, k + 1


def test_the_stream_in_blocks_gives_the_whole_runs_numbers(rows):
    rec, params = rows
    whole = _core.run_estimator(params, rec.time, rec.i_m, rec.theta_m, rec.theta_l)
    stream = _core.EstimatorStream(params, float(rec.time[0]))
    parts = []
    for start, stop in in_blocks(rec, BLOCK_SIZES):
        end = rec.time[stop] if stop < len(rec) else rec.time[-1] + params["Ts"]
        parts.append(stream.run(rec.time[start:stop], rec.i_m[start:stop], rec.theta_m[start:stop],
                                rec.theta_l[start:stop], float(end)))
    assert set(parts[0]) == set(whole)
    for name, values in whole.items():
        np.testing.assert_array_equal(np.concatenate([p[name] for p in parts]), values, err_msg=name)


def test_the_smoother_over_reverse_blocks_of_records_gives_the_in_memory_smoother(rows):
    rec, params = rows
    whole = _core.run_estimator(params, rec.time, rec.i_m, rec.theta_m, rec.theta_l, smooth=True)
    stream = _core.EstimatorStream(params, float(rec.time[0]), keep_records=True)
    out = stream.run(rec.time, rec.i_m, rec.theta_m, rec.theta_l, float(rec.time[-1] + params["Ts"]))
    records = out["records"]
    assert records.shape == (int(out["last_record"][-1]) + 1, _core.RECORD_VALUES)
    smoother = _core.RtsSmoother(params)
    tau, tau_std = np.empty(len(records)), np.empty(len(records))
    bounds = list(in_blocks(records, (13, 400, 1)))
    for start, stop in reversed(bounds):
        block = smoother.run(np.ascontiguousarray(records[start:stop]))
        tau[start:stop], tau_std[start:stop] = block["tau_smooth"], block["tau_smooth_std"]
    index = out["last_record"].astype(int)
    started = index >= 0
    np.testing.assert_array_equal(tau[index[started]], whole["tau_smooth"][started])
    np.testing.assert_array_equal(tau_std[index[started]], whole["tau_smooth_std"][started])


def test_the_smoother_refuses_records_of_another_width(rows):
    _, params = rows
    with pytest.raises(ValueError, match=f"{_core.RECORD_VALUES} columns"):
        _core.RtsSmoother(params).run(np.zeros((3, 5)))


@pytest.mark.parametrize("engine, smooth", [("batch", False), ("batch", True), ("fmu", True), ("fmu", False)])
def test_estimate_in_small_blocks_writes_the_same_file(rec_csv, tmp_path, engine, smooth):
    # A gap split in the middle: the smoother restarts with the segment too.
    rec = read_recording(rec_csv)
    rec.time[1200:] += 1.0
    write_recording(rec_csv, rec)
    written = {}
    for block_rows in (100_000, 333):
        out = tmp_path / f"{block_rows}.csv"
        estimate_to_file(Options(str(rec_csv), str(out), engine=engine, smooth=smooth, split_gaps=True,
                                 block_rows=block_rows))
        written[block_rows] = out.read_text()
    assert written[333] == written[100_000]
    assert len(written[333].splitlines()) == len(rec) + 1
