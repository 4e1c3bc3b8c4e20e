#!/usr/bin/env bash
# The lane loops are compiled as run-time clones (AVX-512, AVX2, baseline: core/lane_clones.h) and
# must give the same images whichever the CPU picks. A machine runs one of them, so this builds the
# other two alone (build-lanes-avx2/, build-lanes-baseline/; the renderer only, a few minutes each)
# and compares their images with build/'s, bit for bit, for every method with a lane loop: the path
# tracer, the purcell renderer with the sorted and stencil maps, micro-rendering. Needs an AVX2 CPU.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x build/lucent ] || scripts/build.sh
out=out/lane-clones
mkdir -p "$out"
renders=(
  "pt scenes/cornell-box.json --method pt --spp 16 --resolution 96x96"
  "pt-sponza scenes/sponza.json --method pt --spp 4 --resolution 96x60"
  "purcell-sort scenes/ring.json --method purcell --map sort --resolution 128x96"
  "purcell-stencil scenes/glass-ball.json --method purcell --map stencil --resolution 128x96"
  "micro scenes/cornell-box.json --method micro --resolution 48x48"
  "micro-glossy scenes/cornell-box-glossy.json --method micro --resolution 48x48"
)
render_all() {  # binary, tag
  for r in "${renders[@]}"; do
    read -r name args <<< "$r"
    # shellcheck disable=SC2086
    "$1" render $args --threads 2 --quiet -o "$out/$name-$2.exr" > /dev/null
  done
}
render_all build/lucent clones
failed=0
for target in avx2 baseline; do
  cmake -S . -B "build-lanes-$target" -DCMAKE_BUILD_TYPE=Release -DLUCENT_BUILD_TESTS=OFF \
    -DLUCENT_LANE_TARGET="$target" > /dev/null
  cmake --build "build-lanes-$target" -j "$(nproc)" --target lucent > /dev/null
  render_all "build-lanes-$target/lucent" "$target"
  for r in "${renders[@]}"; do
    name=${r%% *}
    if oiiotool --fail 0 --warn 0 "$out/$name-clones.exr" "$out/$name-$target.exr" --diff > /dev/null; then
      echo "$name: $target equals the clones"
    else
      echo "$name: $target DIFFERS from the clones"
      failed=1
    fi
  done
done
exit $failed
