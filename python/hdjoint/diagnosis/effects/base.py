"""The small base class every effect of the library derives from (or
instantiates): what part of the joint it lives in, which parameters of the
C++ model carry it, how a fit of it starts, what a recording must show for
it to be testable, its look-alikes, and hooks with the usual behaviour that
an effect overrides for its special cases. The stages call only these; they
never name an effect."""
from __future__ import annotations

from dataclasses import dataclass, field


def slot_on(p: dict, slot: str) -> bool:
    """The set already carries the term in `slot` (<slot>_a or <slot>_b nonzero)."""
    return bool(p.get(f"{slot}_a", 0.0) or p.get(f"{slot}_b", 0.0))


@dataclass(frozen=True)
class Size:
    """What sets an effect's size, for the smallest size a recording would
    show (detection_limit.py): the parameter scaled, how the effect grows
    with it (Kw: -1, a stiffer bearing twists less), a reference size (the
    table's defaults for any of the effect's parameters not stated), and the
    reference's source ("" : a size of the fit's grid, no claim that it is typical).
    For an effect at angle orders the parameter is an order slot's amplitude
    and the reference states the slot's order: it is planted at that one order."""
    parameter: str
    grows: float = 1.0
    reference: tuple[tuple[str, float], ...] = ()
    source: str = ""


TABLE_JOINT = "the parameter table's SHD-17-100-class joint"


@dataclass(frozen=True)
class RecordingScale:
    """What a fitted effect is judged physical against: the recording's
    torsion (5-95 %, rad) and its length (s)."""
    torsion_span: float
    duration: float


@dataclass(frozen=True)
class TruthDraw:
    """What an effect may use to plant itself in the independent truth
    (benchmarks/hdjoint_truth): the truth's parameter dict, its model form,
    its current sensor, the random generator, and the concealed size factor
    (`size` times a uniform 0.8-1.2 draw, `jitter` the draw alone)."""
    truth: dict
    form: object
    sensor: object
    rng: object
    size: float

    def jitter(self) -> float:
        return float(self.rng.uniform(0.8, 1.2))

    def scaled(self) -> float:
        return self.size * self.jitter()


