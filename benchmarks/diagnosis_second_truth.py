"""The diagnosis examined on the second truth (benchmarks/second_truth/), a
simulator written apart from it: runs `hdjoint diagnose` (the installed CLI)
on sealed-seed cases and scores findings.json against the truth's manifest.

  python benchmarks/diagnosis_second_truth.py --cases DIR [--make --limit 20 --duration 20]
      [--out docs/results/diagnosis_second_truth.md]

--make writes the cases first (python -m second_truth.cases --seeds sealed);
a case already diagnosed (DIR/diag_SEED/findings.json) is read, not rerun.
Scores: a control is alarmed when the verdict is not `consistent`; a single
effect is named first when the first finding's effect is the planted ID
(named anywhere: in any finding or its alternatives); the far-off Kf is
resized when a `resized` finding carries Kf, and held when its interval
holds the truth. Nothing here is tuned to the diagnosis.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import stamp  # noqa: E402
from second_truth.forms import HELD_OUT  # noqa: E402

DEFAULT_OUT = HERE.parent / "docs" / "results" / "diagnosis_second_truth.md"
# the installed console script beside this interpreter (a pyenv shim can fail while pyenv rehashes)
_BESIDE = Path(sys.executable).parent / "hdjoint"
HDJOINT = str(_BESIDE) if _BESIDE.exists() else "hdjoint"


def diagnose(case_dir: Path, rec: dict, timeout: float = 600.0) -> dict:
    out = case_dir / f"diag_{rec['seed']}"
    fj = out / "findings.json"
    if not fj.exists():
        cmd = [HDJOINT, "diagnose", str(case_dir / rec["csv"]), "--params", str(case_dir / rec["params"]),
               "--out", str(out)]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        if p.returncode != 0:
            return {"error": (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]}
    return json.loads(fj.read_text())


def _kf_interval(d: dict):
    """(estimate, lo, hi, resized) for Kf: a resized finding's, else the calibration's."""
    for f in d.get("findings", []):
        k = (f.get("parameters") or {}).get("Kf")
        if f.get("kind") == "resized" and isinstance(k, dict):
            return k.get("estimate"), k.get("lo"), k.get("hi"), True
    k = (d.get("calibration") or {}).get("Kf") or {}
    return k.get("estimate"), k.get("lo"), k.get("hi"), False


def score(rec: dict, d: dict) -> dict:
    row = {"seed": rec["seed"], "control": rec["control"], "planted": [p["id"] for p in rec["planted"]],
           "families": rec["families"], "excitation": rec["excitation"], "with_sensor": rec["with_sensor"]}
    if "error" in d:
        row["error"] = d["error"]
        return row
    fs = d.get("findings", [])
    row["verdict"] = d.get("verdict")
    row["findings"] = [f"{f.get('effect')}:{f.get('kind')}" for f in fs]
    # the current's true lateness behind the encoders (sensor delay + lag + a planted delay) against a found i_delay
    cs = next((f["params"] for f in rec["forms"] if f["role"] == "current_sensor"), {})
    row["current_delay_truth"] = cs.get("delay", 0.0) + cs.get("tau_s", 0.0) + cs.get("extra_delay", 0.0)
    row["i_delay_found"] = next(((f.get("parameters") or {}).get("i_delay") for f in fs
                                 if f.get("effect") == "time_delay"), None)
    named = {f.get("effect") for f in fs} | {a.get("effect") if isinstance(a, dict) else a
                                              for f in fs for a in (f.get("alternatives") or [])}
    if rec["control"]:
        row["alarmed"] = row["verdict"] != "consistent"
    elif row["planted"] == ["kf_far_off"]:
        est, lo, hi, resized = _kf_interval(d)
        truth = rec["truth_params"]["Kf"]
        row.update(kf_estimate=est, kf_lo=lo, kf_hi=hi, kf_truth=truth, resized=resized,
                   holds=bool(lo is not None and hi is not None and lo <= truth <= hi))
    else:
        eid = row["planted"][0]
        row["named_first"] = bool(fs) and fs[0].get("effect") == eid
        row["named_anywhere"] = eid in named
    return row


def _frac(rows, key):
    n = len(rows)
    k = sum(bool(r.get(key)) for r in rows)
    return f"{k}/{n}" if n else "-"


def report(rows: list[dict], cmd: str, truth_commit: str) -> str:
    ok = [r for r in rows if "error" not in r]
    ctrl = [r for r in ok if r["control"]]
    eff = [r for r in ok if not r["control"] and r["planted"] != ["kf_far_off"]]
    far = [r for r in ok if r["planted"] == ["kf_far_off"]]
    L = [stamp.generated_by(cmd), "",
         f"Engine commit (last change to the diagnosis): {stamp.engine()}; second truth at {truth_commit}.", "",
         "# The diagnosis on the second truth", "",
         "Cases from `benchmarks/second_truth/` (sealed seeds), written apart from the diagnosis; "
         "see [benchmarks.md](../benchmarks.md). Measured, not tuned.", "",
         "| what | result |", "|---|---|",
         f"| controls alarmed (verdict not `consistent`) | {_frac(ctrl, 'alarmed')} |",
         f"| single effects named first | {_frac(eff, 'named_first')} |",
         f"| single effects named anywhere | {_frac(eff, 'named_anywhere')} |",
         f"| far-off Kf resized | {_frac(far, 'resized')} |",
         f"| far-off Kf interval holds the truth | {_frac(far, 'holds')} |",
         f"| cases that failed to run | {len(rows) - len(ok)} |", "",
         "## Per form family", "",
         "Each case draws one form per family; a row counts the cases that used that form.", "",
         "| family | form | controls alarmed | effects named first |", "|---|---|---|---|"]
    by = defaultdict(list)
    for r in ok:
        for fam, form in r["families"].items():
            by[(fam, str(form))].append(r)
    for (fam, form), rs in sorted(by.items()):
        shown = f"{fam} (held out: no choice looked at it)" if fam in HELD_OUT else fam
        L.append(f"| {shown} | {form} | {_frac([r for r in rs if r['control']], 'alarmed')} | "
                 f"{_frac([r for r in rs if r in eff], 'named_first')} |")
    L += ["", "## Cases", "",
          "Current delay: the truth's current reading behind the encoders (sensor delay + lag + any planted "
          "delay) and, after the arrow, the `i_delay` of a `time_delay` finding.", "",
          "| seed | planted | excitation | sensor | verdict | findings (first first) | score | current delay (ms) |",
          "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            L.append(f"| {r['seed']} | {', '.join(r['planted']) or 'control'} | {r['excitation']} | "
                     f"{r['with_sensor']} | error | {r['error'][:80]} | |")
            continue
        if r["control"]:
            s = "alarmed" if r["alarmed"] else "quiet"
        elif r["planted"] == ["kf_far_off"]:
            s = (f"Kf {r['kf_estimate']:.0f} [{r['kf_lo']:.0f}, {r['kf_hi']:.0f}] vs {r['kf_truth']:.0f}, "
                 f"{'resized' if r['resized'] else 'not resized'}, {'holds' if r['holds'] else 'misses'}"
                 if r["kf_estimate"] is not None else "no Kf")
        else:
            s = "first" if r["named_first"] else ("named" if r["named_anywhere"] else "missed")
        found = r.get("i_delay_found")
        delay = f"{1e3 * r.get('current_delay_truth', 0.0):.3f}" + (f" -> {1e3 * found:.3f}" if isinstance(found, (int, float)) else "")
        L.append(f"| {r['seed']} | {', '.join(r['planted']) or 'control'} | {r['excitation']} | {r['with_sensor']} | "
                 f"{r['verdict']} | {', '.join(r['findings']) or '-'} | {s} | {delay} |")
    return "\n".join(L) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", required=True, type=Path)
    ap.add_argument("--make", action="store_true")
    ap.add_argument("--limit", type=int, default=20)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    a = ap.parse_args(argv)
    if a.make:
        subprocess.run([sys.executable, "-m", "second_truth.cases", "--out", str(a.cases), "--seeds", "sealed",
                        "--limit", str(a.limit), "--duration", str(a.duration)], check=True,
                       env={**__import__("os").environ, "PYTHONPATH": str(HERE)})
    manifest = json.loads((a.cases / "truth.json").read_text())
    if manifest.get("seeds") != "sealed":
        raise SystemExit("the benchmark measures on sealed seeds only")
    rows = []
    for rec in manifest["cases"]:
        rows.append(score(rec, diagnose(a.cases, rec)))
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    truth_commit = stamp.git("log", "-1", "--format=%h", "--", "benchmarks/second_truth") or "unknown"
    cmd = "python benchmarks/diagnosis_second_truth.py " + " ".join(argv if argv is not None else sys.argv[1:])
    a.out.write_text(report(rows, cmd, truth_commit))
    a.out.with_suffix(".jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
