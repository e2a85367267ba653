"""The smallest size of each untold effect this recording would have shown.

`consistent` says nothing is missing, but only as far as the recording can
tell. On the independent truth's joints a wave-generator compliance (Kw 40,
Cw 10) came out `consistent` on every seed: over the +-4.4 N.m those
recordings carry, it is a 2.5 % softer flexspline and a curvature of a
seventh of an encoder count, which Kf and Cf take. Its own terms, fitted
from the truth's values, gained under 0.8 % held out (effect_detectability.md).
A verdict should say that, and how large the effect must be to show.

For every effect the last round tested without accepting it (and that does
not sit at angle orders: those say which orders their search saw), the
effect is planted into the corrected model at sizes around a reference
(Effect.size), and the diagnosis's own test is run on what it would add:

  - its signature: the change of the normalised residuals the effect makes;
  - what calibration would take of it: the signature's least-squares fit by
    the part's calibrated parameters on the training rows (their Jacobian,
    as each hypothesis refits them), removed;
  - the rest added to the recording's own residual and taken away by the
    effect's fit: held-out gain, fold z and the p-value against the
    simulated null, with the acceptance rules of a hypothesis (gain > 0.3 %,
    z > 3 over >= 70 % of the folds, or pooled against the null for an
    effect uneven over the folds; p <= the false discovery rate).

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

from . import parameters
from .effects import Effect
from .forked import map_forked
from .diagnosis import MIN_GAIN, steady_over_folds
from .significance import FALSE_DISCOVERY_RATE, null_gain, null_z, p_value
from .structure import held_out_gain_sq

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

    def as_dict(self) -> dict:
        unit = parameters.table()[self.parameter].unit
        out = {"effect": self.effect, "parameter": self.parameter, "unit": unit,
               "reference": self.reference, "limit": _rounded(self.limit),
               "times_reference": _rounded(self.factor)}
        if self.sourced:
            out["reference_source"] = self.sourced
        return out

    def hides_reference(self) -> bool:
        """An effect as large as the sourced reference would not have shown."""
        return bool(self.sourced) and (self.factor is None or self.factor > 1.0)

    def sentence(self) -> str:
        if self.limit is None:
            return (f"it would not show at any size up to {LARGEST:g} times the reference "
                    f"({self.parameter} = {self.reference:.3g}) within the parameter's valid range")
        unit = _unit(self.parameter)
        return (f"it shows only from a size of {self.parameter} = {self.limit:.3g}{unit} ({self.factor:.2g} "
                f"times the size at {self.parameter} = {self.reference:.3g}"
                f"{', ' + self.sourced if self.sourced else ''})")


def _unit(name: str) -> str:
    """' N.m' for a sentence; nothing for a ratio (unit "1")."""
    unit = parameters.table()[name].unit
    return "" if unit == "1" else f" {unit}"


def _rounded(x: float | None) -> float | None:
    return None if x is None else float(f"{x:.4g}")


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


class _Planting:
    """One effect planted into the corrected set `p` of a diagnosis at any size."""

    def __init__(self, diag, effect: Effect, p: dict, shared: dict):
        """`shared`: what every effect's planting on this set reads (the null's noise, the anchors' Jacobians)."""
        self.diag, self.effect, self.p = diag, effect, p
        self.channels = diag.channels_of(effect.part)
        self.base = self._residuals(p)
        anchors = diag._anchors(effect.part, effect.stateful)
        key = (effect.part, tuple(anchors))
        if key not in shared:
            shared[key] = diag._jacobian(p, anchors, self.channels) if anchors else None
        self.anchor_jacobian = shared[key]
        self.reference = reference_set(effect, p)
        # The null: the effect's own parameters and the anchors, linearised at the reference size.
        names = list(dict.fromkeys(list(effect.params) + anchors))
        jacobian = diag._jacobian(self.reference, names, self.channels)
        rows = [diag.channels.index(c) for c in self.channels]
        if "noise" not in shared:
            shared["noise"] = diag._null_noise(p)
        noise = shared["noise"].replicates(rows)
        if effect.uneven_over_folds:
            self.null = null_gain(noise, jacobian, diag.fit_index, diag.fold, diag.test)
        else:
            self.null = null_z(noise, jacobian, diag.fit_index, diag.fold, diag.test)

    def _residuals(self, q: dict) -> np.ndarray:
        d = self.diag
        return np.stack([np.where(d.used, np.nan_to_num(d.eval.residual(c, q) / d.sigma[c.name]), 0.0)
                         for c in self.channels])

    def _left_after_calibration(self, signature: np.ndarray) -> np.ndarray:
        if self.anchor_jacobian is None:
            return signature
        rows = self.diag.fit_index
        j = self.anchor_jacobian
        coef = np.linalg.lstsq(j[:, rows, :].reshape(-1, j.shape[2]), signature[:, rows].ravel(), rcond=None)[0]
        return signature - np.einsum("csk,k->cs", j, coef)

    def shown(self, factor: float) -> bool:
        d = self.diag
        # What the effect adds to the residual of a model that lacks it.
        signature = self.base - self._residuals(at_size(self.effect, self.reference, factor))
        left = self._left_after_calibration(signature)
        before = np.sum((self.base + left) ** 2, axis=0)
        after = np.sum(self.base ** 2, axis=0)
        gain = held_out_gain_sq(before, after, d.fold, d.test)
        if gain.gain <= MIN_GAIN:
            return False
        if self.effect.uneven_over_folds:
            return p_value(gain.gain, self.null) <= FALSE_DISCOVERY_RATE
        return steady_over_folds(gain) and p_value(gain.z, self.null) <= FALSE_DISCOVERY_RATE


def smallest_shown(diag, effect: Effect, p: dict, shared: dict | None = None) -> Limit:
    """Down from the reference size while it shows, else up until it does;
    then the step refined between the last size not shown and the first shown."""
    planting = _Planting(diag, effect, p, {} if shared is None else shared)
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
    if found is None:
        return Limit(effect.id, name, ref, None, None, effect.size.grows, effect.size.source)
    step = COARSE
    for _ in range(2):
        step = step ** 0.5
        if found / step >= SMALLEST and planting.shown(found / step):
            found /= step
    return Limit(effect.id, name, ref, at_size(effect, planting.reference, found)[name], found, effect.size.grows,
                 effect.size.source)


def detection_limits(diag, p: dict) -> list[Limit]:
    """The limit of each effect the last round tested and did not accept,
    the effects side by side in forked processes (forked.py: the same limits)."""
    effects = [h.effect for h in diag.last_round
               if not h.accepted() and not h.effect.order_angles and h.effect.size is not None]
    shared: dict = {}  # in one process, the effects of a part share the anchors' Jacobian
    return map_forked(lambda i: smallest_shown(diag, effects[i], p, shared), len(effects), diag.workers)
