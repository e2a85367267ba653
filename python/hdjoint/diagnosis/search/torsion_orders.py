"""The kinematic error seen on the encoders alone: angle orders of the torsion.

Without a torque sensor, the transmission's torque is compared with what the
motor model makes of the current and what the link model makes of the link's
motion. A kinematic-error ripple, small at the flexspline's stiffness, then
sits under whatever either model lacks: motor-side mismatch, or gravity a
short recording cannot confirm (docs/diagnosis_lara8.md). The torsion
theta_m/N - theta_l, less the model's own kinematic error, needs neither
model. It is regressed on nuisances every
recording has: a constant (the encoder zero), the reference torque (the
flexspline's twist, whatever its stiffness) and the link angle (gravity,
drift and link orders a short travel cannot tell apart). Each candidate order
is then fitted on the training folds of what is left and judged on the
held-out folds, against the simulated null (significance.py: phase-randomised
copies of the nuisance residual, the order's two columns as the hypothesis),
with Benjamini-Hochberg across the orders.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdjoint.diagnosis.search.significance import NullNoise, benjamini_hochberg, null_z, p_value
from hdjoint.diagnosis.rules import INTERVAL_Z
from hdjoint.diagnosis.model.structure import HeldOutGain, held_out_gain

# A motor order needs the motor to turn this often: half orders apart, a ripple told from a drift.
MIN_REVOLUTIONS = 2.0


@dataclass
class TorsionOrder:
    angle: str          # "theta_m" or "theta_l"
    order: float        # cycles per revolution
    cos: float          # rad, fitted jointly with the nuisances
    sin: float
    half_width: float   # rad, the larger of the two coefficients' 95 % half-widths
    gain: HeldOutGain   # of the torsion residual, held out
    p_raw: float        # against the simulated null
    p_value: float = 1.0  # Benjamini-Hochberg over the orders tried

    @property
    def amplitude(self) -> float:
        return math.hypot(self.cos, self.sin)


def correlation_length(r: np.ndarray) -> int:
    """Samples over which a residual stays correlated (first drop of its autocorrelation below 1/e)."""
    r = r - r.mean()
    spectrum = np.fft.rfft(r, 2 * len(r))
    acf = np.fft.irfft(spectrum * np.conj(spectrum))[: len(r)]
    below = np.flatnonzero(acf / max(acf[0], 1e-300) < math.exp(-1))
    return max(1, int(below[0]) if len(below) else len(r))


def nuisances(torque: np.ndarray, theta_l: np.ndarray) -> np.ndarray:
    """(sample, column): a constant, the reference torque (one column, or
    several: (sample, column)), the link angle (centred)."""
    torque = torque.reshape(len(theta_l), -1)
    return np.column_stack([np.ones(len(theta_l)), torque, theta_l - np.mean(theta_l)])


def _nuisance_residual(torsion, nuisance, train, test):
    """The torsion less its nuisances fitted on the training rows (0 outside
    the compared rows), and the training and held-out rows where it is finite."""
    train, test = train & np.isfinite(torsion), test & np.isfinite(torsion)
    y = np.nan_to_num(torsion)
    coef = np.linalg.lstsq(nuisance[train], y[train], rcond=None)[0]
    return np.where(train | test, y - nuisance @ coef, 0.0), train, test


def _ripple(nuisance, terms, train) -> np.ndarray:
    """cos, sin of each (angle values, order), made orthogonal to the nuisances on
    the training rows: fitting them to the nuisance residual is then the joint
    fit (a jog's torque swings with the angle)."""
    ripple = np.column_stack([f(k * values) for values, k in terms for f in (np.cos, np.sin)])
    return ripple - nuisance @ np.linalg.lstsq(nuisance[train], ripple[train], rcond=None)[0]


def order_evidence(torsion: np.ndarray, nuisance: np.ndarray, angle: np.ndarray, orders, fold: np.ndarray,
                   train: np.ndarray, test: np.ndarray, angle_name: str = "theta_m") -> list[TorsionOrder]:
    """Each order of `angle` tried on the torsion's nuisance residual: held-out
    gain and z over the folds, p from the simulated null, BH-adjusted p."""
    residual, train, test = _nuisance_residual(torsion, nuisance, train, test)
    noise = NullNoise(residual[None, :]).replicates([0])
    rows = np.flatnonzero(train)
    out = []
    for k in orders:
        ripple = _ripple(nuisance, [(angle, k)], train)
        c = np.linalg.lstsq(ripple[train], residual[train], rcond=None)[0]
        left = residual[train] - ripple[train] @ c
        dof = max(len(rows) - nuisance.shape[1] - 2, 1)
        cov = np.linalg.pinv(ripple[train].T @ ripple[train]) * float(left @ left) / dof * correlation_length(left)
        half = float(INTERVAL_Z * np.sqrt(np.max(np.clip(np.diag(cov), 0.0, None))))
        gain = held_out_gain(residual, ripple @ c, fold, test)
        z_null = null_z(noise, ripple[None, :, :], rows, fold, test)
        out.append(TorsionOrder(angle_name, float(k), float(c[0]), float(c[1]), half, gain,
                                p_value(gain.z, z_null)))
    for o, adjusted in zip(out, benjamini_hochberg([o.p_raw for o in out])):
        o.p_value = adjusted
    return out


@dataclass
class JointFit:
    """Several orders fitted together with the nuisances (training folds)."""
    coefficients: list[tuple[float, float]]  # (cos, sin) per order, rad
    gain: HeldOutGain                        # of the torsion's nuisance residual, held out
    mse_before: float                        # training mean square, nuisances alone
    mse_after: float                         # and with the orders
    correlation: int                         # samples per independent one in the nuisance residual


def fit_orders(torsion: np.ndarray, nuisance: np.ndarray, terms: list[tuple[np.ndarray, float]], fold: np.ndarray,
               train: np.ndarray, test: np.ndarray) -> JointFit:
    """The orders `terms` ((angle values, order) each) fitted jointly with the nuisances."""
    residual, train, test = _nuisance_residual(torsion, nuisance, train, test)
    ripple = _ripple(nuisance, terms, train)
    c = np.linalg.lstsq(ripple[train], residual[train], rcond=None)[0]
    after = residual[train] - ripple[train] @ c
    return JointFit([(float(c[2 * i]), float(c[2 * i + 1])) for i in range(len(terms))],
                    held_out_gain(residual, ripple @ c, fold, test), float(np.mean(residual[train] ** 2)),
                    float(np.mean(after ** 2)), correlation_length(residual[train]))
