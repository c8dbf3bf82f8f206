#!/usr/bin/env bash
# slurm_array STATE_DIR OUT_DIR: a job array through the local cluster.
# shellcheck source=tests/slurm/common.sh
. "$(dirname "$0")/common.sh"

# Each task records its index and when it ran (start, end in ns).
cat >"$out/task.sh" <<'TASK'
#!/bin/sh
start=$(date +%s%N)
sleep 0.5
printf '%s %s %s %s\n' "$SLURM_ARRAY_JOB_ID" "$SLURM_ARRAY_TASK_ID" "$start" "$(date +%s%N)" >"$1/ran.$SLURM_ARRAY_TASK_ID"
[ "$SLURM_ARRAY_TASK_ID" != "$2" ] || exit 3
TASK

# most_at_once: the most tasks running at one task's start (itself included).
most_at_once() {
  cat "$out"/ran.* | awk '{ s[NR] = $3; e[NR] = $4 }
    END { for (i = 1; i <= NR; i++) { c = 0; for (k = 1; k <= NR; k++) if (s[k] <= s[i] && s[i] < e[k]) c++; if (c > m) m = c } print m }'
}

# 1. Four tasks, two at a time (on 2 CPUs the throttle does not bind: part
# 2 checks it), all succeed: each index runs once, sbatch --wait says 0.
set +e
job=$(sbatch --parsable --wait --array=0-3%2 -D "$out" -o "$out/log.%a" "$out/task.sh" "$out" none)
status=$?
set -e
echo "job $job: sbatch --wait exit status $status"
((status == 0)) || fail "sbatch --wait exit status $status, expected 0"
for i in 0 1 2 3; do
  [ -f "$out/ran.$i" ] || fail "task $i did not run"
  read -r j t _ <"$out/ran.$i"
  [ "$j $t" = "$job $i" ] || fail "task $i wrote '$j $t', expected '$job $i'"
done
n=$(find "$out" -name 'ran.*' | wc -l)
((n == 4)) || fail "$n tasks ran, expected 4"
most=$(most_at_once)
echo "at most $most tasks ran at once"
((most <= 2)) || fail "$most tasks ran at once with --array=0-3%2"
states=$(task_states "$job" | tr '\n' ' ')
echo "squeue: $states"
[ "$states" = "0 COMPLETED 1 COMPLETED 2 COMPLETED 3 COMPLETED " ] || fail "squeue says '$states'"

# 2. The throttle where it binds on 2 CPUs: %1 runs one task at a time
# (without it, 2 at once). Polls squeue, quicker than sbatch --wait.
rm -f "$out"/ran.*
job=$(sbatch --parsable --array=0-2%1 -D "$out" -o "$out/log.%a" "$out/task.sh" "$out" none)
all_done() { [ "$(task_states "$job" | tr '\n' ' ')" = "0 COMPLETED 1 COMPLETED 2 COMPLETED " ]; }
wait_for 60 "job $job's 3 tasks to complete" all_done
most=$(most_at_once)
echo "--array=0-2%1: $(find "$out" -name 'ran.*' | wc -l) tasks ran, at most $most at once"
((most == 1)) || fail "$most tasks ran at once with --array=0-2%1"

# 3. Task 2 fails: its exit status comes back, squeue marks it FAILED.
rm -f "$out"/ran.*
set +e
job=$(sbatch --parsable --wait --array=0-3 -D "$out" -o "$out/log.%a" "$out/task.sh" "$out" 2)
status=$?
set -e
echo "job $job (task 2 exits 3): sbatch --wait exit status $status"
((status == 3)) || fail "sbatch --wait exit status $status, expected 3 (task 2's)"
states=$(task_states "$job" | tr '\n' ' ')
echo "squeue: $states"
[ "$states" = "0 COMPLETED 1 COMPLETED 2 FAILED 3 COMPLETED " ] || fail "squeue says '$states'"
echo "ok"
