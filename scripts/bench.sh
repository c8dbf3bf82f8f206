#!/usr/bin/env bash
# Speed against error (issue 6): `bash scripts/bench.sh`. Builds in Release
# if needed, then runs
#   clayfit bench eval           the evaluator alone (ns per evaluation);
#   clayfit bench fit            synthetic M4 captures of about 1e4, 1.5e5 and
#                                7e5 observations (and the DiLiGenT ball when
#                                ../shared/data has it): every observation, and
#                                budgets of 1e5, 3e4 and 1e4 drawn uniform,
#                                stratified and importance; time, peak memory,
#                                relative RMSE on all pixels, worst parameter
#                                error, the Pareto front, the evaluator's floor,
#                                the scaling;
#   scripts/bench_peers.sh       Ceres AutoDiff, NumericDiff and SciPy on the
#                                same observations (bench/PEERS.md);
#   scripts/bench_cli.py         `clayfit fit --model M4` on DiLiGenT as a user
#                                runs it (auto footprints; the default budget
#                                and every observation);
#   clayfit --version            the process start (the best of five);
# and writes bench/RESULTS.md and bench/speed_error.svg (the curve). Numbers
# are reported, never asserted; the machine is shared, so runs vary (up to
# about 1.5x).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bash scripts/install-deps.sh
bash scripts/build.sh release
cmake --build build/release -j2 --target clayfit-peers >/dev/null
clayfit=build/release/src/cli/clayfit
out=out/bench
mkdir -p "$out" bench

"$clayfit" bench eval --min-time 0.5 --json > "$out/eval.json"
extra=()
if [ -d ../shared/data/diligent_ball ]; then
  extra=(--capture tests/diligent_ball.capture.json)
fi
"$clayfit" bench fit --work "$out" --json "$out/fit.json" "${extra[@]}" | tee "$out/fit.txt"
bash scripts/bench_peers.sh build/release
# `clayfit fit` as a user runs it: auto footprints, on the real capture
cli_captures=()
if [ -d ../shared/data/diligent_ball ]; then
  cli_captures=(tests/diligent_ball.capture.json)
fi
python3 scripts/bench_cli.py "$clayfit" "$out" "${cli_captures[@]}" > "$out/cli.json"
# the process start: the best of five `clayfit --version`
start=$(python3 - "$clayfit" <<'PY'
import subprocess, sys, time
best = float("inf")
for _ in range(5):
    t = time.perf_counter()
    subprocess.run([sys.argv[1], "--version"], stdout=subprocess.DEVNULL, check=True)
    best = min(best, time.perf_counter() - t)
print(f"{best:.4f}")
PY
)
python3 scripts/bench_report.py "$out/eval.json" "$out/fit.json" bench/PEERS.md \
  bench/RESULTS.md bench/speed_error.svg "$start" "$out/cli.json"
echo "bench: bench/RESULTS.md, bench/speed_error.svg"
