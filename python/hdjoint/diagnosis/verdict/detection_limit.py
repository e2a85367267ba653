"""The smallest size of each untold effect this recording would have shown.

`consistent` says nothing is missing, but only as far as the recording can
tell. An effect small against the torques a recording carries looks like
a slight change of the calibrated parameters (a wave-generator compliance
like a softer flexspline, which Kf and Cf take) and is not named
(benchmarks/effect_detectability.py asks whether missed effects could
have been found). A verdict should say that, and how large the effect must
be to show.

For every effect the last round tested without accepting it, the effect is
planted into the corrected model at sizes around a reference (Effect.size),
and the diagnosis's own test is run on what it would add:

  - its signature: the change of the normalised residuals the effect makes;
  - what calibration would take of it: the signature's least-squares fit by
    the part's calibrated parameters on the training rows (their Jacobian,
    as each hypothesis refits them), removed;
  - the rest added to the recording's own residual and taken away by the
    effect's fit (on its own, as if independent of the residual, it must
    also explain over MIN_GAIN of it: planted_gains): held-out gain, fold
    z and the p-value against the simulated null, with the acceptance
    rules of a hypothesis (rules.passes: gain over MIN_GAIN, z over
    EVIDENCE_Z over STEADY_FOLD_SHARE of the folds, or pooled against the
    null for an effect uneven over the folds; p within the false discovery
    rate).

An effect at angle orders (the kinematic error) is planted at the one order
its Size states, in a free slot, and the calibrated terms of eq. (7) join
what calibration takes: over a short travel, link order 1 takes most of a
link order 2. It shows when the diagnosis's order search,
run on the residual with what is left of it, finds an order of its angle
and the test above passes; or when calibration would move a term of eq.
(7) from within its tolerance to beyond it (the diagnosis reports that
move). Without a torque sensor the orders are judged on the encoders'
torsion, as the diagnosis judges them (HypothesisSearch.torsion_orders).

The smallest such size (searched from the reference down or up by factors
of 2 over 2^-10 .. 2^10, refined to 2^(1/4)) is the recording's detection limit for that effect. Idealised: the
effect's fit is taken to find its exact terms, and the correction over the
round's hypotheses is left out, so a limit is a lower bound. When the limit
lies beyond the reference size and the reference has a source, the
recording cannot tell an effect that large: `cannot_tell` says so, with
what to record."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hdjoint.io import parameters
from hdjoint.diagnosis.model.torque_estimates import torsion_less_kinematic
from hdjoint.diagnosis.rules import MIN_GAIN, RESIZE_Z, passes
from hdjoint.diagnosis.effects import Effect, slot_on
from hdjoint.diagnosis.forked import Deferred, map_forked
from hdjoint.diagnosis.search.significance import null_gain, null_z, p_value
from hdjoint.diagnosis.model.structure import held_out_gain_sq
from hdjoint.diagnosis.search.torsion_orders import nuisances as torsion_nuisances

COARSE = 2.0      # the size grid's step, then refined by halving its exponent twice
SMALLEST, LARGEST = 1.0 / 1024.0, 1024.0  # sizes searched, as multiples of the reference


@dataclass
class Limit:
    effect: str
    parameter: str
    reference: float      # the parameter at the reference size
    limit: float | None   # the parameter at the smallest size shown (None: not even at LARGEST)
    factor: float | None  # that size over the reference size
    grows: float          # the effect grows with parameter**grows (Effect.size)
    sourced: str          # where the reference comes from ("": no claim about typical sizes)
    at: tuple[str, float] | None = None  # (angle, order) an effect at angle orders was planted at
    # The effect's other terms it was planted with (the reference's, else the table's defaults): a
    # limit holds for that shape (a Stribeck rise over its omega_s), not for every form of the effect.
    shape: tuple[tuple[str, float], ...] = ()

    def as_dict(self) -> dict:
        unit = parameters.table()[self.parameter].unit
        out = {"effect": self.effect, "parameter": self.parameter, "unit": unit,
               "reference": self.reference, "limit": _rounded(self.limit),
               "times_reference": _rounded(self.factor)}
        if self.at:
            out["orders"] = [list(self.at)]  # as a finding's orders
        if self.shape:
            out["with"] = dict(self.shape)
        if self.sourced:
            out["reference_source"] = self.sourced
        return out

    def hides_reference(self) -> bool:
        """An effect as large as the sourced reference would not have shown."""
        return bool(self.sourced) and (self.factor is None or self.factor > 1.0)

    def sentence(self) -> str:
        where = f"at {self.at[0]} order {self.at[1]:g}, " if self.at else ""
        where += f"with {parameters.values_in_text(dict(self.shape), described=True)}, " if self.shape else ""
        size = size_in_words(self.parameter, bool(self.at))
        unit = parameters.unit_in_text(parameters.table()[self.parameter].unit)
        reference = f"{self.reference:.3g}{unit}{', ' + self.sourced if self.sourced else ''}"
        if self.limit is None:
            return (f"{where}it would not show at any size up to {LARGEST:g} times the reference "
                    f"({size} of {reference}) within the parameter's valid range")
        return (f"{where}it shows only from {size} of {self.limit:.3g}{unit} ({self.factor:.2g} "
                f"times the reference, {reference})")


def size_in_words(parameter: str, in_a_slot: bool) -> str:
    """What an effect's size is, for a person: 'a Stribeck friction Fs'. An
    effect at an angle order is planted in a slot whose symbol (ke_l1_a)
    means nothing outside the model: its role says it ('a cosine amplitude')."""
    if in_a_slot:
        return "a " + parameters.table()[parameter].description.split(": ", 1)[-1].split(" (")[0]
    return f"a {parameters.meaning(parameter)} {parameter}"


def planted_shape(effect: Effect, reference: dict) -> tuple[tuple[str, float], ...]:
    """The effect's terms other than its size that shape it, as planted (those switched off left out)."""
    return tuple((n, float(reference[n])) for n in effect.params if n != effect.size.parameter and reference[n] != 0.0)


