"""The wave generator loaded by the transmitted torque rather than the motor current."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, Size

EFFECT = Effect(
    "wave_generator_load", "transmission", ("wg_load",),
    "the wave generator is loaded by the transmitted torque tau/N, not by the motor current Kt*i_m "
    "(the paper's approximation carries friction and inertia into the wave generator's torsion)",
    "wave generator torque (1 - wg_load)*Kt*i_m + wg_load*tau/N",
    switched_by=("wg_load",), starts=({"wg_load": 1.0}, {"wg_load": 0.5}), needs=("speed_reversals",),
    lookalikes=("coulomb_friction", "wave_generator_compliance", "hysteresis", "backlash"),
    revealed_by="speed reversals at constant load (friction flips, the transmitted torque does not)",
    resizes=("wg_load",), size=Size("wg_load", reference=(("wg_load", 1.0),),
                                     source="the wave generator loaded by the transmitted torque alone"),
    rank=3)
