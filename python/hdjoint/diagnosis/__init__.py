"""The mismatch diagnosis: where a model and a recording differ, which
physics is left out, the corrected parameter set, and the report.

The stages live in subpackages, imported bottom to top: `model` (the joint's
torque estimates and residual channels), `fit` (objective, priors, the
nominal calibration), `search` (hypotheses, significance, selection),
`verdict` (floors, resize, detection limits, findings) and `output` (report,
plots); `pipeline` runs them in order. The upper layers (jobs, fleet, app)
import only the names below, each loaded on first use so that importing the
package stays cheap. docs/diagnosis.md says how it works; docs/architecture.md
lists the modules."""
from __future__ import annotations

import importlib

_FACADE = {  # name -> the module that declares it
    "diagnose": "pipeline", "DiagnosisResult": "results",
    "DiagnosisError": "model.prepare", "check_recording": "model.prepare", "place_offset": "model.prepare",
    "ENCODER_ZERO": "model.prepare",
    "kinematics": "model.kinematics", "Prepared": "model.torque_estimates",
    "Evaluator": "model.residual_channels", "channels_for": "model.residual_channels",
    "where": "verdict.findings", "validate": "verdict.validation", "summary_line": "verdict.validation",
    "prepare_drawing": "output.plots", "helper": "forked",
    "EFFECTS": "effects", "HELD_WITHOUT_SENSOR": "effects", "KINEMATIC_EQ7": "effects",
    "INTERVAL": "rules", "INTERVAL_Z": "rules", "RESIZE_Z": "rules",
}
_MODULES = {"report": "output.report"}  # modules the upper layers use whole
__all__ = sorted([*_FACADE, *_MODULES])


def __getattr__(name: str):
    if name in _MODULES:
        return importlib.import_module(f"{__name__}.{_MODULES[name]}")
    if name in _FACADE:
        return getattr(importlib.import_module(f"{__name__}.{_FACADE[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
