#!/usr/bin/env bash
# The lane loops (LUCENT_LANE_VERSIONS) are vector code in the built program: each AVX2 version
# uses ymm registers and calls no function. A call left in a loop body keeps GCC from vectorizing
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
# Each AVX2 version (its mangled name holds <name>Avx2E): the name, its count of ymm operands, its
# count of calls.
counts=$(awk '
  /^[0-9a-f]+ <.*Avx2E.*>:$/ { name = $2; gsub(/[<>:]/, "", name); ymm[name] = 0; calls[name] = 0; current = name; next }
  /^[0-9a-f]+ </ { current = ""; next }
  current != "" && /ymm/ { ymm[current]++ }
  current != "" && /\tcall/ { calls[current]++ }
  END { for (n in ymm) print n, ymm[n], calls[n] }' "$listing" | sort)
echo "$counts" | c++filt
found=$(echo "$counts" | grep -c . || true)
if [ "$found" -lt 10 ]; then
  echo "FAILED: only $found AVX2 lane loops found in $binary"
  exit 1
fi
failed=0
while read -r name ymm calls; do
  if [ "$ymm" -eq 0 ]; then
    echo "FAILED: $(echo "$name" | c++filt) is scalar (no ymm register)"
    failed=1
  fi
  if [ "$calls" -gt 0 ] && [[ "$name" != *startCameraPathsAvx2E* ]]; then
    echo "FAILED: $(echo "$name" | c++filt) calls $calls functions"
    failed=1
  fi
done <<< "$counts"
for loop in shadeDiffuseLanesAvx2 shadeGltfInFramesAvx2 gltfShadingFramesAvx2; do
  echo "$counts" | grep -q "${loop}E" || { echo "FAILED: $loop not found"; failed=1; }
done
exit $failed
