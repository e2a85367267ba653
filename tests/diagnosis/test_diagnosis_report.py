"""The diagnosis report renders, with its figures, in a real headless
browser; it opens with the summary box, and prints no raw dict or JSON."""
import json
import re
import shutil
import subprocess

import numpy as np
import pytest
from hdjoint.app import cli
from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
from hdjoint.io.parameters import save
from hdjoint.io.recording import write_recording
from matplotlib.image import imread

pytestmark = pytest.mark.slow  # a diagnosis to report on, and Chromium

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory):
    case = next(c for c in CASES if c.present == ("backlash",))
    out = tmp_path_factory.mktemp("diag")
    write_recording(out / "rec.csv", record(case, duration=12.0))
    save(out / "nominal.json", nominal_for(case))
    assert cli.main(["diagnose", str(out / "rec.csv"), "--params", str(out / "nominal.json"),
                     "--out", str(out / "result")]) == 0
    return out / "result"


def test_report_is_self_contained(report_dir):
    page = (report_dir / "report.html").read_text()
    assert page.count("data:image/png;base64,") >= 5
    assert "src=\"http" not in page and "href=\"http" not in page


def _visible_text(page: str) -> str:
    page = re.sub(r"<style>.*?</style>", "", page, flags=re.DOTALL)
    return re.sub(r"<[^>]+>", " ", page)


def test_report_has_a_summary_first_and_no_raw_dicts(report_dir):
    page = (report_dir / "report.html").read_text()
    doc = json.loads((report_dir / "findings.json").read_text())
    text = _visible_text(page)
    assert "{" not in text and "}" not in text, "a raw dict or JSON object is printed in the report"
    summary = page[page.index("id='summary'"):page.index("</section>")]
    assert f"Verdict: {doc['verdict'].replace('_', ' ')}" in summary
    for f in doc["findings"]:
        assert f["effect"] in summary and f"p = {f['p_value']:.2g}" in summary
    assert "What to record next" in summary and "beyond their tolerance" in summary
    assert page.index("id='summary'") < page.index("<figure>")


def _screenshot(report_dir, tmp_path, height: int):
    shot = tmp_path / f"report_{height}.png"
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                    "--disable-background-networking", "--disable-component-update", "--disable-sync",
                    f"--user-data-dir={tmp_path / 'profile'}", "--hide-scrollbars", f"--window-size=1200,{height}",
                    f"--screenshot={shot}", (report_dir / "report.html").as_uri()],
                   check=True, capture_output=True, timeout=120)
    return imread(shot)[..., :3]


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (scripts/test.sh installs it)")
def test_the_summary_box_is_whole_on_the_first_screen(report_dir, tmp_path):
    """The summary's frame (#446 border) must show its top and bottom edges
    inside a laptop's first screen (1200 x 800): pushed below the fold, or
    longer than a screen, it fails."""
    image = _screenshot(report_dir, tmp_path, 800)
    frame = np.all(np.abs(image - np.array([0x44, 0x44, 0x66]) / 255.0) < 0.06, axis=2)
    edge_rows = np.flatnonzero(frame.sum(axis=1) > 0.5 * image.shape[1])
    assert len(edge_rows) >= 2, "the summary box's frame is not on the first screen"
    assert edge_rows[-1] - edge_rows[0] > 60, "only one edge of the summary box is on the first screen"


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (scripts/test.sh installs it)")
def test_report_renders_with_its_figures_in_chromium(report_dir, tmp_path):
    image = _screenshot(report_dir, tmp_path, 2400)
    assert image.shape[0] >= 2000
    # Figures are drawn in colour (red/blue residual lines); a page of text alone is grey.
    colourful = np.mean(np.ptp(image, axis=2) > 0.25)
    assert colourful > 0.002, f"the rendered report shows no figures ({colourful:.4%} coloured pixels)"


# ---------------------------------------------------------------- the evidence's numbers, each said once


def test_the_evidence_terms_are_explained_once_and_used_as_explained(report_dir):
    """ΔBIC, the simulated null and the fold counts ("13/20 folds") were printed with no word on
    what they are. The page now explains them once, and each finding's evidence uses those words."""
    page = (report_dir / "report.html").read_text()
    doc = json.loads((report_dir / "findings.json").read_text())
    assert page.count("Reading the evidence.") == 1
    terms = page[page.index("Reading the evidence."):]
    for term in ("Held-out gain", "held-out folds", "simulated null", "ΔBIC", "Bayesian information criterion"):
        assert term in terms[:terms.index("</ul>")], term
    for f in doc["findings"]:
        better, compared = f["evidence"]["folds_improved"].split("/")
        assert f"better in {better} of {compared} held-out folds" in page
    assert not re.search(r"\d+/\d+ folds", _visible_text(page))


