#!/usr/bin/env bash
# Fuzz everything clayfit reads with libFuzzer for a bounded time.
#   scripts/fuzz.sh [SECONDS]        seconds per target (default 60)
# The targets (tests/fuzz/; their sources and flags: tests/fuzz/fuzz.mk):
#   fuzz_colmap_binary  COLMAP models, binary and text
#   fuzz_capture_spec   capture files (the JSON, and the image list it names)
#   fuzz_text           image lists, light directions and intensities
#   fuzz_fit_file       fit.json, as export and report read it
#   fuzz_image          images through clayfit's codecs: PNG, EXR, JPEG, PFM
#                       (headers first, pixels of small ones)
# Builds them into build/fuzz with clang (-fsanitize=fuzzer,address,
# undefined; incremental), seeds each (build/fuzz/seeds/TARGET: clayfit's
# own writers, tests/fuzz/seeds, the test fixtures, and the inputs that
# once found a bug, tests/fuzz/regressions), and fuzzes as many targets at
# a time as there are cores, each for SECONDS. New inputs go to
# build/fuzz/corpus/TARGET, kept between runs. Fails on any crash,
# sanitizer report, broken promise of a reader, leak, timeout or
# out-of-memory; the input that did it is saved as
# build/fuzz/TARGET-crash-* (or -leak-, -timeout-, -oom-).
# Needs clang, clang++ and libFuzzer (Debian: clang, libclang-rt-14-dev).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
case $seconds in
  '' | *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS]" >&2; exit 2 ;;
esac
clang=${CLANG:-$(command -v clang || command -v clang-14 || true)}
clangxx=${CLANGXX:-$(command -v clang++ || command -v clang++-14 || true)}
if [ -z "$clang" ] || [ -z "$clangxx" ]; then
  echo "fuzz: clang or clang++ not found (set CLANG=... CLANGXX=...)" >&2
  exit 1
fi
start=$(date +%s)
jobs=$(nproc)
out=build/fuzz
targets=(fuzz_colmap_binary fuzz_capture_spec fuzz_text fuzz_fit_file fuzz_image)
declare -A max_len=([fuzz_colmap_binary]=16384 [fuzz_capture_spec]=8192 [fuzz_text]=4096
                    [fuzz_fit_file]=32768 [fuzz_image]=16384)

mkdir -p "$out"
if ! make -f tests/fuzz/fuzz.mk -j "$jobs" OUT="$out" CC="$clang" CXX="$clangxx" \
    > "$out/build.log" 2>&1; then
  tail -n 40 "$out/build.log" >&2
  echo "fuzz: the build failed; log in $out/build.log" >&2
  exit 1
fi
built=$(date +%s)

# scratch files of the targets (fuzz_files.h): inside build/fuzz, removed after
export TMPDIR="$PWD/$out/tmp"
rm -rf "$TMPDIR"
mkdir -p "$TMPDIR"

# ---- seeds ----
rm -rf "$out/seeds" "$out/seed-models"
for t in "${targets[@]}"; do
  mkdir -p "$out/seeds/$t" "$out/corpus/$t"
  if [ -d "tests/fuzz/regressions/$t" ]; then
    cp tests/fuzz/regressions/"$t"/* "$out/seeds/$t/"
  fi
done
# an older corpus of the COLMAP target, from before there were several
find "$out/corpus" -maxdepth 1 -type f -exec mv -t "$out/corpus/fuzz_colmap_binary" {} +
mkdir -p "$out/seed-models"
"$out/make_seeds" "$out/seed-models"
for file in "$out"/seed-models/*/*; do
  cp "$file" "$out/seeds/fuzz_colmap_binary/$(basename "$(dirname "$file")")-$(basename "$file")"
done
cp tests/fuzz/seeds/capture_spec/* tests/*.capture.json "$out/seeds/fuzz_capture_spec/"
cp tests/fuzz/seeds/text/* "$out/seeds/fuzz_text/"
diligent=../shared/data/diligent_ball
if [ -f "$diligent/filenames.txt" ]; then
  { cat "$diligent/filenames.txt"; echo '%%'; cat "$diligent/light_directions.txt"; echo '%%'
    cat "$diligent/light_intensities.txt"; } > "$out/seeds/fuzz_text/diligent_ball"
fi
cp tests/fuzz/seeds/fit_file/* "$out/seeds/fuzz_fit_file/"
"$out/make_image_seeds" "$out/seeds/fuzz_image" 2> "$out/make_image_seeds.log" || {
  cat "$out/make_image_seeds.log" >&2
  exit 1
}

# ---- fuzzing, `jobs` targets at a time ----
fuzz_one() {
  local t=$1 status=0
  "$out/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=512 \
    -max_len="${max_len[$t]}" -print_final_stats=1 -artifact_prefix="$out/$t-" \
    "$out/corpus/$t" "$out/seeds/$t" > "$out/$t.log" 2>&1 || status=$?
  echo "$status" > "$out/$t.status"
}
running=0
for t in "${targets[@]}"; do
  rm -f "$out/$t.status"
  fuzz_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
done
wait

failed=0
for t in "${targets[@]}"; do
  status=$(cat "$out/$t.status" 2>/dev/null || echo missing)
  runs=$(sed -n 's/^Done \([0-9]*\) runs in \([0-9]*\) second.*/\1 executions in \2 s/p' \
    "$out/$t.log")
  if [ "$status" != 0 ]; then
    tail -n 60 "$out/$t.log" >&2
    echo "fuzz: $t FAILED (status $status); log in $out/$t.log" >&2
    failed=1
  else
    echo "fuzz: $t: ${runs:-? executions}, $(ls "$out/seeds/$t" | wc -l) seeds," \
      "$(ls "$out/corpus/$t" | wc -l) inputs in the corpus"
  fi
done
rm -rf "$TMPDIR"
end=$(date +%s)
if [ "$failed" -ne 0 ]; then
  echo "fuzz: FAILED; logs in $out/TARGET.log" >&2
  exit 1
fi
echo "fuzz: no crash in ${#targets[@]} targets x ${seconds} s ($((end - start)) s in all," \
  "of which $((built - start)) s building)"
