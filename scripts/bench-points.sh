#!/usr/bin/env bash
# Point hierarchy (src/techniques/points): best-candidate sampling, median split, node data and refit
# times from 2^16 to 2^21 points with 2 threads, point spacing against uniform sampling, leaf-disc
# coverage and the packed nodes' quantization error (bench/bench_points.cpp), on the Cornell box and
# Sponza. One JSON object per scene. Run it on an otherwise idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh > /dev/null
scenes=(scenes/cornell-box.json scenes/sponza.json)
for scene in "${scenes[@]}"; do
  build/lucent_bench_points "$scene" --min-log2 "${MIN_LOG2:-16}" --max-log2 "${MAX_LOG2:-21}" \
    --threads "${THREADS:-2}" --repeats "${REPEATS:-3}" ${NO_QUALITY:+--no-quality}
done
