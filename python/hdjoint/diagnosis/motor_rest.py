"""Where the motor rests, and why the motor equation is not compared there.

At rest the motor's friction is static: it takes whatever the drive pushes
against it, up to breakaway, and keeps it until the motor slides again. No
law of speed can say what it is there (the nominal tanh law says 0). On a
sweep with dwells (the independent truth's `sweep`: 1.5 s held after every
3 s move) a joint with bristle friction (LuGre) holds its last sliding
friction, +-Fc, through each dwell while the controller's integrator winds
against it: N*Fc = 1.5 N.m of motor-channel residual for a third of the
recording. Calibration then moved Jm to 2.3-4x and Kt to 0.7-0.8x on every
LuGre sweep, controls included, and no hypothesis of the motor's part
could be confirmed over it. The same truths with a tanh law do not move
them (docs/diagnosis_measurements.md, "Sweeps: the motor at rest").

So a channel with the motor's estimate compares nothing where the motor
rests (its residual there is 0 before and after every hypothesis), widened
by the smoothing filter's reach, through which the motor estimate sees the
rest. A swing through zero speed is not a rest: a 0.25 Hz swing of the
smallest amplitude the benchmark draws spends about 0.1 s below REST_SPEED
(more where the motor sticks at the reversal), a dwell 1.5 s; with
REST_FOR at 0.1 s such reversals were masked on the paper excitation and
the time delay case of seed 0 lost evidence.
A slow run cut by a window's end is a rest however short: the benchmark's
30 s sweep ends as its last move stops, where the tanh truth's friction
held on while the model's let go (0.67 N.m in the last 60 ms), and a
thermal drift fitted that one fold (22.7 % of the held-out residual).
"""
from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_dilation

from hdjoint.diagnosis.kinematics import Kinematics

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
