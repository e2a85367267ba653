"""The mismatch diagnosis: calibrate, locate, name, model, show the fit.

  1. Calibrate: fit the nominal model's own parameters (those it switches
     on, plus offsets, gains and shape parameters) on the training folds:
     maximum a posteriori with each parameter's tolerance as its prior
     (calibration.py), with a Laplace posterior for each.
  2. Locate: residual channels between independent torque estimates (see
     channels.py), scanned for held-out structure over time, regime and angle.
  3. Name: forward selection over the effect library (effects.py): each
     candidate is fitted on the training folds; its held-out gain gets a
     p-value from a simulated null (significance.py), corrected across the
     round's hypotheses (Benjamini-Hochberg); the best one by held-out gain
     is accepted when it is significant and BIC agrees, or reported with a
     look-alike that explains the same structure as one ambiguous finding;
     repeat until nothing significant remains.
  4. Model: the accepted effects are parameters of the C++ model; the
     corrected set is written as params.json (and .ssv).
  5. Show the fit: RMS before and after on all data and on held-out folds,
     per finding; the torque estimator with nominal vs corrected parameters.
  6. Resized: a calibrated parameter beyond its tolerance is a finding of
     the effect it belongs to.
  7. Verdict: missing_physics, consistent, or unexplained (structure remains
     that no hypothesis explains, with where).
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import replace
from typing import Callable

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import norm

from hdjoint.diagnosis.calibration import Calibrated, Prior, posterior_std, priors, robust_std, widened
from hdjoint.diagnosis.channels import TORSION_VIEW, Channel, Evaluator, channels_for
from hdjoint.diagnosis.current_alignment import align_current
from hdjoint.diagnosis.decide import finding_for
from hdjoint.diagnosis.effects import (
    ALWAYS_CALIBRATED,
    EFFECTS,
    Effect,
    calibrated_parameters,
    orthogonal_parameters,
    owner,
    slot_on,
    testable,
)
from hdjoint.diagnosis.forked import map_forked
from hdjoint.diagnosis.hypotheses import Finding, Fit, Hypothesis, delta_bic
from hdjoint.diagnosis.kinematics import kinematics
from hdjoint.diagnosis.part_torques import Prepared, sharp_transmission, tau_transmission, torsion_less_kinematic
from hdjoint.diagnosis.prepare import check_recording, eq7_orders, joined, place_offset, unresolved_harmonics
from hdjoint.diagnosis.rules import (
    ANALYSED_SECONDS,
    DOMINANT_GAIN,
    EVIDENCE_Z,
    FALSE_DISCOVERY_RATE,
    FIT_SAMPLES,
    HYPOTHESIS_FTOL,
    MIN_GAIN,
    ORDER_PROMINENCE,
    RESIZE_Z,
    SCORE_BLOCKS,
    STRUCTURE_GAIN,
    UNRESOLVED_GAIN,
)
from hdjoint.diagnosis.significance import NullNoise, benjamini_hochberg, null_gain, null_z, p_value, standardised
from hdjoint.diagnosis.structure import (
    Order,
    candidate_orders,
    held_out_gain_sq,
    lowest_unresolved_order,
    order_search,
    unresolved_order,
    unresolved_trend,
)
from hdjoint.diagnosis.torsion_orders import MIN_REVOLUTIONS, fit_orders, order_evidence
from hdjoint.diagnosis.torsion_orders import nuisances as torsion_nuisances
from hdjoint.io import parameters
from hdjoint.io.recording import Recording


def _typical_size(name: str, value: float) -> float:
    """The fit's unit for a parameter without a prior (a hypothesis's own):
    its size, or at zero its tolerance's absolute floor. A cogging or ripple
    term starts at 0, where |value| gave a unit of 1e-12: the solver's
    finite-difference step (1e-6 units) then moved cog_a by 1e-18 N.m, a
    residual change of a few ulps, and the fit stayed at 0 on a ripple the
    order search had found at a held-out gain of 68 % (or did not, as the
    rounding fell)."""
    info = parameters.table()[name]
    floor = info.tolerance_absolute if info.calibrated() else 0.0
    return max(abs(float(value)), floor, 1e-12)



class Diagnosis:
    """Runs the diagnosis of one or several recordings of a joint against a nominal parameter set."""

    def __init__(self, rec: Recording | list[Recording], nominal: dict[str, float],
                 progress: Callable[[str], None] | None = None, tolerance: dict[str, float] | None = None,
                 workers: int | None = None):
        self.workers = workers  # processes that fit a round's hypotheses (None: one per core)
        recordings = list(rec) if isinstance(rec, (list, tuple)) else [rec]
        for r in recordings:
            check_recording(r)
        self.source = recordings[0]  # the first recording whole; `rec` is what is analysed
        self.recordings = recordings
        self.rec, starts, t_rel, self.fold = joined(recordings)
        rec = self.rec
        self.nominal = dict(nominal)
        self.tolerance = dict(tolerance or {})
        self.say = progress or (lambda message: None)
        self.started = _time.perf_counter()
        if len(starts) > len(recordings):
            self.say(f"analysing {len(starts)} windows spread over the recordings, {ANALYSED_SECONDS:.0f} s in all")
        self.prep = Prepared(rec, kinematics(rec, starts=starts), t_rel, starts)
        self.has_sensor = rec.tau_sensor is not None
        self.channels = channels_for(self.has_sensor)
        self.eval = Evaluator(self.prep, self.channels)
        # Samples where the smoothing filter runs off a window's ends take no part.
        self.train = (self.fold % 2 == 0) & self.prep.kin.valid
        self.test = (self.fold % 2 == 1) & self.prep.kin.valid
        self.used = self.train | self.test
        self.stride = max(1, int(np.count_nonzero(self.train) // FIT_SAMPLES))
        self.fit_index = np.flatnonzero(self.train)[::self.stride]
        self.eval.offset_rows = self.fit_index
        self.sigma = {c.name: 1.0 for c in self.channels}
        self._noise_measured_at: dict[str, float] = {}  # scaled parameters at the last noise update (noise_scale)
        # Fit samples per independent one: the data's weight against the priors.
        self.data_weight = 1.0
        self.priors: dict[str, Prior] = {}
        self.calibrated_names: list[str] = []
        self._added_names: list[str] = []  # parameters of accepted findings
        self._fitted_before: dict[str, dict] = {}  # each hypothesis's own parameters where its last fit ended
        self.not_testable: list[dict] = []
        self.current_alignment: dict | None = None  # set by calibrate (current_alignment.py)
        self.orders_not_found: list[dict] = []  # effects at angle orders whose order search found none
        self.unconfirmed: list[Hypothesis] = []  # large held-out structure the simulated null cannot confirm
        self._orders_seen: list[Order] = []
        self.tested: list[list[dict]] = []  # every hypothesis tried, per round (evidence for the report)
        self.last_round: list[Hypothesis] = []  # the hypotheses of the round that ended the selection
        self.last_candidates: list[Effect] = []  # that round's effects, those without a hypothesis too (no order found)
        self._noise: NullNoise | None = None  # the simulated null's noise of the last round (or test_alone) ...
        self._noise_at: dict | None = None   # ... and the parameter set it was made at
        self._correlation: tuple | None = None  # (parameters, length), see _correlation_length

    def shown_residual(self, channel: Channel, p: dict) -> np.ndarray:
        """The residual for figures, figures of merit and the search for
        structure: NaN where no test looks, nor the channel (the motor at rest)."""
        compared = self.eval.compared(channel)
        looked = self.used if compared is None else self.used & compared
        return np.where(looked, self.eval.residual(channel, p), np.nan)

    def channels_of(self, part: str) -> list[Channel]:
        return [c for c in self.channels if part in c.parts()]

    # ---- fitting -------------------------------------------------------------
    def noise_scale(self, channel: Channel, p: dict) -> float:
        """The channel's noise at `p`: measured at the last noise update, and
        for a channel that `scales_with` a parameter, scaled as it moved. The
        link against the transmission (no sensor) has no torque of its own:
        scaling Kf, Jl, Bl and mgl together (bl1 taking up the gravity's
        share of the torsion) scales its residual and leaves its fit alone.
        Against a fixed noise, shrinking the scale shrank the residual, a
        pull the data do not carry: on the independent truth's controls the
        calibration put Kf and Jl at 0.5-0.7 times the truth's, with bl1 8
        tolerances off, and 13 of 20 raised a false alarm."""
        sigma = self.sigma[channel.name]
        if channel.scales_with is None or channel.scales_with not in self._noise_measured_at:
            return sigma
        return sigma * abs(p[channel.scales_with] / self._noise_measured_at[channel.scales_with])

    def normalised_residual(self, channel: Channel, p: dict, index: np.ndarray | None = None) -> np.ndarray:
        r = self.eval.residual(channel, p) if index is None else self.eval.residual_at(channel, p, index)
        return r / self.noise_scale(channel, p)

    def _normalised(self, p, channels, index=None) -> np.ndarray:
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
            data = self._normalised(trial, channels, self.fit_index) * weight
            return np.concatenate([data, (z[with_prior] * scale[with_prior] - centre) / prior_std[with_prior]])

        try:
            # max_nfev counts steps (scipy does not count the finite-difference Jacobian's calls).
            sol = least_squares(residuals, x0 / scale, bounds=(lo / scale, hi / scale), method="trf",
                                x_scale="jac", max_nfev=max_nfev, diff_step=1e-6, ftol=ftol)
        except ValueError:
            return Fit(dict(x0_params), list(names), float("inf"))
        fitted = dict(x0_params)
        fitted.update(zip(names, sol.x * scale))
        laplace = posterior_std(sol.jac, scale)
        blocks = np.tile(self.fit_index * SCORE_BLOCKS // len(self.rec), len(channels))
        robust = robust_std(sol.jac, sol.fun, blocks, scale)
        wider = {n: widened(n, s) for n, s in zip(names, np.maximum(laplace, robust))}
        return Fit(fitted, list(names), float(sol.cost), wider,
                   dict(zip(names, laplace)), dict(zip(names, robust)))

    # ---- the steps -------------------------------------------------------------
    def reference_torque(self, p) -> np.ndarray:
        return self.rec.tau_sensor if self.has_sensor else self.eval.estimate("motor", p)

    def initial_offset(self, p) -> dict:
        return place_offset(self.rec, p, self.reference_torque(p))

    def _update_noise(self, p) -> None:
        """Noise scales per channel (they equalise the channels: smoothed ones
        have no white floor), and the data's weight: one over the number of
        fit samples per independent sample, from the residual's correlation."""
        for c in self.channels:
            compared = self.eval.compared(c)
            used = self.eval.residual(c, p)[self.used if compared is None else self.used & compared]
            self.sigma[c.name] = max(float(np.sqrt(np.nanmean(used * used))), 1e-9)
        self._noise_measured_at = {c.scales_with: p[c.scales_with] for c in self.channels
                                   if c.scales_with is not None and p.get(c.scales_with)}
        self.data_weight = min(1.0, self.stride / self._correlation_length(p))

    def calibrate(self) -> tuple[dict, Fit]:
        self.say("calibrating the nominal model's parameters (maximum a posteriori)")
        p = self.initial_offset(self.nominal)
        names = []
        for part in ("transmission", "motor", "link"):
            if self.channels_of(part):
                names += [n for n in calibrated_parameters(part, self.nominal, self.has_sensor) if n not in names]
        self.priors = priors(names, self.nominal, self.tolerance, centres={"a0": p["a0"]})
        self.calibrated_names = names
        self._update_noise(p)
        # Two passes: the noise scales come from the first pass's residuals,
        # and the current's alignment (a property of the recording) from its parameters.
        for first in (True, False):
            fit = self.fit(p, names, self.channels)
            p = fit.params
            if first:
                self.current_alignment = align_current(self, p)
            self._update_noise(p)
        return p, fit

    def order_search(self, p, part: str, channels: list[Channel], angles: tuple[str, ...],
                     added: dict[str, np.ndarray] | None = None) -> list[Order]:
        """Orders of `angles` the residuals of `channels` carry, strongest first
        (orders the nominal model already has at that angle excluded). Every
        channel of the part is searched: on LARA8 the kinematic error is most
        of the link channel's residual (0.7 N.m) and 5 % of the motor
        channel's (14 N.m of motor-side mismatch, broadband in the angle).
        `added`: a residual added to each named channel's (an effect planted
        by detection_limit.py)."""
        added = added or {}
        smoothed = self.prep.kin.smooth if all(c.smoothed() for c in channels) else None
        existing = eq7_orders(p) if part == "transmission" else {}
        found: dict[tuple[str, float], Order] = {}
        self._orders_seen = []
        # Per angle, what every channel's search shares: its values, filter, grid and unresolved trend.
        searched = {}
        for angle in angles:
            values = getattr(self.rec, angle)
            through = smoothed if angle == "theta_m" else None
            searched[angle] = (values, through, candidate_orders(angle, np.ptp(values)),
                               unresolved_trend(values, angle, through))
        for channel in channels:
            # Not the fit's residual, 0 where the channel is blind: a ripple's
            # prediction there counted as error (and a fold of rest, 0/0, as -1e295).
            r = self.shown_residual(channel, p) + added.get(channel.name, 0.0)
            for angle, (values, through, orders, trend) in searched.items():
                seen = []
                for o in order_search(values, r, self.fold, self.train, self.test, orders, existing.get(angle, ()),
                                      angle, through=through, seen=seen, trend=trend):
                    if (o.angle, o.order) not in found or o.gain.gain > found[o.angle, o.order].gain.gain:
                        found[o.angle, o.order] = replace(o, channel=channel.name)
                self._orders_seen += [replace(o, channel=channel.name) for o in seen]
        if not found and "theta_l" in searched:
            return self._unresolved_link_order(p, channels, existing.get("theta_l", ()), added)
        return sorted(found.values(), key=lambda o: -o.gain.gain)

    def _unresolved_link_order(self, p, channels: list[Channel], existing, added: dict) -> list[Order]:
        """With no resolved order, the lowest link order the model lacks and the
        travel does not resolve, in the channel it explains best, when it
        explains more than UNRESOLVED_GAIN there held out. The circular
        spline's run-out sits at the lowest link orders; a link that turns a
        fraction of a revolution shows it as slow structure along its angle
        (the independent truth's link order 2 over 0.38 revolutions: 24 % of
        the held-out transmission residual, left `unexplained`). It is tried
        as that order and judged pooled (structure.unresolved_order)."""
        order = lowest_unresolved_order(self.rec.theta_l, "theta_l", existing)
        if order is None:
            return []
        tried = [replace(unresolved_order(self.rec.theta_l, self.shown_residual(c, p) + added.get(c.name, 0.0),
                                          self.fold, self.train, self.test, order, "theta_l"), channel=c.name)
                 for c in channels]
        best = max(tried, key=lambda o: o.gain.gain)
        self._orders_seen += tried
        return [best] if best.gain.gain > UNRESOLVED_GAIN else []

    def _no_order_found(self, effect: Effect, channels: list[Channel]) -> None:
        """Say why an effect at angle orders was not tested: no order passed the
        order search (the strongest ones, with their held-out evidence)."""
        if any(n["effect"] == effect.id for n in self.orders_not_found):
            return  # said in the first round
        travel = {a: round(float(np.ptp(getattr(self.rec, a))) / (2 * math.pi), 3) for a in effect.order_angles}
        strongest = sorted(self._orders_seen, key=lambda o: -o.gain.z)[:3]
        self.orders_not_found.append({
            "effect": effect.id, "channel": " and ".join(c.name for c in channels), "revolutions": travel,
            "strongest": [{"angle": o.angle, "order": o.order, "amplitude": round(o.amplitude, 5),
                           "held_out_gain": round(o.gain.gain, 4), "z": round(o.gain.z, 2),
                           "prominence": round(o.prominence, 2) if math.isfinite(o.prominence) else None,
                           "channel": o.channel} for o in strongest],
            "reason": _why_no_order(effect, strongest[0] if strongest else None)})

    def _anchors(self, part: str, stateful: bool = False) -> list[str]:
        """The calibrated parameters of `part`, refitted with every hypothesis
        of that part: calibration has already absorbed what it could of the
        missing effect (a viscous term leaks into Kt and Fc), and a hypothesis
        judged against that absorption alone helps some folds and hurts the rest."""
        own = ALWAYS_CALIBRATED[part] if stateful else calibrated_parameters(part, self.nominal, self.has_sensor)
        # Terms at their own angle orders are orthogonal to every other
        # effect: left out, they make each fit much cheaper.
        skip = orthogonal_parameters()
        return [n for n in self.calibrated_names if n in own and n not in skip]

    def _correlation_length(self, p) -> int:
        """Samples over which the residual stays correlated (1/e), at most the
        smoothing window. Cached for the last parameter set: every hypothesis
        of a round reads it at the round's parameters."""
        key = tuple(sorted(p.items())) + (self.prep.current_shift,)
        if self._correlation is None or self._correlation[0] != key:
            self._correlation = (key, self._measure_correlation_length(p))
        return self._correlation[1]

    def _measure_correlation_length(self, p) -> int:
        channel = self.channels[0]
        if channel.reference == "sensor" and sharp_transmission(self.prep):
            # Before the transmission's filter, as the encoders and the sensor give it: the
            # white floor it takes away is what a fit sample's weight counts (through it, the
            # model's slow mismatch set the length, 49 samples on the paper recording, not 1).
            r = (self.rec.tau_sensor - tau_transmission(self.prep, p, sharp=False))[self.train]
        else:
            r = self.eval.residual(channel, p)[self.train]
        r = r[np.isfinite(r)] - np.nanmean(r)
        if len(r) < 10:
            return 1
        spectrum = np.fft.rfft(r, 2 * len(r))
        acf = np.fft.irfft(spectrum * np.conj(spectrum))[: min(len(r), 2000)]
        acf /= acf[0]
        below = np.flatnonzero(acf < math.exp(-1))
        length = int(below[0]) if len(below) else 2000
        # Slow structure (the very thing being tested) lengthens the
        # correlation; the noise itself is correlated only over the smoothing window.
        return max(1, min(length, self.prep.kin.smooth.window))

    def _jacobian(self, p: dict, names: list[str], channels: list[Channel]) -> np.ndarray:
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

    def _try(self, effect: Effect, p: dict) -> Hypothesis | None:
        channels = self.channels_of(effect.part)
        if not channels:
            return None
        if effect.seen_on_torsion and not self.has_sensor:
            return self._try_on_torsion(effect, p, channels)
        trial, names, orders = effect.trial(
            p, lambda q, angles: self.order_search(q, effect.part, channels, angles))
        if not names:
            if effect.order_angles:
                self._no_order_found(effect, channels)
            return None
        anchors = self._anchors(effect.part, effect.stateful)
        names_all = names + [a for a in anchors if a not in names]
        fit = self.fit(trial, names_all, channels, self._starts(effect, names), HYPOTHESIS_FTOL)
        per_before = [self.squared(p, [c]) for c in channels]
        per_after = [self.squared(fit.params, [c]) for c in channels]
        before, after = sum(per_before), sum(per_after)
        gain = held_out_gain_sq(before, after, self.fold, self.test)
        # Held-out change of each channel on its own: a real effect does not
        # make another view of the same joint worse.
        worst = max(float(np.nanmean(a[self.test]) / max(np.nanmean(b[self.test]), 1e-300))
                    for b, a in zip(per_before, per_after))
        n_eff = np.count_nonzero(self.train) / self._correlation_length(p)
        dbic = delta_bic(n_eff, np.mean(before[self.train]), np.mean(after[self.train]), len(names))
        degenerate = effect.degenerate(fit.params, self._torsion_span(p))
        if degenerate is None and effect.own_gain_checked:
            degenerate = self._borrowed_gain(effect, p, fit.params, names, channels, after)
        hypothesis = Hypothesis(effect, p, fit.params, names, gain, float(dbic), orders, worst_channel_ratio=worst,
                                degenerate=degenerate)
        # The simulated null: the same test on noise with the residual's colour,
        # the hypothesis linearised at its fit.
        rows = [self.channels.index(c) for c in channels]
        jac = self._jacobian(fit.params, names_all, channels)
        noise = self._noise.replicates(rows)
        if effect.uneven_over_folds or any(not o.resolved for o in orders):
            gain_null = null_gain(noise, jac, self.fit_index, self.fold, self.test)
            hypothesis.p_raw = p_value(gain.gain, gain_null)
            hypothesis.z_against_null = standardised(gain.gain, gain_null)
        else:
            hypothesis.p_raw = p_value(gain.z, null_z(noise, jac, self.fit_index, self.fold, self.test))
        return hypothesis

    def torsion_torque(self, p: dict) -> np.ndarray:
        """The torque the torsion is regressed on (its nuisance), as columns:
        without a sensor, the motor's estimate at both ends of the current
        alignment's interval when the recording leaves it open (a shift
        between them is nearly a mix of the two). On LARA8 joint2 the
        alignment sits anywhere in [-2, 0] ms; as it moved from -0.3 to -2.0
        ms (the channels smoothed alike), the motor estimate moved by up to
        0.67 N.m where the motor stops, and the torsion's order 2 went from
        z 5.1 to 2.9 at the same 69 % held out. Spanning the interval: z 5.9
        either way."""
        alignment = self.current_alignment
        if self.has_sensor or alignment is None or alignment["hi"] - alignment["lo"] <= 0.0:
            return np.nan_to_num(self.reference_torque(p))
        kept = self.prep.current_shift
        try:
            columns = []
            for shift in (alignment["lo"], alignment["hi"]):
                self.prep.current_shift = shift
                columns.append(np.nan_to_num(self.reference_torque(p)).copy())
        finally:
            self.prep.current_shift = kept
        return np.column_stack(columns)

    def _borrowed_gain(self, effect: Effect, p: dict, fitted: dict, names: list[str], channels: list[Channel],
                       after: np.ndarray) -> str | None:
        """Why a hypothesis's gain is not its own, or None: with its terms back
        at `p`'s values and the part's refitted parameters kept, the fit must
        predict held-out data worse by more than MIN_GAIN. On LARA8 joint1_jog
        (no torque sensor) a Dahl loop of 0.023 N.m, its interval spanning
        0, came with Kf refitted from 21500 to 9100 N.m/rad; without the loop
        the refitted set kept its whole held-out gain (56 %)."""
        without = dict(fitted, **{n: p[n] for n in names})
        own = held_out_gain_sq(self.squared(without, channels), after, self.fold, self.test)
        if own.gain > MIN_GAIN:
            return None
        moved = [n for n in fitted if n not in names and fitted[n] != p.get(n)]
        return (f"without its own terms ({', '.join(names)}) the refitted {', '.join(moved) or 'parameters'} keep "
                f"its held-out gain (the terms add {100 * own.gain:.2g} %): the gain is theirs, not {effect.id}'s")

    def _try_on_torsion(self, effect: Effect, p: dict, channels: list[Channel]) -> Hypothesis | None:
        """An effect at angle orders, without a torque sensor: its orders
        judged on the encoders' torsion less the model's own kinematic error
        (torsion_orders.py), Benjamini-Hochberg over every order tried. Without
        a sensor the torque channels compare the transmission with the motor
        and link models, whose own mismatch buries a kinematic ripple: on LARA8
        joint 2 order 2 (6e-5 rad, 1.9 N.m at K1) lay under 14 N.m of
        motor-side mismatch and 115 N.m of gravity the 4 s jog cannot confirm."""
        torsion = torsion_less_kinematic(self.prep, p)
        nuisance = torsion_nuisances(self.torsion_torque(p), self.rec.theta_l)
        tried, passing = self.torsion_orders(effect, p, torsion, nuisance, effect.order_angles)
        trial, names, chosen = effect.fill_slots(p, passing, limit=2)
        if not chosen:
            self._orders_seen = [Order(o.angle, o.order, o.amplitude, o.gain, float("nan"), TORSION_VIEW)
                                 for o in tried]
            self._no_order_found(effect, channels)
            return None
        joint = fit_orders(torsion, nuisance, [(getattr(self.rec, o.angle), o.order) for _, o in chosen],
                           self.fold, self.train, self.test)
        intervals = {}
        for (slot, o), (a, b) in zip(chosen, joint.coefficients):
            trial.update({f"{slot}_a": a, f"{slot}_b": b})
            intervals.update({f"{slot}_a": [a - o.half_width, a + o.half_width],
                              f"{slot}_b": [b - o.half_width, b + o.half_width]})
        n_eff = np.count_nonzero(self.train) / joint.correlation
        dbic = delta_bic(n_eff, joint.mse_before, joint.mse_after, len(names))
        # The part's calibrated parameters settle around it (the stiffening law turns a ripple
        # at high load into a shift of the mean torque), and then the torque views together must
        # not predict held-out data worse, as they would for a torsion ripple the gear really
        # transmits as torque (a cogging ripple), which the motor or link model then misses.
        # Pooled, as every hypothesis's gain pools them: on LARA8 joint 2 the motor view's held-out
        # error fell 33 % while the link view's, 117 N.m of gravity the nominal set lacks, rose 2.8 %.
        trial = self.fit(trial, self._anchors(effect.part), channels, ftol=HYPOTHESIS_FTOL).params
        pooled = float(np.nanmean(self.squared(trial, channels)[self.test]) /
                       max(np.nanmean(self.squared(p, channels)[self.test]), 1e-300))
        orders = [Order(o.angle, o.order, o.amplitude, o.gain, float("nan"), TORSION_VIEW) for _, o in chosen]
        return Hypothesis(effect, p, trial, names, joint.gain, float(dbic), orders, pooled_ratio=pooled,
                          p_raw=min(o.p_value for _, o in chosen), seen_on=TORSION_VIEW, intervals=intervals)

    def torsion_orders(self, effect: Effect, p: dict, torsion: np.ndarray, nuisance: np.ndarray,
                       angles: tuple[str, ...]) -> tuple[list, list]:
        """Each order of `angles` the model lacks, tried on the torsion
        (Benjamini-Hochberg over them all); and those that pass, strongest first."""
        free = {a for s, a in effect.slots if not slot_on(p, s)}
        modelled = {a: eq7_orders(p).get(a, ()) + tuple(p[f"{s}_order"] for s, angle in effect.slots
                                                         if angle == a and slot_on(p, s)) for a in angles}
        tried = []
        for angle in angles:
            values = getattr(self.rec, angle)
            if angle not in free or (angle == "theta_m" and np.ptp(values) < MIN_REVOLUTIONS * 2 * math.pi):
                continue
            orders = [k for k in candidate_orders(angle, np.ptp(values))
                      if all(abs(k - e) > 1e-9 for e in modelled[angle])]
            tried += order_evidence(torsion, nuisance, values, orders, self.fold, self.train, self.test, angle)
        for o, adjusted in zip(tried, benjamini_hochberg([o.p_raw for o in tried])):
            o.p_value = adjusted
        passing = [o for o in sorted(tried, key=lambda o: -o.gain.gain)
                   if o.p_value <= FALSE_DISCOVERY_RATE and o.gain.gain > MIN_GAIN and o.gain.z > EVIDENCE_Z]
        return tried, passing

    def _torsion_span(self, p: dict) -> float:
        """The torsion of the recording (5-95 %), rad: the smaller of what the
        reference torque would twist the flexspline by and what the encoders
        measured. On LARA8 the current's torque (mostly the motor's own
        inertia and friction) would twist it 20 times more than it turns."""
        torque = self.reference_torque(p)[self.used]
        from_torque = float(np.nanpercentile(torque, 95) - np.nanpercentile(torque, 5)) / p["Kf"]
        torsion = (self.rec.theta_m / p["N"] - self.rec.theta_l)[self.used]
        return min(from_torque, float(np.percentile(torsion, 95) - np.percentile(torsion, 5)))

    def _starts(self, effect: Effect, names: list[str]) -> tuple[dict, ...]:
        """Where a hypothesis's fit starts: its grid of starts in the first round;
        in a later round, where its fit ended in the round before (the accepted
        effect moves its optimum a little, not to another basin), which spares
        the grid's probes and most of the refinement. The stateful hypotheses'
        fits run the whole recording per evaluation: this halved their cost."""
        before = self._fitted_before.get(effect.id)
        # (Not for terms at angle orders: the order search may pick other orders.)
        if before is not None and not effect.order_angles and set(before) == set(names):
            return (before,)
        return effect.starts or ({},)

    def _try_all(self, candidates: list[Effect], p: dict) -> list[Hypothesis]:
        """Every candidate's hypothesis, fitted side by side (forked.py): the
        same results as one after the other."""
        def piece(i):
            said = len(self.orders_not_found)
            h = self._try(candidates[i], p)
            # An Effect holds functions: not pickled. What _try noted comes back with it.
            return None if h is None else replace(h, effect=None), self.orders_not_found[said:]
        # The null's noise of each channel set, made once here for every hypothesis (and forked child).
        self._noise.prepare([[self.channels.index(c) for c in self.channels_of(e.part)] for e in candidates])
        found = map_forked(piece, len(candidates), self.workers)
        for _, notes in found:  # a forked child's notes reach this process only here
            self.orders_not_found += [n for n in notes if n not in self.orders_not_found]
        tried = [replace(h, effect=e) for (h, _), e in zip(found, candidates) if h is not None]
        for h in tried:
            self._fitted_before[h.effect.id] = {n: h.params_after[n] for n in h.fitted}
        return tried

    def test_alone(self, effect: Effect, p: dict) -> Hypothesis | None:
        """One hypothesis tested on its own, as a round of `select` tests each
        (its simulated null included); its p-value is its raw one, with nothing
        to adjust over. None when this recording has no channel for it."""
        self._noise, self._noise_at = self._null_noise(p), p
        self._noise.prepare([[self.channels.index(c) for c in self.channels_of(effect.part)]])
        hypothesis = self._try(effect, p)
        if hypothesis is not None:
            hypothesis.p_value = hypothesis.p_raw
        return hypothesis

    def null_noise_at(self, p: dict) -> NullNoise:
        """The simulated null's noise at `p`: the last round's when it was made
        at this very set (a round that accepts nothing leaves the set as it
        was, and sigma is fixed after calibration), else made now. The same
        noise either way (NullNoise is seeded), its replicates already made."""
        return self._noise if self._noise is not None and self._noise_at is p else self._null_noise(p)

    def _null_noise(self, p) -> NullNoise:
        return NullNoise(np.stack([np.where(self.used, np.nan_to_num(self.normalised_residual(c, p)),
                                            0.0) for c in self.channels]), compared=self.eval.compared_by_channel())

    def testable_effects(self, p: dict) -> list[Effect]:
        """Effects the nominal set lacks that this recording can test."""
        out = []
        known = parameters.table()
        for effect in EFFECTS.values():
            if not self.channels_of(effect.part) or effect.is_on(self.nominal):
                continue
            if any(n not in known for n in effect.carries()):
                continue  # this build of the model has no terms for it
            why = testable(effect, self.prep, self.reference_torque(p))
            if why:
                self.not_testable.append({"effect": effect.id, "reason": f"not testable on this recording: {why}"})
                continue
            out.append(effect)
        return out

    def select(self, p: dict) -> tuple[dict, list[Finding]]:
        candidates = self.testable_effects(p)
        findings: list[Finding] = []
        while candidates:
            self.say(f"testing {len(candidates)} hypotheses ({', '.join(e.id for e in candidates)})")
            self._noise, self._noise_at = self._null_noise(p), p
            self._correlation_length(p)  # here, once: the forked fits of the round inherit it
            tried = self._try_all(candidates, p)
            self.last_candidates = list(candidates)
            for h, adjusted in zip(tried, benjamini_hochberg([h.p_raw for h in tried])):
                h.p_value = adjusted
            tried.sort(key=lambda h: -h.gain.gain)
            self.last_round = tried
            self.tested.append([{"effect": h.effect.id, "held_out_gain": round(h.gain.gain, 5),
                                 "z": round(h.gain.z, 2), "p_value": h.p_value, "delta_bic": round(h.delta_bic, 1),
                                 "folds_improved": f"{h.gain.folds_improved}/{h.gain.folds_compared}",
                                 **({"pooled_channel_ratio": round(h.pooled_ratio, 4)} if h.seen_on else
                                    {"worst_channel_ratio": round(h.worst_channel_ratio, 4)}),
                                 "accepted": h.accepted(), **({"degenerate": h.degenerate} if h.degenerate else {}),
                                 **({"seen_on": h.seen_on, "orders": [{"angle": o.angle, "order": o.order}
                                                                      for o in h.orders]} if h.seen_on else {}),
                                 **h.pooled_evidence()}
                                for h in tried])
            accepted = [h for h in tried if h.accepted()]
            if not accepted:
                self.unconfirmed = [h for h in tried if h.unconfirmed()]
                break
            best = accepted[0]
            others = [h for h in tried if h is not best]
            finding = finding_for(best, others)
            finding = best.effect.settle(finding, self)  # the effect's own special case, if any
            self.say(f"found {finding.effect.id} ({finding.kind}): held-out gain {100 * best.gain.gain:.1f} %, "
                     f"p = {best.p_value:.2g}")
            # Refit everything so calibration and the new terms settle together (terms seen on
            # the encoders' torsion stay as fitted there: the torque channels are blind to them).
            refitted = [] if best.seen_on else finding.fitted
            names = self.calibrated_names + self._added_names + refitted
            refit = self.fit(best.params_after, list(dict.fromkeys(names)), self.channels)
            finding.params_after = refit.params
            findings.append(finding)
            self._added_names = list(dict.fromkeys(self._added_names + refitted))
            self.last_fit = refit
            p = refit.params
            lookalike_ids = {a.effect.id for a in finding.alternatives}
            candidates = [e for e in candidates if e is not best.effect and e.id not in lookalike_ids]
        return p, findings

    def unconfirmed_structure(self) -> list[dict]:
        """The unconfirmed hypotheses of the last round, as unexplained structure in their channels."""
        return [{"channel": c.name, "feature": f"what {h.effect.id} would explain (the simulated null cannot "
                                               f"confirm it: p = {h.p_value:.2g}; record longer or a wider motion)",
                 "held_out_gain": round(h.gain.gain, 4), "z": round(h.gain.z, 1), "p_value": h.p_value,
                 "largest_at": "-"} for h in self.unconfirmed for c in self.channels_of(h.effect.part)]

    def calibration_of(self, fit: Fit, p: dict) -> dict[str, Calibrated]:
        return {n: Calibrated(n, self.nominal.get(n, parameters.table()[n].default), p[n],
                              fit.std.get(n, self.priors[n].std), self.priors[n]) for n in self.calibrated_names}

    def resized(self, calibration: dict[str, Calibrated], p: dict) -> tuple[list[Finding], list[dict]]:
        """Effects of the nominal model with a parameter beyond its tolerance,
        and needed there: held at the edge of its tolerance (the rest refitted),
        the model must predict held-out data significantly worse. A parameter
        that only wandered along a look-alike's direction (bl1 against a0 and
        Kf on a short link travel) costs nothing held out and is not a finding.
        The held fit starts at the edge of the band (RESIZE_Z tolerances).
        Returns the resized findings, and as unexplained structure the needed
        moves of harmonics the recording's travel does not resolve
        (unresolved_harmonics)."""
        moved: dict[tuple[str, bool], list[Calibrated]] = {}
        unresolved = unresolved_harmonics(self.rec, p)
        for c in calibration.values():
            effect = owner(c.name)
            if effect is not None and c.beyond_tolerance:
                moved.setdefault((effect.id, c.name in unresolved), []).append(c)
        out, unattributed = [], []
        for (effect_id, is_unresolved), params in moved.items():
            edge = {c.name: c.prior.centre + math.copysign(RESIZE_Z * c.prior.std, c.z) for c in params}
            free = [n for n in self.calibrated_names + self._added_names if n not in edge]
            # Both fits from the same start and by the same steps: only the held parameters differ.
            held = self.fit(dict(p, **edge), free, self.channels)
            unheld = self.fit(p, free + list(edge), self.channels)
            gain = held_out_gain_sq(self.squared(held.params, self.channels),
                                    self.squared(unheld.params, self.channels), self.fold, self.test)
            p_value = float(norm.sf(gain.z))
            self.say(f"{effect_id}: {', '.join(edge)} beyond tolerance; held to it, held-out gain "
                     f"{100 * gain.gain:.2f} % (z = {gain.z:.1f})")
            if not (gain.gain > MIN_GAIN and p_value <= FALSE_DISCOVERY_RATE / max(1, len(moved)) and gain.z > EVIDENCE_Z):
                continue
            if is_unresolved:
                unattributed += self._unattributed_move(EFFECTS[effect_id], params, unresolved, gain, p_value)
                continue
            out.append(self._resize_or_lookalike(Finding(
                EFFECTS[effect_id], "resized", held.params, p, [c.name for c in params], p_value,
                round(float(norm.cdf(gain.z - 2.0)), 3), resized=params, resize_gain=gain)))
        return sorted(out, key=lambda f: f.p_value), unattributed

    def _unattributed_move(self, effect: Effect, params: list[Calibrated], unresolved: dict[str, str],
                           gain, p_value: float) -> list[dict]:
        """A needed move of harmonics the travel does not resolve: structure
        the model needs, not a resized `effect` (a confident name it cannot back)."""
        moves = ", ".join(f"{c.name} {c.nominal:.2g} -> {c.estimate:.2g}" for c in params)
        why = "; and ".join(dict.fromkeys(unresolved[c.name] for c in params))  # both angles' terms may have moved
        feature = (f"what {moves} take up beyond tolerance (held to it, {100 * gain.gain:.0f} % worse held out), "
                   f"but {why}: {effect.id} is one candidate, not a finding")
        return [{"channel": c.name, "feature": feature, "held_out_gain": round(gain.gain, 4),
                 "z": round(gain.z, 1), "p_value": p_value, "largest_at": "-"}
                for c in self.channels_of(effect.part)]

    def _resize_or_lookalike(self, finding: Finding) -> Finding:
        """A resized finding, or an ambiguous one when a look-alike the model
        lacks, tested in the last round, explains at least as much held-out
        structure of the same part as the resize does. The resize is fitted
        first (calibration), so it takes what it can of the look-alike's
        structure: on backlash s0 of the independent truth `Cw` was resized
        (11.6 % held out, confidence 0.88) while the backlash hypothesis
        explained 18 % more on top of it, in too few folds to be accepted."""
        effect = finding.effect
        rivals = [h for h in self.last_round
                  if h.effect.part == effect.part and not h.degenerate
                  and effect.looks_like(h.effect)
                  and h.gain.gain >= finding.resize_gain.gain]
        if not rivals:
            return finding
        share = finding.resize_gain.gain / (finding.resize_gain.gain + sum(h.gain.gain for h in rivals))
        return replace(finding, kind="ambiguous", alternatives=rivals, confidence=round(finding.confidence * share, 3))



