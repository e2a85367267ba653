"""Where another recording leaves the operating range a diagnosis was fitted on.

A parameter fitted on a recording is only known where that recording went:
friction at the speeds it reached, stiffness at the torques it applied,
gravity at the link angles it visited. A recording of the same joint that
goes elsewhere tests the model's form there, not its fit: a residual that
grows there is extrapolation, and it must read as such.

The fitted range is the central 99 % of the fitted recording's analysed
samples (so a few spikes do not widen it; 1 % of the fitted recording itself
lies outside by construction), and a quantity is flagged when more than
EXTRAPOLATED_SHARE of the other recording's samples lie outside it.
"""
from __future__ import annotations

import numpy as np

from hdjoint.diagnosis.model.torque_estimates import Prepared

CENTRAL = 99.0            # percent of the fitted samples that make its range
EXTRAPOLATED_SHARE = 0.05  # five times the fitted recording's own share outside

# quantity, unit, how to read it from a prepared recording (on its analysed samples)
QUANTITIES = (
    ("motor speed", "rad/s", lambda prep: prep.kin.omega_m),
    ("motor current", "A", lambda prep: prep.rec.i_m),
    ("link angle", "rad", lambda prep: prep.rec.theta_l),
)


def _analysed(prep: Prepared, read) -> np.ndarray:
    x = np.asarray(read(prep), dtype=float)[prep.kin.valid]
    return x[np.isfinite(x)]


def beyond_fitted_range(fitted: Prepared, other: Prepared) -> list[dict]:
    """Per quantity: the fitted recording's range, the share of `other`'s
    samples outside it, and a sentence when that share is large."""
    tail = (100.0 - CENTRAL) / 2
    out = []
    for name, unit, read in QUANTITIES:
        seen, there = _analysed(fitted, read), _analysed(other, read)
        if not len(seen) or not len(there):
            continue
        lo, hi = np.percentile(seen, [tail, 100.0 - tail])
        outside = float(np.mean((there < lo) | (there > hi)))
        row = {"quantity": name, "unit": unit, "fitted": [float(lo), float(hi)],
               "other": [float(there.min()), float(there.max())], "outside": round(outside, 4)}
        if outside > EXTRAPOLATED_SHARE:
            row["warning"] = (f"{outside:.0%} of its samples have a {name} outside the fitted range "
                              f"[{lo:.3g}, {hi:.3g}] {unit} (this recording spans "
                              f"[{there.min():.3g}, {there.max():.3g}] {unit})")
        out.append(row)
    return out
