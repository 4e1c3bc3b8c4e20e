#!/usr/bin/env bash
# Issue 3's bar: pmfg at its default settings (130,000 photons, 4,096 gather rays at every pixel,
# k = 50, kd-tree, one camera ray per pixel) on the Cornell box at 512x512, against a converged
# path-traced reference (references/cornell-box-pt.exr, made by scripts/make-reference.sh if
# missing), must have relMSE below 0.005. Takes of the order of 10-20 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -f references/cornell-box-pt.exr ] ||
  scripts/make-reference.sh cornell-box-pt scenes/cornell-box.json --method pt --spp 8192 --seed 1
mkdir -p out
build/lucent render scenes/cornell-box.json --method pmfg -o out/cornell-box-pmfg.exr --quiet
build/lucent compare out/cornell-box-pmfg.exr references/cornell-box-pt.exr --metric relmse \
  --max-error "${MAX_ERROR:-0.005}" --heatmap out/cornell-box-pmfg-error.png
