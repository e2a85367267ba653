"""Lost motion: a dead zone of torsion around zero torque."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, RecordingScale, Size, TruthDraw


class Backlash(Effect):
    def degenerate(self, p: dict, scale: RecordingScale) -> str | None:
        """A dead zone at least half as wide as the recorded torsion leaves the
        transmission carrying no torque over most of the recording: not lost
        motion, a transmission blinded to whatever it failed to explain (a
        dead zone can swallow torsion that is kinematic error, leaving eq.
        (7) at its nominal value)."""
        if p["backlash"] < 0.5 * scale.torsion_span:
            return None
        return (f"the fitted dead zone ({p['backlash']:.2g} rad) is at least half the recorded torsion "
                f"({scale.torsion_span:.2g} rad): a transmission that carries no torque, not lost motion")

    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.truth["backlash"] = 2e-5 * draw.scaled()


EFFECT = Backlash(
    "backlash", "transmission", ("backlash",),
    "lost motion: a dead zone of torsion around zero torque", "dead zone of width `backlash` on the torsion",
    switched_by=("backlash",), starts=({"backlash": 1e-5}, {"backlash": 4e-5}, {"backlash": 1.5e-4}),
    needs=("torque_reversals", "load_through_zero"),
    lookalikes=("hysteresis", "wave_generator_compliance", "wave_generator_load"),
    revealed_by="a dwell at zero load between slow reversals (a flat of torsion without torque)",
    resizes=("backlash",), uneven_over_folds=True,
    size=Size("backlash", reference=(("backlash", 2.9e-4),), source="lost motion of 1 arcmin (catalogue)"), rank=6)
