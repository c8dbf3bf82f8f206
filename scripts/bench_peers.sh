#!/usr/bin/env bash
# clayfit against its peers (issue 6): `scripts/bench_peers.sh [BUILD_DIR]`.
# Builds clayfit and clayfit-peers if needed (default build/release; -j2),
# synthesises the captures into out/bench_peers/, runs clayfit-peers on each
# (every peer on the same observations as clayfit, in the same run) and
# writes bench/PEERS.md (and a JSON per run next to the captures). Times are
# reported, never asserted: this is not part of the test suite.
#
# Captures (clayfit synth, 8 images 320x240, linear EXR, 1 sample per pixel):
#   M2 and M4 at a tenth of the default noise (read 0.0002, shot 5e-6), all
#   observations, every peer, started from the truth moved by 5 % of each
#   range (--start-from-truth);
#   M4 at the default noise, an even subsample of 20 000 observations: the
#   minimum has the Oren-Nayar sigma near 0, where a solver in sigma (the
#   Ceres peers) sees no derivative.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build/release}"
python=/usr/bin/python3
[ -x "$python" ] || python="$(command -v python3)"

if [ ! -x "$build/bench/peers/clayfit-peers" ] || [ ! -x "$build/src/cli/clayfit" ]; then
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCLAYFIT_WERROR=ON >/dev/null
  cmake --build "$build" -j2 --target clayfit clayfit-peers
fi
clayfit="$build/src/cli/clayfit"
peers="$build/bench/peers/clayfit-peers"
out="$root/out/bench_peers"
mkdir -p "$out" "$root/bench"

m2_params=(--param albedo=0.7,0.5,0.3 --param diffuse_roughness=0.5 --param roughness=0.3
           --param f0=0.05)
m4_params=(--param albedo=0.6,0.45,0.3 --param diffuse_roughness=0.5 --param film_roughness=0.2
           --param film_f0=0.03 --param optical_depth=0.3,0.2,0.1 --param base_roughness=0.4
           --param base_f0=0.006)
common=(--images 8 --size 320x240 --format exr --supersample 1)
quiet=(--read-noise 0.0002 --shot-noise 0.000005)

commands=()
synth() {  # name model params...
  local name=$1
  shift
  if [ ! -f "$out/$name/capture.json" ]; then
    "$clayfit" --quiet synth -o "$out/$name" "$@"
  fi
  commands+=("clayfit synth -o out/bench_peers/$name ${*}")
}
synth m2 --model M2 "${common[@]}" "${quiet[@]}" "${m2_params[@]}"
synth m4 --model M4 "${common[@]}" "${quiet[@]}" "${m4_params[@]}"
synth m4_noisy --model M4 "${common[@]}" "${m4_params[@]}"

report="$root/bench/PEERS.md"
tmp="$report.tmp"
{
  echo "# clayfit against its peers (issue 6)"
  echo
  echo "Written by \`scripts/bench_peers.sh\` on $(date -u '+%Y-%m-%d %H:%M UTC'); machine:"
  echo "$(nproc) cores, $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1); load"
  echo "average at the start $(cut -d' ' -f1-3 /proc/loadavg) (other work slows every contestant)."
  echo "Every contestant solves the same problem: the capture's lit, unclipped"
  echo "observations, unweighted least squares on linear RGB (no loss, no noise"
  echo "weights, no scale or exposures), every parameter free within docs/model.md's"
  echo "bounds, one start, Levenberg-Marquardt (Ceres: DENSE_NORMAL_CHOLESKY, 2"
  echo "threads; SciPy: least_squares 'trf' with the 2-point Jacobian), tolerances"
  echo "function 1e-10, gradient 1e-12, parameter 1e-10. Wall times include the"
  echo "problem's set-up (SciPy: not Python's start-up nor loading the arrays)."
  echo "A peer counts when its final cost (every contestant's solution costed by"
  echo "the C evaluator) is within 1e-6 relative of clayfit's, or lower. Ratios are"
  echo "the peer's time over clayfit's. Targets (issue 31, not asserted), at equal"
  echo "cost: on M2 AutoDiff >= 10x and SciPy >= 30x clayfit's time, on M4 >= 30x"
  echo "and >= 60x."
  echo
  echo "Captures:"
  echo
  for c in "${commands[@]}"; do echo "    $c"; done
  echo
} >"$tmp"

run() {  # title name model args...
  local title=$1 name=$2 model=$3
  shift 3
  local cmd=(clayfit-peers "out/bench_peers/$name/capture.json" --model "$model"
             --start-from-truth "out/bench_peers/$name/truth.json" "$@")
  echo "bench_peers: $title" >&2
  local text
  text="$("$peers" "$out/$name/capture.json" --model "$model" \
      --start-from-truth "$out/$name/truth.json" --scipy-script "$root/scripts/peer_scipy.py" \
      --python "$python" --json "$out/$name.$model.json" "$@")"
  {
    echo "## $title"
    echo
    echo "    ${cmd[*]}"
    echo
    echo "$text" | sed -n '/^|/p'
    echo
    echo "$text" | sed -n 's/^\(model check\|evaluator floor\)/\1/p'
    echo
  } >>"$tmp"
  echo "$text"
}
run "M2, 8 x 320x240, low noise, all observations" m2 M2
run "M4, 8 x 320x240, low noise, all observations" m4 M4
run "M4, default noise, 20 000 observations (sigma near its bound)" m4_noisy M4 --max-obs 20000
mv "$tmp" "$report"
echo "bench_peers: wrote $report" >&2
