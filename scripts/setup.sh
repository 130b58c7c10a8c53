#!/usr/bin/env bash
# The full set-up: installs every Debian package range_nlm's parts and tests need (if missing,
# scripts/install_packages.sh all) and builds everything (Release) in build/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_packages.sh all
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2
