#!/usr/bin/env bash
# Fuzzes the scene loader (fuzz/scene_loader_fuzzer.cpp) with libFuzzer for SECONDS on JOBS cores,
# starting from the seeds scripts/fuzz-corpus.py writes from tests/data and from the corpus of
# earlier runs (build-fuzz/corpus). Builds with Debian's Clang, the library instrumented by
# AddressSanitizer and UndefinedBehaviorSanitizer. Prints the executions done; exits 1 if any run
# found a crash, a sanitizer report, a leak, a hang over 10 s or an allocation over 1 GiB (the
# input is then in build-fuzz/artifacts/, the report in build-fuzz/logs/).
#
# Usage: scripts/fuzz-loader.sh [SECONDS (default 600)] [JOBS (default: the cores)]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
jobs=${2:-$(nproc)}
scripts/setup.sh clang libclang-rt-dev
CXX=clang++ cmake -S . -B build-fuzz -DLUCENT_FUZZ=ON -DLUCENT_BUILD_TESTS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build build-fuzz -j "$(nproc)" --target lucent_fuzz_scene_loader
rm -rf build-fuzz/seeds build-fuzz/logs
mkdir -p build-fuzz/corpus build-fuzz/artifacts build-fuzz/logs
scripts/fuzz-corpus.py build-fuzz/seeds
fuzzer=$PWD/build-fuzz/lucent_fuzz_scene_loader
# One job per core, each for the whole time; they share the corpus. -malloc_limit_mb: a scene of at
# most 64 KiB must not need a gigabyte at once.
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan-suppressions.txt print_suppressions=0"
(cd build-fuzz/logs && "$fuzzer" -jobs="$jobs" -workers="$jobs" -max_total_time="$seconds" -timeout=10 \
   -max_len=65536 -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 \
   -artifact_prefix="$PWD/../artifacts/" ../corpus ../seeds > /dev/null 2>&1) || true
runs=$(awk '/^stat::number_of_executed_units:/ { n += $2 } END { print n + 0 }' build-fuzz/logs/fuzz-*.log)
echo "fuzz-loader: ${runs} executions in ${seconds} s on ${jobs} jobs, corpus of $(ls build-fuzz/corpus | wc -l) inputs"
if grep -l -E "^==[0-9]+==ERROR|runtime error:|ERROR: libFuzzer|deadly signal|Timeout|out-of-memory|malloc\(" \
     build-fuzz/logs/fuzz-*.log; then
  echo "fuzz-loader: defects found; inputs in build-fuzz/artifacts/, reports in the logs above" >&2
  exit 1
fi
