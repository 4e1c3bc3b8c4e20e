#!/usr/bin/env bash
# What contribution roulette gains over throughput roulette: for each scene, renders at the
# resolution of its reference in references/ with N samples per pixel, seeds 1, 2 and 3, each with
# --roulette throughput and --roulette contribution, and each render's relMSE against that
# reference (whose own error is in both) times its seconds (trace_paths). Prints per scene the
# medians over the seeds and the gain, throughput's relMSE x seconds over contribution's.
#   scripts/roulette-gain.sh N SCENE...    e.g. scripts/roulette-gain.sh 64 cornell-box sponza
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n 2,7p "$0" >&2; exit 2; }
spp=$1; shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
field() { /usr/bin/python3 -c "import json, sys; d = json.loads(sys.stdin.read().splitlines()[-1]); print($1)"; }
printf "%-22s %5s %12s %12s %9s %9s %12s %12s %7s\n" scene spp "relMSE thr." "relMSE con." "s thr." "s con." "x s thr." "x s con." gain
for scene in "$@"; do
  resolution=$(/usr/bin/python3 -c "import json; print(json.load(open('references/$scene.json'))['resolution'])")
  rows=()
  for seed in 1 2 3; do
    row=""
    for roulette in throughput contribution; do
      seconds=$(build/lucent render "scenes/$scene.json" --resolution "$resolution" --spp "$spp" --seed "$seed" \
                --roulette "$roulette" --quiet -o "$out/$roulette.exr" | field 'd["stages"]["trace_paths"]')
      error=$(build/lucent compare "$out/$roulette.exr" "references/$scene.exr" --metric relmse | field 'd["value"]')
      row="$row $error $seconds"
    done
    rows+=("$row")
  done
  /usr/bin/python3 -c "
import statistics as st
runs = [[float(v) for v in r.split()] for r in '''$(printf '%s\n' "${rows[@]}")'''.strip().splitlines()]
med = lambda i: st.median(r[i] for r in runs)
thr = st.median(r[0] * r[1] for r in runs)
con = st.median(r[2] * r[3] for r in runs)
print('%-22s %5d %12.4g %12.4g %9.3f %9.3f %12.4g %12.4g %6.2fx' % ('$scene', $spp, med(0), med(2), med(1), med(3), thr, con, thr / con))"
done
