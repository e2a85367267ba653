"""The drive's current measurement: a Hall-effect transducer and an ADC.
i_meas = g*(i_s + c3*I_FS*(i_s/I_FS)^3) + offset + noise, quantised by a
12-bit ADC over +-10 A, where i_s is the true current through a first-order
lag tau_s (the transducer's and anti-alias filter's bandwidth) read `delay`
before the sample tick. The lag is computed exactly on the solver's dense
output by 6-node Gauss-Laguerre quadrature of the exponential kernel.
Sizes: Hall transducers state gain errors of about 0.5-2 % and offsets of a
few mA to tens of mA (e.g. LEM datasheets); the planted `time_delay` effect
adds `extra_delay` (a drive that reports its current samples late)."""
from __future__ import annotations

import numpy as np

from .base import Form

I_FS = 10.0
LSB = 2 * I_FS / 4096
NODES, WEIGHTS = np.polynomial.laguerre.laggauss(6)


class CurrentSensor(Form):
    name = "current_sensor"
    family = "current_sensor"
    role = "current_sensor"
    ranges = {"gain": (0.98, 1.02), "offset": (-0.005, 0.005), "c3": (-0.003, 0.003),
              "tau_s": (1e-5, 6e-5), "delay": (0.0, 1e-4), "noise": (0.002, 0.006)}

    def total_delay(self) -> float:
        return self.params["delay"] + self.params.get("extra_delay", 0.0)

    def probe_times(self, ticks: np.ndarray) -> np.ndarray:
        """Where the true current is read: per tick, one time per quadrature node."""
        return (ticks[:, None] - self.total_delay() - self.params["tau_s"] * NODES[None, :]).ravel()

    def apply(self, rec: dict, rng) -> None:
        p = self.params
        i_nodes = rec["i_nodes"].reshape(len(rec["ticks"]), len(NODES))
        i_s = i_nodes @ WEIGHTS
        x = i_s + p["c3"] * I_FS * (i_s / I_FS) ** 3
        meas = p["gain"] * x + p["offset"] + rng.normal(0.0, p["noise"], len(x))
        rec["i_m"] = np.round(meas / LSB) * LSB