def _rounded(x: float | None) -> float | None:
    return None if x is None else float(f"{x:.4g}")


def planted_slot(effect: Effect) -> tuple[str, str] | None:
    """(slot, angle) of an effect at angle orders whose Size plants it in that slot."""
    return next(((slot, angle) for slot, angle in effect.slots if effect.size.parameter.startswith(slot + "_")), None)


def _planted_at(effect: Effect, reference: dict) -> tuple[str, float] | None:
    """(angle, order) the effect is planted at, or None for an effect not at angle orders."""
    slot = planted_slot(effect)
    return (slot[1], reference[f"{slot[0]}_order"]) if slot else None


def reference_set(effect: Effect, p: dict) -> dict:
    """`p` with the effect at its reference size: the stated values, and the
    table's defaults for the rest of its parameters."""
    table = parameters.table()
    names = dict.fromkeys(effect.params + (effect.size.parameter,))
    out = dict(p, **{n: table[n].default for n in names})
    out.update(dict(effect.size.reference))
    return out


def at_size(effect: Effect, reference: dict, factor: float) -> dict:
    name = effect.size.parameter
    return dict(reference, **{name: reference[name] * factor ** effect.size.grows})


def in_range(effect: Effect, reference: dict, factor: float) -> bool:
    """The effect at this size is a valid parameter set (backlash stops at 0.01 rad, a warm-up at -50 %)."""
    name = effect.size.parameter
    info = parameters.table()[name]
    return info.min <= at_size(effect, reference, factor)[name] <= info.max


def planted_gains(base: np.ndarray, left: np.ndarray, fold: np.ndarray, test: np.ndarray):
    """Held-out gains of taking away what is `left` of a planted effect from
    the residual `base` + `left` (channels x samples, normalised): with what
    the residual already holds (their cross term: an effect of the same
    sign hidden there adds to it, as a real one would), and on its own (as
    if independent of the residual). The effect shows only if it passes the
    test with the first and explains over MIN_GAIN with the second: with the
    first alone, a negligible planting would "show" through its cross term
    with a larger effect the residual already hides."""
    after = np.sum(base ** 2, axis=0)
    return (held_out_gain_sq(np.sum((base + left) ** 2, axis=0), after, fold, test),
            held_out_gain_sq(after + np.sum(left ** 2, axis=0), after, fold, test))


def _anchor_fit(jacobian: np.ndarray, rows) -> tuple[np.ndarray, np.ndarray]:
    """The anchors' Jacobian (channels x samples x anchors) and its least-squares
    solve on the fit's rows (lstsq's pseudo-inverse, cut-off and all), made
    once: every size a limit tries fits its planting by the same columns."""
    a = jacobian[:, rows, :].reshape(-1, jacobian.shape[2])
    return jacobian, np.linalg.pinv(a, rcond=np.finfo(float).eps * max(a.shape))


