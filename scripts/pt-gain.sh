#!/usr/bin/env bash
# What one set of the path tracer's options gains over another: for each scene, renders at the
# resolution of its reference in references/ with N samples per pixel, seeds 1, 2 and 3, each with
# options A and with options B, and each render's relMSE against that reference (whose own error is
# in both) times its seconds (trace_paths). Prints per scene the medians over the seeds and the
# gain, A's relMSE x seconds over B's.
#   scripts/pt-gain.sh N A B SCENE...
#   e.g. scripts/pt-gain.sh 64 "--roulette throughput" "--roulette contribution" cornell-box sponza
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 4 ] || { sed -n 2,8p "$0" >&2; exit 2; }
spp=$1; optionsA=$2; optionsB=$3; shift 3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
field() { /usr/bin/python3 -c "import json, sys; d = json.loads(sys.stdin.read().splitlines()[-1]); print($1)"; }
printf "%-22s %5s %12s %12s %9s %9s %12s %12s %7s\n" scene spp "relMSE A" "relMSE B" "s A" "s B" "x s A" "x s B" gain
for scene in "$@"; do
  resolution=$(/usr/bin/python3 -c "import json; print(json.load(open('references/$scene.json'))['resolution'])")
  rows=()
  for seed in 1 2 3; do
    row=""
    for options in "$optionsA" "$optionsB"; do
      # shellcheck disable=SC2086 # the options are words
      seconds=$(build/lucent render "scenes/$scene.json" --resolution "$resolution" --spp "$spp" --seed "$seed" \
                $options --quiet -o "$out/render.exr" | field 'd["stages"]["trace_paths"]')
      error=$(build/lucent compare "$out/render.exr" "references/$scene.exr" --metric relmse | field 'd["value"]')
      row="$row $error $seconds"
    done
    rows+=("$row")
  done
  /usr/bin/python3 -c "
import statistics as st
runs = [[float(v) for v in r.split()] for r in '''$(printf '%s\n' "${rows[@]}")'''.strip().splitlines()]
med = lambda i: st.median(r[i] for r in runs)
a = st.median(r[0] * r[1] for r in runs)
b = st.median(r[2] * r[3] for r in runs)
print('%-22s %5d %12.4g %12.4g %9.3f %9.3f %12.4g %12.4g %6.2fx' % ('$scene', $spp, med(0), med(2), med(1), med(3), a, b, a / b))"
done
