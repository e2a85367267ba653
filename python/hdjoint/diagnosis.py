"""The mismatch diagnosis: calibrate, locate, name, model, show the fit.

  1. Calibrate: fit the nominal model's own parameters (those it switches
     on, plus offsets and gains) on the training folds, within physical bounds.
  2. Locate: residual channels between independent torque estimates (see
     channels.py), scanned for held-out structure over time, regime and angle.
  3. Name: forward selection over the effect library (effects.py): each
     candidate is fitted on the training folds; the best one by held-out gain
     is accepted when the gain is significant fold by fold and BIC agrees;
     repeat until nothing significant remains.
  4. Model: the accepted effects are parameters of the C++ model; the
     corrected set is written as params.json (and .ssv).
  5. Show the fit: RMS before and after on all data and on held-out folds,
     per finding; the torque estimator with nominal vs corrected parameters.
  6. Verdict: missing_physics, consistent, or unexplained (structure remains
     that no hypothesis explains, with where).
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import norm
from threadpoolctl import threadpool_limits

from . import parameters
from .channels import ESTIMATES, SMOOTHED_PARTS, Prepared, depends_on
from .effects import ALWAYS_CALIBRATED, EFFECTS, KINEMATIC_EQ7, Effect, calibrated_parameters, testable
from .recording import Recording
from .signals import folds as make_folds, kinematics, sample_windows, window_labels
from .structure import HeldOutGain, Order, held_out_gain_sq, order_search, scan

MIN_SAMPLES = 500
MIN_DURATION = 2.0
FIT_SAMPLES = 5000  # training samples a fit looks at (spread over all training blocks)
FOLDS = 40  # contiguous blocks; even ones fit, odd ones are held out
# A longer recording is analysed in FOLDS windows spread over it, this long
# in all: the diagnosis time then stops growing with the recording's length.
ANALYSED_SECONDS = 120.0


class DiagnosisError(ValueError):
    """The recording cannot be diagnosed (too short, gaps, ...)."""


@dataclass
class Channel:
    """A residual between two torque estimates: reference minus model part."""
    name: str
    reference: str  # "sensor" or a part
    part: str       # the part whose estimate is subtracted

    def parts(self) -> set[str]:
        return {self.part} | ({self.reference} - {"sensor"})


def channels_for(has_sensor: bool) -> list[Channel]:
    if has_sensor:
        return [Channel("transmission", "sensor", "transmission"), Channel("motor", "sensor", "motor"),
                Channel("link", "sensor", "link")]
    # Without a sensor the transmission (encoders) is the reference: its
    # quantisation noise is far below the motor's (current, acceleration).
    return [Channel("motor vs transmission", "motor", "transmission"),
            Channel("link vs transmission", "link", "transmission")]


def check_recording(rec: Recording) -> None:
    where = rec.path or "recording"
    if len(rec) < MIN_SAMPLES or rec.duration < MIN_DURATION:
        raise DiagnosisError(f"{where}: too short to diagnose ({len(rec)} samples, {rec.duration:.2f} s; "
                             f"need at least {MIN_SAMPLES} samples and {MIN_DURATION} s)")
    dt = np.diff(rec.time)
    step = float(np.median(dt))
    gaps = np.flatnonzero(dt > 10.0 * step)
    if len(gaps):
        g = gaps[0]
        raise DiagnosisError(f"{where}: a gap of {dt[g]:.4g} s after t = {rec.time[g]:.6g} s (line {g + 2}); "
                             f"the median step is {step:.4g} s. Split the recording at its gaps.")


class Evaluator:
    """Torque estimates and channel residuals for a parameter set, with the
    estimates of parts whose parameters did not change reused."""

    def __init__(self, prep: Prepared, channels: list[Channel]):
        self.prep = prep
        self.channels = channels
        self._cache: dict[str, tuple[tuple, np.ndarray]] = {}
        self.part_params = {part: depends_on(part) for part in ESTIMATES}

    def estimate(self, part: str, p: dict) -> np.ndarray:
        if part == "sensor":
            return self.prep.rec.tau_sensor
        key = tuple(p.get(n, 0.0) for n in self.part_params[part])
        hit = self._cache.get(part)
        if hit is not None and hit[0] == key:
            return hit[1]
        value = ESTIMATES[part](self.prep, p)
        self._cache[part] = (key, value)
        return value

    def reference(self, channel: Channel, p: dict) -> np.ndarray:
        """The channel's reference over the whole run, through the smoothing
        filter when the part it is compared with sees the world through it."""
        reference = self.estimate(channel.reference, p)
        if channel.part in SMOOTHED_PARTS and channel.reference not in SMOOTHED_PARTS:
            if channel.reference == "sensor":
                return self.prep.smoothed("tau_sensor", reference)
            return self.prep.kin.smooth(np.nan_to_num(reference))
        return reference

    def residual(self, channel: Channel, p: dict) -> np.ndarray:
        return self.reference(channel, p) - self.estimate(channel.part, p)

    def residual_at(self, channel: Channel, p: dict, index: np.ndarray) -> np.ndarray:
        """The residual at `index` only: fits look at a sample of the training
        blocks, and the part being fitted need not be evaluated elsewhere."""
        key = (id(index),) + tuple(p.get(n, 0.0) for n in self.part_params[channel.part])
        slot = f"{channel.part}@index"
        hit = self._cache.get(slot)
        if hit is None or hit[0] != key:
            hit = (key, ESTIMATES[channel.part](self.prep, p, index))
            self._cache[slot] = hit
        return self.reference(channel, p)[index] - hit[1]


@dataclass
class Fit:
    params: dict
    names: list[str]
    cost: float


@dataclass
class Finding:
    effect: Effect
    params_before: dict
    params_after: dict
    fitted: list[str]
    gain: HeldOutGain
    delta_bic: float
    runner_up: tuple[str, float] | None
    orders: list[Order] = field(default_factory=list)
    confidence: float = 0.0
    worst_channel_ratio: float = 1.0  # largest held-out MSE after/before over the effect's channels


class Diagnosis:
    """Runs the diagnosis of one recording against a nominal parameter set."""

    def __init__(self, rec: Recording, nominal: dict[str, float], progress: Callable[[str], None] | None = None):
        check_recording(rec)
        self.source = rec  # the whole recording; `rec` is what is analysed
        self.rec, starts = sample_windows(rec, ANALYSED_SECONDS, FOLDS)
        rec = self.rec
        self.nominal = dict(nominal)
        self.say = progress or (lambda message: None)
        self.started = _time.perf_counter()
        if len(starts) > 1:
            self.say(f"analysing {FOLDS} windows spread over the {self.source.duration:.0f} s recording, "
                     f"{ANALYSED_SECONDS:.0f} s in all")
        self.prep = Prepared(rec, kinematics(rec, starts=starts), rec.time - self.source.time[0], starts)
        self.has_sensor = rec.tau_sensor is not None
        self.channels = channels_for(self.has_sensor)
        self.eval = Evaluator(self.prep, self.channels)
        n = len(rec)
        # The folds: contiguous blocks, or the sampled windows themselves.
        self.fold = make_folds(n, FOLDS) if len(starts) == 1 else window_labels(n, starts)
        # Samples where the smoothing filter runs off a window's ends take no part.
        self.train = (self.fold % 2 == 0) & self.prep.kin.valid
        self.test = (self.fold % 2 == 1) & self.prep.kin.valid
        self.used = self.train | self.test
        stride = max(1, int(np.count_nonzero(self.train) // FIT_SAMPLES))
        self.fit_index = np.flatnonzero(self.train)[::stride]
        self.sigma = {c.name: 1.0 for c in self.channels}
        self.findings: list[Finding] = []
        self.not_testable: list[dict] = []
        self.calibration: dict[str, tuple[float, float]] = {}
        self.a0_shift = 0.0
        self.tested: list[dict] = []  # every hypothesis tried, per round (evidence for the report)

    def shown_residual(self, channel: Channel, p: dict) -> np.ndarray:
        """The residual for figures and figures of merit: NaN where no test looks."""
        return np.where(self.used, self.eval.residual(channel, p), np.nan)

    # ---- fitting -------------------------------------------------------------
    def _channels_of(self, part: str) -> list[Channel]:
        return [c for c in self.channels if part in c.parts()]

    def _normalised(self, p, channels, index=None) -> np.ndarray:
        out = []
        for c in channels:
            r = self.eval.residual(c, p) if index is None else self.eval.residual_at(c, p, index)
            out.append(np.where(np.isfinite(r), r / self.sigma[c.name], 1e3))
        return np.concatenate(out)

    def _squared(self, p, channels) -> np.ndarray:
        """Per-sample sum of normalised squared residuals over `channels`."""
        total = np.zeros(len(self.rec))
        for c in channels:
            r = self.eval.residual(c, p) / self.sigma[c.name]
            total += np.where(np.isfinite(r), r * r, 1e6)
        return total

    def _bounds(self, name: str, value: float, calibrating: bool) -> tuple[float, float]:
        info = parameters.table()[name]
        lo, hi = info.min, info.max
        if calibrating:
            if name == "a0":
                lo, hi = value - 0.05 + self.a0_shift, value + 0.05 + self.a0_shift
            elif name in KINEMATIC_EQ7 or name.endswith(("_a", "_b")):
                lo, hi = value - 1e-3, value + 1e-3
            elif value > 0:
                lo, hi = 0.7 * value, 1.3 * value
            elif value < 0:
                lo, hi = 1.3 * value, 0.7 * value
        return max(lo, info.min), min(hi, info.max)

    def fit(self, p: dict, names: list[str], channels: list[Channel], calibrating: set[str],
            starts: tuple[dict, ...] = ({},)) -> Fit:
        """Least squares over `names` on the training sample: a few iterations
        from each start, then the best of them to convergence."""
        full = 60 * (len(names) + 1)
        if len(starts) == 1:
            return self._least_squares(dict(p, **starts[0]), names, channels, calibrating, full)
        tries = [self._least_squares(dict(p, **start), names, channels, calibrating, 5) for start in starts]
        best = min(tries, key=lambda f: f.cost)
        if not np.isfinite(best.cost):
            return best
        return self._least_squares(best.params, names, channels, calibrating, full)

    def _least_squares(self, x0_params: dict, names: list[str], channels: list[Channel],
                       calibrating: set[str], max_nfev: int) -> Fit:
        """One bounded trust-region fit from x0_params; bounds of calibrated
        parameters are taken around their nominal values."""
        x0 = np.array([x0_params[n] for n in names], float)
        bounds = [self._bounds(n, self.nominal.get(n, x0_params[n]) if n in calibrating else x0_params[n],
                               n in calibrating) for n in names]
        lo = np.array([b[0] for b in bounds])
        hi = np.array([b[1] for b in bounds])
        x0 = np.clip(x0, lo, hi)
        scale = np.maximum(np.abs(x0), np.maximum((hi - lo) * 1e-3, 1e-12))
        scale = np.where(np.isfinite(scale), scale, 1.0)

        def residuals(z):
            trial = dict(x0_params)
            trial.update(zip(names, z * scale))
            return self._normalised(trial, channels, self.fit_index)

        try:
            # max_nfev counts steps (scipy does not count the finite-difference Jacobian's calls).
            sol = least_squares(residuals, x0 / scale, bounds=(lo / scale, hi / scale), method="trf",
                                x_scale="jac", max_nfev=max_nfev, diff_step=1e-6)
        except ValueError:
            return Fit(dict(x0_params), list(names), float("inf"))
        fitted = dict(x0_params)
        fitted.update(zip(names, sol.x * scale))
        return Fit(fitted, list(names), float(sol.cost))

    # ---- the steps -------------------------------------------------------------
    def reference_torque(self, p) -> np.ndarray:
        return self.rec.tau_sensor if self.has_sensor else self.eval.estimate("motor", p)

    def initial_offset(self, p) -> dict:
        """Place a0 so the transmission's median torsion matches the reference
        torque's: encoder zeros are arbitrary, and a singular start helps no fit."""
        from . import _core
        est = _core.compliance(parameters.for_estimator(p), self.rec.i_m, self.rec.theta_m, self.rec.theta_l)
        ref = self.reference_torque(p)
        cf, kf = p["Cf"], p["Kf"]
        ref_torsion = np.arctan(cf * ref) / (cf * kf) if cf > 1e-12 else ref / kf
        shift = float(np.nanmedian(est["dtheta_f"] - ref_torsion))
        self.a0_shift = shift
        return dict(p, a0=p["a0"] + shift)

    def calibrate(self) -> dict:
        self.say("calibrating the nominal model's parameters")
        p = self.initial_offset(self.nominal)
        names, calibrating = [], set()
        for part in ("transmission", "motor", "link"):
            if not self._channels_of(part):
                continue
            for n in calibrated_parameters(part, self.nominal, self.has_sensor):
                if n not in names:
                    names.append(n)
        calibrating.update(names)
        # Two passes: the noise scales come from the first pass's residuals.
        for _ in range(2):
            fit = self.fit(p, names, self.channels, calibrating)
            p = fit.params
            for c in self.channels:
                # Weights equalise the channels' residual levels: smoothed
                # channels have no white floor that differences would reveal.
                r = self.eval.residual(c, p)
                used = r[self.used]
                self.sigma[c.name] = max(float(np.sqrt(np.nanmean(used * used))), 1e-9)
        self.calibration = {n: (self.nominal.get(n, parameters.table()[n].default), p[n]) for n in names}
        self.calibrated_names = names
        return p

    def _order_candidates(self, p, part: str, channel: Channel) -> list[Order]:
        rec = self.rec
        r = self.eval.residual(channel, p)
        travel_m, travel_l = np.ptp(rec.theta_m), np.ptp(rec.theta_l)
        found = []
        motor_orders = [k / 2 for k in range(1, 25) if k / 2 * travel_m >= 3 * np.pi]
        exclude_m = (p["omega_w"], 2 * p["omega_w"]) if part == "transmission" else ()
        smoothed = self.prep.kin.smooth if part in SMOOTHED_PARTS else None
        found += order_search(rec.theta_m, r, self.fold, self.train, self.test, motor_orders, exclude_m, "theta_m",
                              through=smoothed)
        if part == "transmission":
            link_orders = [k for k in range(1, 41) if k * travel_l >= 3 * np.pi]
            found += order_search(rec.theta_l, r, self.fold, self.train, self.test, link_orders, (p["omega_l"],),
                                  "theta_l")
        return found

    def _candidate_params(self, effect: Effect, p: dict, channel: Channel):
        """Parameters to fit for `effect` (and the orders that define them)."""
        if effect.id == "kinematic_error":
            orders = self._order_candidates(p, "transmission", channel)
            slots = {"theta_m": ["ke_m1", "ke_m2"], "theta_l": ["ke_l1", "ke_l2"]}
            trial, names = dict(p), []
            for o in orders:
                if not slots[o.angle]:
                    continue
                slot = slots[o.angle].pop(0)
                trial[f"{slot}_order"] = o.order
                names += [f"{slot}_a", f"{slot}_b"]
            return trial, names, orders
        if effect.id == "cogging":
            orders = [o for o in self._order_candidates(p, "motor", channel) if o.angle == "theta_m"][:1]
            if not orders:
                return p, [], []
            return dict(p, cog_order=orders[0].order), ["cog_a", "cog_b"], orders
        return p, list(effect.params), []

    def _anchors(self, part: str, stateful: bool = False) -> list[str]:
        """The calibrated parameters of `part`, refitted with every hypothesis
        of that part: calibration has already absorbed what it could of the
        missing effect (a viscous term leaks into Kt and Fc), and a hypothesis
        judged against that absorption alone helps some folds and hurts the rest."""
        own = ALWAYS_CALIBRATED[part] if stateful else calibrated_parameters(part, self.nominal, self.has_sensor)
        # The eq. (7) terms are orthogonal to every other effect (they live at
        # their own angle orders): left out, they make each fit much cheaper.
        return [n for n in self.calibrated_names if n in own and n not in KINEMATIC_EQ7]

    def _n_eff(self, p) -> float:
        """Training samples divided by the residual's correlation length."""
        c = self.channels[0]
        r = self.eval.residual(c, p)[self.train]
        r = r[np.isfinite(r)] - np.nanmean(r)
        if len(r) < 10:
            return 1.0
        spectrum = np.fft.rfft(r, 2 * len(r))
        acf = np.fft.irfft(spectrum * np.conj(spectrum))[: min(len(r), 2000)]
        acf /= acf[0]
        below = np.flatnonzero(acf < math.exp(-1))
        length = int(below[0]) if len(below) else 2000
        # Slow structure (the very thing being tested) lengthens the
        # correlation; the noise itself is correlated only over the smoothing window.
        return len(r) / max(1, min(length, self.prep.kin.smooth.window))

    def _try(self, effect: Effect, p: dict) -> Finding | None:
        channels = self._channels_of(effect.part)
        if not channels:
            return None
        trial, names, orders = self._candidate_params(effect, p, channels[0])
        if not names:
            return None
        anchors = self._anchors(effect.part, effect.stateful)
        names_all = names + [a for a in anchors if a not in names]
        fit = self.fit(trial, names_all, channels, set(anchors), effect.starts or ({},))
        per_before = [self._squared(p, [c]) for c in channels]
        per_after = [self._squared(fit.params, [c]) for c in channels]
        before, after = sum(per_before), sum(per_after)
        gain = held_out_gain_sq(before, after, self.fold, self.test)
        # Held-out change of each channel on its own: a real effect does not
        # make another view of the same joint worse.
        worst = max(float(np.nanmean(a[self.test]) / max(np.nanmean(b[self.test]), 1e-300))
                    for b, a in zip(per_before, per_after))
        n_eff = self._n_eff(p)
        mse_b, mse_a = np.mean(before[self.train]), np.mean(after[self.train])
        dbic = n_eff * math.log(max(mse_a, 1e-300) / max(mse_b, 1e-300)) + len(names) * math.log(n_eff)
        return Finding(effect, p, fit.params, names, gain, float(dbic), None, orders, worst_channel_ratio=worst)

    def select(self, p: dict) -> dict:
        candidates = []
        known = parameters.table()
        for effect in EFFECTS.values():
            if not self._channels_of(effect.part) or effect.is_on(self.nominal):
                continue
            needed = effect.params or {"kinematic_error": ("ke_m1_a",), "cogging": ("cog_a",)}[effect.id]
            if any(n not in known for n in needed):
                continue  # this build of the model has no terms for it
            why = testable(effect, self.prep, self.reference_torque(p))
            if why:
                self.not_testable.append({"effect": effect.id, "reason": f"not testable on this recording: {why}"})
                continue
            candidates.append(effect)
        while candidates:
            self.say(f"testing {len(candidates)} hypotheses ({', '.join(e.id for e in candidates)})")
            tried = [f for f in (self._try(e, p) for e in candidates) if f is not None]
            tried.sort(key=lambda f: -f.gain.gain)
            self.tested.append([{"effect": f.effect.id, "held_out_gain": round(f.gain.gain, 5),
                                 "z": round(f.gain.z, 2), "delta_bic": round(f.delta_bic, 1),
                                 "accepted": _accept(f)} for f in tried])
            accepted = [f for f in tried if _accept(f)]
            if not accepted:
                break
            best = accepted[0]
            others = [f for f in tried if f is not best]
            best.runner_up = (others[0].effect.id, others[0].gain.gain) if others else None
            best.confidence = _confidence(best, others)
            self.say(f"found {best.effect.id}: held-out gain {100 * best.gain.gain:.1f} %, z = {best.gain.z:.1f}")
            # Refit everything so calibration and the new terms settle together.
            names = self.calibrated_names + [n for f in self.findings + [best] for n in f.fitted]
            names = list(dict.fromkeys(names))
            refit = self.fit(best.params_after, names, self.channels, set(self.calibrated_names))
            best.params_after = refit.params
            self.findings.append(best)
            p = refit.params
            candidates = [e for e in candidates if e is not best.effect]
        return p


