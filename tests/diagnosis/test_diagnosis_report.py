"""The diagnosis report renders, with its figures, in a real headless browser."""
import shutil
import subprocess

import numpy as np
import pytest
from matplotlib.image import imread

from hdjoint import cli
from hdjoint.cases import CASES, nominal_for, record
from hdjoint.parameters import save
from hdjoint.recording import write_recording

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


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (scripts/test.sh installs it)")
def test_report_renders_with_its_figures_in_chromium(report_dir, tmp_path):
    shot = tmp_path / "report.png"
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                    "--disable-background-networking", "--disable-component-update", "--disable-sync",
                    f"--user-data-dir={tmp_path / 'profile'}", "--hide-scrollbars", "--window-size=1200,2400",
                    f"--screenshot={shot}", (report_dir / "report.html").as_uri()],
                   check=True, capture_output=True, timeout=120)
    image = imread(shot)[..., :3]
    assert image.shape[0] >= 2000
    # Figures are drawn in colour (red/blue residual lines); a page of text alone is grey.
    colourful = np.mean(np.ptp(image, axis=2) > 0.25)
    assert colourful > 0.002, f"the rendered report shows no figures ({colourful:.4%} coloured pixels)"
