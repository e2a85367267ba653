"""The demo's first screen, in words a controls engineer reads in 30 seconds:
what was hidden, what the diagnosis named (with its interval, in units),
closure on the second recording, and tau_hat's error before and after. The
same lines are printed, written to summary.md, and open index.html."""
from __future__ import annotations

import html
from pathlib import Path

from hdjoint.app.demo_story import DURATION, FIRST, HIDDEN, SECOND, Story
from hdjoint.diagnosis import INTERVAL
from hdjoint.io import parameters
from hdjoint.io.outputs import write_whole

TITLE = "hdjoint demo: a hidden effect named, modelled and closed without a torque sensor"
# The files a reader opens next, with what each one is.
LINKS = (("diagnosis/report.html", "the diagnosis of the first recording (report)"),
         ("diagnosis/params.json", "the corrected parameter set"),
         ("closure/report.html", "the corrected set diagnosed on the second recording (report)"),
         ("second_tau_hat.csv", "tau_hat on the second recording, nominal and corrected sets, and the true torque"),
         ("paper_table.md", "the paper's table (its experiment, its estimators)"))
FIGURES = (("second_tau_hat.png", "tau_hat against the true torque on the second recording"),
           ("paper_torque.png", "the paper's experiment: estimates against the true torque"))


def _meaning(name: str) -> str:
    """A parameter's description up to its first clause: what it is, not its formula."""
    text = parameters.table()[name].description
    for stop in (", ", " ("):
        text = text.split(stop)[0]
    return text


def _value(name: str, value: float) -> str:
    return f"{value:.3g} {parameters.table()[name].unit}"


def hidden_line(story: Story) -> str:
    sizes = "; ".join(f"{_meaning(n)} = {_value(n, v)}" for n, v in story.hidden.items())
    return (f"Hidden in the paper's joint, left out of its nominal parameter set: {HIDDEN.name} ({sizes}). "
            f"Recorded twice without a torque sensor: {DURATION:.0f} s {FIRST}, then {DURATION:.0f} s {SECOND}.")


def _named(finding: dict) -> str:
    intervals = finding.get("intervals") or {}
    sizes = []
    for name, value in finding["parameters"].items():
        if name not in intervals:
            continue
        lo, hi = intervals[name] or (None, None)
        bounds = (f", {100 * INTERVAL:.0f} % interval {lo:.3g} to {_value(name, hi)}" if lo is not None
                  else ", no interval")
        sizes.append(f"{_meaning(name)} = {_value(name, value)}{bounds}")
    return f"{finding['effect']} ({finding['kind']}, p = {finding['p_value']:.2g}): " + "; ".join(sizes)


def named_line(story: Story) -> str:
    findings = story.diagnosis["findings"]
    hits = [f for f in findings if f["effect"] in HIDDEN.present]
    others = [f["effect"] for f in findings if f not in hits]
    if not hits:
        return (f"Named on the {FIRST} recording: not {HIDDEN.name} (verdict "
                f"{story.diagnosis['verdict'].replace('_', ' ')}; findings: {', '.join(others) or 'none'}).")
    also = f" Also named: {', '.join(others)}." if others else ""
    beyond = story.diagnosis["beyond_tolerance"]
    rest = ("beyond their tolerance: " + ", ".join(f"{n} ({_meaning(n)})" for n in beyond) if beyond
            else "within their tolerances")
    return (f"Named on the {FIRST} recording: " + "; ".join(map(_named, hits)) +
            f". Corrected set (the other parameters calibrated, {rest}): diagnosis/params.json.{also}")


def closure_line(story: Story) -> str:
    verdict = story.closure["verdict"].replace("_", " ")
    closed = "closed" if story.closure["verdict"] == "consistent" else "not closed"
    checks = story.diagnosis.get("validation") or []
    residuals = "; ".join(f"{name} {row['nominal']['rms']:.3g} -> {row['corrected']['rms']:.3g} N.m"
                          for name, row in (checks[0]["channels"].items() if checks else ()))
    untold = [x.get("effect") or x["parameter"] for x in story.closure.get("cannot_tell", [])]
    caveat = f" (that recording cannot tell {', '.join(untold)})" if untold else ""
    return (f"Closure on the {SECOND} recording (another excitation): {closed}, the corrected set's "
            f"diagnosis there is {verdict}{caveat}. Residual RMS there, nominal -> corrected set: {residuals}.")


def tau_hat_line(story: Story) -> str:
    before, after = story.tau_hat["nominal"], story.tau_hat["corrected"]
    share = lambda x: 100.0 * x / story.torque_span
    return (f"tau_hat (JointTorqueEstimator.fmu) on the {SECOND} recording against the true joint torque, nominal -> corrected set: "
            f"RMS {before.rms:.3f} -> {after.rms:.3f} N.m ({share(before.rms):.1f} % -> {share(after.rms):.1f} % "
            f"of its {story.torque_span:.1f} N.m span), max {before.max:.3f} -> {after.max:.3f} N.m.")


def summary_lines(story: Story) -> list[str]:
    return [hidden_line(story), named_line(story), closure_line(story), tau_hat_line(story)]


def write_summary(out: Path, story: Story) -> None:
    lines = [f"# {TITLE}", "", *[f"- {line}" for line in summary_lines(story)], "",
             *[f"- [{target}]({target}): {what}" for target, what in LINKS]]
    write_whole(out / "summary.md", "\n".join(lines) + "\n")


def write_index(out: Path, story: Story) -> None:
    """index.html: the summary box first, then links and figures (files beside it)."""
    items = "".join(f"<li>{html.escape(line)}</li>" for line in summary_lines(story))
    links = "".join(f"<li><a href='{target}'>{html.escape(what)}</a></li>" for target, what in LINKS)
    figures = "".join(f"<figure><img src='{image}' alt='{html.escape(what)}' style='max-width:100%'>"
                      f"<figcaption>{html.escape(what)}</figcaption></figure>" for image, what in FIGURES)
    page = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(TITLE)}</title>"
            "<style>body{font-family:sans-serif;max-width:1100px;margin:1em auto;line-height:1.4}"
            "#summary{border:3px solid #446;padding:0.3em 1em;margin-bottom:1em}li{margin:0.3em 0}</style></head>"
            f"<body><section id='summary'><h1>{html.escape(TITLE)}</h1><ul>{items}</ul></section>"
            f"<section><h2>Files</h2><ul>{links}</ul></section>{figures}</body></html>\n")
    write_whole(out / "index.html", page)
