"""The diagnosis report: one self-contained HTML page (figures embedded as
PNG data URIs) that shows where the mismatch is, what was left out, the
model added and the fit before and after."""
from __future__ import annotations

import html

import numpy as np

from hdjoint.diagnosis.output import plots as dp
from hdjoint.diagnosis.verdict.detection_limit import size_in_words
from hdjoint.diagnosis.forked import map_forked
from hdjoint.diagnosis.rules import (
    EVIDENCE_Z,
    FALSE_DISCOVERY_RATE,
    FOLDS,
    SEEN_BIC,
    STEADY_FOLD_SHARE,
)
from hdjoint.diagnosis.model.structure import candidate_orders
from hdjoint.io.parameters import unit_in_text, values_in_text
from hdjoint.io.screening import found_anything

VERDICT_TEXT = {
    "missing_physics": "Physics is missing from the nominal model: the findings below name it, model it and "
                       "show the fit improve on held-out data.",
    "consistent": "Nothing is missing: after calibration the residuals hold no structure that predicts held-out "
                  "data; what remains is noise and quantisation.",
    "unexplained": "Structure remains that no hypothesis of the library explains; where it is is listed below.",
}


# What the evidence's numbers mean, said once on the page (before the first section that uses them).
EVIDENCE_TERMS = (
    f"<p><b>Reading the evidence.</b> The recording is cut into {FOLDS} blocks; the model is fitted on every "
    "other one and judged on the rest, the held-out folds.</p><ul class='terms'>"
    "<li><b>Held-out gain</b>: the share of the mean-square residual on the held-out folds that the effect "
    "removes, pooled over the channels that see its part (each in units of its own noise), at the effect's own "
    "fit. The findings table's RMS columns are one channel's residual in N.m, before and after the corrected "
    "model's final fit, so the gain is not 1 - (after / before)².</li>"
    "<li><b>z</b>: the mean improvement over the held-out folds in standard errors; <b>better in k of n held-out "
    f"folds</b>: how many of them it improved. An effect present all the time needs z above {EVIDENCE_Z:g} and "
    f"{STEADY_FOLD_SHARE:.0%} of the folds; for one uneven over time by nature (a dead zone, a drift) p decides.</li>"
    "<li><b>p</b>, against the <b>simulated null</b>: copies of the calibrated model's own residuals with their "
    "phases randomised (the same spectrum, nothing locked to angle, speed or load), fitted and judged like the "
    f"recording. p below {FALSE_DISCOVERY_RATE:g} after the Benjamini-Hochberg correction over the hypotheses "
    "counts.</li>"
    "<li><b>ΔBIC</b>: the Bayesian information criterion with the effect minus without it, on the fitted folds; "
    f"below {SEEN_BIC:g} is very strong support for the extra parameters.</li></ul>")


def _gain(g: float) -> str:
    """A held-out gain (a share) as the page writes every one: a percentage."""
    return f"{100 * g:.1f} %"


class Figures:
    """The page's figures, drawn together in forked processes (forked.py):
    matplotlib's layout and PNG encoding take most of the report's time, and
    each figure is independent of the others. Each job names its plot
    function and arrays, so a helper forked before the diagnosis, with
    matplotlib imported meanwhile, can draw them while the diagnosis ends.
    `where`, `loop` and `fit` are the page's parts that show them."""

    def __init__(self, helper=None):
        self.jobs: list[tuple] = []
        self.helper = helper
        self.where = self.loop = self.fit = ""

    def add(self, plot, args: tuple, size=(9, 3.2)) -> str:
        """A placeholder for the figure plot(ax, *args) makes, filled in by fill()."""
        self.jobs.append((plot, args, size))
        return f"\x00figure {len(self.jobs) - 1}\x00"

    def fill(self, page: str) -> str:
        if self.helper is not None:
            uris = self.helper.collect()
        else:
            uris = map_forked(lambda i: dp.png_uri(self.jobs[i]), len(self.jobs))
        for i, uri in enumerate(uris):
            page = page.replace(f"\x00figure {i}\x00", uri)
        return page


