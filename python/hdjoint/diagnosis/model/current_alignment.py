"""Where a recording's current sits against its encoder samples.

A digital drive logs the current in one of two ways: the value sampled at
the encoders' instant, or the command it holds over the sample period that
follows its time stamp (a zero-order hold; the independent truth and the
project's own plant both log that one). A held current i_k acts from t_k to
t_k+1, so the encoders' acceleration at t_k, smoothed symmetrically, matches
(i_k-1 + i_k)/2: the logged current read half a sample earlier. Taken as
sampled, the motor equation then carries N*Kt*Ts/2*di/dt, which on a chirp
or a constant-speed run with current steps reads as unexplained structure.

Which convention a logger follows is not in the recording, so it is
calibrated: a shift in [-Ts/2, 0] of the current (i_delay's sense: the
current at t is the logged one at t + shift), fitted once on the motor
channels after the first calibration pass. Anything beyond it is a delay
of the current (the `time_delay` effect, i_delay >= 0, tested on top).

Within one sample the charge the motor equation differentiates
(channels.current_charge) is quadratic in the shift, so the residual is
nearly linear in it: one secant step between 0 and -Ts/2 is the
least-squares optimum up to the current's change within a sample, and its
curvature the interval."""
from __future__ import annotations

import math

import numpy as np

from hdjoint.diagnosis.rules import INTERVAL_Z


def fit_shift(residual, step: float) -> tuple[float, float]:
    """The least-squares shift in [-step/2, 0] of `residual(shift)` (a vector,
    linear in the shift within one sample) and the curvature of its sum of squares."""
    held = -0.5 * step
    r0, r1 = residual(0.0), residual(held)
    finite = np.isfinite(r0) & np.isfinite(r1)  # NaN where the torsion is singular
    r0, slope = r0[finite], (r1[finite] - r0[finite]) / held
    curvature = float(slope @ slope)
    estimate = float(np.clip(-(r0 @ slope) / curvature, held, 0.0)) if curvature > 0 else 0.0
    return estimate, curvature


def align_current(diag, p: dict) -> dict | None:
    """Fit the recording's current shift on the motor channels at parameters
    `p`, leave it in diag.prep.current_shift, and describe it (None: no motor channel)."""
    channels = diag.channels_of("motor")
    if not channels:
        return None
    step = float(np.median(np.diff(diag.rec.time)))
    held = -0.5 * step

    def residual(shift):
        diag.prep.current_shift = shift
        return diag.normalised(p, channels, diag.fit_index)

    estimate, curvature = fit_shift(residual, step)
    diag.prep.current_shift = estimate
    # Laplace on the data term (weighted as the calibration's), flat within the bounds.
    std = 1.0 / math.sqrt(diag.data_weight * curvature) if curvature > 0 else math.inf
    half = INTERVAL_Z * std
    return {"estimate": estimate, "lo": float(max(estimate - half, held)), "hi": float(min(estimate + half, 0.0)),
            "bounds": [held, 0.0], "unit": "s",
            "meaning": "the current at an encoder sample is the logged one read this much later "
                       "(0: sampled with the encoders; -Ts/2: held over the following sample)"}