def _why_no_order(effect: Effect, strongest: Order | None) -> str:
    if strongest is not None and strongest.channel == TORSION_VIEW:
        return (f"on {TORSION_VIEW}, no order of " + " or ".join(effect.order_angles) + " passes (held-out gain "
                f"> {100 * MIN_GAIN:g} %, z > {EVIDENCE_Z:g}, p <= {FALSE_DISCOVERY_RATE:g} after Benjamini-Hochberg "
                f"over the orders); the "
                f"strongest, {strongest.angle} order {strongest.order:g}, has z = {strongest.gain.z:.1f}")
    why = ("no order of " + " or ".join(effect.order_angles) + f" has a significant held-out gain (z > {EVIDENCE_Z:g}, "
           f"gain > {100 * STRUCTURE_GAIN:g} %) standing out of the spectrum (prominence > {ORDER_PROMINENCE:g}) "
           "or explaining over "
           f"{100 * DOMINANT_GAIN:.0f} % of the held-out residual")
    if strongest is None:
        return why + "; the angles cover too few periods for any order"
    head = f"; the strongest, {strongest.angle} order {strongest.order:g} (z = {strongest.gain.z:.1f}),"
    if strongest.prominence <= ORDER_PROMINENCE:
        return why + (f"{head} is {strongest.prominence:.2g} times its neighbouring off-orders: broadband "
                      f"structure in the {strongest.channel} residual, not a ripple")
    return why + f"{head} stands out of the spectrum but predicts too little held out"


