"""`hdjoint fleet diagnose` on a real 2-worker LocalCluster: each recording's
findings equal a single-process diagnosis, and fleet.html renders in
headless Chromium with the drift ranking, the parameters over time and the
failures."""
import json
import shutil
import subprocess

import numpy as np
import pyarrow.parquet as pq
import pytest
from matplotlib.image import imread

from hdjoint.app import cli
from hdjoint.fleet.generate import JOINT_PATTERN, Drift, generate
from hdjoint.jobs.diagnose import diagnose_to_directory

pytestmark = pytest.mark.slow  # diagnoses: several seconds each

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory, fleet_client):
    root = tmp_path_factory.mktemp("fleet")
    # Fc +25 % a day: +50 % over the three days, beyond its 30 % tolerance (so the trend is relevant).
    pmap = generate(root, joints=1, days=3, duration=4.0, drifts={"j1": Drift(("Fc",), 0.25, "coulomb_friction")})
    (root / "logs" / "robot1" / "j1" / "2026-03-09.csv").write_text("time,i_m,theta_m\n0,0,0\n0.001,0,0\n")
    fleet_client.wait_for_workers(2, timeout=120)
    out = root / "out"
    # Through the command line, on the shared cluster's scheduler.
    assert cli.main(["fleet", "diagnose", str(root / "logs/**/*.csv"), "--params-map", str(pmap),
                     "--joint-pattern", JOINT_PATTERN, "--out", str(out), "--quiet",
                     "--scheduler", fleet_client.scheduler.address]) == 0
    return root, pmap, out


def test_fleet_findings_equal_a_single_process_diagnosis(diagnosed, tmp_path):
    root, pmap, out = diagnosed
    table = pq.read_table(out / "fleet.parquet").to_pylist()
    assert [r["status"] for r in table] == ["ok", "ok", "ok", "failed"]
    assert "theta_l" in table[-1]["error"]
    row = table[1]
    single = diagnose_to_directory(row["recording"], str(root / "params" / "robot1-j1.json"), tmp_path / "single")
    fleet_doc = json.loads((out / row["outputs"] / "findings.json").read_text())
    assert fleet_doc["params"] == single["params"]
    assert fleet_doc["verdict"] == single["verdict"] == row["verdict"]
    assert [f["effect"] for f in fleet_doc["findings"]] == [f["effect"] for f in single["findings"]]
    assert row["param.Fc"] == single["params"]["Fc"] and row["joint"] == "robot1/j1"
    assert (out / row["outputs"] / "report.html").is_file()


@pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not installed (scripts/test.sh installs it)")
def test_fleet_report_renders_in_chromium(diagnosed, tmp_path):
    _, _, out = diagnosed
    page = out / "fleet.html"
    assert "src=\"http" not in page.read_text()
    flags = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={tmp_path / 'profile'}"]
    dom = subprocess.run(flags + ["--dump-dom", page.as_uri()], check=True, capture_output=True, text=True,
                         timeout=120).stdout
    for text in ("Joints ranked by drift", "robot1/j1", "coulomb_friction", "Effects found per recording",
                 "Failures", "2026-03-09.csv", "Bonferroni"):
        assert text in dom, text
    shot = tmp_path / "fleet.png"
    subprocess.run(flags + ["--hide-scrollbars", "--window-size=1200,1600", f"--screenshot={shot}", page.as_uri()],
                   check=True, capture_output=True, timeout=120)
    image = imread(shot)[..., :3]
    colourful = np.mean(np.ptp(image, axis=2) > 0.25)
    assert colourful > 0.002, f"the rendered fleet report shows no figures ({colourful:.4%} coloured pixels)"
