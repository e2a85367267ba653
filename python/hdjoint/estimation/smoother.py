"""The RTS smoother of `hdjoint estimate --smooth` over a recording too long
to hold, in two passes. Forward, the rows' causal outputs and the joint-state
filter's samples (its records, ~1 kB each: what the backward pass needs) go
to temporary files; backward, the records are read back a block at a time,
the last first, and smoothed; last, the rows are read back in order and
written with their smoothed torque. Memory holds two doubles a sample (the
smoothed torque and its deviation) and a block; the same numbers as the
smoother on the whole recording in memory (_core.run_estimator(smooth=True))."""
from __future__ import annotations

import contextlib
import errno
import os
import tempfile

import numpy as np

from hdjoint.io.outputs import printable, temp_dir

BACKWARD_BLOCK = 8192  # records read at a time (8 MB)
SMOOTH_COLUMNS = ("tau_smooth", "tau_smooth_std")


class SmoothedRows:
    """Collects the forward pass (`add`, `end_segment`), then `rows()` yields the rows in blocks with
    tau_smooth and tau_smooth_std: the smoothed torque of the last filter sample each row's step ran,
    the causal tau_hat and tau_hat_std before the filter starts."""

    def __init__(self, params: dict, outputs):
        from hdjoint import _core
        self.params, self.outputs = params, list(outputs)
        self.record_values = _core.RECORD_VALUES
        # Named with the pid: a run killed outright leaves it, and the next run removes it.
        with self._temporary_space():
            self._dir = temp_dir("hdjoint-smooth")
        self._rows = self._records = None
        try:
            with self._temporary_space():
                self._rows = open(os.path.join(self._dir.name, "rows.f8"), "w+b")
                self._records = open(os.path.join(self._dir.name, "records.f8"), "w+b")
        except BaseException:
            self.close()
            raise
        # Per row: time, outputs, last_record (global), sensor (NaN without one).
        self._width = 1 + len(self.outputs) + 2
        self._segments = [0]  # the first record of each segment, then the total
        self._records_written = 0

    def add(self, time, outputs: dict, sensor=None) -> None:
        offset = self._segments[-1]
        local = np.asarray(outputs["last_record"])
        table = np.column_stack([time, *(outputs[name] for name in self.outputs),
                                 np.where(local >= 0, local + offset, -1.0),
                                 sensor if sensor is not None else np.full(len(time), np.nan)])
        records = np.asarray(outputs["records"], dtype=np.float64)
        with self._temporary_space():
            table.astype(np.float64).tofile(self._rows)
            records.tofile(self._records)
        self._records_written += len(records)

    @contextlib.contextmanager
    def _temporary_space(self):
        """A write into the temporary folder that fails (numpy's short write says only "N requested and M
        written") told plainly: the folder is full, named, with what it takes."""
        try:
            yield
        except OSError as e:
            folder = tempfile.gettempdir()
            if e.errno in (None, errno.ENOSPC, errno.EDQUOT):
                raise OSError(errno.ENOSPC, f"the temporary folder {printable(folder)} is full: --smooth keeps about "
                                            f"{8 * self.record_values // 1000} kB a sample there for its backward "
                                            "pass; free room there or set TMPDIR to a folder with room") from None
            raise OSError(e.errno, f"the temporary folder {printable(folder)}: {e.strerror}") from None

    def end_segment(self) -> None:
        self._segments.append(self._records_written)

    def _backward(self) -> tuple[np.ndarray, np.ndarray]:
        from hdjoint import _core
        with self._temporary_space():
            self._records.flush()
        n = self._records_written
        tau, tau_std = np.empty(n), np.empty(n)
        row_bytes = 8 * self.record_values
        bounds = sorted(set(self._segments + [n]))
        for first, end in zip(bounds[:-1], bounds[1:]):
            smoother = _core.RtsSmoother(self.params)
            for stop in range(end, first, -BACKWARD_BLOCK):
                start = max(first, stop - BACKWARD_BLOCK)
                self._records.seek(start * row_bytes)
                block = np.fromfile(self._records, np.float64, (stop - start) * self.record_values)
                smoothed = smoother.run(block.reshape(stop - start, self.record_values))
                tau[start:stop], tau_std[start:stop] = smoothed["tau_smooth"], smoothed["tau_smooth_std"]
        return tau, tau_std

    def rows(self, block_rows: int):
        """(time, {output and smoothed column: values}, sensor (NaN without one)) a block at a time."""
        tau, tau_std = self._backward()
        with self._temporary_space():
            self._rows.flush()
        self._rows.seek(0)
        hat, hat_std = self.outputs.index("tau_hat"), self.outputs.index("tau_hat_std")
        while True:
            table = np.fromfile(self._rows, np.float64, block_rows * self._width)
            if table.size == 0:
                return
            table = table.reshape(-1, self._width)
            record = table[:, -2].astype(np.int64)
            found = record >= 0
            columns = {name: table[:, 1 + k] for k, name in enumerate(self.outputs)}
            columns["tau_smooth"] = np.where(found, tau[np.where(found, record, 0)], table[:, 1 + hat])
            columns["tau_smooth_std"] = np.where(found, tau_std[np.where(found, record, 0)], table[:, 1 + hat_std])
            yield table[:, 0], columns, table[:, -1]

    def close(self) -> None:
        try:
            for f in (self._rows, self._records):
                if f is not None:
                    try:
                        f.close()  # flushes: on a full folder this fails too, and the files go all the same
                    except OSError:
                        pass
        finally:
            self._dir.cleanup()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
