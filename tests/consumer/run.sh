#!/usr/bin/env bash
# Installs the build into a temporary prefix, builds tests/consumer against it with find_package,
# and runs it: it renders the Cornell box by typed options, by name and through a RenderSession,
# each of which must match `lucent render`'s image bit for bit, and reads back a stage dump. Only the
# marked headers are installed (CMakeLists.txt: LUCENT_API_HEADERS, LUCENT_DETAIL_HEADERS; listed in
# include/lucent/headers.txt), and each compiles on its own from the installed tree.
# Usage: run.sh BUILD_DIR SOURCE_DIR LUCENT_CLI
set -euo pipefail
build=$1 source=$2 cli=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
if [ -e "$tmp/prefix/include/lucent/core/lane_clones.h" ] || [ -e "$tmp/prefix/include/lucent/core/uninitialized.h" ]; then
  echo "run.sh: internal headers were installed:" >&2
  find "$tmp/prefix/include" -name '*.h' >&2
  exit 1
fi
# Installed: exactly the headers the marked list names (api or detail), none of the rest.
listed=$(grep -E '^(api|detail) ' "$tmp/prefix/include/lucent/headers.txt" | cut -d' ' -f2 | sort)
installed=$(cd "$tmp/prefix/include" && find lucent -name '*.h' | sort)
if [ "$listed" != "$installed" ]; then
  echo "run.sh: the installed headers differ from include/lucent/headers.txt:" >&2
  diff <(echo "$listed") <(echo "$installed") >&2
  exit 1
fi
cmake -S "$source/tests/consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release \
  > "$tmp/configure.log" || { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/build" > "$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
"$cli" render "$source/scenes/cornell-box.json" --method pt --spp 16 --seed 1 --resolution 16x16 --quiet \
  -o "$tmp/reference.exr" > /dev/null
mkdir "$tmp/dumps"
"$tmp/build/consumer" "$source/scenes/cornell-box.json" "$tmp/reference.exr" "$tmp/dumps"
