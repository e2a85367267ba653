"""The corrected model on recordings the diagnosis never saw.

Held-out folds show that a finding predicts the part of the recording it
was not fitted on; another recording of the same joint (another day, another
trajectory) is the stronger test. For each one the residual channels are
evaluated with the nominal, the calibrated (no findings) and the corrected
parameter sets, each with its encoder offset a0 placed on that recording
(the encoders' zeros are arbitrary per recording), and, where it has a torque sensor, the torque estimators'
error with the nominal and the corrected sets.
"""
from __future__ import annotations

from .channels import Prepared
from .diagnosis import Evaluator, channels_for, check_recording, place_offset
from .findings import estimator_comparison
from .metrics import error_figures
from .recording import Recording
from .signals import kinematics


class _Source:
    """What estimator_comparison needs of a diagnosis, for another recording."""

    def __init__(self, rec: Recording, nominal: dict):
        self.source = rec
        self.nominal = nominal
        self.has_sensor = rec.tau_sensor is not None


def validate(rec: Recording, nominal: dict, calibrated: dict, corrected: dict) -> dict:
    """Residual RMS / max per channel with each parameter set, on `rec`."""
    check_recording(rec)
    prep = Prepared(rec, kinematics(rec), rec.time - rec.time[0])
    channels = channels_for(rec.tau_sensor is not None)
    evaluator = Evaluator(prep, channels)
    sets = {label: place_offset(rec, p, rec.tau_sensor if rec.tau_sensor is not None else
                                evaluator.estimate("motor", p))
            for label, p in (("nominal", nominal), ("calibrated", calibrated), ("corrected", corrected))}
    figures = {}
    for c in channels:
        row = {}
        for label, p in sets.items():
            f = error_figures(evaluator.residual(c, p)[prep.kin.valid], 0.0)
            row[label] = {"rms": round(f.rms, 5), "max": round(f.max, 5)}
        figures[c.name] = row
    return {"path": rec.path, "duration": round(rec.duration, 3), "channels": figures,
            "estimator": estimator_comparison(_Source(rec, sets["nominal"]), sets["corrected"])}


def summary_line(entry: dict) -> str:
    parts = [f"{name} {row['calibrated']['rms']:.4f} -> {row['corrected']['rms']:.4f}"
             for name, row in entry["channels"].items()]
    return f"{entry['path']}: residual RMS (calibrated -> corrected, N.m) " + "; ".join(parts)

