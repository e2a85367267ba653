#!/usr/bin/env bash
# Quick start, one command: install everything, then run the main job on the
# built-in example data (FMUs, paper table, a hidden effect diagnosed and closed).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install.sh
hdjoint demo --out "${1:-hdjoint-demo}"
