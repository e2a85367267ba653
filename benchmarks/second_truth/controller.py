"""The drive: a PD(+feed-forward) position controller run at the sample rate
with zero-order hold, as a real servo drive does. It reads its own encoders
(floored counts), feeds back on the motor angle over N (collocated, so the
flexspline's resonance stays damped), and feeds forward the nominal inertia,
gravity and friction for the link reference. The command is the current,
held over the sample and saturated at +-i_max."""
from __future__ import annotations

import math

import numpy as np


class PDController:
    def __init__(self, nominal: dict, r, rd, rdd, Ts: float, bandwidth: float = 30.0,
                 zeta: float = 0.8, i_max: float = 8.0, f_speed: float = 200.0):
        self.n, self.r, self.rd, self.rdd, self.Ts = nominal, r, rd, rdd, Ts
        N = nominal["N"]
        self.J = nominal["Jl"] + N * N * nominal["Jm"]
        self.Kp = self.J * bandwidth ** 2
        self.Kd = 2 * zeta * self.J * bandwidth
        self.i_max = i_max
        self.a = math.exp(-2 * math.pi * f_speed * Ts)  # speed filter pole
        self.qm = 2 * math.pi / nominal["motor_counts"]
        self.prev = None
        self.speed = 0.0

    def start_angle(self) -> float:
        return float(self.r[0])

    def command(self, k: int, theta_m_true: float) -> float:
        n, N = self.n, self.n["N"]
        th = math.floor(theta_m_true / self.qm) * self.qm / N
        if self.prev is None:
            self.prev = th
        self.speed = self.a * self.speed + (1 - self.a) * (th - self.prev) / self.Ts
        self.prev = th
        r, rd, rdd = self.r[k], self.rd[k], self.rdd[k]
        tau = (self.Kp * (r - th) + self.Kd * (rd - self.speed) + self.J * rdd
               + n["mgl"] * math.sin(r) + n["Bl"] * rd
               + N * (n["Fc"] * math.tanh(N * rd / 0.5) + n["Bm"] * N * rd))
        i = tau / (N * n["Kt"])
        return float(np.clip(i, -self.i_max, self.i_max))
