"""Figures of a diagnosis. Each takes the arrays it shows (the report
module gathers them) and an Axes, and returns the Axes. matplotlib is
imported only where a figure is drawn (png_uri)."""
from __future__ import annotations

import numpy as np

from hdjoint.diagnosis.model.structure import harmonic_amplitude
from hdjoint.io.figures import bare_figure, envelope, png_data_uri


def png_uri(job: tuple) -> str:
    """A figure as a PNG data URI: job is (plot, its arguments after the Axes, size)."""
    plot, args, size = job
    fig = bare_figure(size)
    plot(fig.add_subplot(), *args)
    return png_data_uri(fig)


def _title(ax, text):
    ax.set_title(text)
    return ax


def prepare_drawing() -> None:
    """What a process's first figure would wait for: matplotlib imported, a font loaded."""
    png_uri((_title, ("warm-up",), (1, 1)))

# Where the two models agree the corrected curve lies on the nominal one: drawn dashed and thinner on top, so
# the nominal curve still shows beneath it.
NOMINAL_STYLE = {"color": "tab:red", "ls": "-", "lw": 2.0}
CORRECTED_STYLE = {"color": "tab:blue", "ls": "--", "lw": 1.0}


def residual_over_time(ax, t, before, after, segments, title):
    """Both residuals over time. A channel the findings leave unchanged is one curve, labelled so:
    the corrected one drawn over an equal nominal one hid it (a noisy trace shows no dashes)."""
    if np.array_equal(before, after, equal_nan=True):
        ax.plot(*envelope(t, before), lw=0.4, color="tab:red", alpha=0.7,
                label="calibrated nominal model = corrected model (unchanged here)")
    else:
        ax.plot(*envelope(t, before), lw=0.4, color="tab:red", alpha=0.7, label="calibrated nominal model")
        ax.plot(*envelope(t, after), lw=0.4, color="tab:blue", alpha=0.8, label="corrected model")
    for a, b in segments:
        ax.axvspan(a, b, color="orange", alpha=0.15, lw=0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("residual (N.m)")
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper right", fontsize=7)
    return ax


def residual_vs_feature(ax, x, before, after, xlabel, bins=30):
    """Mean residual per bin of a regime variable (speed, torque...)."""
    ok = np.isfinite(x) & np.isfinite(before) & np.isfinite(after)
    edges = np.unique(np.percentile(x[ok], np.linspace(0, 100, bins + 1))) if ok.any() else np.array([])
    if len(edges) < 2:  # the channel compares nothing here (the motor at rest throughout), or at one value
        ax.text(0.5, 0.5, "no samples compared over a range of it", ha="center", va="center", transform=ax.transAxes)
        ax.set_xlabel(xlabel)
        return ax
    centres = 0.5 * (edges[1:] + edges[:-1])
    idx = np.clip(np.searchsorted(edges, x[ok], side="right") - 1, 0, len(edges) - 2)
    for y, style, label in ((before[ok], NOMINAL_STYLE, "calibrated nominal"),
                            (after[ok], CORRECTED_STYLE, "corrected")):
        mean = np.bincount(idx, weights=y, minlength=len(centres)) / np.maximum(
            np.bincount(idx, minlength=len(centres)), 1)
        ax.plot(centres, mean, marker=".", label=label, **style)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("mean residual (N.m)")
    ax.legend(fontsize=7)
    return ax


def order_amplitudes(angle, curves, orders) -> list[np.ndarray]:
    """Each curve's amplitude at each order of `angle` (least squares on its
    finite samples, with a constant); curves finite on the same samples share
    each order's basis and solve (the residuals before and after mostly do)."""
    out: list = [None] * len(curves)
    finite = [np.isfinite(y) for y in curves]
    for i, ok in enumerate(finite):
        group = [j for j in range(i, len(curves)) if out[j] is None and np.array_equal(finite[j], ok)]
        if not group:
            continue
        a, ys = angle[ok], np.column_stack([curves[j][ok] for j in group])
        amps = [harmonic_amplitude(a, ys, k) for k in orders]
        for column, j in enumerate(group):
            out[j] = np.array([amp[column] for amp in amps])
    return out


def order_spectrum(ax, angle, before, after, orders, angle_name):
    """Amplitude of the residual at each order of an angle (least squares per order)."""
    amplitudes = order_amplitudes(angle, (before, after), orders)
    for amps, style, label in zip(amplitudes, (NOMINAL_STYLE, CORRECTED_STYLE), ("calibrated nominal", "corrected")):
        ax.plot(orders, amps, marker="o", ms=3, label=label, **style)
    ax.set_xlabel(f"order of {angle_name} (cycles per revolution)")
    ax.set_ylabel("amplitude (N.m)")
    ax.legend(fontsize=7)
    return ax


def torque_torsion_loop(ax, torsion, torque_ref, torque_model, max_points=20000):
    """Reference torque against elastic torsion: hysteresis and backlash show as loops and flats."""
    step = max(1, len(torsion) // max_points)
    ax.plot(torsion[::step] * 1e3, torque_ref[::step], ".", ms=1, color="k", alpha=0.3, label="reference torque")
    ax.plot(torsion[::step] * 1e3, torque_model[::step], ".", ms=1, color="tab:blue", alpha=0.3,
            label="corrected model")
    ax.set_xlabel("flexspline torsion (mrad)")
    ax.set_ylabel("torque (N.m)")
    ax.legend(fontsize=7, markerscale=8)
    return ax


def rms_bars(ax, labels, before, after, ylabel="RMS (N.m)"):
    x = np.arange(len(labels))
    ax.bar(x - 0.2, before, 0.4, color="tab:red", label="before")
    ax.bar(x + 0.2, after, 0.4, color="tab:blue", label="after")
    ax.set_xticks(x, labels, rotation=15, ha="right", fontsize=7)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7)
    return ax
