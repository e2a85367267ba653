"""The plug-in base of the second truth: a model form or a sensor nuisance.

A form has a name, a family (results are reported per family), the
parameters it draws per seed from stated ranges, and one contribution:
either a torque inside the joint's ODE (roles `motor_friction`,
`transmission`, `motor_torque`, `stiffness`) with optional internal states,
or a change to the sampled readings (roles `current_sensor`, `encoder`,
`timing`, `dropouts`), applied after the integration.
"""
from __future__ import annotations

import math


class Form:
    name = "form"
    family = "none"
    role = "none"
    # parameter -> (low, high): drawn uniformly per seed; names in LOG are drawn log-uniformly.
    ranges: dict[str, tuple[float, float]] = {}
    LOG: frozenset[str] = frozenset()
    n_states = 0
    state_atol: tuple[float, ...] = ()

    def __init__(self, rng=None, **fixed):
        self.params = {}
        for key, (lo, hi) in self.ranges.items():
            if key in fixed:
                continue
            if rng is None:
                self.params[key] = math.sqrt(lo * hi) if key in self.LOG else 0.5 * (lo + hi)
            elif key in self.LOG:
                self.params[key] = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
            else:
                self.params[key] = float(rng.uniform(lo, hi))
        self.params.update({k: float(v) for k, v in fixed.items()})

    # ---- inside the ODE -------------------------------------------------
    def initial_states(self, ctx) -> list[float]:
        return [0.0] * self.n_states

    def rates(self, ctx, z) -> list[float]:
        return []

    def torque(self, ctx, z) -> float:
        return 0.0

    # ---- on the sampled readings ----------------------------------------
    def apply(self, rec: dict, rng) -> None:
        """Change the sampled channels in `rec` in place (sensor roles)."""

    def describe(self) -> dict:
        return {"name": self.name, "family": self.family, "role": self.role, "params": dict(self.params)}
