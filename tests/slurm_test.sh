#!/usr/bin/env bash
# scripts/slurm/ on a real Slurm cluster of one node, started here (scripts/slurm/local-cluster.sh):
# a four-task job array renders the Cornell box by rows, a dependent job merges the parts, and the
# merged image equals a single render's, pixel for pixel. Skipped (exit 77, with the reason) where
# Slurm cannot start: not root, or its packages missing.
#   tests/slurm_test.sh LUCENT SOURCE_DIR
set -euo pipefail
lucent=$1 source=$2
work=$(mktemp -d /tmp/lucent-slurm-XXXXXX)
cleanup() { "$source/scripts/slurm/local-cluster.sh" stop "$work/cluster" || true; rm -rf "$work"; }
trap cleanup EXIT

status=0
conf=$("$source/scripts/slurm/local-cluster.sh" start "$work/cluster") || status=$?
if [ "$status" -eq 77 ]; then echo "SKIPPED: the one-node Slurm cluster cannot start here (message above)"; exit 77; fi
[ "$status" -eq 0 ] || exit "$status"
export SLURM_CONF=$conf

render=("$source/scenes/cornell-box.json" --spp 8 --resolution 48x40)
jobs=$(LUCENT=$lucent "$source/scripts/slurm/submit.sh" --parts 4 --split rows --out-dir "$work/out" --name box \
         --checkpoint 60 -- "${render[@]}")
echo "submitted: $jobs"
merge=$(python3 -c 'import json, sys; print(json.load(sys.stdin)["merge_job"])' <<< "$jobs")

state=""
for _ in $(seq 1200); do
  state=$(scontrol show job "$merge" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
  case "$state" in COMPLETED|FAILED|CANCELLED|TIMEOUT|NODE_FAIL|OUT_OF_MEMORY) break ;; esac
  sleep 0.25
done
if [ "$state" != COMPLETED ]; then
  echo "FAILED: the merge job ended $state"
  tail -n +1 "$work"/out/*.log "$work/cluster/log/"*.log || true
  exit 1
fi
echo "merge: $(cat "$work/out/merge.log")"

"$lucent" render "${render[@]}" --quiet -o "$work/single.exr" > /dev/null
"$lucent" render "${render[@]}" --seed 1 --quiet -o "$work/other-seed.exr" > /dev/null
idiff -fail 0 -warn 0 "$work/single.exr" "$work/out/box.exr"
# The comparison can fail: another seed's image differs.
if idiff -fail 0 -warn 0 "$work/other-seed.exr" "$work/out/box.exr" > /dev/null; then
  echo "FAILED: idiff did not tell another seed's image from the merge"
  exit 1
fi
for k in 0 1 2 3; do
  grep -q "\"crop\":\[0,$((k * 10)),48,$((k * 10 + 10))\]" "$work/out/part-$k.film" ||
    { echo "FAILED: part $k is not rows $((k * 10)) to $((k * 10 + 10))"; exit 1; }
done
echo "PASSED: the merged job array equals the single render"