def figures(diag, p0: dict, p1: dict, segments: list, helper=None) -> Figures:
    """The report's figures of a diagnosis (its Objective) from the
    calibrated set p0 to the corrected set p1, the findings' time
    `segments` shaded: started now by `helper` (forked.Helper, prepared with
    plots.prepare_drawing) if given, else drawn by processes forked in fill()."""
    rec, kin = diag.rec, diag.prep.kin
    drawn = Figures(helper)
    # Where: every channel's residual over time, before and after, segments marked.
    figs = []
    for c in diag.channels:
        before, after = diag.shown_residual(c, p0), diag.shown_residual(c, p1)
        figs.append(_img(drawn.add(dp.residual_over_time, (rec.time, before, after, segments, f"{c.name} residual")),
                         f"Residual of the {c.name} channel over time (located segments shaded)"))
        figs.append(_img(drawn.add(dp.residual_vs_feature, (kin.omega_m, before, after, "motor speed (rad/s)"),
                                   (6, 3)),
                         f"{c.name}: mean residual vs motor speed (regime)"))
        orders = candidate_orders("theta_m", np.ptp(rec.theta_m))
        if orders:
            figs.append(_img(drawn.add(dp.order_spectrum, (rec.theta_m, before, after, orders, "theta_m"), (6, 3)),
                             f"{c.name}: order spectrum of the residual over the motor angle"))
    drawn.where = "<h2>Where the model and the recording differ</h2>" + "".join(figs)

    # The torque-torsion loop, where the transmission is involved.
    if any("transmission" in c.parts() for c in diag.channels):
        from hdjoint import _core
        from hdjoint.io import parameters
        est = _core.compliance(parameters.for_estimator(p1), rec.i_m, rec.theta_m, rec.theta_l)
        reference = diag.reference_torque(p1)
        drawn.loop = "<h2>Torque against torsion</h2>" + _img(
            drawn.add(dp.torque_torsion_loop, (est["dtheta_f"], reference, est["tau_compliance"]), (6, 4)),
            "Reference torque vs flexspline torsion: loops mean hysteresis, flats backlash")

    labels = [c.name for c in diag.channels]
    rb = [float(np.sqrt(np.nanmean(diag.shown_residual(c, p0)[diag.test] ** 2))) for c in diag.channels]
    ra = [float(np.sqrt(np.nanmean(diag.shown_residual(c, p1)[diag.test] ** 2))) for c in diag.channels]
    drawn.fit = _img(drawn.add(dp.rms_bars, (labels, rb, ra, "held-out RMS residual (N.m)"), (6, 3)),
                     "Held-out residual RMS per channel: calibrated nominal vs corrected model")
    if helper is not None:
        helper.submit(dp.png_uri, drawn.jobs)
    return drawn


def _img(uri: str, alt: str) -> str:
    return f'<figure><img src="{uri}" alt="{html.escape(alt)}"><figcaption>{html.escape(alt)}</figcaption></figure>'


def _table(rows, header) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _fmt(x) -> str:
    return f"{x:.4g}" if isinstance(x, (int, float)) else str(x)


def _meaning(name: str) -> tuple[str, str]:
    """A parameter's unit and the first clause of its description (the parameter table's), or blanks."""
    from hdjoint.io.parameters import meaning, table
    info = table().get(name)
    if info is None:
        return "", ""
    return ("" if info.unit == "1" else info.unit), meaning(name)


