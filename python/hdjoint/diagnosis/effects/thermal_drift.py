"""The motor warming up over the run: its torque constant (magnets) or its
friction (lubricant). Both forms in one fit; which one carries the drift is
read from their fitted sizes and intervals."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, RecordingScale, Size, TruthDraw

# The fastest a motor's temperature moves is its winding's thermal time
# constant, a few seconds for the smallest catalogue motors and tens of
# seconds for robot-joint sizes (maxon catalogue, "Thermal time constant
# winding", line 19); the magnets that set Kt follow the slower motor
# constant (line 20, minutes). A warm-up faster than this is not thermal.
MIN_THERMAL_TC = 3.0  # s
# NdFeB magnets lose 0.1-0.12 % of their remanence per kelvin (magnet makers'
# grade tables); over at most about 125 K of warm-up (insulation class F,
# 155 degC) Kt falls by at most this share.
MAX_KT_WARMUP = 0.15
# Below this the warm-up term carries no Kt change (a 1 K warm-up of NdFeB):
# its time constant is then not read.
KT_WARMUP_CARRIED = 1e-3


class ThermalDrift(Effect):
    def degenerate(self, p: dict, scale: RecordingScale) -> str | None:
        """A fit no warm-up can produce: a Kt change faster than any motor
        heats or larger than its magnets allow, or friction driven through
        zero within the recording."""
        kt, tc, drift = p["Kt_warmup"], p["Kt_warmup_tc"], p["Fc_drift"]
        if abs(kt) > KT_WARMUP_CARRIED and tc < MIN_THERMAL_TC:
            return (f"the fitted warm-up changes Kt by {100 * kt:+.1f} % with a {tc:.2g} s time constant, faster "
                    f"than a motor heats (a winding's thermal time constant is at least about {MIN_THERMAL_TC:g} s): "
                    "a step in the current's torque, not a thermal process")
        if abs(kt) > MAX_KT_WARMUP:
            return (f"the fitted warm-up changes Kt by {100 * kt:+.1f} %, more than magnets lose over any "
                    f"warm-up a motor survives (about {100 * MAX_KT_WARMUP:.0f} %)")
        if 1.0 + drift * scale.duration <= 0.0:
            return (f"the fitted friction drift ({drift:.2g} /s) drives friction through zero within the "
                    f"{scale.duration:.3g} s recording: not a warm-up")
        return None

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