def test_the_held_out_gain_reads_the_same_wherever_it_is_shown(report_dir):
    """The evidence said 'held-out gain 11.76 %' beside a table whose RMS before and after give
    about 7 %: two quantities under one name. The table now shows the gain itself (the share of the
    held-out mean square removed, pooled over channels) beside the one channel's RMS, as the evidence does."""
    page = (report_dir / "report.html").read_text()
    doc = json.loads((report_dir / "findings.json").read_text())
    table = page[page.index("<h2>Findings</h2>"):]
    table = table[table.index("<table>"):table.index("</table>")]
    assert "<th>held-out gain</th>" in table and "<th>channel shown</th>" in table
    for f in doc["findings"]:
        gain = f"{100 * f['evidence']['held_out_gain']:.1f} %"
        assert f"<td>{gain}</td>" in table and f"held-out gain {gain}" in page


def test_a_finding_is_printed_once(report_dir):
    """The summary's line of a finding ('added: backlash (p = ...): backlash = ...') was printed again,
    whole, at the end of its Findings entry. That entry now gives its fitted values only."""
    page = (report_dir / "report.html").read_text()
    doc = json.loads((report_dir / "findings.json").read_text())
    for f in doc["findings"]:
        assert page.count(f"<b>{f['kind']}</b>: {f['effect']} (p = ") == 1
    assert page.count("<b>Fitted:</b>") + page.count("<b>Resized:</b>") == len(doc["findings"])


def test_a_resized_parameter_is_given_with_its_unit_and_meaning():
    """A resized finding read 'wg_load 0.9973 [0.9895, 1.005] (nominal ...)': a raw name, no unit,
    no meaning (an added one had them). Both now say what the parameter is, from the parameter table."""
    from hdjoint.diagnosis.output.report import _finding_line
    from hdjoint.io.parameters import table
    entry = {"estimate": 0.9973, "lo": 0.9895, "hi": 1.005, "nominal": 0.5, "tolerance": 0.25}
    line = _finding_line({"kind": "resized", "effect": "wave_generator_load", "p_value": 1e-3, "resized": True,
                          "parameters": {"wg_load": entry, "Kf": dict(entry, estimate=9000.0, nominal=10000.0)}})
    assert "wg_load = 0.9973 [0.9895, 1.005] (share of the wave generator torque" in line
    assert "Kf = 9000 [0.9895, 1.005] N.m/rad (flexspline stiffness" in line and "nominal 1e+04" in line
    assert table()["Kf"].unit == "N.m/rad"


def test_the_figures_started_when_the_corrected_set_is_settled_are_the_finished_diagnosis_ones():
    """`hdjoint diagnose` starts drawing before the detection limits and the
    findings document: from what the pipeline hands over then, the same figures."""
    from hdjoint.diagnosis.output import report
    from hdjoint.diagnosis.verdict.findings import where
    from hdjoint.diagnosis.pipeline import diagnose
    case = next(c for c in CASES if c.present == ("backlash",))
    settled = []
    result, doc = diagnose(record(case, duration=12.0), nominal_for(case), workers=1,
                           when_settled=lambda *handed: settled.append(handed))
    assert len(settled) == 1 and doc["findings"]
    objective, calibrated, corrected, findings = settled[0]
    early = report.figures(objective, calibrated, corrected,
                           [s for f in findings for s in where(objective, f)["time_segments"]])
    late = report.figures(result.objective, result.calibrated_params, doc["params"],
                          [s for f in doc["findings"] for s in f["where"]["time_segments"]])
    assert (early.where, early.loop, early.fit) == (late.where, late.loop, late.fit)
    assert len(early.jobs) == len(late.jobs)
    for (plot, args, size), (plot_late, args_late, size_late) in zip(early.jobs, late.jobs):
        assert plot is plot_late and size == size_late
        for a, b in zip(args, args_late):
            assert np.array_equal(a, b, equal_nan=True) if isinstance(a, np.ndarray) else a == b
