"""The fit stage's objective: each channel's residual normalised by its noise,
the parameters' priors, and the data's weight against them; the maximum a
posteriori fit over any set of parameters, and the residuals' derivatives.

An Objective does not change: calibration makes a new one each time it
measures the noise (with_noise), and every later stage reads the last."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from hdjoint.diagnosis.fit.priors import (Prior, correlation, deviations, posterior_std, robust_covariance,
                                           widened)
from hdjoint.diagnosis.model.residual_channels import Channel
from hdjoint.diagnosis.effects import ALWAYS_CALIBRATED, calibrated_parameters, orthogonal_parameters
from hdjoint.diagnosis.effects.base import RecordingScale
from hdjoint.diagnosis.forked import forked_map
from hdjoint.diagnosis.model.torque_estimates import sharp_transmission, tau_transmission
from hdjoint.diagnosis.model.prepare import Setup, place_offset
from hdjoint.diagnosis.rules import SCORE_BLOCKS
from hdjoint.io import parameters


@dataclass
class Fit:
    params: dict
    names: list[str]
    cost: float
    # Posterior std of each fitted parameter: the wider of the two below, times its model-form factor (calibration.py).
    std: dict = field(default_factory=dict)
    std_laplace: dict = field(default_factory=dict)
    std_robust: dict = field(default_factory=dict)
    # The fitted parameters' posterior correlation matrix (the cluster-robust covariance's), in `names` order.
    correlation: np.ndarray | None = None


def _typical_size(name: str, value: float) -> float:
    """The fit's unit for a parameter without a prior (a hypothesis's own):
    its size, or at zero its tolerance's absolute floor. A cogging or ripple
    term starts at 0, where |value| would give a unit of 1e-12: the solver's
    finite-difference step would then move it by ulps of the residual, and
    the fit stay at 0 on a ripple the order search found."""
    info = parameters.table()[name]
    floor = info.tolerance_absolute if info.calibrated() else 0.0
    return max(abs(float(value)), floor, 1e-12)


class Objective:
    """The objective over a Setup; it reads the setup's fields as its own
    (rec, prep, channels, fold, train, test, ...)."""

    def __init__(self, setup: Setup, priors: dict[str, Prior] | None = None, calibrated_names: list[str] = (),
                 sigma: dict[str, float] | None = None, noise_measured_at: dict[str, float] | None = None,
                 data_weight: float = 1.0, correlation: dict | None = None):
        self.setup = setup
        self.priors = dict(priors or {})
        self.calibrated_names = list(calibrated_names)
        self.sigma = dict(sigma or {c.name: 1.0 for c in setup.channels})
        self.noise_measured_at = dict(noise_measured_at or {})  # scaled parameters where the noise was measured
        # Fit samples per independent one: the data's weight against the priors.
        self.data_weight = data_weight
        self._correlation = correlation if correlation is not None else {}  # a memo: (parameters) -> length

    def __getattr__(self, name):
        if name == "setup":
            raise AttributeError(name)
        return getattr(self.setup, name)

    # ---- the noise ---------------------------------------------------------
    def with_noise(self, p: dict) -> "Objective":
        """The same objective with each channel's noise measured at `p` (they
        equalise the channels: smoothed ones have no white floor), and the
        data's weight: one over the number of fit samples per independent
        sample, from the residual's correlation."""
        sigma = {}
        for c in self.channels:
            compared = self.eval.compared(c)
            used = self.eval.residual(c, p)[self.used if compared is None else self.used & compared]
            sigma[c.name] = max(float(np.sqrt(np.nanmean(used * used))), 1e-9)
        measured_at = {c.scales_with: p[c.scales_with] for c in self.channels
                       if c.scales_with is not None and p.get(c.scales_with)}
        weight = min(1.0, self.stride / self.correlation_length(p))
        return Objective(self.setup, self.priors, self.calibrated_names, sigma, measured_at, weight, self._correlation)

    def with_priors(self, priors: dict[str, Prior]) -> "Objective":
        """The same objective with some priors replaced (resize.released widens them)."""
        return Objective(self.setup, dict(self.priors, **priors), self.calibrated_names, self.sigma,
                         self.noise_measured_at, self.data_weight, self._correlation)

    def at_measured_noise(self, p: dict, channels: list[Channel] | None = None) -> np.ndarray:
        """Per-sample sum of squared residuals over each channel's noise as
        measured, not scaled with `p`: two sets whose Jl differs are compared
        on one yardstick (Objective.noise_scale would rescale the link channel)."""
        total = np.zeros(len(self.rec))
        for c in channels or self.channels:
            r = self.eval.residual(c, p) / self.sigma[c.name]
            total += np.where(np.isfinite(r), r * r, 1e6)
        return total

    def noise_scale(self, channel: Channel, p: dict) -> float:
        """The channel's noise at `p`: as measured, and for a channel that
        `scales_with` a parameter, scaled as it moved. The link against the
        transmission (no sensor) has no torque of its own: scaling Kf, Jl, Bl
        and mgl together scales its residual and leaves its fit alone; against
        a fixed noise, shrinking the scale would shrink the residual, a pull
        the data do not carry."""
        sigma = self.sigma[channel.name]
        if channel.scales_with is None or channel.scales_with not in self.noise_measured_at:
            return sigma
        return sigma * abs(p[channel.scales_with] / self.noise_measured_at[channel.scales_with])

    def correlation_length(self, p) -> int:
        """Samples over which the residual stays correlated (1/e), at most the
        smoothing window. Remembered per parameter set: every hypothesis of a
        round reads it at the round's parameters."""
        key = tuple(sorted(p.items())) + (self.prep.current_shift,)
        if key not in self._correlation:
            self._correlation.clear()  # only the last set is read again
            self._correlation[key] = self._measure_correlation_length(p)
        return self._correlation[key]

    def _measure_correlation_length(self, p) -> int:
        channel = self.channels[0]
        if channel.reference == "sensor" and sharp_transmission(self.prep):
            # Before the transmission's filter, as the encoders and the sensor give it: the
            # white floor it takes away is what a fit sample's weight counts (through it, the
            # model's slow mismatch would set the length, not the noise).
            r = (self.rec.tau_sensor - tau_transmission(self.prep, p, sharp=False))[self.train]
        else:
            r = self.eval.residual(channel, p)[self.train]
        r = r[np.isfinite(r)] - np.nanmean(r)
        if len(r) < 10:
            return 1
        spectrum = np.fft.rfft(r, 2 * len(r))
        acf = np.fft.irfft(spectrum * np.conj(spectrum))[: min(len(r), 2000)]
        if not acf[0] > 0.0:  # a residual without variation (a channel that compares nothing): no correlation
            return 1
        acf /= acf[0]
        below = np.flatnonzero(acf < math.exp(-1))
        length = int(below[0]) if len(below) else 2000
        # Slow structure (the very thing being tested) lengthens the
        # correlation; the noise itself is correlated only over the smoothing window.
        return max(1, min(length, self.prep.kin.smooth.window))

    # ---- residuals -----------------------------------------------------------
    def shown_residual(self, channel: Channel, p: dict) -> np.ndarray:
        """The residual for figures, figures of merit and the search for
        structure: NaN where no test looks, nor the channel (the motor at rest)."""
        compared = self.eval.compared(channel)
        looked = self.used if compared is None else self.used & compared
        return np.where(looked, self.eval.residual(channel, p), np.nan)

    def normalised_residual(self, channel: Channel, p: dict, index: np.ndarray | None = None) -> np.ndarray:
        r = self.eval.residual(channel, p) if index is None else self.eval.residual_at(channel, p, index)
        return r / self.noise_scale(channel, p)

    def normalised(self, p, channels, index=None) -> np.ndarray:
        """The channels' normalised residuals end to end, a large finite value where one is not finite."""
        out = []
        for c in channels:
            r = self.normalised_residual(c, p, index)
            out.append(np.where(np.isfinite(r), r, 1e3))
        return np.concatenate(out)

    def squared(self, p, channels) -> np.ndarray:
        """Per-sample sum of normalised squared residuals over `channels`."""
        total = np.zeros(len(self.rec))
        for c in channels:
            r = self.normalised_residual(c, p)
            total += np.where(np.isfinite(r), r * r, 1e6)
        return total

    def jacobian(self, p: dict, names: list[str], channels: list[Channel]) -> np.ndarray:
        """(channel, sample, parameter) derivative of the normalised residuals, by forward differences."""
        base = np.stack([np.nan_to_num(self.normalised_residual(c, p)) for c in channels])
        columns = []
        for n in names:
            h = 1e-4 * max(abs(p[n]), self.priors[n].std if n in self.priors else 1e-9, 1e-12)
            if p[n] + h > parameters.table()[n].max:
                h = -h  # at the top of its range: a backward difference
            shifted = np.stack([np.nan_to_num(self.normalised_residual(c, dict(p, **{n: p[n] + h})))
                                for c in channels])
            columns.append((shifted - base) / h)
        return np.where(self.used[None, :, None], np.stack(columns, axis=2), 0.0)

    # ---- the fit -------------------------------------------------------------
    def fit(self, p: dict, names: list[str], channels: list[Channel], starts: tuple[dict, ...] = ({},),
            ftol: float = 1e-8) -> Fit:
        """MAP fit over `names` on the training sample (the priors of those in
        self.priors, the physical range for all): a few iterations from each
        start, then the best of them to convergence (relative change of the cost below `ftol`)."""
        full = 60 * (len(names) + 1)
        if len(starts) == 1:
            return self._least_squares(dict(p, **starts[0]), names, channels, full, ftol)
        tries = [self._least_squares(dict(p, **start), names, channels, 5) for start in starts]
        best = min(tries, key=lambda f: f.cost)
        if not np.isfinite(best.cost):
            return best
        return self._least_squares(best.params, names, channels, full, ftol)

    def _least_squares(self, x0_params: dict, names: list[str], channels: list[Channel], max_nfev: int,
                       ftol: float = 1e-8) -> Fit:
        table = parameters.table()
        x0 = np.array([x0_params[n] for n in names], float)
        lo = np.array([table[n].min for n in names])
        hi = np.array([table[n].max for n in names])
        x0 = np.clip(x0, lo, hi)
        prior_std = np.array([self.priors[n].std if n in self.priors else np.nan for n in names])
        scale = np.where(np.isfinite(prior_std), prior_std, [_typical_size(n, x) for n, x in zip(names, x0)])
        scale = np.maximum(scale, 1e-12)
        with_prior = np.flatnonzero(np.isfinite(prior_std))
        centre = np.array([self.priors[names[i]].centre for i in with_prior])
        weight = math.sqrt(self.data_weight)

        def residuals(z):
            trial = dict(x0_params)
            trial.update(zip(names, z * scale))
            data = self.normalised(trial, channels, self.fit_index) * weight
            return np.concatenate([data, (z[with_prior] * scale[with_prior] - centre) / prior_std[with_prior]])

        try:
            # max_nfev counts steps (scipy does not count the finite-difference Jacobian's calls).
            # The Jacobian's columns side by side where this fit is not itself one of several.
            with forked_map(residuals, self.workers if len(names) > 1 else 1) as (function, columns):
                sol = least_squares(function, x0 / scale, bounds=(lo / scale, hi / scale), method="trf",
                                    x_scale="jac", max_nfev=max_nfev, diff_step=1e-6, ftol=ftol, workers=columns)
        except ValueError:
            return Fit(dict(x0_params), list(names), float("inf"))
        fitted = dict(x0_params)
        fitted.update(zip(names, sol.x * scale))
        laplace = posterior_std(sol.jac, scale)
        blocks = np.tile(self.fit_index * SCORE_BLOCKS // len(self.rec), len(channels))
        cov = robust_covariance(sol.jac, sol.fun, blocks)
        robust = deviations(cov, scale)
        wider = {n: widened(n, s) for n, s in zip(names, np.maximum(laplace, robust))}
        return Fit(fitted, list(names), float(sol.cost), wider, dict(zip(names, laplace)), dict(zip(names, robust)),
                   correlation(cov))  # scale-free: the same in the parameters' own units

    def anchors(self, part: str, stateful: bool = False) -> list[str]:
        """The calibrated parameters of `part`, refitted with every hypothesis
        of that part: calibration has already absorbed what it could of the
        missing effect (a viscous term leaks into Kt and Fc), and a hypothesis
        judged against that absorption alone helps some folds and hurts the rest."""
        own = ALWAYS_CALIBRATED[part] if stateful else calibrated_parameters(part, self.nominal, self.has_sensor)
        # Terms at their own angle orders are orthogonal to every other
        # effect: left out, they make each fit much cheaper.
        skip = orthogonal_parameters()
        return [n for n in self.calibrated_names if n in own and n not in skip]

    # ---- torques the recording shows ----------------------------------------
    def reference_torque(self, p) -> np.ndarray:
        return self.rec.tau_sensor if self.has_sensor else self.eval.estimate("motor", p)

    def initial_offset(self, p) -> dict:
        return place_offset(self.rec, p, self.reference_torque(p))

    def recording_scale(self, p: dict) -> RecordingScale:
        """What a fitted effect is judged physical against (Effect.degenerate)."""
        time = self.rec.time[self.used]
        return RecordingScale(self.torsion_span(p), float(time[-1] - time[0]) if len(time) else 0.0)

    def torsion_span(self, p: dict) -> float:
        """The torsion of the recording (5-95 %), rad: the smaller of what the
        reference torque would twist the flexspline by and what the encoders
        measured (the current's torque, mostly the motor's own inertia and
        friction, may twist it far more than it turns)."""
        torque = self.reference_torque(p)[self.used]
        from_torque = float(np.nanpercentile(torque, 95) - np.nanpercentile(torque, 5)) / p["Kf"]
        torsion = (self.rec.theta_m / p["N"] - self.rec.theta_l)[self.used]
        return min(from_torque, float(np.percentile(torsion, 95) - np.percentile(torsion, 5)))
