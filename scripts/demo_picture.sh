#!/usr/bin/env bash
# The README's picture, docs/images/demo_fit.png: one photo of the demo
# capture (`clayfit synth`'s default, as scripts/demo.sh renders it), its
# re-rendering and residual from `clayfit report` for the chosen model (M4)
# and for a forced M2, side by side, with the report's colour scale.
#   bash scripts/demo_picture.sh [CLAYFIT]   (default build/release/src/cli/clayfit)
# Needs oiiotool (OpenImageIO's tools) and the DejaVu fonts for the labels.
set -euo pipefail
cd "$(dirname "$0")/.."

clayfit=${1:-build/release/src/cli/clayfit}
out=out/demo_picture
image=000                       # the report's first image: camera 1 of 16
tile=184                        # pixels per picture side in the mosaic
band=26                         # the label band above each picture
gap=6                           # white space between the pictures
cell=$((tile + 2 * gap))
font=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf
target=docs/images/demo_fit.png

[ -f "$font" ] || { echo "demo_picture: no $font (apt-get install fonts-dejavu-core)" >&2; exit 1; }
command -v oiiotool >/dev/null || { echo "demo_picture: no oiiotool (apt-get install openimageio-tools)" >&2; exit 1; }
rm -rf "$out"
mkdir -p "$out" "$(dirname "$target")"
"$clayfit" --quiet synth -o "$out/capture"
"$clayfit" --quiet fit "$out/capture/capture.json" -o "$out/fit_auto" > "$out/fit_auto.txt"
"$clayfit" --quiet fit "$out/capture/capture.json" -o "$out/fit_m2" --model M2 > "$out/fit_m2.txt"
"$clayfit" --quiet report "$out/fit_auto/fit.json" -o "$out/report_auto" > /dev/null
"$clayfit" --quiet report "$out/fit_m2/fit.json" -o "$out/report_m2" > /dev/null
chosen=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["model"]["code"])' \
  "$out/fit_auto/fit.json")

# One labelled tile: a picture scaled to the tile under a band with its label,
# on a white cell (the mosaic's gaps).
labelled() {
  oiiotool "$1" --resize "${tile}x${tile}" \
    --create "${cell}x$((tile + band + gap))" 3 --fill:color=1,1,1 "0,0,${cell},$((tile + band + gap))" \
    --text:x=$((gap + 4)):y=18:size=14:color=0,0,0:font="$font" "$2" \
    --paste "+${gap}+${band}" -o "$3"
}

# The colour scale tile: the report page's gradient stops (index.html), drawn
# as 10 linear segments, with its key.
legend() {
  local stops=() seg=$(( (tile - 8) / 10 )) left=$((gap + 4)) args=()
  mapfile -t stops < <(grep -o 'stop-color="rgb([0-9,]*)"' "$out/report_auto/index.html" |
    head -11 | sed 's/.*rgb(\([0-9,]*\)).*/\1/' |
    awk -F, '{printf "%.4f,%.4f,%.4f\n", $1/255, $2/255, $3/255}')
  [ "${#stops[@]}" -eq 11 ] || { echo "demo_picture: no colour scale in the report" >&2; exit 1; }
  for i in $(seq 0 9); do
    local x0=$((left + i * seg)) x1=$((left + (i + 1) * seg))
    args+=(--fill:left="${stops[$i]}":right="${stops[$((i + 1))]}" "${x0},86,${x1},108")
  done
  local t="--text:size=12:color=0,0,0:font=$font" right=$((left + 10 * seg))
  oiiotool --create "${cell}x$((tile + band + gap))" 3 --fill:color=1,1,1 "0,0,${cell},$((tile + band + gap))" \
    "${args[@]}" \
    "$t:x=$left:y=18" "the residual map:" \
    "$t:x=$left:y=40" "(render - photo) / sigma" \
    "$t:x=$left:y=56" "(sigma: the noise, per pixel);" \
    "$t:x=$left:y=72" "noise alone gives N(0, 1)" \
    "$t:x=$left:y=124" "-5" "$t:x=$((left + 5 * seg - 4)):y=124" "0" "$t:x=$((right - 16)):y=124" "+5" \
    "$t:x=$left:y=142" "render darker ... brighter" \
    "$t:x=$left:y=176:color=1,0,1" "magenta: clipped (censored)" \
    "$t:x=$left:y=194:color=0,0.45,0" "green: beyond the loss scale" \
    -o "$1"
}

ra="$out/report_auto/images" rm2="$out/report_m2/images"
labelled "$ra/${image}_photo.png" "photo (1 of 16)" "$out/t0.png"
labelled "$ra/${image}_render.png" "$chosen re-rendered (chosen)" "$out/t1.png"
labelled "$ra/${image}_residual.png" "$chosen residual: the noise" "$out/t2.png"
legend "$out/t3.png"
labelled "$rm2/${image}_render.png" "M2 re-rendered (forced)" "$out/t4.png"
labelled "$rm2/${image}_residual.png" "M2 residual: structure" "$out/t5.png"
oiiotool "$out"/t{0,1,2,3,4,5}.png --mosaic 3x2 -d uint8 --attrib png:compressionLevel 9 -o "$target"
echo "demo_picture: $target ($(stat -c %s "$target") bytes)"
