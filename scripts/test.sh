#!/usr/bin/env bash
# Tests, one command: install everything, build and run the C++ unit tests,
# then the Python test suite (which loads the real FMUs through fmpy).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh
# The other co-simulation masters and FMI checkers (PyPI, Debian, Maven Central).
bash scripts/install_cosim.sh

# From Debian: GoogleTest for the C++ tests, Chromium for the report-rendering test.
missing=()
[ -e /usr/include/gtest/gtest.h ] || missing+=(libgtest-dev)
command -v chromium >/dev/null || missing+=(chromium)
if [ ${#missing[@]} -gt 0 ] && command -v apt-get >/dev/null; then
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}") >/dev/null
fi
cmake -S . -B build/cpp-tests -G Ninja -DHDJOINT_BUILD_TESTS=ON -DHDJOINT_BUILD_FMUS=OFF \
    -DPython_EXECUTABLE="$(command -v python3)" >/dev/null
cmake --build build/cpp-tests
ctest --test-dir build/cpp-tests --output-on-failure

python3 -m pytest -q tests "$@"
