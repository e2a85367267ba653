"""What the right hypothesis would gain on one independent-truth recording,
with the truth's own effect size: whether the recording can reveal the
effect at all (cannot_tell.py says so beside a `consistent` verdict).

  python benchmarks/truth_gain.py "coulomb friction" 2 coulomb_friction

Calibrates as the diagnosis does, then prints (1) the effect's hypothesis
fitted from the truth's value (held-out gain, z, p from the simulated null,
delta BIC), (2) the model held at the truth's value with the part's
calibrated parameters refitted, and (3) the calibrated parameters beyond
three tolerances."""
from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from hdjoint.diagnosis.fit.nominal_calibration import calibrate, calibration_table
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint.diagnosis.search.hypothesis_search import HypothesisSearch
from hdjoint.diagnosis.effects import EFFECTS
from hdjoint.diagnosis.model.structure import held_out_gain_sq
from hdjoint_truth import cases as tc


def truth_values(effect: str, joint) -> dict:
    """The effect's model parameters at the truth's size (those the truth has in the model's terms)."""
    t, sensor = joint.truth, joint.setups[0].current_sensor
    table = {"coulomb_friction": {"Fc": t["Fc"]}, "viscous_friction": {"Bm": t["Bm"]},
             "backlash": {"backlash": t.get("backlash", 0.0)}, "time_delay": {"i_delay": max(sensor.delay, sensor.lag)},
             "stribeck_friction": {"Fs": t.get("Fs", 0.0), "omega_s": t.get("omega_s", 10.0)},
             "link_friction": {"Fl": t.get("Fl", 0.0)}, "gravity_load": {"mgl": t["mgl"]}}
    if effect not in table:
        raise SystemExit(f"no truth value for {effect!r}: one of {', '.join(table)}")
    return table[effect]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", help="a substring of an effect case's name (hdjoint_truth.cases)")
    ap.add_argument("seed", type=int)
    ap.add_argument("effect", help="the effect ID to try at the truth's size")
    args = ap.parse_args()
    case = next(c for c in tc.EFFECT_CASES if args.case in c.name)
    joint = tc.draw(case, args.seed)
    calibrated = calibrate(prepare(tc.record(joint, 0), joint.nominal, workers=1))
    p, diag = calibrated.params, calibrated.objective
    search = HypothesisSearch(diag, calibrated.current_alignment)
    search.start_round(p)
    values = truth_values(args.effect, joint)
    effect = dataclasses.replace(EFFECTS[args.effect], starts=(values,))
    h = search.try_effect(effect, p)
    print(f"{case.name}, seed {args.seed} ({joint.description['excitations'][0]}, {joint.description['friction']} "
          f"friction), {args.effect} at the truth's {values}")
    print(f"  fitted from the truth: held-out gain {h.gain.gain:.3f}, z {h.gain.z:.2f}, p {h.p_raw:.2g}, "
          f"delta BIC {h.delta_bic:.0f}; " + ", ".join(f"{n} = {h.params_after[n]:.3g}" for n in h.fitted))
    channels = diag.channels_of(effect.part)
    held = diag.fit(dict(p, **values), diag.anchors(effect.part, effect.stateful), channels)
    g = held_out_gain_sq(diag.squared(p, channels), diag.squared(held.params, channels), diag.fold, diag.test)
    print(f"  held at the truth: held-out gain {g.gain:.3f}, z {g.z:.2f}, folds better {np.mean(g.fold_gains > 0):.2f}")
    moved = {n: round(float(c.z), 1) for n, c in calibration_table(diag, calibrated.fit, p).items() if abs(c.z) > 3}
    print(f"  calibrated beyond three tolerances: {moved or 'none'}")


if __name__ == "__main__":
    main()
