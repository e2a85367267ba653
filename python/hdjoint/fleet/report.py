"""fleet.html: one self-contained page (figures as PNG data URIs) with the
joints ranked by drift, each joint's calibrated parameters and intervals
over time, the effects found per recording, and the failures."""
from __future__ import annotations

import html
import math
from datetime import datetime, timezone
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from hdjoint.fleet import store, trend
from hdjoint.io import parameters
from hdjoint.io.figures import to_data_uri

STYLE = ("body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
         "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #bbb;padding:2px 6px;"
         "font-size:90%}th{background:#eee}.drift{background:#fdd}img{max-width:100%}")


def _cell(x) -> str:
    if isinstance(x, float):
        return "" if math.isnan(x) else f"{x:.4g}"
    return html.escape(str(x))


def _html_table(header, body_rows, marked=()) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    lines = []
    for i, r in enumerate(body_rows):
        cls = ' class="drift"' if i in marked else ""
        lines.append(f"<tr{cls}>" + "".join(f"<td>{_cell(c)}</td>" for c in r) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(lines)}</table>"


def _drifting(d) -> str:
    """The drifting cell: yes, or no with the rule's part the joint misses (a significant change in
    full view read "no" with no reason: it was below its tolerance)."""
    s = d.strongest
    if d.drifting:
        return "yes"
    if s is None:
        return "no: nothing to test"
    if not d.p_value < trend.ALPHA:
        return f"no: p = {d.p_value:.2g}, not below {trend.ALPHA:g}"
    return (f"no: significant, but {s.quantity} changes {100 * s.change:+.0f} %, under the "
            f"{100 * s.needed:.0f} % its tolerance asks")


def _quantity(name: str) -> tuple[str, str]:
    """A tracked quantity's name for a reader (the symbol with its meaning) and its unit."""
    if name in trend.KINEMATIC_TERMS:  # an amplitude over a revolution of eq. (7)'s and the extra slots' terms
        return f"{name.replace('_', ' ')} (amplitude)", "rad"
    info = parameters.table().get(name)
    if info is None:
        return name, ""
    return f"{name} ({parameters.meaning(name)})", ("" if info.unit == "1" else info.unit)


def _slope(s) -> str:
    unit = _quantity(s.quantity)[1]
    return f"{s.slope_per_day:.4g} {unit + '/' if unit else ''}day"


def _ranking(drifts) -> str:
    body, marked = [], set()
    for i, d in enumerate(drifts):
        s = d.strongest
        if d.drifting:
            marked.add(i)
        body.append((i + 1, d.joint, d.p_value, _drifting(d),
                     d.effect if s else "", _quantity(s.quantity)[0] if s else "", d.direction,
                     100 * s.change if s else math.nan, _slope(s) if s else "",
                     len(d.trends)))
    return ("<h2>Joints ranked by drift</h2>"
            f"<p>Trend test: weighted least-squares slope t-test of each tracked quantity against time (weights "
            f"from the 95 % intervals when every point has one; residual scale from the scatter; two-sided, "
            f"n-2 degrees of freedom); a joint's p-value is its smallest one times the number of quantities "
            f"tested (Bonferroni). Drifting: p &lt; {trend.ALPHA} and a change over the period of at least the "
            f"parameter's tolerance (or {trend.RELEVANT_CHANGE:.0%} of its first value where none is stated), so "
            f"a joint without drift is flagged with probability at most {trend.ALPHA:.0%} (measured false-alarm "
            f"rate: docs/fleet.md). Ranking: drifting joints first, then each group by its p-value (smallest "
            f"first); the effect and quantity shown are the joint's strongest trend: one whose change reaches its "
            f"tolerance before any other, then the smallest p-value. A joint that is not drifting says which part "
            f"of the rule it misses: a large change that is not significant, or a significant one below its "
            f"tolerance.</p>"
            + _html_table(("rank", "joint", "drift p", "drifting", "effect", "quantity", "direction",
                           "change over the period (%)", "slope", "quantities tested"), body, marked))


