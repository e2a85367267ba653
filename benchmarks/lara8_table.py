"""The diagnosis on the real LARA8 recordings (../shared/data/lara8, see its
README): what each recording contains (and so what it can say), the
verdict and findings, where the kinematic error (the thesis' dominant
effect) ends up, and the torsion residual on ANOTHER recording of the same
joint before and after (validation.validate, as `hdjoint diagnose
--validate`, which places each set's encoder zero a0 on that recording).
Joint 1 has two recordings, each validated on the other; joints 2 and 3
have one, so each is diagnosed on its first half and validated on its
second half (said so in the table).

The recordings are read with the current in the encoders' sense
(CURRENT_SIGN) and the gears' tooth ratios (TOOTH_RATIO). The nominal set
per joint: the contract defaults with the README's Kt = 0.1 N.m/A, the
catalogue stiffness of a size-25 gear (Kf = K1 = 31000 N.m/rad; Cf: eq. (5)
fitted to the catalogue's K1/K2/K3 curve up to T_MAX), and no gravity
(mgl = 0: the diagnosis may add it).
Run: python benchmarks/lara8_table.py [--data DIR]  -> docs/results/lara8.md
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import lara8_kinematic
from hdjoint.diagnosis.effects import KINEMATIC_EQ7
from hdjoint.diagnosis.model.kinematics import kinematics
from hdjoint.diagnosis.model.torque_estimates import Prepared
from hdjoint.diagnosis.verdict.validation import validate
from hdjoint.io import parameters
from hdjoint.io.recording import write_recording
from hdjoint.jobs.diagnose import diagnose_to_directory
from hdjoint.jobs.inputs import UserError
from lara8_data import (  # noqa: F401  (the LARA8 conventions)
    CURRENT_SIGN,
    DATA,
    EXAMPLES,
    JOINTS,
    K1,
    KT,
    ROOT,
    T_MAX,
    TABLE,
    TOOTH_RATIO,
    calibrated_set,
    calibrated_value,
    catalogue_cf,
    catalogue_torsion,
    contents,
    gear_ratio,
    generated_by,
    halves,
    markdown_table,
    nominal_for,
    read_joint,
)


def _diagnose(rec, n: float, tmp: Path, name: str, nominal: dict | None = None) -> dict:
    params, path = tmp / f"{name}-nominal.json", tmp / f"{name}.csv"
    parameters.save(params, nominal or nominal_for(n))
    write_recording(path, rec)
    return diagnose_to_directory(str(path), str(params), str(tmp / name))


def run_joint(joint: str, files: list[str], data: Path, tmp: Path) -> list[dict]:
    """Each recording diagnosed whole; its corrected set validated on the joint's
    other recording, or (a joint with one recording) the diagnosis of its first
    half validated on its second half."""
    recs = [read_joint(data / f) for f in files]
    n = TOOTH_RATIO[joint]
    rows = []
    for k, (name, rec) in enumerate(zip(files, recs)):
        doc = _diagnose(rec, n, tmp, f"{joint}-{k}")
        calibration = doc.get("calibration", {})
        row = {"joint": joint, "recording": name, "N": n, "N_encoders": round(gear_ratio(rec), 3),
               "contents": contents(rec, n, doc),
               "verdict": doc["verdict"],
               "findings": [{"effect": f["effect"], "kind": f.get("kind", "added"),
                             "orders": {key: v for key, v in f["parameters"].items() if key.endswith("_order")}}
                            for f in doc["findings"]],
               "kinematic_calibration": {key: calibration[key] for key in KINEMATIC_EQ7 if key in calibration},
               "kinematic_error_says": kinematic_error_says(doc),
               "proposed_terms": doc.get("proposed_terms", []), "seconds": doc.get("seconds"), "validation": []}
        # examples/lara8's own command: the file as logged, its parameter file, --current-sign.
        shipped = diagnose_to_directory(str(data / name), str(EXAMPLES[joint]), str(tmp / f"{joint}-{k}-example"),
                                        current_sign=CURRENT_SIGN[joint])
        row["with_example_parameters"] = {"verdict": shipped["verdict"],
                                          "kinematic_error_says": kinematic_error_says(shipped),
                                          "kinematic_error_short": kinematic_error_short(shipped)}
        row["yardstick"] = {"the table's set": yardstick(doc), "examples/lara8": yardstick(shipped)}
        for label, nominal in small_joint_sets(n).items():
            row["yardstick"][label] = yardstick(_diagnose(rec, n, tmp, f"{joint}-{k}-{len(row['yardstick'])}", nominal))
        fitted = rec
        if len(recs) > 1:
            other = recs[1 - k]
            row["validated_on"] = files[1 - k]
        else:
            first, other = halves(rec)
            fitted = first
            row["validated_on"] = f"second half of {name} (diagnosed on its first half)"
            turns = float(np.ptp(first.theta_m)) / (2 * math.pi)
            if turns < 1.0:
                row["validated_on"] += (f"; that half stands still ({turns:.3f} motor revolutions at one load): what "
                                        "it calibrates is extrapolated on the moving second half")
            try:
                doc = _diagnose(first, n, tmp, f"{joint}-{k}-half")
                calibration = doc.get("calibration", {})
            except UserError as e:
                reason = str(e).split(": ", 1)[-1]  # drop the temporary file's name
                row["validated_on"] = f"none: only one recording of this joint, and its first half is {reason}"
                other = None
        if other is not None:
            row["validation"] = [validate(other, nominal_for(n), calibrated_set(nominal_for(n), calibration), doc["params"],
                                          fitted_on=Prepared(fitted, kinematics(fitted), fitted.time - fitted.time[0]))]
        # The torsion needs no diagnosis of the half: joint2's first half (2.0 s) is judged on its second too.
        row["torsion"] = torsion_alone(name, rec, *((rec, recs[1 - k]) if len(recs) > 1 else halves(rec)), n)
        rows.append(row)
        print(f"{name}: {row['verdict']} {[f['effect'] for f in row['findings']]}", flush=True)
    return rows


def torsion_alone(name: str, rec, fitted, other, n: int) -> dict:
    """The kinematic error measured on the encoders alone (lara8_kinematic.py):
    the orders named on the recording, and the torsion residual on the other
    recording (or half) with those orders fitted on `fitted` (eq. (7)'s 2 and 4 when none is named)."""
    found = lara8_kinematic.analyse(name, rec)
    named = [o for o in found["orders"] if o["named"]]
    return {"named": [{k: o[k] for k in ("order", "amplitude", "half_width", "gain", "z", "p")} for o in named],
            "says": lara8_kinematic.can_say(found),
            "closure": lara8_kinematic.closure(fitted, other, n, [o["order"] for o in named] or [2.0, 4.0])}


def small_joint_sets(n: float) -> dict[str, dict]:
    """Nominal sets a user may bring to a LARA8 joint (issue 38): the contract's
    defaults (a small joint: Kf 10000, Cf 0.0645, mgl 5 N.m) with the ratio and
    Kt, and the catalogue's stiffness with that small joint's link model and no eq. (7)."""
    defaults = dict(parameters.defaults(), N=n, Kt=KT)
    return {"contract defaults (N, Kt)": defaults,
            "catalogue stiffness, mgl 5, no eq. (7)": dict(defaults, Kf=K1, Cf=catalogue_cf(),
                                                             **{k: 0.0 for k in KINEMATIC_EQ7})}


def yardstick(doc: dict) -> dict:
    """The verdict, its findings, and each channel's held-out miss beyond the sensors' floor (N.m, share of the span)."""
    accuracy = doc.get("accuracy") or {}
    return {"verdict": doc["verdict"], "findings": [f"{f['effect']} ({f['kind']})" for f in doc["findings"]],
            "span": accuracy.get("torque_span"), "allowed": accuracy.get("allowed"),
            "miss": {ch: [c["miss"], c["miss_share_of_span"]] for ch, c in accuracy.get("channels", {}).items()}}


def _yardstick_cell(y: dict) -> str:
    miss = ", ".join(f"{ch} {m:.3g} N.m ({100 * share:.0f} %)" for ch, (m, share) in y["miss"].items())
    return f"{y['verdict']}" + (f" ({'; '.join(y['findings'])})" if y["findings"] else "") + f"; miss: {miss}"


def _torsion_cells(r: dict) -> list[str]:
    t = r["torsion"]
    named = "; ".join(f"order {o['order']:g}: {o['amplitude']:.1e} ± {o['half_width']:.1e} rad (held-out gain "
                      f"{100 * o['gain']:.0f} %, p = {o['p']:.1g})" for o in t["named"]) or t["says"]
    c = t["closure"]
    if c["cannot"]:
        return [named, f"cannot tell: {c['cannot']}"]
    return [named, (f"{c['none']:.2e} -> {c['fitted']:.2e} (eq. (7) nominal: {c['eq7_nominal']:.2e}; orders "
                   f"{', '.join(f'{k:g}' for k in c['orders'])})")]


def kinematic_error_says(doc: dict) -> str:
    """What the diagnosis says about the kinematic error, in one phrase."""
    for f in doc["findings"]:
        if f["effect"] == "kinematic_error":
            p = f.get("parameters", {})
            orders = ", ".join(f"order {p[s + '_order']:g}, {math.hypot(p[s + '_a'], p[s + '_b']):.1e} rad"
                               for s in ("ke_m1", "ke_m2", "ke_l1", "ke_l2") if s + "_order" in p)
            seen = f", seen on {f['evidence']['seen_on']}" if f.get("evidence", {}).get("seen_on") else ""
            return f"{f.get('kind')} ({orders}; p = {f.get('p_value', 1.0):.2g}{seen})"
    zs = {n: c["z"] for n, c in doc.get("calibration", {}).items() if n in KINEMATIC_EQ7}
    within = f"eq. (7) within tolerance (largest abs(z) {max(abs(z) for z in zs.values()):.1f}, resized needs 3)" \
        if zs else "eq. (7) not calibrated"
    said = next((n for n in doc.get("orders_not_found", []) if n["effect"] == "kinematic_error"), None)
    if said and said["reason"].startswith("on the encoders' torsion"):
        return f"not named: {within}; {said['reason']}"
    if said and said["strongest"]:
        o = said["strongest"][0]
        return (f"not named: {within}; no added order: strongest {o['angle']} order {o['order']:g}, held-out z "
                f"{o['z']}, prominence {o['prominence']} (needs 3 and 3)")
    tested = [h for r in doc.get("hypotheses_tested", []) for h in r if h["effect"] == "kinematic_error"]
    if tested:
        t = tested[0]
        seen = f" on {t['seen_on']}" if t.get("seen_on") else ""
        return (f"not named: {within}; tested{seen}, held-out gain {100 * t['held_out_gain']:.0f} %, z {t['z']}, "
                f"p = {t['p_value']:.2g}, delta BIC {t['delta_bic']} (needs < -10)")
    untestable = next((n["reason"] for n in doc.get("not_testable", []) if n["effect"] == "kinematic_error"), "")
    return f"not named: {within}; {untestable or 'no order searched'}"


def kinematic_error_short(doc: dict) -> str:
    """The README's phrase for what the diagnosis says of the kinematic error: added or resized with
    its orders, amplitudes and p, else not testable or not named."""
    for f in doc["findings"]:
        if f["effect"] == "kinematic_error":
            p = f.get("parameters", {})
            orders = ", ".join(f"order {p[s + '_order']:g}, {_e(math.hypot(p[s + '_a'], p[s + '_b']))} rad"
                               for s in ("ke_m1", "ke_m2", "ke_l1", "ke_l2") if s + "_order" in p)
            return f"{f.get('kind')}, {orders}, p = {f.get('p_value', 1.0):.1g}"
    if any(n["effect"] == "kinematic_error" for n in doc.get("not_testable", [])):
        return "not testable"
    return "not named"


def _e(x: float) -> str:
    """A small number in two significant digits, as the README writes it (6.2e-5)."""
    return f"{x:.1e}".replace("e-0", "e-")


def readme_table(rows: list[dict]) -> list[str]:
    """The README's LARA8 table: per recording, what examples/lara8's commands give (verdict, findings, the
    kinematic error), the kinematic error on the torsion alone, and the torsion residual on another recording."""
    cells = []
    for r in rows:
        shipped = r["yardstick"]["examples/lara8"]
        verdict = shipped["verdict"] + (": " + ", ".join(f.replace("_", " ").replace(" (", " ").rstrip(")")
                                                         for f in shipped["findings"]) if shipped["findings"] else "")
        t = r["torsion"]
        alone = "; ".join(f"order {o['order']:g}, {_e(o['amplitude'])} ± {_e(o['half_width'])} rad, p = {o['p']:.0e}"
                          .replace("e-0", "e-") for o in t["named"])
        if not alone:
            alone = (f"cannot tell: {r['contents']['motor_revolutions']:g} motor revolutions"
                     if t["says"].startswith("cannot tell") else "none holds out")
        c = t["closure"]
        where = "" if r["validated_on"].endswith(".csv") else "second half: "
        closure = "cannot tell" if c["cannot"] else f"{where}{c['none']:.2e} → {c['fitted']:.2e}".replace("e-0", "e-")
        cells.append([r["recording"].removesuffix(".csv"), verdict,
                      f"{r['with_example_parameters']['kinematic_error_short']}; {alone}", closure])
    return markdown_table(["recording", "verdict (examples/lara8)", "kinematic error: diagnosis; torsion alone",
                           "torsion residual on another recording, rad: none → fitted"], cells)


def _contents_row(r: dict) -> list:
    c = r["contents"]
    return [r["recording"], c["duration_s"], c["samples"], c["median_step_ms"], c["motor_revolutions"],
            c["link_travel_rad"], f"{c['motor_reversals']} / {c['link_reversals']}",
            f"{c['torque_range_Nm'][0]} .. {c['torque_range_Nm'][1]}", "; ".join(c["cannot_say"]) or "-"]


def _verdict_row(r: dict) -> list:
    found = "; ".join(f"{f['effect']} ({f['kind']}" + (f", orders {f['orders']}" if f["orders"] else "") + ")"
                      for f in r["findings"]) or "-"
    kin = ", ".join(f"{k} {v['nominal']:.2g} -> {calibrated_value(v):.2g} ({calibrated_value(v) / v['nominal']:.1f}x)"
                    for k, v in r["kinematic_calibration"].items() if v["nominal"]) or "not calibrated"
    val = "; ".join(f"{ch}: {row['nominal']['rms']:.3f} -> {row['calibrated']['rms']:.3f} -> "
                    f"{row['corrected']['rms']:.3f}" for v in r["validation"] for ch, row in v["channels"].items())
    beyond = ", ".join(f"{q['quantity']} {q['outside']:.0%}" for v in r["validation"]
                       for q in v.get("extrapolation", []) if q.get("warning"))
    val += f" (extrapolated, samples beyond the fitted range: {beyond})" if beyond else ""
    shipped = r["with_example_parameters"]
    return [r["recording"], f"{r['N']} ({r['N_encoders']})", r["verdict"], found, r["kinematic_error_says"], kin,
            f"{shipped['verdict']}; kinematic error: {shipped['kinematic_error_says']}",
            r["validated_on"], val or "-", *_torsion_cells(r)]


def write_table(rows: list[dict], path: Path = TABLE) -> str:
    lines = ["# The diagnosis on the real LARA8 recordings", "", generated_by("lara8_table.py"),
             ("Recordings read with the current's sign turned to the encoders' (joints 1 and 2) and N the tooth ratio "
             "(121 / 101; the encoders' least-squares slope is given beside it). "
             f"Nominal set: contract defaults with Kt = {KT}, Kf = K1 = {K1:g} N.m/rad, Cf = {catalogue_cf():.4f} "
             f"1/(N.m) (eq. (5) fitted to the catalogue's K1/K2/K3 curve up to {T_MAX:g} N.m), mgl = 0."), "",
             "## What each recording contains", ""]
    lines += markdown_table(["recording", "s", "samples", "step (ms)", "motor rev", "link travel (rad)",
                             "motor / link reversals", "torque 2-98 % (N.m)", "what it cannot say"],
                            [_contents_row(r) for r in rows])
    lines += ["", "## Verdict, the kinematic error, and the torsion residual on another recording", ""]
    lines += markdown_table(["recording", "N (encoders' slope)", "verdict", "findings (kind, orders)", "kinematic error",
                             "eq. (7) coefficients: nominal -> calibrated (x nominal)",
                             "with the parameter file examples/lara8 ships (no eq. (7))", "validated on",
                             "residual RMS on it, N.m: nominal -> calibrated -> corrected",
                             "kinematic error on the torsion alone (lara8_kinematic.py)",
                             "torsion residual RMS on it, rad: no kinematic error -> orders fitted here"],
                            [_verdict_row(r) for r in rows])
    labels = list(rows[0]["yardstick"]) if rows else []
    lines += ["", "## The verdict's yardstick: what each set misses", "",
              ("Each channel's held-out residual beyond its sensors' floor at the corrected set (diagnosis/verdict/floors.py), "
              "in N.m and as a share of the torque span; more than the default accuracy (5 %) is `unexplained`, "
              "more than 10 % never `consistent`."), ""]
    lines += markdown_table(["recording", "torque span (N.m)", *labels],
                            [[r["recording"], f"{r['yardstick'][labels[0]]['span']:.3g}",
                              *[_yardstick_cell(r["yardstick"][label]) for label in labels]] for r in rows])
    kinematic = [r for r in rows if any(f["effect"] == "kinematic_error" for f in r["findings"])]
    shipped = [r for r in rows if r["with_example_parameters"]["kinematic_error_says"].startswith(("added", "resized"))]
    on_torsion = [r for r in rows if r["torsion"]["named"]]
    lines += ["", f"Kinematic error named (added or resized): {len(kinematic)} of {len(rows)} diagnoses against the "
              f"contract's eq. (7), {len(shipped)} of {len(rows)} with the parameter files examples/lara8 ships "
              f"({', '.join(r['recording'] for r in shipped) or 'none'}); on the "
              f"torsion alone: {len(on_torsion)} of {len(rows)} recordings "
              f"({', '.join(r['recording'] for r in on_torsion) or 'none'}). "
              "Proposed open-library terms: " + ("; ".join(f"{r['recording']}: {t['channel']} {t['terms']} "
                                                           f"(held-out gain {t['holdout_gain']})"
                                                           for r in rows for t in r["proposed_terms"]) or "none") + "."]
    lines += ["", "## The README's table", "",
              ("examples/lara8's commands on each recording (its parameter file, `--current-sign -1` for joints 1 "
              "and 2); the kinematic error on the torsion alone and its residual from the columns above."), ""]
    lines += readme_table(rows)
    text = "\n".join(lines) + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    (path.with_suffix(".json")).write_text(json.dumps(rows, indent=1) + "\n")
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA, help="folder of the LARA8 recordings")
    ap.add_argument("--joints", nargs="+", default=list(JOINTS), choices=list(JOINTS))
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory(prefix="hdjoint-lara8-") as tmp:
        for joint in args.joints:
            rows += run_joint(joint, JOINTS[joint], args.data, Path(tmp))
    print(write_table(rows))


if __name__ == "__main__":
    main()
