#!/usr/bin/env bash
# Installs dependencies if missing, then configures and builds Lucent (Release) in build/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j "$(nproc)"
