"""The library of harmonic-drive physics the diagnosis tests: one module per
effect in this folder, each defining `EFFECT` (an instance of base.Effect or
of a subclass that overrides its special cases). The registry finds them
itself, so a new effect is one file; `register` adds one at run time (a
test's, a user's plug-in). The stages read effects through this registry
and the base class's hooks only.

Also here: the parameters calibrated whenever a part of the model is
fitted, and what follows from the effects' definitions (which parameters
each part's torque estimate reads, which the friction law reads)."""
from __future__ import annotations

import importlib
import pkgutil

from hdjoint.diagnosis.effects.base import TABLE_JOINT, Effect, Size, TruthDraw, slot_on
from hdjoint.diagnosis.effects.kinematic_error import KINEMATIC_EQ7
from hdjoint.diagnosis.effects.needs import testable

PARTS = ("transmission", "motor", "link")
_NOT_EFFECTS = {"base", "needs"}

# Parameters calibrated whenever their part of the model is fitted: the
# nominal set has them, and a few percent of error in them must not be
# mistaken for missing physics.
# Without a torque sensor only the ratio Kt/Kf is observable: Kt, the joint's
# torque scale, stays at its nominal value (jobs/joint_scale.py sets the scale after).
HELD_WITHOUT_SENSOR = "Kt"

ALWAYS_CALIBRATED = {
    "transmission": ("a0", "Kf", "Df"),  # Df: structural damping, which every real flexspline has
    "motor": ("Kt", "Jm"),
    "link": ("Jl", "Bl"),
}

EFFECTS: dict[str, Effect] = {}


def _ordered(effects) -> dict[str, Effect]:
    """By part (transmission, motor, link), then rank: the order hypotheses are tried and listed."""
    return {e.id: e for e in sorted(effects, key=lambda e: (PARTS.index(e.part), e.rank, e.id))}


def _discover() -> None:
    found = []
    for info in pkgutil.iter_modules(__path__):
        if info.name in _NOT_EFFECTS or info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        effect = getattr(module, "EFFECT", None)
        if not isinstance(effect, Effect):
            raise TypeError(f"{module.__name__} defines no EFFECT (an Effect)")
        found.append(effect)
    EFFECTS.update(_ordered(found))


def register(effect: Effect) -> Effect:
    """Add an effect to the library (or replace the one with its ID)."""
    if effect.part not in PARTS:
        raise ValueError(f"{effect.id}: part {effect.part!r} is none of {PARTS}")
    merged = {k: v for k, v in EFFECTS.items() if k != effect.id}
    merged[effect.id] = effect
    EFFECTS.clear()
    EFFECTS.update(_ordered(merged.values()))
    return effect


def unregister(effect_id: str) -> None:
    EFFECTS.pop(effect_id, None)


def calibrated_parameters(part: str, nominal: dict, sensor: bool) -> list[str]:
    """Parameters of `part` to calibrate: the always-calibrated ones, the
    shape of every effect the nominal set switches on, and every nonzero
    parameter an effect may resize."""
    names = list(ALWAYS_CALIBRATED[part])
    if part == "motor" and not sensor:
        names.remove(HELD_WITHOUT_SENSOR)
    for effect in EFFECTS.values():
        if effect.part != part:
            continue
        # A term the model carries beside the effect's switch (eq. (7), Kf) is calibrated when nonzero;
        # the effect's own parameters only when it is on (hys_sigma means nothing while hys_H = 0).
        own = effect.params + effect.shape
        on = [n for n in effect.resizes if nominal.get(n, 0.0) and (n not in own or effect.is_on(nominal))]
        names += [n for n in (*effect.calibrates(nominal), *on) if n not in names]
    return list(dict.fromkeys(names))  # an effect's shape may also be a parameter it resizes: once each


def owner(name: str) -> Effect | None:
    """The effect a calibrated parameter belongs to (None: a constant of the joint, e.g. Kt)."""
    return next((e for e in EFFECTS.values() if name in e.resizes or name in e.shape), None)


def orthogonal_parameters() -> set[str]:
    """Parameters of terms at their own angle orders: no other effect's fit needs them refitted."""
    return {n for e in EFFECTS.values() if e.order_angles for n in e.resizes}


def part_parameters(part: str) -> tuple[str, ...]:
    """Every parameter the motor's or the link's torque estimate reads: the
    gear ratio (motor), the part's always-calibrated ones and every parameter
    its effects carry. Keys the estimate's cache, so a new effect's
    parameters are never missed."""
    head = ("N",) if part == "motor" else ()
    return tuple(dict.fromkeys(head + ALWAYS_CALIBRATED[part] +
                               tuple(n for e in EFFECTS.values() if e.part == part for n in e.carries())))


def friction_law_parameters() -> tuple[str, ...]:
    """Every parameter of the motor friction law (friction.h): those of the effects in it."""
    return tuple(dict.fromkeys(n for e in EFFECTS.values() if e.in_friction_law for n in e.carries()))


_discover()

__all__ = ["ALWAYS_CALIBRATED", "EFFECTS", "KINEMATIC_EQ7", "PARTS", "TABLE_JOINT", "Effect", "Size", "TruthDraw",
           "calibrated_parameters", "friction_law_parameters", "orthogonal_parameters", "owner", "part_parameters",
           "register", "slot_on", "testable", "unregister"]