def _fixed(x: float, digits: int = 2) -> str:
    """X to DIGITS decimals, never '-0.00' (a negative number that rounds to zero reads as zero)."""
    text = f"{x:.{digits}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def _where_text(w: dict) -> str:
    """A finding's location in words (never a raw dict)."""
    regime = w["regime"] if isinstance(w["regime"], str) else ", ".join(
        f"{name} ({ratio}x its share of time)" for name, ratio in w["regime"].items())
    text = (f"the {w['part']} ({w['channel']} channel), {100 * w['fraction_of_time']:.0f} % of the time; "
            f"concentrated: {regime}")
    if w.get("time_segments"):
        text += "; strongest at " + ", ".join(f"{a:g}-{b:g} s" for a, b in w["time_segments"][:3])
    if w.get("angle"):
        text += "; at " + ", ".join(f"order {o['order']:g} of {o['angle']}" + (f" ({o['note']})" if "note" in o else "")
                                    for o in w["angle"])
    return text


def _one_of(f: dict) -> str:
    """A look-alike set's members with their shares of the evidence."""
    return " or ".join(f"{html.escape(a['effect'])} ({100 * a['evidence_share']:.0f} % of the evidence)"
                       for a in f["alternatives"])


def _finding_line(f: dict) -> str:
    head = f"<b>{html.escape(f['kind'])}</b>: {html.escape(f['effect'])} (p = {f['p_value']:.2g})"
    values = _finding_values(f)
    if f["kind"] == "ambiguous":
        resized = " resized" if f.get("resized") else ""
        return f"{head}: one of {_one_of(f)}; modelled as {html.escape(f['effect'])}{resized}: {values}"
    return f"{head}: {values}"


def _named(n: str, value: str, extra: str = "") -> str:
    """NAME = VALUE UNIT (MEANING; EXTRA), escaped: a parameter as a reader needs it."""
    unit, meaning = _meaning(n)
    said = "; ".join(x for x in (meaning, extra) if x)
    return html.escape(f"{n} = {value}" + (f" {unit}" if unit else "") + (f" ({said})" if said else ""))


def _calibrated_text(n: str, v: dict) -> str:
    """A calibrated or resized parameter: estimate, interval, unit, meaning, nominal and tolerance."""
    return _named(n, f"{_fmt(v['estimate'])} [{_fmt(v['lo'])}, {_fmt(v['hi'])}]",
                  f"nominal {_fmt(v['nominal'])} ± {_fmt(v['tolerance'])}")


def _finding_values(f: dict) -> str:
    """A finding's parameters with intervals, units and meanings (a resized one's with its nominal value),
    and the estimator's caveat."""
    if f.get("resized"):
        return "; ".join(_calibrated_text(n, v) for n, v in f["parameters"].items())
    intervals = f.get("intervals", {})
    values = "; ".join(_named(n, _fmt(v) + (f" [{_fmt(intervals[n][0])}, {_fmt(intervals[n][1])}]"
                                             if intervals.get(n) else ""))
                       for n, v in f["parameters"].items())
    caveat = f.get("in_the_estimator", {}).get("caveat")
    return values + (f". <i>Caveat: {html.escape(caveat)}</i>" if caveat else "")


