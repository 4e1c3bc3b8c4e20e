#!/usr/bin/env bash
# Installs dependencies if missing, then configures and builds Lucent (Release) in build/: the
# targets named (scripts/build.sh lucent: the command line alone), or every target.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# The maze scene's 241,080-triangle mesh is procedural: written here, not kept in the repository.
[ -f scenes/maze/maze.obj ] || python3 scripts/make-maze.py > /dev/null
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j "$(nproc)" ${1:+--target "$@"}
