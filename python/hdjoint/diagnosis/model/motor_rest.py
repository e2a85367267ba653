"""Where the motor rests, and why the motor equation is not compared there.

At rest the motor's friction is static: it takes whatever the drive pushes
against it, up to breakaway, and keeps it until the motor slides again. No
law of speed can say what it is there (the nominal tanh law says 0). A
joint with bristle friction (LuGre) holds its last sliding friction, +-Fc,
through a dwell while the controller's integrator winds against it: the
motor channel's residual then carries N*Fc for as long as the motor rests,
calibration bends Jm and Kt to it, and no hypothesis of the motor's part
can be confirmed over it (benchmarks/sweep_calibration.py measures what
calibration makes of sweeps with dwells).

So a channel with the motor's estimate compares nothing where the motor
rests (its residual there is 0 before and after every hypothesis), widened
by the smoothing filter's reach, through which the motor estimate sees the
rest. A swing through zero speed is not a rest: it passes below REST_SPEED
in less than REST_FOR, a dwell does not; a shorter REST_FOR would mask the
reversals of an ordinary excitation and take evidence from effects that
show there. A slow run cut by a window's end is a rest however short: the
model's friction and the joint's can disagree there, and a fit of one fold
would read it as structure.
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_dilation

from hdjoint.diagnosis.model.kinematics import Kinematics

REST_SPEED = 0.5   # rad/s of the motor: below it, for REST_FOR, the motor rests
REST_FOR = 0.3     # s: a dwell; a swing through zero speed passes in less


def motor_at_rest(kin: Kinematics, time: np.ndarray, starts: np.ndarray | None = None) -> np.ndarray:
    """True where the motor rests (|omega_m| < REST_SPEED for at least
    REST_FOR, or up to the end of its window: `starts`, the first sample of
    each contiguous window; a short start from rest is compared: the motor breaks away there), widened by half the smoothing filter's window on both sides."""
    slow = np.abs(kin.omega_m) < REST_SPEED
    rest = np.zeros(len(time), bool)
    bounds = np.append([0] if starts is None else starts, len(time))
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        edges = lo + np.flatnonzero(np.diff(np.concatenate([[0], slow[lo:hi].astype(np.int8), [0]])))
        for start, stop in zip(edges[::2], edges[1::2]):
            if stop == hi or time[stop - 1] - time[start] >= REST_FOR:
                rest[start:stop] = True
    reach = kin.smooth.window // 2
    return binary_dilation(rest, np.ones(2 * reach + 1, bool)) if rest.any() and reach else rest
