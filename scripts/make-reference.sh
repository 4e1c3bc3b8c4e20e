#!/usr/bin/env bash
# Renders a reference image to references/NAME.exr with a JSON sidecar references/NAME.json saying
# exactly how it was made: the command, the render's JSON summary (method, options, seed, times,
# Embree version, scene hash), the git commit and whether the tree was clean, the date and the CPU.
#   scripts/make-reference.sh NAME SCENE.json [lucent render options...]
# e.g. scripts/make-reference.sh cornell-box-pt scenes/cornell-box.json --method pt --spp 8192
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n 2,6p "$0" >&2; exit 2; }
name=$1; scene=$2; shift 2
scripts/build.sh > /dev/null
mkdir -p references
summary=$(build/lucent render "$scene" "$@" -o "references/$name.exr" --quiet)
commit=$(git rev-parse HEAD)
dirty=$(git status --porcelain --untracked-files=no | grep -q . && echo true || echo false)
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
/usr/bin/python3 - "$name" "$scene" "$commit" "$dirty" "$cpu" "$summary" "$@" > "references/$name.json" <<'PY'
import datetime, json, sys
name, scene, commit, dirty, cpu, summary, *options = sys.argv[1:]
print(json.dumps({
    "name": name,
    "command": " ".join(["build/lucent", "render", scene] + options + ["-o", f"references/{name}.exr"]),
    "scene": scene,
    "git_commit": commit,
    "git_tree_modified": dirty == "true",
    "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    "cpu": cpu,
    "render": json.loads(summary),
}, indent=1))
PY
echo "references/$name.exr, references/$name.json"
