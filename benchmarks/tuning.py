"""Tuning an estimator's noise settings on a bench recording with a torque sensor.

The joint-state filter's defaults come from the sensors (quantisation of the
encoders, current noise) and from one tuning run (README); a joint whose
friction, load changes or sensors differ is tuned the same way: record a few
tens of seconds with a torque sensor (`tau_sensor`), then

    best, table = tune(recording, params, JOINT_FILTER_GRID, "tau_hat")

picks the grid point with the smallest RMS error of `tau_hat` against the
sensor. The grid is searched with the native batch path (a 20 s recording
costs about 10 ms a point). Tune on one recording, judge on others.
"""
from __future__ import annotations

import itertools

import numpy as np

from hdjoint import _core
from hdjoint.estimation.metrics import error_figures
from hdjoint.io.parameters import for_estimator

# Settings searched for the joint-state filter (tau_hat) and for the paper's UKF (tau_ukf).
JOINT_FILTER_GRID = {
    "jsf_q_load": (0.001, 0.003, 0.01, 0.03),
    "jsf_q_load_rate": (0.0, 0.1, 0.3, 1.0, 3.0),
    "jsf_q_motor": (0.0, 0.001, 0.003),
    "jsf_q_torque": (1e-4, 3e-4, 1e-3),
}
PAPER_UKF_GRID = {
    "ukf_q_tau": (0.005, 0.01, 0.02, 0.05, 0.1, 0.2),
    "ukf_r_torsion": (2e-6, 6e-6, 2e-5, 6e-5, 2e-4),
    "ukf_r_omega": (0.3, 0.9, 3.0),
}


def tune(recording, params: dict[str, float], grid: dict[str, tuple], output: str = "tau_hat",
         reference=None) -> tuple[dict[str, float], list[tuple[dict[str, float], float]]]:
    """Grid search: the settings of `grid` minimising the RMS error of `output`
    against `reference` (default: the recording's tau_sensor).

    Returns (params with the best settings, [(settings, rms), ...] for every point)."""
    reference = recording.tau_sensor if reference is None else reference
    if reference is None:
        raise ValueError("tuning needs a reference torque: a recording with tau_sensor")
    reference = np.asarray(reference, float)
    base = for_estimator(params)
    names = list(grid)
    results = []
    for values in itertools.product(*(grid[n] for n in names)):
        settings = dict(zip(names, values))
        est = _core.run_estimator({**base, **settings}, recording.time, recording.i_m, recording.theta_m,
                                  recording.theta_l)
        results.append((settings, error_figures(est[output], reference).rms))
    best = min(results, key=lambda r: r[1])[0]
    return {**params, **best}, results
