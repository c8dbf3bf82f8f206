#!/usr/bin/env bash
# The whole test suite on a fresh Debian 12 machine: installs what is
# missing (scripts/install-deps.sh test: the demo's packages and every
# component a test runs), builds, and runs every ctest test.
#   1. Release build (warnings are errors): every test.
#   2. AddressSanitizer + UBSan build: every test but the slow ones.
#   3. libFuzzer on everything clayfit reads: 5 targets, 25 s each (scripts/fuzz.sh).
set -euo pipefail
cd "$(dirname "$0")/.."

start=$(date +%s)
bash scripts/install-deps.sh test
jobs=$(nproc)

bash scripts/build.sh release
(cd build/release && ctest --output-on-failure -j "$jobs")

bash scripts/build.sh sanitize
(cd build/sanitize && ctest --output-on-failure -j "$jobs" -LE slow)

bash scripts/fuzz.sh 25

echo "test: all passed in $(( $(date +%s) - start )) s"
