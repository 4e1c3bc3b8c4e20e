#!/usr/bin/env bash
# The lane loops (LUCENT_LANE_VERSIONS) are vector code in the built program: each AVX2 version
# uses ymm registers, each AVX-512 version ymm or zmm ones, and none calls a function (the versions
# are checked in the binary whatever CPU runs the test). A call left in a loop body keeps GCC from vectorizing
# it, and whether a helper is inlined depends on the inliner's size limits, which depend on what
# else the translation unit holds (a unity build's batch): a change elsewhere can turn a lane loop
# scalar without changing one result, so the tests of images cannot see it. startCameraPaths
# calls the camera and the pixel filter by design. Skipped (exit 77) where objdump is missing.
#   tests/lane_loops_test.sh LUCENT
set -euo pipefail
binary=$1
if ! command -v objdump > /dev/null; then
  echo "SKIPPED: objdump not found (Debian's binutils)"
  exit 77
fi
listing=$(mktemp /tmp/lucent-lane-loops-XXXXXX)
trap 'rm -f "$listing"' EXIT
objdump -d --no-show-raw-insn "$binary" > "$listing"
# Each version for an instruction set (its mangled name holds <name><Isa>E) and the vector
# registers that set brings: the name, its count of such operands, its count of calls.
check() {
  local isa=$1 registers=$2
  local counts
  counts=$(awk -v isa="${isa}E" -v registers="$registers" '
    /^[0-9a-f]+ <.*>:$/ && index($2, isa) { name = $2; gsub(/[<>:]/, "", name); vector[name] = 0; calls[name] = 0; current = name; next }
    /^[0-9a-f]+ </ { current = ""; next }
    current != "" && $0 ~ registers { vector[current]++ }
    current != "" && /\tcall/ { calls[current]++ }
    END { for (n in vector) print n, vector[n], calls[n] }' "$listing" | sort)
  echo "$counts" | c++filt
  local found
  found=$(echo "$counts" | grep -c . || true)
  if [ "$found" -lt 10 ]; then
    echo "FAILED: only $found $isa lane loops found in $binary"
    failed=1
    return
  fi
  while read -r name vector calls; do
    if [ "$vector" -eq 0 ]; then
      echo "FAILED: $(echo "$name" | c++filt) is scalar (no $registers register)"
      failed=1
    fi
    if [ "$calls" -gt 0 ] && [[ "$name" != *startCameraPaths${isa}E* ]]; then
      echo "FAILED: $(echo "$name" | c++filt) calls $calls functions"
      failed=1
    fi
  done <<< "$counts"
  for loop in shadeDiffuseLanes shadeGltfInFrames gltfShadingFrames sobolPairs; do
    echo "$counts" | grep -q "${loop}${isa}E" || { echo "FAILED: ${loop}${isa} not found"; failed=1; }
  done
}
failed=0
check Avx2 ymm
# The AVX-512 versions: zmm registers, or ymm where a loop works on eight lanes by design (the
# photon maps' runs of eight photons).
check Avx512 '[yz]mm'
exit $failed
