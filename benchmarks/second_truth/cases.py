"""Cases of the second truth and the CLI that writes them.

A case = (seed, one form per family, planted effects, excitation, duration,
with/without tau_sensor). Seeds are split once: TUNING_SEEDS may be used to
tune anything; SEALED_SEEDS are for measuring only. On tuning seeds the
held-out families (forms.HELD_OUT) keep their baseline form.
plan(seed): even seeds are controls (nothing planted), odd seeds plant one
effect, cycling through EFFECT_ORDER.

  python -m second_truth.cases --out DIR --seeds sealed|tuning [--duration 20] [--limit K]
writes per case DIR/case_SEED.csv (the contract's recording) and
DIR/case_SEED.params.json (the user's nominal set), and DIR/truth.json.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from . import nominal, recording
from .controller import PDController
from .effects import EFFECTS
from .excitations import EXCITATIONS, reference
from .forms import BY_NAME, FAMILIES
from .joint import Joint

TUNING_SEEDS = range(0, 50)
SEALED_SEEDS = range(1000, 1050)
EFFECT_ORDER = ("hysteresis", "backlash", "cogging", "kinematic_error", "stribeck_friction",
                "viscous_friction", "time_delay", "wave_generator_compliance", "gravity_load", "kf_far_off")
STREAMS = {"plan": 1, "nominal": 2, "forms": 3, "effects": 4, "excitation": 5, "noise": 6}


def split_of(seed: int) -> str:
    if seed in TUNING_SEEDS:
        return "tuning"
    if seed in SEALED_SEEDS:
        return "sealed"
    return "other"


def _rng(seed: int, stream: str):
    return np.random.default_rng([seed, STREAMS[stream]])


def plan(seed: int) -> dict:
    """The case a seed stands for, unless make_case is told otherwise."""
    rng = _rng(seed, "plan")
    tuning = split_of(seed) == "tuning"
    forms = {}
    for fam, spec in FAMILIES.items():
        choices = spec["forms"]
        base = spec["baseline"]
        if (spec["held_out"] and tuning) or rng.random() < 0.4:
            cls = base
        else:
            cls = choices[int(rng.integers(len(choices)))]
        forms[fam] = None if cls is None else cls.name
    planted = [] if seed % 2 == 0 else [EFFECT_ORDER[(seed // 2) % len(EFFECT_ORDER)]]
    return {"seed": seed, "forms": forms, "planted": planted,
            "excitation": EXCITATIONS[int(rng.integers(len(EXCITATIONS)))],
            "with_sensor": bool(rng.random() < 0.5)}


def make_case(seed: int, out_dir, planted=None, forms=None, excitation=None, duration: float = 20.0,
              with_sensor=None, Ts: float = 1e-3) -> dict:
    """Write case_SEED.csv and case_SEED.params.json into out_dir; return the truth record."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    pl = plan(seed)
    planted = pl["planted"] if planted is None else list(planted)
    choice = dict(pl["forms"], **(forms or {}))
    excitation = excitation or pl["excitation"]
    with_sensor = pl["with_sensor"] if with_sensor is None else bool(with_sensor)
    truth, user = nominal.draw(_rng(seed, "nominal"))
    frng = _rng(seed, "forms")
    form_objs = [BY_NAME[name](frng) for fam, name in sorted(choice.items()) if name]
    erng = _rng(seed, "effects")
    planted_rec = []
    for eid in planted:
        eff = EFFECTS[eid]()
        sizes = eff.draw(erng)
        eff.apply(truth, user, form_objs, sizes)
        planted_rec.append(eff.describe(sizes))
    joint = Joint(truth, form_objs)
    r, rd, rdd = reference(excitation, duration, Ts, _rng(seed, "excitation"))
    drive = dict(user, mgl=truth["mgl"], Kf=truth["Kf"])  # the drive was tuned on the machine
    ctrl = PDController(drive, r, rd, rdd, Ts)
    counts = {"motor_counts": user["motor_counts"], "link_counts": user["link_counts"]}
    sensors = [f for f in form_objs if f.role not in ("motor_friction", "transmission", "motor_torque", "stiffness")]
    rec = recording.record(joint, ctrl, duration, Ts, sensors, _rng(seed, "noise"), counts)
    csv_path = out_dir / f"case_{seed}.csv"
    params_path = out_dir / f"case_{seed}.params.json"
    recording.write_csv(csv_path, rec, with_sensor)
    params_path.write_text(json.dumps(user, indent=1, sort_keys=True))
    tau = rec["tau_true"]
    return {"seed": seed, "split": split_of(seed), "csv": csv_path.name, "params": params_path.name,
            "planted": planted_rec, "control": not planted_rec,
            "forms": [f.describe() for f in form_objs],
            "families": {fam: name for fam, name in choice.items()},
            "held_out_used": [fam for fam, spec in FAMILIES.items()
                              if spec["held_out"] and choice.get(fam) != (spec["baseline"].name if spec["baseline"] else None)],
            "excitation": excitation, "duration": duration, "Ts": Ts, "with_sensor": with_sensor,
            "truth_params": truth, "user_params": user, "rows": int(rec["keep"].sum()), "dropped": rec["dropped"],
            "tau_range": [float(tau.min()), float(tau.max())], "i_peak": float(np.max(np.abs(rec["i_m"])))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m second_truth.cases", description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", choices=("sealed", "tuning"), required=True)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--limit", type=int, default=None, help="only the first K seeds of the set")
    ap.add_argument("--controls-only", action="store_true")
    ap.add_argument("--effects-only", action="store_true")
    a = ap.parse_args(argv)
    seeds = list(SEALED_SEEDS if a.seeds == "sealed" else TUNING_SEEDS)
    if a.controls_only:
        seeds = [s for s in seeds if not plan(s)["planted"]]
    if a.effects_only:
        seeds = [s for s in seeds if plan(s)["planted"]]
    seeds = seeds[: a.limit] if a.limit else seeds
    out = Path(a.out)
    records = []
    for s in seeds:
        records.append(make_case(s, out, duration=a.duration))
        print(f"case {s}: planted {[p['id'] for p in records[-1]['planted']]}", file=sys.stderr, flush=True)
        # rewritten after each case: a long run can be read (and diagnosed) while it goes on
        (out / "truth.json").write_text(json.dumps({"seeds": a.seeds, "cases": records}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
