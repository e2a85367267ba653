"""The corrected model on recordings the diagnosis never saw.

Held-out folds show that a finding predicts the part of the recording it
was not fitted on; another recording of the same joint (another day, another
trajectory) is the stronger test. For each one the residual channels are
evaluated with the nominal, the calibrated (no findings) and the corrected
parameter sets, each with the two properties of a recording rather than of
the joint placed on that recording: its encoder offset a0 (the encoders'
zeros are arbitrary per recording) and its current alignment (how its logger
stamps the current, current_alignment.py). Where it has a torque sensor, the
torque estimators' error with the nominal and the corrected sets too.

A better fit there only says the model holds where the other recording
goes: where it leaves the speeds, currents or link angles the diagnosis was
fitted on, the corrected model is extrapolated (operating_range.py).
"""
from __future__ import annotations

import numpy as np

from hdjoint.diagnosis.model.torque_estimates import Prepared
from hdjoint.diagnosis.model.current_alignment import fit_shift
from hdjoint.diagnosis.model.residual_channels import Evaluator, channels_for
from hdjoint.diagnosis.model.prepare import check_recording, place_offset
from hdjoint.diagnosis.verdict.findings import estimator_comparison
from hdjoint.estimation.metrics import error_figures
from hdjoint.diagnosis.model.operating_range import beyond_fitted_range
from hdjoint.io.recording import Recording
from hdjoint.diagnosis.model.kinematics import kinematics


class _Source:
    """What estimator_comparison needs of a diagnosis, for another recording."""

    def __init__(self, rec: Recording, nominal: dict):
        self.source = rec
        self.nominal = nominal
        self.has_sensor = rec.tau_sensor is not None


def _align(evaluator: Evaluator, p: dict) -> float:
    """The current shift that best fits `rec`'s motor channels at `p` (0 without one)."""
    prep = evaluator.prep
    motor = [c for c in evaluator.channels if "motor" in c.parts()]
    if not motor:
        return 0.0
    valid = prep.kin.valid

    def residual(shift):
        prep.current_shift = shift
        return np.concatenate([evaluator.residual(c, p)[valid] for c in motor])

    return fit_shift(residual, float(np.median(np.diff(prep.rec.time))))[0]


def validate(rec: Recording, nominal: dict, calibrated: dict, corrected: dict,
             fitted_on: Prepared | None = None) -> dict:
    """Residual RMS / max per channel with each parameter set, on `rec`;
    with `fitted_on` (the diagnosed recording), how far `rec` leaves its operating range."""
    check_recording(rec)
    prep = Prepared(rec, kinematics(rec), rec.time - rec.time[0])
    channels = channels_for(rec.tau_sensor is not None)
    evaluator = Evaluator(prep, channels)
    sets, shifts = {}, {}
    for label, p in (("nominal", nominal), ("calibrated", calibrated), ("corrected", corrected)):
        prep.current_shift = 0.0
        placed = place_offset(rec, p, rec.tau_sensor if rec.tau_sensor is not None else evaluator.estimate("motor", p))
        shifts[label] = _align(evaluator, placed)
        sets[label] = placed
    figures = {}
    for c in channels:
        row = {}
        for label, p in sets.items():
            prep.current_shift = shifts[label]
            f = error_figures(evaluator.residual(c, p)[prep.kin.valid], 0.0)
            row[label] = {"rms": round(f.rms, 5), "max": round(f.max, 5)}
        figures[c.name] = row
    entry = {"path": rec.path, "duration": round(rec.duration, 3), "channels": figures,
             "current_alignment": {label: round(s, 7) for label, s in shifts.items()},
             "estimator": estimator_comparison(_Source(rec, sets["nominal"]), sets["corrected"])}
    if fitted_on is not None:
        entry["extrapolation"] = beyond_fitted_range(fitted_on, prep)
    return entry


def summary_line(entry: dict) -> str:
    parts = [f"{name} {row['calibrated']['rms']:.4f} -> {row['corrected']['rms']:.4f}"
             for name, row in entry["channels"].items()]
    line = f"{entry['path']}: residual RMS (calibrated -> corrected, N.m) " + "; ".join(parts)
    warnings = [q["warning"] for q in entry.get("extrapolation", []) if q.get("warning")]
    return line + "".join(f"\n    extrapolated: {w}" for w in warnings)
