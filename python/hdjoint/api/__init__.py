"""hdjoint's Python API (docs/api.md): the `hdjoint` subcommands as functions
on Python objects, for scripts and notebooks. `import hdjoint` offers these
names lazily (hdjoint/__init__.py), so it stays quick.

Layer: above `hdjoint.jobs` and `hdjoint.fleet`, below `hdjoint.app` (the
command line calls it). Results wrap the documents the command line writes.

>>> import hdjoint
>>> p = hdjoint.Parameters({"Kt": 0.05})
>>> p.stated
{'Kt': 0.05}
"""
from hdjoint.api.functions import (UserError, calibrate, diagnose, estimate, export_fmus, read_recording,
                                   simulate)
from hdjoint.api.parameters import ParameterError, Parameters
from hdjoint.api.results import Calibration, Diagnosis, Finding

__all__ = ["read_recording", "simulate", "estimate", "diagnose", "calibrate", "export_fmus", "Parameters",
           "Diagnosis", "Finding", "Calibration", "UserError", "ParameterError"]