class _Planting:
    """One effect planted into the corrected set `p` of a diagnosis at any size."""

    def __init__(self, search, effect: Effect, p: dict, shared: dict):
        """`shared`: what every effect's planting on this set reads (the null's noise, the anchors' Jacobians)."""
        self.search, self.effect, self.p = search, effect, p
        self.channels = search.objective.channels_of(effect.part)
        self.base = self._residuals(p)
        anchors = search.objective.anchors(effect.part, effect.stateful) + _orders_calibrated(search, effect)
        self.anchors = anchors
        key = (effect.part, tuple(anchors))
        if key not in shared:
            shared[key] = _anchor_fit(search.objective.jacobian(p, anchors, self.channels), search.objective.fit_index) \
                if anchors else (None, None)
        self.anchor_jacobian, self.anchor_solve = shared[key]
        self.reference = reference_set(effect, p)
        # The null: the effect's own parameters and the anchors, linearised at the reference size.
        slot = planted_slot(effect)
        self.at = _planted_at(effect, self.reference)
        own = list(effect.params) + ([f"{slot[0]}_a", f"{slot[0]}_b"] if slot else [])
        names = list(dict.fromkeys(own + anchors))
        jacobian = search.objective.jacobian(self.reference, names, self.channels)
        rows = [search.objective.channels.index(c) for c in self.channels]
        if "noise" not in shared:
            shared["noise"] = search.null_noise_at(p)
        noise = shared["noise"].replicates(rows)
        if effect.uneven_over_folds:
            self.null = null_gain(noise, jacobian, search.objective.fit_index, search.objective.fold, search.objective.test)
        else:
            self.null = null_z(noise, jacobian, search.objective.fit_index, search.objective.fold, search.objective.test)

    def _residuals(self, q: dict) -> np.ndarray:
        d = self.search
        return np.stack([np.where(d.objective.used, np.nan_to_num(d.objective.normalised_residual(c, q)), 0.0)
                         for c in self.channels])

    def _calibrated(self, signature: np.ndarray) -> tuple[np.ndarray, dict]:
        """What calibration would leave of the signature, and the moves of the anchors that take the rest."""
        if self.anchor_jacobian is None:
            return signature, {}
        coef = self.anchor_solve @ signature[:, self.search.objective.fit_index].ravel()
        # The residual base + signature + J @ move is least with move = -coef.
        return signature - np.einsum("csk,k->cs", self.anchor_jacobian, coef), dict(zip(self.anchors, -coef))

    def shown(self, factor: float) -> bool:
        d = self.search
        # What the effect adds to the residual of a model that lacks it.
        signature = self.base - self._residuals(at_size(self.effect, self.reference, factor))
        left, moves = self._calibrated(signature)
        if self.at is not None and resized(d, self.effect, self.p, moves):
            return True
        combined, alone = planted_gains(self.base, left, d.objective.fold, d.objective.test)
        shown = alone.gain > MIN_GAIN and self._passes(combined)
        return shown and (self.at is None or self._order_found(left))

    def _passes(self, gain) -> bool:
        """A hypothesis's acceptance rules, on the planting's held-out gain."""
        if gain.gain <= MIN_GAIN:
            return False  # no need to read the null
        uneven = self.effect.uneven_over_folds
        return passes(gain, p_value(gain.gain if uneven else gain.z, self.null), uneven)

    def _order_found(self, left: np.ndarray) -> bool:
        """The diagnosis's order search, run on the residual with the ripple
        left in, finds an order of its angle (the effect is then tested
        there). Without this gate a planted ripple would show at sizes far
        below what the diagnosis finds: over a fraction of a period the
        search reads slow structure along the angle, beside a polynomial
        trend, and only when it is most of the residual."""
        d, angle = self.search, self.at[0]
        added = {c.name: left[i] * d.objective.noise_scale(c, self.p) for i, c in enumerate(self.channels)}
        found = d.order_search(self.p, self.effect.part, self.channels, (angle,), added=added, every_order=False).found
        return any(o.angle == angle for o in found)


def _moved(search, effect: Effect, p: dict) -> bool:
    """Calibration took one of the effect's terms beyond its tolerance. The
    route by which a resized term shows the effect is then closed, and what
    the term took cannot be told from the ripple: no limit is claimed. Where
    the move is needed held out the diagnosis says so (a resized finding, or
    unexplained structure when the travel does not resolve the harmonic),
    and a limit beside it would contradict that move."""
    return any(_tolerances(search, n, p[n]) > RESIZE_Z
               for n in effect.resizes if n in search.objective.priors and n in search.objective.calibrated_names)


def _tolerances(search, name: str, value: float) -> float:
    """How many tolerances `value` lies from the parameter's prior centre."""
    return abs(value - search.objective.priors[name].centre) / search.objective.priors[name].std


def resized(search, effect: Effect, p: dict, moves: dict) -> bool:
    """Calibration's moves would take one of the effect's own terms (eq. (7)
    for the kinematic error), within its tolerance in `p`, beyond it: the
    diagnosis then reports it (a resized finding, or unexplained structure
    when the travel does not resolve that harmonic), so the effect shows."""
    return any(_tolerances(search, n, p[n]) <= RESIZE_Z < _tolerances(search, n, p[n] + m)
               for n, m in moves.items() if n in effect.resizes and n in search.objective.priors)


