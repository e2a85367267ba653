#!/usr/bin/env bash
# Tests, one command: install everything, build and run the C++ unit tests (sanitized),
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
# The C++ unit tests and the FMUs built with AddressSanitizer and UBSan (any
# finding aborts; one build serves both, as building the tests twice costs
# minutes on 2 cores); then fmpy runs each sanitized FMU and the
# JointTorqueFeedback system, with the ASan runtime preloaded into the Python
# host (whose own allocations are not ours to leak-check). The release FMUs
# that users get are the ones pip installed above, tested by pytest below.
cmake -S . -B build/sanitize -G Ninja -DHDJOINT_SANITIZE=ON -DHDJOINT_BUILD_TESTS=ON -DCMAKE_BUILD_TYPE=Sanitize \
    -DPython_EXECUTABLE="$(command -v python3)" >/dev/null
cmake --build build/sanitize
ctest --test-dir build/sanitize --output-on-failure
LD_PRELOAD="$(g++ -print-file-name=libasan.so)" ASAN_OPTIONS=detect_leaks=0 \
    python3 scripts/run_sanitized_fmus.py build/sanitize

# Two workers, whole files each (a module's fixtures, e.g. a diagnosis a file's tests share, are made once).
python3 -m pytest -q -n 2 --dist loadfile tests "$@"
