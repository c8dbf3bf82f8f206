#!/usr/bin/env bash
# The report of a fit of the real DiLiGenT ball: every picture and plot of
# its 96 images, and the page in a browser. Skipped (77) without the data.
# usage: report_diligent.sh SOURCE SHARED_DATA OUT SCHEMA (CLAYFIT, PYTHON in the environment)
set -euo pipefail
source=$1 data=$2 out=$3 schema=$4
if [ ! -d "$data/diligent_ball" ]; then
  echo "SKIP: $data/diligent_ball is absent"
  exit 77
fi
rm -rf "$out"
"$CLAYFIT" --quiet fit "$source/tests/diligent_ball.capture.json" -o "$out/fit" --model M2 \
  --footprint centre >/dev/null
"$CLAYFIT" --quiet report "$out/fit/fit.json" -o "$out/report" >/dev/null
"$PYTHON" "$source/tests/report/check_report.py" "$out/report" "$schema" 96
status=0
"$PYTHON" "$source/tests/report/check_report_browser.py" "$out/report" "$out/screenshot.png" || status=$?
[ "$status" -eq 0 ] || [ "$status" -eq 77 ] || exit "$status"
