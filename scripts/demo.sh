#!/usr/bin/env bash
# The main job on a fresh Debian 12 machine: installs what is missing of
# what the demo needs (scripts/install-deps.sh demo: the compiler, CMake and
# the libraries clayfit links), builds the clayfit program in Release
# (scripts/build.sh demo), and runs clayfit on its built-in default capture.
# The test command (scripts/test.sh) installs and builds the rest.
#
# Today (issues 2 to 4): render the default synthetic capture (16 photos of
# wet clay, model M4, with their COLMAP model), load it and draw the pixels
# it uses, fit it (the model chosen from the ladder, then its parameters with
# uncertainties: out/demo/fit/fit.json), then the evaluator's benchmark and
# one evaluation with gradient, and the residual report of the fit
# (out/demo/report/index.html) and its presets (out/demo/presets/).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh demo
installed=$SECONDS
bash scripts/build.sh demo
built=$SECONDS
clayfit=build/release/src/cli/clayfit
out=out/demo
rm -rf "$out"
mkdir -p "$out"

echo
echo "== clayfit synth: the default capture (16 photos, 640x480, wet clay M4) =="
"$clayfit" synth -o "$out/capture"

echo
echo "== clayfit inspect: the capture as observations =="
"$clayfit" inspect "$out/capture/capture.json" -o "$out/inspect" | tee "$out/inspect.txt"

echo
echo "== clayfit fit: the model chosen from the ladder, its parameters (truth: capture/truth.json) =="
"$clayfit" fit "$out/capture/capture.json" -o "$out/fit" | tee "$out/fit.txt"

echo
echo "== clayfit export: the fitted material as presets (clayfit json, MaterialX, glTF, Blender, Mitsuba) =="
mkdir -p "$out/presets"
for format in json:clay.json mtlx:clay.mtlx mtlx-openpbr:clay_openpbr.mtlx gltf:clay.gltf \
              blender:clay_blender.py mitsuba:clay_mitsuba.xml; do
  "$clayfit" export "$out/fit/fit.json" --format "${format%%:*}" -o "$out/presets/${format#*:}"
done
ls "$out/presets"

echo
echo "== clayfit report: photo, re-rendering and residual of every image, plots (open report/index.html) =="
"$clayfit" report "$out/fit/fit.json" -o "$out/report"
if [ ! -f "$(dirname "$clayfit")/clayfit-report-viewer.js" ]; then
  echo "(the report's interactive three.js view is not built by the demo: it needs Node.js and npm"
  echo " packages; bash scripts/install-deps.sh test, then bash scripts/build.sh release, build it)"
fi

echo
echo "== clayfit bench eval (evaluator speed, one thread) =="
"$clayfit" bench eval --min-time 0.1 | tee "$out/bench-eval.txt"

echo
echo "== clayfit eval: default wet clay (M4), light 30 deg, view 20 deg on the other side =="
"$clayfit" eval --model clay --light 0.5,0,0.866 --view -0.342,0,0.940 --grad \
  > "$out/eval-clay.json"
head -c 600 "$out/eval-clay.json"
echo "..."
echo
echo "demo: installed in $installed s, built in $((built - installed)) s, ran in $((SECONDS - built)) s"
echo "demo: outputs in $out/ (capture/, inspect/ overlays, fit/fit.json, presets/, report/index.html, bench-eval.txt, eval-clay.json)"