@dataclass(frozen=True)
class Effect:
    id: str
    part: str                     # "transmission", "motor" or "link"
    params: tuple[str, ...]       # what a fit of this effect adjusts
    physics: str                  # what was left out, in words
    model: str                    # the model terms that represent it
    # The nominal set has it when one of these is nonzero (then it is calibrated, not hypothesised).
    switched_by: tuple[str, ...] = ()
    starts: tuple[dict, ...] = ()  # starting values for fits (grids over nonlinear parameters)
    needs: tuple[str, ...] = ()   # what the excitation must do, every one of them (needs.py)
    lookalikes: tuple[str, ...] = field(default=())
    revealed_by: str = ""         # the excitation that shows this effect and not its look-alikes
    # Its state runs through time, so every fit evaluation simulates the whole
    # recording: it is refitted with the part's always-calibrated parameters
    # only, not with everything calibration touched (far fewer evaluations).
    stateful: bool = False
    # Shape parameters of the law, calibrated (not hypothesised) when the nominal set has the effect on.
    shape: tuple[str, ...] = ()
    # Parameters the nominal model may already carry for this effect: a
    # calibration that moves one beyond its tolerance is a "resized" finding of it.
    resizes: tuple[str, ...] = ()
    # Effects whose terms sit at angle orders: the angles searched and the slots filled.
    order_angles: tuple[str, ...] = ()
    slots: tuple[tuple[str, str], ...] = ()
    # Its held-out gain is uneven over the time folds by nature (a drift lives
    # in time, a dead zone at the slow reversals), so its evidence is the
    # pooled held-out gain against the simulated null, not the folds' z.
    uneven_over_folds: bool = False
    # Without a torque sensor its orders are judged on the encoders' torsion
    # (torsion_orders.py), not on torque channels that carry the motor and link models' mismatch.
    seen_on_torsion: bool = False
    # Its gain must be its own: with its terms back off and the part's refitted
    # parameters kept, the fit must lose held-out gain (HypothesisSearch.borrowed_gain).
    own_gain_checked: bool = False
    # Its parameters enter the motor friction law (friction.h): they key that law's cache.
    in_friction_law: bool = False
    size: Size | None = None  # None: no detection limit
    rank: int = 100           # its place among its part's effects (the order hypotheses are tried and listed)

    # ---- hooks: the usual behaviour; an effect overrides what is special to it ----
    def is_on(self, p: dict) -> bool:
        """The nominal set already has it: calibrate, don't hypothesise."""
        return any(p.get(n, 0.0) != 0.0 for n in self.switched_by)

    def trial(self, p: dict, search) -> tuple[dict, list[str], list]:
        """The trial set, the names to fit and the orders used. `search(p,
        angles)` is the order search, strongest first; the usual effect fits
        its own parameters from its starts."""
        if not self.order_angles:
            return p, list(self.params), []
        trial, names, used = self.fill_slots(p, search(p, self.order_angles))
        return trial, names, [o for _, o in used]

    def degenerate(self, p: dict, scale: RecordingScale) -> str | None:
        """Why a fit is not this effect, or is not physical on this recording (a
        thermal time constant of a fraction of a second), or None."""
        return None

    def settle(self, finding, objective):
        """An accepted finding of this effect, told apart from a look-alike the
        library cannot fit (or made ambiguous with it). Usual: as it is."""
        return finding

    def in_the_estimator(self, objective, params: dict) -> dict | None:
        """How the fitted effect does in the estimator FMU, when that differs from the diagnosis's view."""
        return None

    def plant_in_truth(self, draw: TruthDraw) -> None:
        """Put the effect into the independent truth, in a form of its own, at its concealed size."""
        raise NotImplementedError(f"{self.id} has no form in the independent truth")

    # ---- derived -----------------------------------------------------------
    def looks_like(self, other: "Effect") -> bool:
        """Either names the other a look-alike (the relation is read both ways)."""
        return other.id in self.lookalikes or self.id in other.lookalikes

    def carries(self) -> tuple[str, ...]:
        """Every model parameter of this effect (for checking the build has them)."""
        slot_terms = tuple(f"{slot}_{k}" for slot, _ in self.slots for k in ("order", "a", "b"))
        return tuple(dict.fromkeys(self.params + self.shape + self.resizes + slot_terms))

    def calibrates(self, nominal: dict) -> tuple[str, ...]:
        """Parameters of this effect to calibrate on a nominal set: its own when it is on, and
        any order slot the nominal set fills."""
        names = self.params + self.shape if self.is_on(nominal) else ()
        filled = tuple(f"{slot}_{k}" for slot, _ in self.slots for k in ("a", "b")
                       if nominal.get(f"{slot}_a", 0.0) or nominal.get(f"{slot}_b", 0.0))
        return tuple(dict.fromkeys(names + filled))

    def fill_slots(self, p: dict, orders, limit: int | None = None) -> tuple[dict, list[str], list]:
        """Each order (strongest first) fills a free slot of `slots` (prefix ->
        angle) at its angle, up to `limit` orders: the set with <slot>_order
        written, the <slot>_a, <slot>_b names to fit, and the (slot, order)
        pairs used. An order whose angle has no free slot is skipped."""
        free = {angle: [slot for slot, a in self.slots if a == angle and not slot_on(p, slot)]
                for angle in self.order_angles}
        trial, names, used = dict(p), [], []
        for o in orders:
            if limit is not None and len(used) >= limit:
                break
            if not free[o.angle]:
                continue
            slot = free[o.angle].pop(0)
            trial[f"{slot}_order"] = o.order
            names += [f"{slot}_a", f"{slot}_b"]
            used.append((slot, o))
        return trial, names, used
