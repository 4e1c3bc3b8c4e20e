#!/usr/bin/env bash
# What rendering to an error target gains over uniform sampling: for each scene, a render with
# --target-error E, then one with its mean samples per pixel everywhere (the same seed), both at
# the resolution of the scene's reference in references/, and each one's relMSE against that
# reference (which adds the reference's own error to both) and relMSE x seconds (trace_paths).
#   scripts/adaptive-gain.sh E SCENE...    e.g. scripts/adaptive-gain.sh 0.003 cornell-box sponza
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n 2,6p "$0" >&2; exit 2; }
target=$1; shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
field() { /usr/bin/python3 -c "import json, sys; d = json.loads(sys.stdin.read().splitlines()[-1]); print($1)"; }
printf "%-22s %8s %10s %10s %10s %10s %10s %7s\n" scene spp estimate adaptive uniform "x seconds" "x seconds" gain
for scene in "$@"; do
  resolution=$(/usr/bin/python3 -c "import json; print(json.load(open('references/$scene.json'))['resolution'])")
  summary=$(build/lucent render "scenes/$scene.json" --resolution "$resolution" --target-error "$target" --spp 1000000 \
            --seed 3 --quiet -o "$out/adaptive.exr")
  pixels=$(( ${resolution%x*} * ${resolution#*x} ))
  spp=$(echo "$summary" | field "round(d['samples_spent'] / $pixels)")
  estimate=$(echo "$summary" | field 'd["estimated_relmse"]')
  adaptiveSeconds=$(echo "$summary" | field 'd["stages"]["trace_paths"]')
  uniformSeconds=$(build/lucent render "scenes/$scene.json" --resolution "$resolution" --spp "$spp" --seed 3 --quiet \
                   -o "$out/uniform.exr" | field 'd["stages"]["trace_paths"]')
  adaptive=$(build/lucent compare "$out/adaptive.exr" "references/$scene.exr" --metric relmse | field 'd["value"]')
  uniform=$(build/lucent compare "$out/uniform.exr" "references/$scene.exr" --metric relmse | field 'd["value"]')
  /usr/bin/python3 -c "
a, u, ta, tu = $adaptive, $uniform, $adaptiveSeconds, $uniformSeconds
print('%-22s %8d %10.3g %10.3g %10.3g %10.3g %10.3g %6.2fx' % ('$scene', $spp, $estimate, a, u, a * ta, u * tu, u * tu / (a * ta)))"
done
