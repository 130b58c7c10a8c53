#!/usr/bin/env bash
# Runs the whole test suite (builds first if needed) and prints CTest's summary.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ ! -f build/CMakeCache.txt ]]; then
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
fi
cmake --build build -j2
ctest --test-dir build --output-on-failure -j2
