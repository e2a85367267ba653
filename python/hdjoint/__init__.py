"""hdjoint: torque estimation for harmonic-drive robot joints.

Layers, each importing only those below it (tests/unit/test_module_structure.py):

  _core        the C++ core (nanobind): joint model, estimators, parameter table
  io           recordings, parameter files, time bases, figure files
  fmu          the shipped FMUs, running them through fmpy, experiments, co-simulation
  estimation   torque estimation over whole recordings, its smoother, error figures
  diagnosis    what a model leaves out of a recording, and the corrected set
  jobs         whole jobs from files to files, with the user's inputs checked
  fleet        many recordings on Dask
  app          the `hdjoint` command and the demo
"""
