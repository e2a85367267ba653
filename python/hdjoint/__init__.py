"""hdjoint: torque estimation for harmonic-drive robot joints.

Layers, each importing only those below it (tests/unit/test_module_structure.py):

  _core        the C++ core (nanobind): joint model, estimators, parameter table
  io           recordings, parameter files, time bases, figure files
  fmu          the shipped FMUs, running them through fmpy, experiments, co-simulation
  estimation   torque estimation over whole recordings, its smoother, error figures
  diagnosis    what a model leaves out of a recording, and the corrected set
  jobs         whole jobs from files to files, with the user's inputs checked
  fleet        many recordings on Dask
  api          the Python API: read_recording, simulate, estimate, diagnose, calibrate, export_fmus, Parameters
  app          the `hdjoint` command and the demo

The API's names are imported on first use (module __getattr__), so `import hdjoint` stays quick:

>>> import hdjoint
>>> hdjoint.Parameters().unit("Kt")
'N.m/A'
"""
from __future__ import annotations

# The API's names, each imported from hdjoint.api on first access.
_API = ("read_recording", "simulate", "estimate", "diagnose", "calibrate", "export_fmus", "Parameters",
        "Diagnosis", "Finding", "Calibration", "UserError", "ParameterError")
__all__ = [*_API, "__version__"]


def __getattr__(name: str):
    if name == "__version__":  # the installed distribution's (importlib.metadata costs time: on first use only)
        from importlib.metadata import PackageNotFoundError, version
        try:
            return version("hdjoint")
        except PackageNotFoundError:  # pragma: no cover - run from a source tree
            return "0+unknown"
    if name in _API:
        from hdjoint import api
        value = getattr(api, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'hdjoint' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
