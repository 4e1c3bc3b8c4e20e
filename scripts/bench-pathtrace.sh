#!/usr/bin/env bash
# Path tracer throughput on the Cornell box and Sponza next to a raw Embree loop over the same rays
# (bench/bench_pathtrace.cpp), with 1 and 2 threads. One JSON line per scene.
# Targets: path tracer rays/s >= 70% of the raw loop's with 2 threads; 2 threads >= 1.8x 1.
# pt_over_raw is against single rays; pt_over_raw_shadow_packets against the raw loop with its
# shadow rays in packets of 16, as the path tracer traces them (like with like).
# The path tracer runs with the independent sampler (the raw loop's paths); pt_sobol_seconds_over_independent
# is the default Sobol sampler's time over it.
# Run it on an otherwise idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh > /dev/null
build/lucent_bench_pathtrace scenes/cornell-box.json scenes/sponza.json --resolution "${RESOLUTION:-256x256}" \
  --spp "${SPP:-16}" --repeats "${REPEATS:-10}"
