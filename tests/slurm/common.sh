# shellcheck shell=bash
# Sourced by the slurm_* tests: STATE_DIR OUT_DIR from the arguments, the
# local cluster's environment, a fresh OUT_DIR; exit 77 without Slurm.
set -euo pipefail
state=$1
out=$2
command -v sbatch >/dev/null || { echo "skipped: slurm-wlm is not installed (scripts/install-deps.sh)"; exit 77; }
[ -s "$state/env.sh" ] || { echo "FAIL: no local cluster in $state (the slurm_start test sets it up)"; exit 1; }
. "$state/env.sh"
rm -rf "$out"
mkdir -p "$out"

fail() { echo "FAIL: $*"; exit 1; }

# task_states JOBID: "INDEX STATE" per array task, sorted (squeue keeps
# finished jobs for MinJobAge, 300 s; there is no sacct without slurmdbd).
task_states() { squeue -h -r -t all -j "$1" -o '%K %T' | sort -n; }

# wait_for SECONDS WHAT COMMAND...: polls COMMAND every 0.2 s.
wait_for() {
  local seconds=$1 what=$2 i
  shift 2
  for ((i = 0; i < seconds * 5; i++)); do
    "$@" && return 0
    sleep 0.2
  done
  fail "timed out after $seconds s waiting for $what"
}