def _summary(doc: dict) -> str:
    """The box a reader sees first: verdict, findings, moved parameters, what remains, what to record next."""
    items = [(f"<p class='verdict'><b>Verdict: {html.escape(doc['verdict'].replace('_', ' '))}.</b> "
             f"{html.escape(VERDICT_TEXT[doc['verdict']])}</p>")]
    if doc["findings"]:
        items.append("<ul>" + "".join(f"<li>{_finding_line(f)}</li>" for f in doc["findings"]) + "</ul>")
    moved = [n for n in doc.get("beyond_tolerance", [])]
    items.append("<p><b>Parameters beyond their tolerance:</b> " + ("; ".join(
        _calibrated_text(n, doc["calibration"][n]) for n in moved) if moved else "none") + ".</p>")
    items.append("<p><b>Unexplained:</b> " + (html.escape("; ".join(
        f"{u['channel']} channel against {u['feature']} (held-out gain {_gain(u['held_out_gain'])})"
        for u in doc["unexplained"])) if doc["unexplained"] else "nothing") + ".</p>")
    if any(found_anything(x) for x in doc.get("screening", [])):
        items.append("<p><b>Screening:</b> " + html.escape("; ".join(
            f"{x['recording'] or 'recording'}: {x['summary']}" for x in doc["screening"] if found_anything(x)))
            + ".</p>")
    if doc.get("cannot_tell"):
        items.append("<p><b>This recording cannot tell:</b> " + html.escape("; ".join(
            f"{x.get('effect') or x['parameter']}: {x['why']}" for x in doc["cannot_tell"])) + ".</p>")
    advice = [f["separate_by"] for f in doc["findings"] if f.get("separate_by")]
    # An effect a look-alike set already names has its excitation in that set's sentence.
    in_a_set = {a["effect"] for f in doc["findings"] for a in f.get("alternatives") or []}
    advice += [f"To settle {x['effect']}, record {x['record']}." for x in doc.get("cannot_tell", [])
               if x.get("effect") and x["record"] and x["effect"] not in in_a_set]
    untested: dict[str, list[str]] = {}  # one sentence per reason, naming every effect it keeps untested
    for n in doc["not_testable"]:
        untested.setdefault(n["reason"].removeprefix("not testable on this recording: "), []).append(n["effect"])
    advice += [f"To test {', '.join(effects)}, record a motion that removes this: {reason}."
               for reason, effects in untested.items()]
    items.append("<p><b>What to record next:</b> " + (html.escape(" ".join(advice)) if advice
                                                      else "nothing needed to settle these findings") + "</p>")
    return "<section id='summary' class='summary'>" + "".join(items) + "</section>"


def _recording_text(doc: dict) -> str:
    recordings = doc.get("recordings") or [doc["recording"]]
    parts = [f"{r['path'] or 'recording'} ({r['samples']} samples, {r['duration']:.1f} s)" for r in recordings]
    sensor = "with" if doc["recording"]["torque_sensor"] else "without"
    return (f"Recording{'s fitted jointly' if len(parts) > 1 else ''}: {'; '.join(parts)}, {sensor} a torque sensor; "
            f"{doc['recording']['analysed_samples']} samples analysed" + _alignment_text(doc["recording"]))


def _alignment_text(recording: dict) -> str:
    a = recording.get("current_alignment")
    if not a:
        return ""
    return (f"; the current acting at each encoder sample is the one logged {_fixed(-a['estimate'] * 1e3)} ms before "
            f"it (95 % interval {_fixed(-a['hi'] * 1e3)} to {_fixed(-a['lo'] * 1e3)} ms; "
            f"{_fixed(-a['bounds'][0] * 1e3)} ms is a current held over each sample)")


def _validation_section(entries: list[dict]) -> str:
    rows = []
    for v in entries:
        for channel, row in v["channels"].items():
            rows.append((v["path"], channel, _fmt(row["nominal"]["rms"]), _fmt(row["calibrated"]["rms"]),
                         _fmt(row["corrected"]["rms"]), _fmt(row["calibrated"]["max"]), _fmt(row["corrected"]["max"])))
        e = v.get("estimator")
        if e and "error" not in e["nominal"] and "error" not in e["corrected"]:
            for name in ("tau_compliance", "tau_ukf"):
                rows.append((v["path"], f"{name} vs sensor", _fmt(e["nominal"][name]["rms"]), "",
                             _fmt(e["corrected"][name]["rms"]), "", _fmt(e["corrected"][name]["max"])))
    return ("<h2>Other recordings (never fitted)</h2><p>The corrected model on recordings the diagnosis did not "
            "see: residual per channel with the nominal, the calibrated (no findings) and the corrected "
            "parameters, each with the encoder zero and the current alignment placed on that recording.</p>"
            + _table(rows, ["recording", "channel", "RMS nominal", "RMS calibrated",
                            "RMS corrected", "max calibrated", "max corrected"])
            + _extrapolation_notes(entries))


