#!/usr/bin/env bash
# The solver's ablation (docs/studies/2026-11-26-solver-ablation.md): builds
# `clayfit` once per device switched off, from the commit the ablation
# measured with the switches of lsq_ablate.patch (LSQ_ABLATE, a bit per
# device), into OUT/<name>/clayfit.
#   bash bench/ablation/build_variants.sh OUT
# Needs the project's dependencies (scripts/install-deps.sh); takes a few
# minutes (one Release build, then lsq_ceres.cpp once per variant).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="$(mkdir -p "$1" && cd "$1" && pwd)"
commit=af576d6  # the solver as measured (docs/studies/2026-11-26-solver-ablation.md)
tree="$out/tree"
[ -d "$tree" ] || git -C "$root" worktree add --detach "$tree" "$commit"
git -C "$tree" apply --check "$root/bench/ablation/lsq_ablate.patch" 2>/dev/null &&
  git -C "$tree" apply "$root/bench/ablation/lsq_ablate.patch"
build() {  # name bits
  local name=$1 bits=$2
  cmake -S "$tree" -B "$out/build-$name" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS="-DLSQ_ABLATE=$bits" >/dev/null
  cmake --build "$out/build-$name" -j "$(nproc)" --target clayfit >/dev/null
  mkdir -p "$out/$name"
  cp "$out/build-$name/src/cli/clayfit" "$out/$name/clayfit"
  echo "ablation: $out/$name/clayfit (LSQ_ABLATE=$bits)"
}
build none 0
build spec 1
build cache 3
build active 4
build nstart 8
build line 16
build chunk 32
build radius 64
build closing 128
build all 255
