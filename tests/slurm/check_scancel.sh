#!/usr/bin/env bash
# slurm_scancel STATE_DIR OUT_DIR: scancel of one running array element.
# shellcheck source=tests/slurm/common.sh
. "$(dirname "$0")/common.sh"

# Each task records its pid, sleeps long, and would then write done.N.
cat >"$out/task.sh" <<'TASK'
#!/bin/sh
echo $$ >"$1/pid.$SLURM_ARRAY_TASK_ID"
# (only if sleep ended by itself: scancel signals sleep and this shell
# separately, and the shell may outlive sleep by a moment)
sleep 300 && touch "$1/done.$SLURM_ARRAY_TASK_ID"
TASK

job=$(sbatch --parsable --array=0-1 -D "$out" -o "$out/log.%a" "$out/task.sh" "$out")
echo "job $job"
both_run() { [ "$(task_states "$job" | tr '\n' ' ')" = "0 RUNNING 1 RUNNING " ] && [ -s "$out/pid.0" ] && [ -s "$out/pid.1" ]; }
wait_for 60 "both tasks to run" both_run
pid0=$(<"$out/pid.0")
pid1=$(<"$out/pid.1")
alive() { local s; s=$(cat "/proc/$1/stat" 2>/dev/null) || return 1; s=${s##*) }; [ "${s%% *}" != Z ]; }
alive "$pid0" || fail "task 0's process $pid0 is not there"

scancel "${job}_0"
gone() { ! alive "$pid0"; }
wait_for 30 "task 0's process $pid0 to end" gone
cancelled() { [ "$(task_states "$job" | head -1)" = "0 CANCELLED" ]; }
wait_for 30 "squeue to say task 0 CANCELLED" cancelled
states=$(task_states "$job" | tr '\n' ' ')
echo "after scancel ${job}_0: $states"
[ "$states" = "0 CANCELLED 1 RUNNING " ] || fail "squeue says '$states', expected task 1 still running"
alive "$pid1" || fail "task 1's process $pid1 ended with task 0's cancel"
[ ! -e "$out/done.0" ] || fail "task 0 ran to its end"

scancel "$job"
gone1() { ! alive "$pid1"; }
wait_for 30 "task 1's process $pid1 to end" gone1
[ ! -e "$out/done.1" ] || fail "task 1 ran to its end"
echo "ok"