def _limits_section(limits: list[dict]) -> str:
    """The smallest size of each effect tested and not found that this recording would have shown."""
    rows = [(x["effect"] + "".join(f" at {angle} order {_fmt(order)}" for angle, order in x.get("orders", []))
             + (f" with {values_in_text(x['with'], described=True)}" if x.get("with") else ""),
             f"{size_in_words(x['parameter'], bool(x.get('orders')))} of {_fmt(x['reference'])}"
             f"{unit_in_text(x['unit'])}" + (f" ({x['reference_source']})" if x.get("reference_source") else ""),
             "none up to 1024 times that (or the parameter's valid range)" if x["limit"] is None else
             f"{_fmt(x['limit'])}{unit_in_text(x['unit'])} ({_fmt(x['times_reference'])} times the reference)")
            for x in limits]
    return ("<h2>How large an effect this recording would show</h2><p>Each effect tested and not found, planted "
            "into the corrected model at sizes around a reference; what calibration would take of it removed, the "
            "rest judged by the diagnosis's own test. An effect smaller than its limit may be present unseen; "
            "the limit is a lower bound (the effect's fit is taken to find its exact terms).</p>"
            + _table(rows, ["effect", "reference size", "smallest size shown"]))


def _extrapolation_notes(entries: list[dict]) -> str:
    """A sentence per recording that leaves the fitted operating range: its figures test the model's form there."""
    notes = [f"<li><b>{html.escape(str(v['path']))}</b>: {html.escape(q['warning'])}</li>"
             for v in entries for q in v.get("extrapolation", []) if q.get("warning")]
    if not notes:
        return ""
    return ("<p>Extrapolated: these recordings go where the diagnosed one did not, so their figures test "
            "the model's form there rather than its fitted parameters.</p><ul>" + "".join(notes) + "</ul>")


