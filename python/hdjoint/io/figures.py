"""Figures. Plot functions take an Axes or make a figure, return the figure,
and never compute anything the caller could not inspect. pyplot is imported
only by what needs its figure registry: a report draws on bare Figures."""
from __future__ import annotations

import io
import os
import base64

import numpy as np


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def torque_comparison(time, estimates: dict, title: str = ""):
    """Estimates and the reference over time (top) and their errors (bottom)."""
    fig, (top, bottom) = _pyplot().subplots(2, 1, figsize=(10, 6), sharex=True, constrained_layout=True)
    reference = estimates["reference"]
    top.plot(time, reference, color="k", lw=1.0, label="true torque")
    for name, est in estimates.items():
        if name == "reference":
            continue
        top.plot(time, est, lw=0.6, label=name)
        bottom.plot(time, np.asarray(est) - reference, lw=0.5, label=name)
    top.set_ylabel("joint torque (N.m)")
    top.legend(loc="upper left", fontsize=8)
    bottom.set_ylabel("error (N.m)")
    bottom.set_xlabel("time (s)")
    bottom.legend(loc="upper left", fontsize=8)
    if title:
        top.set_title(title)
    return fig


# Buckets a trace is reduced to before drawing: two per pixel column of a report's widest axes (900 px).
ENVELOPE_BUCKETS = 1800


def envelope(x: np.ndarray, y: np.ndarray, buckets: int = ENVELOPE_BUCKETS) -> tuple[np.ndarray, np.ndarray]:
    """A long trace as the lowest and the highest sample of each of `buckets`
    equal runs of it, in time order: drawn as a line it covers the pixels the
    whole trace covers, at a fraction of the drawing's cost (an hour at 1 kHz
    is 3.6 million points). NaN stays a gap; a short trace is returned as is."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if len(y) <= 2 * buckets:
        return x, y
    run = -(-len(y) // buckets)
    count = -(-len(y) // run)  # every run holds a sample of the trace
    runs = np.full(count * run, np.nan)
    runs[:len(y)] = y
    runs = runs.reshape(count, run)
    nan = np.isnan(runs)
    low = np.where(nan, np.inf, runs).argmin(axis=1)  # a run of NaN only: its first sample, NaN, a gap
    high = np.where(nan, -np.inf, runs).argmax(axis=1)
    index = (np.arange(count)[:, None] * run + np.sort(np.column_stack([low, high]), axis=1)).ravel()
    return x[index], y[index]


def save(fig, path) -> None:
    """FIG as an image at PATH (its format from the suffix), written whole (io.outputs.write_whole)."""
    from hdjoint.io.outputs import write_whole
    buf = io.BytesIO()
    fig.savefig(buf, format=os.path.splitext(os.fspath(path))[1].lstrip(".") or "png", dpi=110)
    _pyplot().close(fig)
    write_whole(path, buf.getvalue())


def png_data_uri(fig) -> str:
    """PNG as a data: URI, for self-contained HTML reports."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def to_data_uri(fig) -> str:
    """png_data_uri of a pyplot figure, closed."""
    uri = png_data_uri(fig)
    _pyplot().close(fig)
    return uri


def bare_figure(size):
    """A Figure with constrained layout outside pyplot (no registry to close it from)."""
    from matplotlib.figure import Figure
    return Figure(figsize=size, constrained_layout=True)
