#!/usr/bin/env bash
# Fuzzes one of Lucent's readers with libFuzzer for SECONDS on JOBS cores, from the seeds
# scripts/fuzz-corpus.py writes and the corpus of earlier runs (build-fuzz/corpus-TARGET). Targets
# (fuzz/): scene_loader (JSON, OBJ, MTL, textures), gltf_loader (.gltf and .glb), film_reader (film and checkpoint files), merge
# (lucent merge's part checks), image_header (the images compare and report read), dump (dump files
# and check-dump's comparison) and command_line (every command's arguments). Builds with
# Debian's Clang, the library instrumented by AddressSanitizer and UndefinedBehaviorSanitizer.
# Prints the executions done; exits 1 if any run found a crash, a sanitizer report, a leak, a hang
# over 10 s or an allocation over 1 GiB (the input is then in build-fuzz/artifacts-TARGET/, the
# report in build-fuzz/logs-TARGET/).
#
# Usage: scripts/fuzz.sh TARGET [SECONDS (default 600)] [JOBS (default: the cores)] [RUNS]
# With RUNS, each job stops after that many executions if SECONDS have not run out first.
set -euo pipefail
cd "$(dirname "$0")/.."
target=${1:?usage: scripts/fuzz.sh scene_loader|gltf_loader|film_reader|merge|image_header|dump|command_line [SECONDS] [JOBS] [RUNS]}
seconds=${2:-600}
jobs=${3:-$(nproc)}
runs=${4:--1}
case "$target" in scene_loader|gltf_loader|film_reader|merge|image_header|dump|command_line) ;; *) echo "fuzz: unknown target $target" >&2; exit 2;; esac
scripts/setup.sh clang libclang-rt-dev
CXX=clang++ cmake -S . -B build-fuzz -DLUCENT_FUZZ=ON -DLUCENT_BUILD_TESTS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build build-fuzz -j "$(nproc)" --target "lucent_fuzz_$target"
rm -rf "build-fuzz/seeds-$target" "build-fuzz/logs-$target"
mkdir -p "build-fuzz/corpus-$target" "build-fuzz/artifacts-$target" "build-fuzz/logs-$target"
scripts/fuzz-corpus.py "$target" "build-fuzz/seeds-$target"
fuzzer=$PWD/build-fuzz/lucent_fuzz_$target
# One job per core, each for the whole time; they share the corpus. -malloc_limit_mb: an input of
# at most 64 KiB must not need a gigabyte at once.
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan-suppressions.txt print_suppressions=0"
started=$(date +%s)
(cd "build-fuzz/logs-$target" && "$fuzzer" -jobs="$jobs" -workers="$jobs" -max_total_time="$seconds" -runs="$runs" -timeout=10 \
   -max_len=65536 -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 \
   -artifact_prefix="$PWD/../artifacts-$target/" "../corpus-$target" "../seeds-$target" > /dev/null 2>&1) || true
executed=$(awk '/^stat::number_of_executed_units:/ { n += $2 } END { print n + 0 }' "build-fuzz/logs-$target"/fuzz-*.log)
echo "fuzz $target: ${executed} executions in $(( $(date +%s) - started )) s on ${jobs} jobs, corpus of $(ls "build-fuzz/corpus-$target" | wc -l) inputs"
if grep -l -E "^==[0-9]+==ERROR|runtime error:|ERROR: libFuzzer|deadly signal|Timeout|out-of-memory|malloc\(" \
     "build-fuzz/logs-$target"/fuzz-*.log; then
  echo "fuzz $target: defects found; inputs in build-fuzz/artifacts-$target/, reports in the logs above" >&2
  exit 1
fi
