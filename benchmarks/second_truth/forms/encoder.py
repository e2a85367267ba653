"""Encoder quantisers with interpolation error. A counter floors (it counts
edges passed), a position estimator may round: the two differ by half a count.
Before quantising, the reading carries an interpolation error periodic in the
signal period (sine/cosine encoders: first and second harmonics of the
period, of order 1 % of it in optical encoders' datasheets; a quadrature
counter's edge placement errors likewise). Motor: 1024 lines (period 2*pi/1024,
4096 counts); link: 2048 sine periods interpolated to 19 bit."""
from __future__ import annotations

import numpy as np

from .base import Form

PERIODS = {"theta_m": 1024, "theta_l": 2048}
COUNTS = {"theta_m": "motor_counts", "theta_l": "link_counts"}


class _Encoder(Form):
    family = "encoder"
    role = "encoder"
    mode = "floor"
    ranges = {"e1_m": (0.0, 0.01), "e2_m": (0.0, 0.005), "e1_l": (0.0, 0.01), "e2_l": (0.0, 0.005),
              "ph1": (0.0, 6.283), "ph2": (0.0, 6.283)}

    def read(self, angle: np.ndarray, channel: str, counts: float) -> np.ndarray:
        k = "m" if channel == "theta_m" else "l"
        period = 2 * np.pi / PERIODS[channel]
        ph = angle / period * 2 * np.pi
        a = angle + period * (self.params[f"e1_{k}"] * np.sin(ph + self.params["ph1"])
                              + self.params[f"e2_{k}"] * np.sin(2 * ph + self.params["ph2"]))
        if not counts:
            return a
        q = 2 * np.pi / counts
        return (np.floor(a / q) if self.mode == "floor" else np.round(a / q)) * q

    def apply(self, rec: dict, rng) -> None:
        for ch in ("theta_m", "theta_l"):
            rec[ch] = self.read(rec[ch + "_true"], ch, rec["counts"][COUNTS[ch]])


class EncoderFloor(_Encoder):
    name = "encoder_floor"
    mode = "floor"


class EncoderRound(_Encoder):
    name = "encoder_round"
    mode = "round"
