"""p-values of the diagnosis's hypothesis tests, calibrated by simulation,
and the Benjamini-Hochberg correction across hypotheses and locations.

The statistic is the held-out gain's z over folds (structure.held_out_gain_sq);
for an effect uneven over the folds by nature (a drift, a dead zone), the pooled held-out gain.
Its distribution when the hypothesis is false is not the normal one: the
residual is coloured (smoothing filters, model-form differences), and a fit
on the training folds always finds something. So the null distribution is
simulated: a parametric bootstrap under the calibrated null model, cheap
enough to run for every hypothesis.

  - Noise: phase-randomised copies of the calibrated model's own residuals
    (every channel rotated by the same random phases), so each replicate has
    exactly their spectrum (their colour) and their cross-spectrum, and no
    structure locked to angle, speed or load.
  - The hypothesis, linearised at its fit: the residual's Jacobian with
    respect to the parameters the fit adjusted. Each replicate is fitted by
    least squares on the training folds and judged on the held-out folds,
    like the real data.
  - p: the observed z against a normal fitted to the replicates' z
    (`REPLICATES` of them; the tail beyond the largest replicate is the
    normal's, so p-values below 1/REPLICATES are still graded).
benchmarks/false_alarms.py measures the false-alarm rate this gives on controls.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from hdjoint.diagnosis import normal as norm
from hdjoint.diagnosis.model.structure import relative_fold_gains


REPLICATES = 48


@lru_cache(maxsize=1)
def _rotation(n: int, seed: int) -> np.ndarray:
    """(replicate, frequency): the random phase rotations of a residual of `n`
    samples, the same for every null drawn with `seed` (each round's, each
    channel's): made once, as their complex exponentials cost as much as the replicates."""
    rng = np.random.default_rng(seed)
    phases = rng.uniform(0.0, 2.0 * np.pi, (REPLICATES, n // 2 + 1))
    phases[:, 0] = 0.0  # the mean stays real
    if n % 2 == 0:
        phases[:, -1] = 0.0  # and so does the Nyquist bin
    rotation = np.exp(1j * phases)
    rotation.flags.writeable = False  # shared by every null of this length
    return rotation


class NullNoise:
    """Phase-randomised replicates of a set of residual channels (rows)."""

    def __init__(self, residuals: np.ndarray, seed: int = 0, compared: np.ndarray | None = None):
        self.spectra = np.fft.rfft(np.nan_to_num(residuals), axis=1)
        # (channel, sample): where a channel compares anything; its replicates
        # are 0 elsewhere, as the data's residual is (diagnosis.Evaluator.compared).
        self.compared = compared
        self.n = residuals.shape[1]
        self.rotation = _rotation(self.n, seed)
        self._made: dict[tuple, np.ndarray] = {}
        self._channel: dict[int, np.ndarray] = {}

    def replicates(self, rows: list[int]) -> np.ndarray:
        """(replicate, channel, sample) noise for the channels `rows` (the same
        array for the same rows: every hypothesis of a part reads one)."""
        key = tuple(rows)
        if key not in self._made:
            made = [self._of_channel(row)[:, None, :] for row in rows]
            self._made[key] = (made[0] if len(made) == 1 else np.concatenate(made, axis=1) if made
                               else np.zeros((REPLICATES, 0, self.n)))
        return self._made[key]

    def _of_channel(self, row: int) -> np.ndarray:
        """(replicate, sample) noise of one channel, made once: without a
        sensor a part's rows overlap another's (the transmission is in both
        channels), and each channel's transform is the same alone or with others."""
        if row not in self._channel:
            made = np.fft.irfft(self.spectra[row][None, :] * self.rotation, n=self.n, axis=1)
            if self.compared is not None:
                made *= self.compared[row][None, :]
            self._channel[row] = made
        return self._channel[row]

    def prepare(self, row_sets: list[list[int]]) -> None:
        """Make the replicates of each set of rows now (before forking: the children share them)."""
        for rows in row_sets:
            if rows:
                self.replicates(rows)


def _null_fold_errors(noise: np.ndarray, jacobian: np.ndarray, fit_rows: np.ndarray, fold, test):
    """A linear hypothesis fitted to each noise replicate on the training rows:
    each replicate's held-out mean squared residual per fold, before and after
    ((replicate, fold) each), and the held-out samples per fold; None when the
    hypothesis moves nothing.

    noise: (replicate, channel, sample); jacobian: (channel, sample, parameter)."""
    channels, _, k = jacobian.shape
    j_fit = jacobian[:, fit_rows, :].reshape(-1, k)
    keep = np.linalg.norm(j_fit, axis=0) > 0
    if not keep.any():
        return None
    j_fit = j_fit[:, keep]
    # Least squares on the training rows, by a QR of the Jacobian shared by all replicates.
    q, r = np.linalg.qr(j_fit)
    targets = noise[:, :, fit_rows].reshape(len(noise), -1)
    delta = np.linalg.lstsq(r, q.T @ targets.T, rcond=None)[0]  # (parameter, replicate)
    # Held out: per-fold mean squared residual before and after, for every replicate.
    rows = np.flatnonzero(test)
    labels, which = np.unique(fold[rows], return_inverse=True)
    counts = np.bincount(which)
    members = np.zeros((len(rows), len(labels)))
    members[np.arange(len(rows)), which] = 1.0 / counts[which]
    held = noise[:, :, rows]
    change = np.einsum("csk,kb->bcs", jacobian[:, rows][:, :, keep], delta)
    before = np.sum(held ** 2, axis=1) @ members
    after = np.sum((held - change) ** 2, axis=1) @ members
    return before, after, counts


def null_z(noise: np.ndarray, jacobian: np.ndarray, fit_rows: np.ndarray, fold, test) -> np.ndarray:
    """The held-out z of a linear hypothesis fitted to each noise replicate
    (structure.held_out_gain_sq's statistic, for all replicates at once).

    noise: (replicate, channel, sample); jacobian: (channel, sample, parameter)."""
    errors = _null_fold_errors(noise, jacobian, fit_rows, fold, test)
    if errors is None or errors[0].shape[1] < 2:
        return np.zeros(len(noise))
    before, after, _ = errors
    relative = relative_fold_gains(before, after)  # the replicates are blind where the recording is
    compared = np.count_nonzero(np.isfinite(relative), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        spread = np.nanstd(relative, axis=1, ddof=1) / np.sqrt(compared)
        return np.nan_to_num(np.nanmean(relative, axis=1) / np.maximum(spread, 1e-300))


def null_gain(noise: np.ndarray, jacobian: np.ndarray, fit_rows: np.ndarray, fold, test) -> np.ndarray:
    """The pooled held-out gain (1 - MSE after / MSE before over every held-out
    sample, structure.HeldOutGain.gain) of a linear hypothesis fitted to each
    noise replicate: the statistic of effects whose gain is uneven over the
    folds by nature (Effect.uneven_over_folds)."""
    errors = _null_fold_errors(noise, jacobian, fit_rows, fold, test)
    if errors is None:
        return np.zeros(len(noise))
    before, after, counts = errors
    return 1.0 - (after @ counts) / np.maximum(before @ counts, 1e-300)


def standardised(observed: float, null: np.ndarray) -> float:
    """The observed statistic in standard deviations above the simulated null's mean."""
    spread = float(np.std(null, ddof=1)) if len(null) > 1 else 1.0
    return (observed - float(np.mean(null))) / max(spread, 1e-9)


def p_value(z_observed: float, z_null: np.ndarray) -> float:
    """One-sided p of the observed statistic against the simulated null (normal fitted to it)."""
    return float(norm.sf(standardised(z_observed, z_null)))


def benjamini_hochberg(p: list[float]) -> list[float]:
    """Adjusted p-values (step-up): reject where adjusted p <= the false discovery rate."""
    if not p:
        return []
    p_arr = np.asarray(p, float)
    m = len(p_arr)
    order = np.argsort(p_arr)
    scaled = p_arr[order] * m / np.arange(1, m + 1)
    adjusted = np.minimum.accumulate(scaled[::-1])[::-1]
    out = np.empty(m)
    out[order] = np.minimum(adjusted, 1.0)
    return [float(x) for x in out]


def null_noise(objective, p) -> NullNoise:
    """The simulated null's noise of an Objective at `p`: replicates with each channel's colour."""
    return NullNoise(np.stack([np.where(objective.used, np.nan_to_num(objective.normalised_residual(c, p)), 0.0)
                               for c in objective.channels]), compared=objective.eval.compared_by_channel())
