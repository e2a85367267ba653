"""A corrected set the estimator cannot run (a singular torsion somewhere in
the recording: on the 1 h benchmark recording, wg_load = 1 at the seam
between repeats) is reported as such; the report still renders, the other
sections whole (it raised KeyError and wrote nothing)."""
import pytest

from hdjoint.diagnosis.output import report
from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.verdict.findings import estimator_comparison

pytestmark = pytest.mark.slow


def test_an_estimator_that_cannot_run_the_corrected_set_is_said_in_the_report():
    case = next(c for c in CASES if c.present == ("backlash",))
    result, doc = diagnose(record(case, duration=8.0), nominal_for(case))
    # Stiffer than any torsion of the run allows: eq. (5)'s atan is singular, the C++ estimator refuses it.
    singular = dict(doc["params"], Cf=0.5, Kf=5e5)
    doc["estimator"] = estimator_comparison(result.objective, singular)
    assert "singular torsion" in doc["estimator"]["corrected"]["error"]
    page = report.build(result, doc)
    assert "The estimator did not run with the corrected parameters: row " in page
    assert "Fit before and after" in page and "Calibration" in page
