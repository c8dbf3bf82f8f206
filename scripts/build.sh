#!/usr/bin/env bash
# Configures and builds clayfit: `scripts/build.sh [release|demo|sanitize]`.
#   release  (default) build/release, optimised, warnings are errors, with
#            the test suite (every target)
#   demo     build/release as release, but only the clayfit program (and the
#            report's three.js view when its npm packages are there): what
#            scripts/demo.sh runs; no test suite, so no Python needed
#   sanitize build/sanitize, AddressSanitizer + UBSan, for the test suite
set -euo pipefail
cd "$(dirname "$0")/.."

kind=${1:-release}
dir=$kind
targets=()
case "$kind" in
  release)  flags=(-DCMAKE_BUILD_TYPE=Release -DCLAYFIT_TESTS=ON) ;;
  demo)     flags=(-DCMAKE_BUILD_TYPE=Release -DCLAYFIT_TESTS=OFF) dir=release targets=(--target clayfit) ;;
  sanitize) flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCLAYFIT_SANITIZE=ON -DCLAYFIT_TESTS=ON) ;;
  *) echo "usage: scripts/build.sh [release|demo|sanitize]" >&2; exit 2 ;;
esac
cmake -S . -B "build/$dir" -DCLAYFIT_WERROR=ON "${flags[@]}" >/dev/null
cmake --build "build/$dir" -j "$(nproc)" "${targets[@]}"
