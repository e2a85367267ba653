#!/usr/bin/env bash
# Installs everything hdjoint needs on a fresh Debian machine with Python 3.11,
# cmake and g++: the Python build and run dependencies from PyPI (Eigen as
# cmeel-eigen, the FMI headers inside fmpy), GoogleTest from Debian if absent,
# then the package itself (which builds the FMUs and the batch extension).
set -euo pipefail
cd "$(dirname "$0")/.."

python3 -m pip install --quiet --upgrade pip
python3 -m pip install --quiet "scikit-build-core>=0.10" "nanobind>=2.0" "cmeel-eigen>=3.4" "fmpy>=0.3.20" \
    numpy scipy matplotlib pytest pytest-xdist ninja threadpoolctl scikit-learn "dask[distributed]>=2024.1" "pyarrow>=14" \
    pandas nbclient nbformat ipykernel  # the API's DataFrames; the example notebook's test runs it on a kernel
python3 -m pip install --quiet --no-build-isolation ".[test]"
