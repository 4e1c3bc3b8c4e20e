#!/usr/bin/env bash
# Submits a render to Slurm as a job array, one task per part, and a merge job that runs when every
# task has succeeded. Prints the two job ids and the image the merge writes.
#
#   scripts/slurm/submit.sh [--parts N] [--split rows|samples] [--out-dir DIR] [--name NAME]
#                           [--checkpoint SECONDS] [--sbatch "SBATCH OPTIONS"] -- SCENE.json [render options]
#
# --parts N (default 4): array tasks 0 to N-1, each rendering `lucent render --part SPLIT:K/N`.
# --split (default rows): split the image's rows (cheapest for photon-mapped methods, whose photon
#   maps every part builds) or each pixel's samples.
# --out-dir (default lucent-NAME): parts, logs and the merged NAME.exr and NAME.png; on a file
#   system every node sees.
# --checkpoint SECONDS: each task checkpoints and, run again (sbatch --requeue, or this script
#   again with the same arguments), resumes (pt, purcell, pmfg).
# --sbatch: options for both jobs (partition, account, time, --cpus-per-task, --requeue ...).
# LUCENT (default: build/lucent of this checkout) names the executable the nodes run.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
parts=4 split=rows outDir="" name=render checkpoint="" sbatchOptions=""
while [ $# -gt 0 ]; do
  case "$1" in
    --parts) parts=$2; shift 2 ;;
    --split) split=$2; shift 2 ;;
    --out-dir) outDir=$2; shift 2 ;;
    --name) name=$2; shift 2 ;;
    --checkpoint) checkpoint=$2; shift 2 ;;
    --sbatch) sbatchOptions=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "submit.sh: unknown option '$1' (the render's arguments go after --)" >&2; exit 1 ;;
  esac
done
[ $# -ge 1 ] || { echo "submit.sh: no scene: give SCENE.json [render options] after --" >&2; exit 1; }
[[ "$parts" =~ ^[1-9][0-9]*$ ]] || { echo "submit.sh: --parts '$parts' is not a positive whole number" >&2; exit 1; }
[ "$split" = rows ] || [ "$split" = samples ] || { echo "submit.sh: --split '$split': rows or samples" >&2; exit 1; }
[[ "$name" =~ ^[A-Za-z0-9._-]+$ ]] || { echo "submit.sh: --name '$name': letters, digits, '.', '_' and '-' only" >&2; exit 1; }
lucent=${LUCENT:-$here/../../build/lucent}
[ -x "$lucent" ] || { echo "submit.sh: '$lucent' is not an executable (build Lucent, or set LUCENT)" >&2; exit 1; }
lucent=$(cd "$(dirname "$lucent")" && pwd)/$(basename "$lucent")
outDir=${outDir:-lucent-$name}
mkdir -p "$outDir"
outDir=$(cd "$outDir" && pwd)

export LUCENT=$lucent LUCENT_OUT_DIR=$outDir LUCENT_SPLIT=$split LUCENT_PARTS=$parts LUCENT_NAME=$name
if [ -n "$checkpoint" ]; then export LUCENT_CHECKPOINT=$checkpoint; else unset LUCENT_CHECKPOINT; fi
# shellcheck disable=SC2086  # the sbatch options are words
array=$(sbatch --parsable --chdir="$PWD" --export=ALL --array="0-$((parts - 1))" \
               --output="$outDir/part-%a.log" $sbatchOptions "$here/render-part.sbatch" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable --chdir="$PWD" --export=ALL --dependency="afterok:$array" --kill-on-invalid-dep=yes \
               --output="$outDir/merge.log" $sbatchOptions "$here/merge.sbatch")
merge=${merge%%;*}
echo "{\"array_job\": $array, \"merge_job\": $merge, \"output\": \"$outDir/$name.exr\"}"
