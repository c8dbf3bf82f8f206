#!/usr/bin/env bash
# Fuzz COLMAP's model readers with libFuzzer for a bounded time.
#   scripts/fuzz.sh [SECONDS]        (default 60)
# Builds build/fuzz/fuzz_colmap_binary with clang (-fsanitize=fuzzer,
# address,undefined) from the sources directly, seeds a corpus with small
# valid models written by clayfit's own writers (build/fuzz/seeds), fuzzes
# (new inputs go to build/fuzz/corpus, kept between runs) and fails on any
# crash, sanitizer report, leak, timeout or out-of-memory; the input that
# did it is saved as build/fuzz/crash-* (or leak-*, timeout-*, oom-*).
# Needs clang and its libFuzzer runtime (Debian: clang, libclang-rt-dev).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
case $seconds in
  '' | *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS]" >&2; exit 2 ;;
esac
clang=${CLANG:-$(command -v clang || command -v clang-14 || true)}
if [ -z "$clang" ]; then
  echo "fuzz: clang not found (set CLANG=...)" >&2
  exit 1
fi

out=build/fuzz
mkdir -p "$out/corpus"
flags=(-std=c11 -g -O1 -fno-omit-frame-pointer -Wall -Wextra -Werror -Iinclude -Isrc)
readers=(src/core/status.c src/core/file.c src/capture/camera_model.c
         src/capture/colmap_common.c src/capture/colmap_binary.c src/capture/colmap_text.c
         src/capture/colmap_read.c)

"$clang" "${flags[@]}" -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  tests/fuzz/fuzz_colmap_binary.c "${readers[@]}" -lm -o "$out/fuzz_colmap_binary"
"$clang" "${flags[@]}" -fsanitize=address,undefined -fno-sanitize-recover=undefined \
  tests/fuzz/make_seeds.c "${readers[@]}" src/capture/colmap_write.c \
  -lm -o "$out/make_seeds"

# the seeds: every file of every model written, one corpus entry each
rm -rf "$out/seeds" "$out/seed-models"
mkdir -p "$out/seeds" "$out/seed-models"
"$out/make_seeds" "$out/seed-models"
for file in "$out"/seed-models/*/*; do
  cp "$file" "$out/seeds/$(basename "$(dirname "$file")")-$(basename "$file")"
done
echo "fuzz: $(ls "$out/seeds" | wc -l) seeds, $(ls "$out/corpus" | wc -l) inputs in the corpus, ${seconds} s"

status=0
"$out/fuzz_colmap_binary" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
  -malloc_limit_mb=512 -max_len=16384 -print_final_stats=1 -artifact_prefix="$out/" \
  "$out/corpus" "$out/seeds" > "$out/fuzz.log" 2>&1 || status=$?
runs=$(sed -n 's/^Done \([0-9]*\) runs in \([0-9]*\) second.*/\1 executions in \2 s/p' "$out/fuzz.log")
if [ "$status" -ne 0 ]; then
  tail -n 60 "$out/fuzz.log" >&2
  echo "fuzz: FAILED (status $status); log in $out/fuzz.log" >&2
  exit 1
fi
echo "fuzz: ${runs:-? executions}, no crash ($(ls "$out/corpus" | wc -l) inputs in the corpus; log in $out/fuzz.log)"
