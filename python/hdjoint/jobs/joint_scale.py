"""The joint's torque scale, which recordings without a torque sensor cannot
tell: every torque-carrying parameter scaled together (Kt with Kf, the
inertias, friction, gravity) scales both sides of every channel alike.
The calibration then holds Kt at its nominal value, which leaves the scale
to Kt's tolerance alone; yet every calibrated parameter's tolerance is a
prior on it as well. The scale used is the one all those priors together
make most probable, leaving out the parameters the recordings moved beyond
their tolerance (`rules.RESIZE_Z`): there the nominal value is ruled out,
a CAD or catalogue value far off, and no evidence on the scale. Within it,
each prior pulls as a normal one up to SCALE_EVIDENCE_Z tolerances and no
harder beyond (a Huber loss): an estimate deep in its tolerance's tail
carries model-form error more likely than the scale (Jm taking up a
friction law the model lacks), and a normal prior would give it the
strongest pull of all. The same cost, as a density, gives the scale its
interval, which Kt, the parameter the scale sets, carries."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.special import huber

from hdjoint.diagnosis import HELD_WITHOUT_SENSOR as HELD, INTERVAL, RESIZE_Z
from hdjoint.io import parameters

# The power of torque in each unit of the joint's model: inertia times acceleration is a torque.
TORQUE_POWER = {"N.m": 1, "N.m/A": 1, "N.m/rad": 1, "N.m.s/rad": 1, "kg.m2": 1, "1/(N.m)": -1}
SCALE_RANGE = (0.5, 2.0)
SCALE_EVIDENCE_Z = 1.5  # tolerances from its nominal value beyond which an estimate pulls the scale no harder
SCALE_GRID = 30001  # points over SCALE_RANGE for the interval: 5e-5 apart, far below any tolerance


def torque_power(name: str) -> int:
    """How a model parameter scales with the joint's torque (0: not at all; estimator settings never)."""
    info = parameters.table()[name]
    return TORQUE_POWER.get(info.unit, 0) if info.in_plant() else 0


def _negative_log_prior(calibration: dict, nominal: dict, tolerance: dict[str, float]):
    """The scale's negative log prior under CALIBRATION's entries and the held Kt's tolerance (see joint_scale)."""
    held = nominal.get(HELD, parameters.table()[HELD].default)
    terms = [(held, held, parameters.table()[HELD].tolerance(held, tolerance.get(HELD)), 1)]
    terms += [(e["estimate"], e["nominal"], e["tolerance"], torque_power(name)) for name, e in calibration.items()
              if torque_power(name) and e["nominal"] and e["tolerance"] > 0 and abs(e["z"]) <= RESIZE_Z]

    def cost(s):  # z^2/2 up to SCALE_EVIDENCE_Z, then linear with its slope there
        return sum(huber(SCALE_EVIDENCE_Z, (x * s ** power - centre) / std) for x, centre, std, power in terms)
    return cost


def joint_scale(calibration: dict, nominal: dict, tolerance: dict[str, float]) -> float:
    """The most probable torque scale under the priors of CALIBRATION's entries
    (nominal, estimate, tolerance: the prior's std, z) and of the held Kt
    (its tolerance, or the user's relative one in TOLERANCE). 1 where the
    calibration fitted Kt itself (a torque sensor sets the scale)."""
    if HELD in calibration:
        return 1.0
    cost = _negative_log_prior(calibration, nominal, tolerance)
    return float(minimize_scalar(cost, bounds=SCALE_RANGE, method="bounded").x)


def scale_interval(calibration: dict, nominal: dict, tolerance: dict[str, float],
                   coverage: float = INTERVAL) -> tuple[float, float] | None:
    """The torque scale's central COVERAGE interval under the same priors: the
    quantiles of exp(-cost) over SCALE_RANGE, summed on a fine grid (one
    dimension: exact up to the grid). None where a sensor fitted Kt."""
    if HELD in calibration:
        return None
    s = np.linspace(*SCALE_RANGE, SCALE_GRID)
    cost = _negative_log_prior(calibration, nominal, tolerance)(s)
    density = np.exp(-(cost - cost.min()))
    cumulative = np.cumsum(density) / density.sum()
    tail = (1.0 - coverage) / 2.0
    return float(np.interp(tail, cumulative, s)), float(np.interp(1.0 - tail, cumulative, s))


def scaled_interval(estimate: float, lo: float, hi: float, power: int, scale: float,
                    interval: tuple[float, float]) -> tuple[float, float]:
    """The interval of a value used, ESTIMATE * SCALE**POWER: the estimate's interval (LO, HI), found with the
    scale held at 1, and the scale's INTERVAL, combined in quadrature on each side. The two are independent:
    the recordings do not inform the scale, only the tolerances do."""
    factor = scale ** power
    ends = sorted(end ** power for end in interval)  # the scale's ends as factors, the lower first
    lower, upper = (ends[0], ends[1]) if estimate >= 0 else (ends[1], ends[0])
    used = estimate * factor
    return (used - math.hypot((estimate - lo) * factor, estimate * (factor - lower)),
            used + math.hypot((hi - estimate) * factor, estimate * (upper - factor)))


def used_interval(name: str, estimate: float, lo: float, hi: float, scale: float,
                  interval: tuple[float, float]) -> tuple[float, float]:
    """The interval of parameter NAME as used (scaled_interval at its torque power), within its range, as
    the value used is (scaled): a limit the range sets is no uncertainty."""
    low, high = scaled_interval(estimate, lo, hi, torque_power(name), scale, interval)
    bounds = parameters.table()[name]
    return max(low, bounds.min), min(high, bounds.max)


def scaled(params: dict, scale: float) -> dict:
    """PARAMS with every torque-carrying parameter scaled by SCALE (to its power),
    within its range: one at a bound stands for a limit (Kw at its top: no compliance)."""
    table = parameters.table()
    return {n: min(max(v * scale ** torque_power(n), table[n].min), table[n].max) if n in table and torque_power(n)
            else v for n, v in params.items()}
