#!/usr/bin/env bash
# Runs the whole test suite: installs what is missing, builds (Release, build/) and prints
# CTest's summary.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
ctest --test-dir build --output-on-failure -j2
