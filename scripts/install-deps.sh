#!/usr/bin/env bash
# Installs the Debian 12 packages clayfit needs, only those not installed.
# Runs as root, or through sudo when available.
set -euo pipefail

packages=(
  build-essential cmake pkg-config   # compiler, build
  libjansson-dev                     # JSON (CLI output, capture files)
  libceres-dev                       # fitting (and ceres::Jet in the tests)
  libopenimageio-dev openimageio-tools  # every image read and written
  libopencv-dev                      # image analysis (sphere detection)
  colmap                             # camera poses (integration tests)
  python3 python3-jsonschema         # test harness: JSON Schema validation
  clang libclang-rt-14-dev           # libFuzzer for the binary readers' fuzz target
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
echo "install-deps: installing ${missing[*]}"
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