def _orders_calibrated(search, effect: Effect) -> list[str]:
    """An effect at angle orders: the calibrated terms of the orders the model
    has (eq. (7)), which calibration refits beside it. Every other effect
    leaves them out as orthogonal (Objective.anchors); to a ripple at
    another order of the same angle over a short travel they are not."""
    return [n for n in search.objective.calibrated_names if n in effect.resizes] if effect.order_angles else []


class _TorsionPlanting:
    """A ripple planted at one angle order of a recording without a torque
    sensor, judged on the encoders' torsion (HypothesisSearch.try_on_torsion)."""

    def __init__(self, search, effect: Effect, p: dict):
        self.search, self.effect, self.p = search, effect, p
        self.reference = reference_set(effect, p)
        self.at = _planted_at(effect, self.reference)
        self.base = torsion_less_kinematic(search.objective.prep, p)
        self.nuisance = torsion_nuisances(search.torsion_torque(p), search.objective.rec.theta_l)
        # The torsion's columns of eq. (7)'s calibrated terms (linear in them): what calibration would take.
        # base + signature - columns @ move is least with move = the signature's fit by the columns.
        self.names, step = _orders_calibrated(search, effect), 1e-4
        columns = [(self.base - torsion_less_kinematic(search.objective.prep, dict(p, **{n: p[n] + step}))) / step
                   for n in self.names]
        self.columns = np.column_stack(columns) if columns else None
        self.fit_rows = search.objective.train & np.isfinite(self.base)

    def shown(self, factor: float) -> bool:
        d = self.search
        # The ripple the model lacks: the torsion a model with it would leave less.
        signature = self.base - torsion_less_kinematic(d.objective.prep, at_size(self.effect, self.reference, factor))
        if self.columns is not None:
            rows = self.fit_rows
            coef = np.linalg.lstsq(self.columns[rows], signature[rows], rcond=None)[0]
            signature = signature - self.columns @ coef
            if resized(d, self.effect, self.p, dict(zip(self.names, coef))):
                return True
        _, passing = d.torsion_orders(self.effect, self.p, self.base + signature, self.nuisance, (self.at[0],))
        return bool(passing)  # an order of its angle: the effect is tested there


def smallest_shown(search, effect: Effect, p: dict, shared: dict | None = None) -> Limit:
    """Down from the reference size while it shows, else up until it does;
    then the step refined between the last size not shown and the first shown."""
    if effect.seen_on_torsion and not search.objective.has_sensor:
        planting = _TorsionPlanting(search, effect, p)
    else:
        planting = _Planting(search, effect, p, {} if shared is None else shared)
    at = planting.at
    name = effect.size.parameter
    ref = planting.reference[name]
    found = None
    if planting.shown(1.0):
        found = 1.0
        while found / COARSE >= SMALLEST and planting.shown(found / COARSE):
            found /= COARSE
    else:
        factor = COARSE
        while factor <= LARGEST and in_range(effect, planting.reference, factor) and found is None:
            found = factor if planting.shown(factor) else None
            factor *= COARSE
    shape = planted_shape(effect, planting.reference)
    if found is None:
        return Limit(effect.id, name, ref, None, None, effect.size.grows, effect.size.source, at, shape)
    step = COARSE
    for _ in range(2):
        step = step ** 0.5
        if found / step >= SMALLEST and planting.shown(found / step):
            found /= step
    return Limit(effect.id, name, ref, at_size(effect, planting.reference, found)[name], found, effect.size.grows,
                 effect.size.source, at, shape)


def untold_effects(search, selection, told: set[str] = frozenset()) -> list[Effect]:
    """The effects detection_limits measures (see there)."""
    p = selection.params
    accepted = {h.effect.id for h in selection.last_round if h.accepted()} | set(told)
    return [e for e in selection.last_candidates if e.id not in accepted and e.size is not None
            and not (planted_slot(e) and (slot_on(p, planted_slot(e)[0]) or _moved(search, e, p)))]


def detection_limits(search, selection, told: set[str] = frozenset(), beside: Deferred | None = None) -> list[Limit]:
    """The limit of each effect the last round tested and did not accept (an
    effect at angle orders also when its search found no order), nor named
    in a finding (`told`: a resized one, a look-alike); an effect at angle
    orders not when its slot is in use or its terms moved (_moved). The
    effects side by side in forked processes (forked.py: the same limits),
    `beside` computed with them."""
    p = selection.params
    effects = untold_effects(search, selection, told)
    shared: dict = {}  # in one process, the effects of a part share the anchors' Jacobian
    return map_forked(lambda i: smallest_shown(search, effects[i], p, shared), len(effects), search.objective.workers,
                      beside)
