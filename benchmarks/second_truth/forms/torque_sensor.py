"""A test bench's joint torque sensor reading the transmitted torque tau_f:
gain error 0.1-0.3 % (strain-gauge torque transducers' accuracy class),
offset up to 0.02 N.m, white noise 0.01-0.03 N.m."""
from __future__ import annotations

from .base import Form


class TorqueSensor(Form):
    name = "torque_sensor"
    family = "torque_sensor"
    role = "torque_sensor"
    ranges = {"gain": (0.997, 1.003), "offset": (-0.02, 0.02), "noise": (0.01, 0.03)}

    def apply(self, rec: dict, rng) -> None:
        p = self.params
        tau = rec["tau_true"]
        rec["tau_sensor"] = p["gain"] * tau + p["offset"] + rng.normal(0.0, p["noise"], len(tau))
