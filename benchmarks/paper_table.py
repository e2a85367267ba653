"""The paper's table (docs/paper.md): `hdjoint demo`'s step 4 on the
built-in paper experiment. The paper's two rows (Yu et al. 2018, Fig. 8
and 10) beside the compliance model, the paper's UKF (default and tuned
on this very run), tau_hat, tau_smooth, and tau_hat with the set
`--calibrate-from` makes from a 30 s multisine run of the same joint
without its torque sensor. Errors against the true transmitted torque.

Run: python benchmarks/paper_table.py   (writes docs/results/paper_table.md)"""
from __future__ import annotations

import tempfile
from pathlib import Path

from results import ResultsPage

from hdjoint.estimation.paper_table import reproduce
from hdjoint.fmu import experiments
from hdjoint.jobs.paper_joint_calibration import sensorless_set


def main():
    page = ResultsPage("paper_table", "The paper's table, reproduced", "python benchmarks/paper_table.py")
    rec = experiments.run("paper")
    with tempfile.TemporaryDirectory() as scratch:
        table = reproduce(rec, calibrated=sensorless_set(rec, Path(scratch)))
    for line in table.markdown().splitlines():
        page.say(line)
    page.write()


if __name__ == "__main__":
    main()
