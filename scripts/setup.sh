#!/usr/bin/env bash
# Installs Lucent's build dependencies from Debian packages, and the packages named as arguments
# (scripts/fuzz.sh adds Clang's); does nothing when they are all there.
set -euo pipefail
packages=(build-essential cmake libembree-dev libtbb-dev libopenimageio-dev openimageio-tools
          libopenexr-dev libpng-dev libcli11-dev catch2 nlohmann-json3-dev libtinygltf-dev python3-imath
          python3-numpy ocl-icd-opencl-dev opencl-c-headers pocl-opencl-icd
          pybind11-dev python3-dev python3-pytest "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
echo "setup: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