def _accept(f: Finding) -> bool:
    folds_better = np.mean(f.gain.fold_gains > 0)
    return (f.gain.gain > 0.003 and f.gain.z > 3.0 and f.delta_bic < -10.0 and folds_better >= 0.7
            and f.worst_channel_ratio <= 1.0)


def _confidence(best: Finding, others: list[Finding]) -> float:
    """Significance of the held-out gain, discounted when a look-alike explains almost as much."""
    c = float(norm.cdf(best.gain.z - 2.0))
    rivals = [o for o in others if o.effect.id in best.effect.lookalikes and o.gain.gain > 0]
    if rivals:
        margin = 1.0 - max(o.gain.gain for o in rivals) / best.gain.gain
        c *= min(1.0, 0.5 + margin)
    return round(c, 3)


def diagnose(rec: Recording, nominal: dict[str, float], progress: Callable[[str], None] | None = None):
    """Run every step; returns (the Diagnosis, the findings document)."""
    # The linear algebra here is tall and thin (thousands of samples by a
    # dozen parameters): one BLAS thread is faster than several fighting
    # over two cores, by up to 7x measured on this machine under load.
    with threadpool_limits(limits=1, user_api="blas"):
        return _diagnose(rec, nominal, progress)


def _diagnose(rec: Recording, nominal: dict[str, float], progress: Callable[[str], None] | None):
    from .findings import document, remaining_structure
    diag = Diagnosis(rec, nominal, progress)
    p = diag.calibrate()
    diag.say("locating structure in the calibrated model's residuals")
    located = remaining_structure(diag, p)
    diag.calibrated_params = dict(p)
    p = diag.select(p)
    diag.say("checking what remains")
    doc = document(diag, p, remaining_structure(diag, p))
    if doc["unexplained"]:  # open-library fallback: propose terms for what no named effect explains
        from .open_library import propose_terms
        doc["proposed_terms"] = propose_terms(diag, p, doc["unexplained"])
    doc["located"] = located
    doc["seconds"] = round(_time.perf_counter() - diag.started, 2)
    return diag, doc
