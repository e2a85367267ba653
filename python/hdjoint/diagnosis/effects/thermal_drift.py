"""The motor warming up over the run: its torque constant (magnets) or its
friction (lubricant). Both forms in one fit; which one carries the drift is
read from their fitted sizes and intervals."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, Size, TruthDraw


class ThermalDrift(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.form.thermal = str(draw.rng.choice(["kt", "friction"]))
        draw.truth.update(warmup_gain=(-0.04 if draw.form.thermal == "kt" else -0.35) * draw.scaled(),
                          warmup_tc=15.0 * draw.jitter())


EFFECT = ThermalDrift(
    "thermal_drift", "motor", ("Kt_warmup", "Kt_warmup_tc", "Fc_drift"),
    "the motor changing over the run as it warms up: its torque constant (magnets) or its friction (lubricant)",
    "Kt scaled by 1 + Kt_warmup*(1 - exp(-t/Kt_warmup_tc)), friction scaled by (1 + Fc_drift*t)",
    switched_by=("Kt_warmup", "Fc_drift"),
    starts=({"Kt_warmup": -0.02, "Kt_warmup_tc": 5.0, "Fc_drift": -2e-3},
            {"Kt_warmup": -0.02, "Kt_warmup_tc": 20.0, "Fc_drift": 2e-3},
            {"Kt_warmup": -0.05, "Kt_warmup_tc": 10.0, "Fc_drift": -1e-3}),
    needs=("duration", "spectrum_steady_in_time"), uneven_over_folds=True,
    revealed_by="the same motion repeated from a cold start for several minutes (at high current for the "
                "torque constant, at high speed for the friction)",
    resizes=("Kt_warmup", "Fc_drift"), in_friction_law=True,
    size=Size("Kt_warmup", reference=(("Kt_warmup", -0.03), ("Kt_warmup_tc", 10.0)),
              source="a 30 K warm-up of NdFeB magnets (-0.1 %/K)"), rank=6)