def build(result, doc: dict, helper=None, drawn: Figures | None = None) -> str:
    """The report's HTML for a finished diagnosis (DiagnosisResult) and its
    findings document; its figures those `drawn` started (figures()), else
    drawn now (by `helper`, if given)."""
    diag = result.objective
    if drawn is None:
        segments = [s for f in doc["findings"] for s in f["where"]["time_segments"]]
        drawn = figures(diag, result.calibrated_params, doc["params"], segments, helper)
    sections = [drawn.where] + ([drawn.loop] if drawn.loop else [])

    # Findings.
    if doc["findings"]:
        rows = [(f["effect"], f["kind"], f["where"]["part"], f"{f['p_value']:.2g}", f["confidence"],
                 _gain(f["evidence"]["held_out_gain"]) if "held_out_gain" in f["evidence"] else "",
                 f["fit"]["channel"], _fmt(f["fit"]["holdout_rms_before"]), _fmt(f["fit"]["holdout_rms_after"]))
                for f in doc["findings"]]
        parts = ["<h2>Findings</h2>", EVIDENCE_TERMS,
                 _table(rows, ["effect", "kind", "part", "p-value", "confidence", "held-out gain",
                               "channel shown", "its held-out RMS before (N.m)", "after (N.m)"])]
        for f in doc["findings"]:
            ev = f["evidence"]
            text = (f"<h3>{html.escape(f['effect'])} ({html.escape(f['kind'])}, p = {f['p_value']:.2g})</h3>"
                    f"<p><b>Left out:</b> {html.escape(ev['physics_left_out'])}. <b>Model:</b> "
                    f"{html.escape(f['model'])}.</p><p><b>Where:</b> {html.escape(_where_text(f['where']))}.</p>")
            if "held_out_gain" in ev:
                runner = (f"{ev['runner_up']['effect']} (held-out gain {_gain(ev['runner_up']['held_out_gain'])})"
                          if ev["runner_up"] else "none")
                better, compared = str(ev["folds_improved"]).split("/")
                seen = (f" of {html.escape(ev['seen_on'])}, the torque channels together predicting no worse with "
                        "it (the encoders cannot tell it from an encoder's own error at that order)"
                        if ev.get("seen_on") else "")
                text += (f"<p><b>Evidence:</b> held-out gain {_gain(ev['held_out_gain'])}{seen} (z = {ev['z']}; "
                         f"better in {better} of {compared} held-out folds), p = {f['p_value']:.2g} against the "
                         f"simulated null, ΔBIC {ev['delta_bic']}, runner-up {html.escape(runner)}.</p>")
            if f.get("separate_by"):
                text += f"<p><b>Look-alikes:</b> {html.escape(f['separate_by'])}</p>"
            # Its values, not the summary's whole line again.
            text += f"<p><b>{'Resized' if f.get('resized') else 'Fitted'}:</b> {_finding_values(f)}</p>"
            parts.append(text)
        sections.append("".join(parts))

    # Fit before/after and the estimator.
    fit_html = drawn.fit
    if doc.get("estimator"):
        e = doc["estimator"]
        rows = [(name, _fmt(e["nominal"][name]["rms"]), _fmt(e["corrected"][name]["rms"]),
                 _fmt(e["nominal"][name]["max"]), _fmt(e["corrected"][name]["max"]))
                for name in ("tau_compliance", "tau_ukf") if "error" not in e["nominal"] and "error" not in e["corrected"]]
        failed = [f"{label} parameters: {e[label]['error']}" for label in ("nominal", "corrected") if "error" in e[label]]
        fit_html += "<h3>Torque estimators against the torque sensor</h3>" + _table(
            rows, ["estimate", "RMS nominal", "RMS corrected", "max nominal", "max corrected"])
        fit_html += "".join(f"<p>The estimator did not run with the {html.escape(f)}</p>" for f in failed)
    sections.append("<h2>Fit before and after</h2>" + fit_html)
    if doc.get("validation"):
        sections.append(_validation_section(doc["validation"]))

    cal = [(n, *_meaning(n), _fmt(v["nominal"]), _fmt(v["estimate"]), f"[{_fmt(v['lo'])}, {_fmt(v['hi'])}]",
            _fmt(v["tolerance"]), _fixed(v['z']), "yes" if v["identified"] else "no")
           for n, v in doc["calibration"].items()]
    sections.append("<h2>Calibration of the nominal parameters</h2><p>Maximum a posteriori, each parameter's "
                    "tolerance its prior; 95 % intervals from the Laplace approximation; z = (estimate - nominal) / "
                    "tolerance; identified: the recording narrows the prior by more than half.</p>" + _table(
                        cal, ["parameter", "unit", "meaning", "nominal", "estimate", "95 % interval", "tolerance", "z",
                              "identified"]))
    if doc["unexplained"]:
        sections.append("<h2>Unexplained structure</h2>" + ("" if doc["findings"] else EVIDENCE_TERMS) + _table(
            [(u["channel"], u["feature"], _gain(u["held_out_gain"]) if u.get("held_out_gain") is not None else "",
              u["largest_at"] if u.get("largest_at") not in (None, "", "-") else "not located")
             for u in doc["unexplained"]],
            ["channel", "feature", "held-out gain", "largest at"]))
    if doc.get("detection_limits"):
        sections.append(_limits_section(doc["detection_limits"]))
    if doc["not_testable"]:
        sections.append("<h2>Not testable on this recording</h2>" + _table(
            [(n["effect"], n["reason"]) for n in doc["not_testable"]], ["effect", "why"]))

    title = f"hdjoint diagnosis: {doc['verdict']}"
    return drawn.fill("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>" + html.escape(title) +
            "</title><style>body{font-family:sans-serif;max-width:70em;margin:1.5em auto;color:#222}"
            "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .5em}"
            "img{max-width:100%}figure{margin:.5em 0}figcaption{font-size:.85em;color:#555}"
            ".summary{border:2px solid #446;padding:.3em 1em;background:#f4f4fb}.verdict{font-size:1.15em}"
            "</style></head><body>"
            f"<h1>{html.escape(title)}</h1>" + _summary(doc) +
            f"<p>{html.escape(_recording_text(doc))}; diagnosed in {doc.get('seconds', '?')} s.</p>"
            + "".join(sections) + "</body></html>")
