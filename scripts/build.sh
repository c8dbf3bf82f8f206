#!/usr/bin/env bash
# Configures and builds clayfit: `scripts/build.sh [release|sanitize]`.
#   release  (default) build/release, optimised, warnings are errors
#   sanitize build/sanitize, AddressSanitizer + UBSan, for the test suite
set -euo pipefail
cd "$(dirname "$0")/.."

kind=${1:-release}
case "$kind" in
  release)  flags=(-DCMAKE_BUILD_TYPE=Release) ;;
  sanitize) flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCLAYFIT_SANITIZE=ON) ;;
  *) echo "usage: scripts/build.sh [release|sanitize]" >&2; exit 2 ;;
esac
cmake -S . -B "build/$kind" -DCLAYFIT_WERROR=ON "${flags[@]}" >/dev/null
cmake --build "build/$kind" -j "$(nproc)"
