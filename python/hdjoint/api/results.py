"""What the API's jobs return: a `Diagnosis` with its `Finding`s, and a
`Calibration`. Each wraps the document the command line writes
(findings.json, est.calibration.json), so a notebook and a shell see the
same results; each has a one-line or short repr in words and units."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from html import escape
from pathlib import Path

from hdjoint.api.parameters import Parameters
from hdjoint.io import parameters as table_io

__all__ = ["Finding", "Diagnosis", "Calibration"]


def _unit(name: str) -> str:
    info = table_io.table().get(name)
    return table_io.unit_in_text(info.unit) if info else ""


def _value(name: str, value) -> str:
    return f"{name} = {value:.3g}{_unit(name)}" if isinstance(value, (int, float)) else f"{name} = {value}"


@dataclass(frozen=True, repr=False)
class Finding:
    """One thing the diagnosis found the model lacks (or mis-sizes), from
    findings.json: which effect, where, its fitted parameters with their
    intervals, and the held-out fit before and after.

    >>> Finding.from_document({"effect": "backlash", "kind": "missing", "confidence": 0.97,
    ...     "where": {"part": "gear"}, "parameters": {"backlash": 0.002},
    ...     "intervals": {"backlash": [0.0018, 0.0022]},
    ...     "fit": {"holdout_rms_before": 0.185, "holdout_rms_after": 0.047}})
    Finding(backlash, missing in the gear: backlash = 0.002 rad (95 % 0.0018 to 0.0022 rad); held-out RMS 0.185 -> 0.047 N.m; confidence 0.97)
    """
    effect: str                      # the effect's ID (CONTRACT.md), e.g. "backlash"
    kind: str                        # "added", "ambiguous" (a look-alike explains as much), ... (findings.json)
    part: str                        # where in the joint: "motor", "gear", "link", ...
    confidence: float                # 0..1
    parameters: dict = field(default_factory=dict)   # name: fitted value (resized: name: {nominal, estimate, ...})
    intervals: dict = field(default_factory=dict)    # name: [lo, hi] at the diagnosis's coverage (95 %)
    holdout_rms: tuple[float, float] | None = None   # the residual's held-out RMS before and after, N.m
    document: dict = field(default_factory=dict)     # the whole entry of findings.json

    @classmethod
    def from_document(cls, entry: dict) -> "Finding":
        fit = entry.get("fit") or {}
        before, after = fit.get("holdout_rms_before"), fit.get("holdout_rms_after")
        return cls(effect=entry["effect"], kind=entry.get("kind", "missing"),
                   part=(entry.get("where") or {}).get("part", ""), confidence=float(entry.get("confidence", 0.0)),
                   parameters=dict(entry.get("parameters") or {}), intervals=dict(entry.get("intervals") or {}),
                   holdout_rms=(before, after) if before is not None and after is not None else None,
                   document=entry)

    def _parameter_words(self) -> list[str]:
        words = []
        for name, value in self.parameters.items():
            if isinstance(value, dict):  # resized: nominal -> estimate
                words.append(f"{name} {value.get('nominal', float('nan')):.3g} -> "
                             f"{value.get('estimate', float('nan')):.3g}{_unit(name)}")
                continue
            interval = self.intervals.get(name)
            text = _value(name, value)
            if interval and None not in interval:
                text += f" (95 % {interval[0]:.3g} to {interval[1]:.3g}{_unit(name)})"
            words.append(text)
        return words

    def __repr__(self) -> str:
        where = f" in the {self.part}" if self.part else ""
        parts = [f"{self.effect}, {self.kind}{where}: " + (", ".join(self._parameter_words()) or "no parameters")]
        if self.holdout_rms:
            parts.append(f"held-out RMS {self.holdout_rms[0]:.3g} -> {self.holdout_rms[1]:.3g} N.m")
        parts.append(f"confidence {self.confidence:.2f}")
        return f"Finding({'; '.join(parts)})"


class Diagnosis:
    """A diagnosis's results: the verdict, the findings, the corrected
    parameter set, and the report; what `hdjoint diagnose` writes into its
    folder (`Diagnosis.load` reads such a folder).

    >>> import hdjoint
    >>> rec = hdjoint.simulate("paper", duration=4.0)   # doctest: +SKIP
    >>> d = hdjoint.diagnose(rec)                        # doctest: +SKIP
    >>> d.verdict                                        # doctest: +SKIP
    'consistent'
    """

    def __init__(self, document: dict, corrected: Parameters, report_html: str = "",
                 names: list[str] | None = None):
        self.document = document
        """findings.json, as a dict (docs/diagnosis.md says what each entry means)."""
        self.corrected = corrected
        """The corrected parameter set (params.json): pass it to `estimate`."""
        self._report = report_html
        self._names = names

    @classmethod
    def load(cls, folder: str | os.PathLike) -> "Diagnosis":
        """The results in a folder `hdjoint diagnose --out` wrote."""
        folder = Path(folder)
        document = json.loads((folder / "findings.json").read_text())
        report = folder / "report.html"
        return cls(document, Parameters.load(folder / "params.json"), report.read_text() if report.exists() else "")

    @property
    def verdict(self) -> str:
        """'consistent', 'missing_physics' or 'unexplained' (docs/diagnosis.md)."""
        return self.document["verdict"]

    @property
    def findings(self) -> list[Finding]:
        return [Finding.from_document(f) for f in self.document.get("findings", [])]

    @property
    def unexplained(self) -> list[str]:
        """Residual structure no effect explains, in words."""
        return [f"{u['channel']} residual depends on {u['feature']}" for u in self.document.get("unexplained", [])]

    @property
    def recordings(self) -> list[str]:
        """The diagnosed recordings' paths ("in memory" for a Recording that came from no file)."""
        if self._names is not None:
            return list(self._names)
        recs = self.document.get("recordings") or [self.document.get("recording") or {}]
        return [str(r.get("path")) for r in recs if r.get("path")]

    def to_json(self) -> str:
        """findings.json's text (strict JSON: NaN written as null)."""
        from hdjoint.io.screening import strict_json
        return json.dumps(strict_json(self.document), indent=2, allow_nan=False) + "\n"

    def report(self, path: str | os.PathLike) -> Path:
        """Write the HTML report (the one `hdjoint diagnose` writes) to PATH; returns PATH."""
        path = Path(path)
        path.write_text(self._report)
        return path

    def plot(self, ax=None):
        """A matplotlib figure: each finding's held-out residual RMS before and
        after its fit and, with a torque sensor, the estimators' RMS error with
        the nominal and the corrected set."""
        import matplotlib.pyplot as plt
        findings = [f for f in self.findings if f.holdout_rms]
        estimator = self.document.get("estimator") or {}
        panels = 1 + bool(estimator)
        if ax is None:
            fig, axes = plt.subplots(1, panels, figsize=(5 * panels, 3.2), squeeze=False)
            axes = list(axes[0])
        else:
            axes, fig = [ax], ax.figure
        first = axes[0]
        names = [f.effect for f in findings] or ["(none)"]
        before = [f.holdout_rms[0] for f in findings] or [0.0]
        after = [f.holdout_rms[1] for f in findings] or [0.0]
        x = range(len(names))
        first.bar([i - 0.2 for i in x], before, 0.4, label="before")
        first.bar([i + 0.2 for i in x], after, 0.4, label="after")
        first.set_xticks(list(x), names, rotation=20, ha="right")
        first.set_ylabel("held-out residual RMS, N.m")
        first.set_title(f"verdict: {self.verdict}")
        first.legend()
        if estimator and len(axes) > 1:
            labels = [k for k in ("nominal", "corrected") if "error" not in estimator.get(k, {"error": 1})]
            est_names = sorted({n for k in labels for n in estimator[k]})
            for j, label in enumerate(labels):
                axes[1].bar([i + 0.4 * j - 0.2 for i in range(len(est_names))],
                            [estimator[label][n]["rms"] for n in est_names], 0.4, label=label)
            axes[1].set_xticks(list(range(len(est_names))), est_names)
            axes[1].set_ylabel("RMS error vs tau_sensor, N.m")
            axes[1].legend()
        fig.tight_layout()
        return fig

    def __repr__(self) -> str:
        lines = [f"Diagnosis({', '.join(self.recordings) or 'a recording'}: {self.verdict}"]
        lines += [f"  {f!r}" for f in self.findings]
        lines += [f"  unexplained: {u}" for u in self.unexplained]
        calibrated = self.document.get("calibration") or {}
        beyond = self.document.get("beyond_tolerance") or []
        lines.append(f"  .corrected: {len(calibrated)} parameters calibrated"
                     + (f", beyond their tolerance: {', '.join(beyond)}" if beyond else "") + ")")
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        rows = "".join(f"<li>{escape(repr(f))}</li>" for f in self.findings)
        rows += "".join(f"<li>unexplained: {escape(u)}</li>" for u in self.unexplained)
        return (f"<p><b>verdict: {escape(self.verdict)}</b> ({escape(', '.join(self.recordings))})</p>"
                f"<ul>{rows or '<li>no findings</li>'}</ul><details><summary>corrected parameters</summary>"
                f"{self.corrected._repr_html_()}</details>")


@dataclass(frozen=True, repr=False)
class Calibration:
    """A parameter set calibrated on recordings without a torque sensor
    (`hdjoint estimate --calibrate-from`'s first half): `.params` to estimate with."""
    params: Parameters
    verdict: str
    scale: float                                 # the joint's torque scale, x nominal
    scale_interval: tuple[float, float] | None   # its 95 % interval (None: a torque sensor measured it)
    in_words: str                                # the scale in a sentence
    table: dict                                  # per parameter: nominal, estimate, interval, value used

    def __repr__(self) -> str:
        moved = ", ".join(_value(n, e["used"]) for n, e in list(self.table.items())[:6] if "used" in e)
        return f"Calibration({self.verdict}; {moved}{', ...' if len(self.table) > 6 else ''}; {self.in_words})"
