"""The search stage: each effect the recording can test, tried as a
hypothesis on the calibrated model. An effect's own parameters (or the
orders the order search finds for it) are fitted with the part's calibrated
parameters; its held-out gain, BIC and channel ratios are measured, and its
p-value comes from the simulated null (the same test on noise with the
residual's colour, the hypothesis linearised at its fit). Without a torque
sensor, effects at angle orders are judged on the encoders' torsion.

A HypothesisSearch keeps what one run of the selection remembers from
round to round: where each hypothesis's fit ended (the next round starts
there), the round's null noise, and what it noted (effects not testable,
orders not found)."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from hdjoint.diagnosis.model.residual_channels import TORSION_VIEW, Channel
from hdjoint.diagnosis.effects import EFFECTS, Effect, slot_on, testable
from hdjoint.diagnosis.forked import Deferred, map_forked
from hdjoint.diagnosis.search.hypotheses import Hypothesis, delta_bic
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.diagnosis.model.torque_estimates import ESTIMATES, torsion_less_kinematic
from hdjoint.diagnosis.model.prepare import eq7_orders
from hdjoint.diagnosis.rules import (DOMINANT_GAIN, EVIDENCE_Z, FALSE_DISCOVERY_RATE, HYPOTHESIS_FTOL, MIN_GAIN,
                                     ORDER_PROMINENCE, STRUCTURE_GAIN, UNRESOLVED_GAIN)
from hdjoint.diagnosis.search.significance import (NullNoise, benjamini_hochberg, null_gain, null_noise, null_z,
                                                   p_value, standardised)
from hdjoint.diagnosis.model.structure import (Order, candidate_orders, held_out_gain_sq, lowest_unresolved_order,
                                         order_search, unresolved_order, unresolved_trend)
from hdjoint.diagnosis.search.torsion_orders import MIN_REVOLUTIONS, fit_orders, order_evidence
from hdjoint.diagnosis.search.torsion_orders import nuisances as torsion_nuisances
from hdjoint.io import parameters


@dataclass(frozen=True)
class OrderSearch:
    """The orders that passed the order search, strongest first, and every order it tried."""
    found: list[Order]
    seen: list[Order]


class HypothesisSearch:
    def __init__(self, objective: Objective, current_alignment: dict | None = None):
        self.objective = objective
        self.current_alignment = current_alignment  # calibration's (current_alignment.py)
        self.fitted_before: dict[str, dict] = {}  # each hypothesis's own parameters where its last fit ended
        self.noise: NullNoise | None = None  # the simulated null's noise of the round ...
        self.noise_at: dict | None = None    # ... and the parameter set it was made at
        self.not_testable: list[dict] = []
        self.orders_not_found: list[dict] = []  # effects at angle orders whose order search found none

    def start_round(self, p: dict) -> None:
        """A round of hypotheses at `p`: its null noise, and the residual's correlation
        measured here once (the forked fits of the round inherit both)."""
        self.noise, self.noise_at = null_noise(self.objective, p), p
        self.objective.correlation_length(p)

    def order_search(self, p, part: str, channels: list[Channel], angles: tuple[str, ...],
                     added: dict[str, np.ndarray] | None = None, every_order: bool = True) -> OrderSearch:
        """Orders of `angles` the residuals of `channels` carry, strongest first
        (orders the nominal model already has at that angle excluded). Every
        channel of the part is searched: a kinematic error can be most of one
        channel's residual and a small share of another's, where other
        mismatch broadband in the angle dominates.
        `added`: a residual added to each named channel's (an effect planted
        by detection_limit.py). Returns what passed, and every order tried
        (for saying why none passed; not with `every_order` False, which
        spares the floors of orders that cannot pass)."""
        added = added or {}
        smoothed = self.objective.prep.kin.smooth if all(c.smoothed() for c in channels) else None
        existing = eq7_orders(p) if part == "transmission" else {}
        found: dict[tuple[str, float], Order] = {}
        tried: list[Order] = []
        # Per angle, what every channel's search shares: its values, filter, grid and unresolved trend.
        searched = {}
        for angle in angles:
            values = getattr(self.objective.rec, angle)
            through = smoothed if angle == "theta_m" else None
            searched[angle] = (values, through, candidate_orders(angle, np.ptp(values)),
                               unresolved_trend(values, angle, through))
        for channel in channels:
            # Not the fit's residual, 0 where the channel is blind: a ripple's
            # prediction there would count as error (and a fold of rest, 0/0, as a huge loss).
            r = self.objective.shown_residual(channel, p) + added.get(channel.name, 0.0)
            for angle, (values, through, orders, trend) in searched.items():
                seen = [] if every_order else None
                for o in order_search(values, r, self.objective.fold, self.objective.train, self.objective.test, orders, existing.get(angle, ()),
                                      angle, through=through, seen=seen, trend=trend):
                    if (o.angle, o.order) not in found or o.gain.gain > found[o.angle, o.order].gain.gain:
                        found[o.angle, o.order] = replace(o, channel=channel.name)
                tried += [replace(o, channel=channel.name) for o in seen or ()]
        if not found and "theta_l" in searched:
            best, unresolved = self.unresolved_link_order(p, channels, existing.get("theta_l", ()), added)
            return OrderSearch(best, tried + unresolved)
        return OrderSearch(sorted(found.values(), key=lambda o: -o.gain.gain), tried)

    def unresolved_link_order(self, p, channels: list[Channel], existing, added: dict) -> tuple[list[Order], list[Order]]:
        """With no resolved order, the lowest link order the model lacks and the
        travel does not resolve, in the channel it explains best, when it
        explains more than UNRESOLVED_GAIN there held out. The circular
        spline's run-out sits at the lowest link orders; a link that turns a
        fraction of a revolution shows it as slow structure along its angle,
        which would otherwise be left `unexplained`. It is tried
        as that order and judged pooled (structure.unresolved_order). Returns
        it (or nothing) and every channel's try."""
        order = lowest_unresolved_order(self.objective.rec.theta_l, "theta_l", existing)
        if order is None:
            return [], []
        tried = [replace(unresolved_order(self.objective.rec.theta_l, self.objective.shown_residual(c, p) + added.get(c.name, 0.0),
                                          self.objective.fold, self.objective.train, self.objective.test, order, "theta_l"), channel=c.name)
                 for c in channels]
        best = max(tried, key=lambda o: o.gain.gain)
        return ([best] if best.gain.gain > UNRESOLVED_GAIN else []), tried

    def no_order_found(self, effect: Effect, channels: list[Channel], seen: list[Order]) -> None:
        """Say why an effect at angle orders was not tested: no order passed the
        order search (the strongest ones, with their held-out evidence)."""
        if any(n["effect"] == effect.id for n in self.orders_not_found):
            return  # said in the first round
        travel = {a: round(float(np.ptp(getattr(self.objective.rec, a))) / (2 * math.pi), 3) for a in effect.order_angles}
        strongest = sorted(seen, key=lambda o: -o.gain.z)[:3]
        self.orders_not_found.append({
            "effect": effect.id, "channel": " and ".join(c.name for c in channels), "revolutions": travel,
            "strongest": [{"angle": o.angle, "order": o.order, "amplitude": round(o.amplitude, 5),
                           "held_out_gain": round(o.gain.gain, 4), "z": round(o.gain.z, 2),
                           "prominence": round(o.prominence, 2) if math.isfinite(o.prominence) else None,
                           "channel": o.channel} for o in strongest],
            "reason": _why_no_order(effect, strongest[0] if strongest else None)})

    def try_effect(self, effect: Effect, p: dict) -> Hypothesis | None:
        channels = self.objective.channels_of(effect.part)
        if not channels:
            return None
        if effect.seen_on_torsion and not self.objective.has_sensor:
            return self.try_on_torsion(effect, p, channels)
        seen: list[Order] = []

        def search(q, angles):
            result = self.order_search(q, effect.part, channels, angles)
            seen[:] = result.seen
            return result.found

        trial, names, orders = effect.trial(p, search)
        if not names:
            if effect.order_angles:
                self.no_order_found(effect, channels, seen)
            return None
        anchors = self.objective.anchors(effect.part, effect.stateful)
        names_all = names + [a for a in anchors if a not in names]
        fit = self.objective.fit(trial, names_all, channels, self.starts(effect, names), HYPOTHESIS_FTOL)
        per_before = [self.objective.squared(p, [c]) for c in channels]
        per_after = [self.objective.squared(fit.params, [c]) for c in channels]
        before, after = sum(per_before), sum(per_after)
        gain = held_out_gain_sq(before, after, self.objective.fold, self.objective.test)
        # Held-out change of each channel on its own: a real effect does not
        # make another view of the same joint worse.
        worst = max(float(np.nanmean(a[self.objective.test]) / max(np.nanmean(b[self.objective.test]), 1e-300))
                    for b, a in zip(per_before, per_after))
        n_eff = np.count_nonzero(self.objective.train) / self.objective.correlation_length(p)
        dbic = delta_bic(n_eff, np.mean(before[self.objective.train]), np.mean(after[self.objective.train]), len(names))
        degenerate = effect.degenerate(fit.params, self.objective.recording_scale(p))
        if degenerate is None and effect.own_gain_checked:
            degenerate = self.borrowed_gain(effect, p, fit.params, names, channels, after)
        hypothesis = Hypothesis(effect, p, fit.params, names, gain, float(dbic), orders, worst_channel_ratio=worst,
                                degenerate=degenerate)
        # The simulated null: the same test on noise with the residual's colour,
        # the hypothesis linearised at its fit.
        rows = [self.objective.channels.index(c) for c in channels]
        jac = self.objective.jacobian(fit.params, names_all, channels)
        noise = self.noise.replicates(rows)
        if effect.uneven_over_folds or any(not o.resolved for o in orders):
            gain_null = null_gain(noise, jac, self.objective.fit_index, self.objective.fold, self.objective.test)
            hypothesis.p_raw = p_value(gain.gain, gain_null)
            hypothesis.z_against_null = standardised(gain.gain, gain_null)
        else:
            hypothesis.p_raw = p_value(gain.z, null_z(noise, jac, self.objective.fit_index, self.objective.fold, self.objective.test))
        return hypothesis

    def torsion_torque(self, p: dict) -> np.ndarray:
        """The torque the torsion is regressed on (its nuisance), as columns:
        without a sensor, the motor's estimate at both ends of the current
        alignment's interval when the recording leaves it open (a shift
        between them is nearly a mix of the two). Where the recording leaves
        the alignment open, the motor estimate moves with it where the motor
        stops, and an order's z with it; spanning the interval makes the
        test independent of where in it the alignment sits."""
        alignment = self.current_alignment
        if self.objective.has_sensor or alignment is None or alignment["hi"] - alignment["lo"] <= 0.0:
            return np.nan_to_num(self.objective.reference_torque(p))
        # The motor's estimate (the reference without a sensor) at each end, on a copy of the prepared recording.
        return np.column_stack([np.nan_to_num(ESTIMATES["motor"](replace(self.objective.prep, current_shift=shift), p))
                                for shift in (alignment["lo"], alignment["hi"])])

    def borrowed_gain(self, effect: Effect, p: dict, fitted: dict, names: list[str], channels: list[Channel],
                       after: np.ndarray) -> str | None:
        """Why a hypothesis's gain is not its own, or None: with its terms back
        at `p`'s values and the part's refitted parameters kept, the fit must
        predict held-out data worse by more than MIN_GAIN: otherwise the gain
        comes from the refitted parameters (a softer Kf, say) and a negligible
        term of the effect rides along."""
        without = dict(fitted, **{n: p[n] for n in names})
        own = held_out_gain_sq(self.objective.squared(without, channels), after, self.objective.fold, self.objective.test)
        if own.gain > MIN_GAIN:
            return None
        moved = [n for n in fitted if n not in names and fitted[n] != p.get(n)]
        return (f"without its own terms ({', '.join(names)}) the refitted {', '.join(moved) or 'parameters'} keep "
                f"its held-out gain (the terms add {100 * own.gain:.2g} %): the gain is theirs, not {effect.id}'s")

    def try_on_torsion(self, effect: Effect, p: dict, channels: list[Channel]) -> Hypothesis | None:
        """An effect at angle orders, without a torque sensor: its orders
        judged on the encoders' torsion less the model's own kinematic error
        (torsion_orders.py), Benjamini-Hochberg over every order tried. Without
        a sensor the torque channels compare the transmission with the motor
        and link models, whose own mismatch (motor-side, and gravity a short
        recording cannot confirm) buries a kinematic ripple
        (benchmarks/torsion_view.py measures this test)."""
        torsion = torsion_less_kinematic(self.objective.prep, p)
        nuisance = torsion_nuisances(self.torsion_torque(p), self.objective.rec.theta_l)
        tried, passing = self.torsion_orders(effect, p, torsion, nuisance, effect.order_angles)
        trial, names, chosen = effect.fill_slots(p, passing, limit=2)
        if not chosen:
            self.no_order_found(effect, channels, [Order(o.angle, o.order, o.amplitude, o.gain, float("nan"),
                                                         TORSION_VIEW) for o in tried])
            return None
        joint = fit_orders(torsion, nuisance, [(getattr(self.objective.rec, o.angle), o.order) for _, o in chosen],
                           self.objective.fold, self.objective.train, self.objective.test)
        intervals = {}
        for (slot, o), (a, b) in zip(chosen, joint.coefficients):
            trial.update({f"{slot}_a": a, f"{slot}_b": b})
            intervals.update({f"{slot}_a": [a - o.half_width, a + o.half_width],
                              f"{slot}_b": [b - o.half_width, b + o.half_width]})
        n_eff = np.count_nonzero(self.objective.train) / joint.correlation
        dbic = delta_bic(n_eff, joint.mse_before, joint.mse_after, len(names))
        # The part's calibrated parameters settle around it (the stiffening law turns a ripple
        # at high load into a shift of the mean torque), and then the torque views together must
        # not predict held-out data worse, as they would for a torsion ripple the gear really
        # transmits as torque (a cogging ripple), which the motor or link model then misses.
        # Pooled, as every hypothesis's gain pools them: one view's error can fall while another's,
        # carrying a mismatch such as gravity the nominal set lacks, rises slightly.
        trial = self.objective.fit(trial, self.objective.anchors(effect.part), channels, ftol=HYPOTHESIS_FTOL).params
        pooled = float(np.nanmean(self.objective.squared(trial, channels)[self.objective.test]) /
                       max(np.nanmean(self.objective.squared(p, channels)[self.objective.test]), 1e-300))
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
            values = getattr(self.objective.rec, angle)
            if angle not in free or (angle == "theta_m" and np.ptp(values) < MIN_REVOLUTIONS * 2 * math.pi):
                continue
            orders = [k for k in candidate_orders(angle, np.ptp(values))
                      if all(abs(k - e) > 1e-9 for e in modelled[angle])]
            tried += order_evidence(torsion, nuisance, values, orders, self.objective.fold, self.objective.train, self.objective.test, angle)
        for o, adjusted in zip(tried, benjamini_hochberg([o.p_raw for o in tried])):
            o.p_value = adjusted
        passing = [o for o in sorted(tried, key=lambda o: -o.gain.gain)
                   if o.p_value <= FALSE_DISCOVERY_RATE and o.gain.gain > MIN_GAIN and o.gain.z > EVIDENCE_Z]
        return tried, passing

    def starts(self, effect: Effect, names: list[str]) -> tuple[dict, ...]:
        """Where a hypothesis's fit starts: its grid of starts in the first round;
        in a later round, where its fit ended in the round before (the accepted
        effect moves its optimum a little, not to another basin), which spares
        the grid's probes and most of the refinement. The stateful hypotheses'
        fits run the whole recording per evaluation: this halved their cost."""
        before = self.fitted_before.get(effect.id)
        # (Not for terms at angle orders: the order search may pick other orders.)
        if before is not None and not effect.order_angles and set(before) == set(names):
            return (before,)
        return effect.starts or ({},)

    def try_all(self, candidates: list[Effect], p: dict, beside: Deferred | None = None) -> list[Hypothesis]:
        """Every candidate's hypothesis, fitted side by side (forked.py): the
        same results as one after the other. `beside`: computed with them."""
        def piece(i):
            said = len(self.orders_not_found)
            h = self.try_effect(candidates[i], p)
            # The effect goes back by its place in the list (a forked copy is not the library's); what the
            # try noted comes back with it.
            return None if h is None else replace(h, effect=None), self.orders_not_found[said:]
        # The null's noise of each channel set, made once here for every hypothesis (and forked child).
        self.noise.prepare([[self.objective.channels.index(c) for c in self.objective.channels_of(e.part)]
                            for e in candidates])
        found = map_forked(piece, len(candidates), self.objective.workers, beside)
        for _, notes in found:  # a forked child's notes reach this process only here
            self.orders_not_found += [n for n in notes if n not in self.orders_not_found]
        tried = [replace(h, effect=e) for (h, _), e in zip(found, candidates) if h is not None]
        for h in tried:
            self.fitted_before[h.effect.id] = {n: h.params_after[n] for n in h.fitted}
        return tried

    def test_alone(self, effect: Effect, p: dict) -> Hypothesis | None:
        """One hypothesis tested on its own, as a round of `select` tests each
        (its simulated null included); its p-value is its raw one, with nothing
        to adjust over. None when this recording has no channel for it."""
        self.start_round(p)
        self.noise.prepare([[self.objective.channels.index(c) for c in self.objective.channels_of(effect.part)]])
        hypothesis = self.try_effect(effect, p)
        if hypothesis is not None:
            hypothesis.p_value = hypothesis.p_raw
        return hypothesis

    def null_noise_at(self, p: dict) -> NullNoise:
        """The simulated null's noise at `p`: the last round's when it was made
        at this very set (a round that accepts nothing leaves the set as it
        was, and sigma is fixed after calibration), else made now. The same
        noise either way (NullNoise is seeded), its replicates already made."""
        return self.noise if self.noise is not None and self.noise_at is p else null_noise(self.objective, p)

    def testable_effects(self, p: dict) -> list[Effect]:
        """Effects the nominal set lacks that this recording can test."""
        out = []
        known = parameters.table()
        for effect in EFFECTS.values():
            if not self.objective.channels_of(effect.part) or effect.is_on(self.objective.nominal):
                continue
            if any(n not in known for n in effect.carries()):
                continue  # this build of the model has no terms for it
            why = testable(effect, self.objective.prep, self.objective.reference_torque(p))
            if why:
                self.not_testable.append({"effect": effect.id, "reason": f"not testable on this recording: {why}"})
                continue
            out.append(effect)
        return out


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


