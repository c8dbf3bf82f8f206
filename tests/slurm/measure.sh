#!/usr/bin/env bash
# Measures the local cluster (not a ctest test; docs/slurm.md has the
# numbers): start and stop times, an array of 20 `true` tasks (through
# sbatch --wait and polling squeue every 50 ms) and one task's latency from
# submit to done. Starts and stops the cluster in STATE_DIR (default
# build/slurm-measure).
#   bash tests/slurm/measure.sh [STATE_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
local_sh="$root/scripts/slurm-local.sh"
state=${1:-$root/build/slurm-measure}

seconds() { echo "scale=3; ($2 - $1) / 1000000000" | bc; }
timed() { local s; s=$(date +%s%N); "$@" >/dev/null 2>&1; seconds "$s" "$(date +%s%N)"; }
# poll JOBID: until no task of the job is pending, running or completing.
poll() { while squeue -h -r -j "$1" -t PD,CF,R,CG -o %T 2>/dev/null | grep -q .; do sleep 0.05; done; }

bash "$local_sh" stop "$state" 2>/dev/null
for _ in 1 2 3 4 5; do
  echo "start $(timed bash "$local_sh" start "$state") s, stop $(timed bash "$local_sh" stop "$state") s"
done
bash "$local_sh" start "$state" >/dev/null
. "$state/env.sh"
work=$(mktemp -d "$state/measure.XXXXXX")
printf '#!/bin/sh\ntrue\n' >"$work/true.sh"
for _ in 1 2 3; do
  w=$(timed sbatch -Q --wait --array=0-19 -o /dev/null -D "$work" "$work/true.sh")
  echo "array of 20, sbatch --wait: $w s, $(echo "scale=3; $w / 20" | bc) s per task"
done
for _ in 1 2 3; do
  s=$(date +%s%N)
  poll "$(sbatch --parsable --array=0-19 -o /dev/null -D "$work" "$work/true.sh")"
  w=$(seconds "$s" "$(date +%s%N)")
  echo "array of 20, polled: $w s, $(echo "scale=3; $w / 20" | bc) s per task"
done
for _ in 1 2 3 4 5; do
  s=$(date +%s%N)
  poll "$(sbatch --parsable -o /dev/null -D "$work" "$work/true.sh")"
  echo "one task, submit to done (polled): $(seconds "$s" "$(date +%s%N)") s"
done
for _ in 1 2 3; do
  echo "one task, sbatch --wait: $(timed sbatch -Q --wait -o /dev/null -D "$work" "$work/true.sh") s"
done
rm -rf "$work"
bash "$local_sh" stop "$state"
