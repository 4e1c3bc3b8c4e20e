#!/usr/bin/env bash
# Fresh machine to first image: install, build, render the default scene (Cornell box) with the
# reference path tracer to out/cornell-box.exr and out/cornell-box.png. Only the command line is
# built (scripts/test.sh builds the rest).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh lucent
mkdir -p out
build/lucent render scenes/cornell-box.json --method pt --spp 256 -o out/cornell-box.exr --png out/cornell-box.png