def _joint_figure(joint: str, joint_rows: list[dict], drift) -> str:
    ok = [r for r in joint_rows if r.get("status") == "ok"]
    shown = [tr.quantity for tr in drift.trends]
    if not ok or not shown:
        return ""
    days = trend._days([r.get("date") for r in ok])
    units = {tr.quantity: _quantity(tr.quantity)[1] for tr in drift.trends}
    labels = {tr.quantity: tr.quantity + (f" ({units[tr.quantity]})" if units[tr.quantity] else "")
              + f", p = {tr.p_value:.2g}" for tr in drift.trends}
    cols = min(3, len(shown))
    nrows = math.ceil(len(shown) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(3.6 * cols, 2.6 * nrows), constrained_layout=True, squeeze=False)
    for ax, name in zip(axes.flat, shown):
        v = np.array([trend.quantity(r, name) for r in ok])
        order = np.argsort(days)
        x, y, lo, hi = days[order], v[order, 0], v[order, 1], v[order, 2]
        err = np.where(np.isfinite(lo) & np.isfinite(hi), np.vstack([y - lo, hi - y]), 0.0)
        colour = "tab:red" if drift.strongest and name == drift.strongest.quantity and drift.drifting else "tab:blue"
        ax.errorbar(x, y, yerr=err, fmt="o-", color=colour, capsize=3, ms=4)
        ax.set_title(labels[name], fontsize=9, parse_math=False)
        ax.set_xlabel("days", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(shown):]:
        ax.axis("off")
    # parse_math=False: a joint id is the user's text ("$x$" is no formula to typeset).
    fig.suptitle(f"joint {joint}: calibrated values and 95 % intervals over time", fontsize=10, parse_math=False)
    uri = to_data_uri(fig)
    return f'<figure><img src="{uri}" alt="joint {html.escape(joint)} parameters over time"></figure>'


def _findings_text(row: dict) -> str:
    parts = []
    for f in row.get("findings") or []:
        kind = f" {f['kind']}" if f.get("kind") else ""
        conf = f.get("confidence")
        p = f.get("p_value")
        stats = [f"confidence {conf:.2f}" if isinstance(conf, float) and math.isfinite(conf) else "",
                 f"p {p:.2g}" if isinstance(p, float) and math.isfinite(p) else ""]
        parts.append(f"{f['effect']}{kind} ({', '.join(s for s in stats if s)})")
    return "; ".join(parts)


def _recordings(found: list[dict]) -> str:
    body = []
    for r in sorted(found, key=lambda r: (str(r.get("joint")), str(r.get("date")))):
        if r.get("status") != "ok":
            continue
        rms = r.get("est.tau_hat.rms", r.get("est.corrected.tau_ukf.rms", math.nan))
        body.append((r.get("joint"), r.get("date"), Path(r["recording"]).name, r.get("verdict") or "",
                     _findings_text(r), rms, r.get("seconds", math.nan)))
    return ("<h2>Effects found per recording</h2>"
            + _html_table(("joint", "date", "recording", "verdict", "findings (kind, confidence, p-value)",
                           "estimator RMS error vs sensor (N.m)", "seconds"), body))


def _failures(found: list[dict]) -> str:
    failed = [r for r in found if r.get("status") != "ok"]
    if not failed:
        return "<h2>Failures</h2><p>None.</p>"
    return (f"<h2>Failures</h2><p>{len(failed)} recording(s) failed; the rest went on.</p>"
            + _html_table(("joint", "recording", "reason"),
                          [(r.get("joint"), r.get("recording"), r.get("error")) for r in failed]))


def build(found: list[dict]) -> str:
    drifts = trend.rank_joints([r for r in found])
    by_joint: dict[str, list[dict]] = {}
    for r in found:
        by_joint.setdefault(str(r.get("joint")), []).append(r)
    commands = sorted({html.escape(str(r.get("command"))) for r in found})
    ok = sum(r.get("status") == "ok" for r in found)
    sections = [(f"<h1>Fleet report</h1><p>{len(found)} recordings of {len(by_joint)} joints ({', '.join(commands)}): "
                f"{ok} done, {len(found) - ok} failed. Written "
                f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC.</p>")]
    if any(d.trends for d in drifts):
        sections.append(_ranking(drifts))
        sections.append("<h2>Parameters over time, per joint</h2>")
        for d in drifts:
            sections.append(f"<h3>{html.escape(d.joint)}</h3>" + _joint_figure(d.joint, by_joint[d.joint], d))
    else:
        sections.append("<h2>Joints ranked by drift</h2><p>No calibrated parameters to follow (estimate runs, "
                        "or fewer than three recordings per joint).</p>")
    sections += [_recordings(found), _failures(found)]
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>hdjoint fleet report</title>"
            f"<style>{STYLE}</style></head><body>{''.join(sections)}</body></html>\n")


def write_report(out: str | Path, found: list[dict]) -> Path:
    path = Path(out) / "fleet.html"
    store.atomic_write(path, build(found).encode())
    return path
