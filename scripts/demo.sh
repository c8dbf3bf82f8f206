#!/usr/bin/env bash
# The main job on a fresh Debian 12 machine: installs what is missing,
# builds in Release, and runs clayfit on its built-in default.
#
# Today clayfit has its evaluator (issue 2): this runs the evaluator
# benchmark and evaluates the default wet-clay model (M4) with its gradient.
# The capture -> fit -> export -> report pipeline replaces this as it lands.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
bash scripts/build.sh release
clayfit=build/release/src/cli/clayfit
out=out/demo
mkdir -p "$out"

echo
echo "== clayfit bench eval (evaluator speed, one thread) =="
"$clayfit" bench eval --min-time 0.5 | tee "$out/bench-eval.txt"

echo
echo "== clayfit eval: default wet clay (M4), light 30 deg, view 20 deg on the other side =="
"$clayfit" eval --model clay --light 0.5,0,0.866 --view -0.342,0,0.940 --grad \
  | tee "$out/eval-clay.json"
echo
echo "demo: outputs in $out/"
