/* The local executor: a pool of worker processes, each running one task
 * as `clayfit batch MANIFEST -o LIBRARY --task I --threads T`, the same
 * command a Slurm array element runs. Processes, not threads: a task that
 * crashes or is killed takes nothing else with it. Each worker dies with
 * the batch (a parent-death signal). */
#define _DEFAULT_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <unistd.h>

#include "batch_internal.h"

extern char **environ;

/* In the child, before exec: the parent-death signal, so that a worker
 * dies with its batch even when the batch is SIGKILLed (it cannot kill its
 * workers then, and a re-run would take over the lock and delete the live
 * worker's folder under it). The parent may have died before prctl: then
 * the child's parent is no longer `parent`, and it ends at once. Only
 * async-signal-safe calls: the child of fork. */
static void child(const cf_batch_local_options *o, pid_t parent, char **argv) {
#ifdef __linux__
  if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);
#endif
  int null = open("/dev/null", O_WRONLY);
  if (null < 0 || dup2(null, STDOUT_FILENO) < 0) _exit(127);
  if (null != STDOUT_FILENO) close(null);
  execve(o->exe, argv, environ);
  _exit(127);
}

static cf_status spawn(const cf_batch_local_options *o, size_t index, pid_t *pid, cf_error *err) {
  char task[32], threads[32];
  snprintf(task, sizeof task, "%zu", index);
  snprintf(threads, sizeof threads, "%d", o->threads);
  char *argv[] = {"clayfit", "--quiet", "batch", (char *)o->manifest, "-o", (char *)o->library,
                  "--task", task, "--threads", threads, NULL};
  pid_t parent = getpid();
  *pid = fork();
  if (*pid < 0) return cf_error_set(err, CF_EIO, "cannot start %s: %s", o->exe, strerror(errno));
  if (*pid == 0) child(o, parent, argv);
  return CF_OK;
}

/* Every running worker killed and reaped (Ctrl-C). */
static void kill_all(const pid_t *pids, int jobs) {
  for (int k = 0; k < jobs; ++k)
    if (pids[k] > 0) kill(pids[k], SIGKILL);
  for (int k = 0; k < jobs; ++k)
    if (pids[k] > 0) waitpid(pids[k], NULL, 0);
}

cf_status cf_batch_run_local(const cf_batch_local_options *o, const size_t *todo, size_t count,
                             int *ok, cf_error *err) {
  pid_t *pids = calloc((size_t)o->jobs, sizeof *pids);
  size_t *slot_task = calloc((size_t)o->jobs, sizeof *slot_task);
  if (!pids || !slot_task) {
    free(pids), free(slot_task);
    return cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  cf_batch_progress progress = {0, 0, 0, count};
  cf_status s = CF_OK;
  size_t next = 0;
  while (s == CF_OK && !*o->interrupted) {
    for (int k = 0; s == CF_OK && k < o->jobs && next < count; ++k) {
      if (pids[k] > 0) continue;
      s = spawn(o, todo[next], &pids[k], err);
      slot_task[k] = next++;
      progress.running++, progress.pending--;
    }
    if (progress.running == 0) break;
    int status = 0;
    pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) continue; /* EINTR: look at the flag */
    for (int k = 0; k < o->jobs; ++k) {
      if (pids[k] != pid) continue;
      pids[k] = 0;
      size_t i = slot_task[k];
      ok[i] = WIFEXITED(status) && WEXITSTATUS(status) == 0;
      progress.running--;
      ok[i] ? progress.done++ : progress.failed++;
      cf_batch_outcome how = ok[i]                 ? CF_BATCH_TASK_FITTED
                             : WIFSIGNALED(status) ? CF_BATCH_TASK_KILLED
                                                   : CF_BATCH_TASK_FAILED;
      if (o->progress) o->progress(o->progress_user, &progress, i, how);
    }
  }
  if (s != CF_OK) kill_all(pids, o->jobs); /* a worker could not start */
  if (s == CF_OK && *o->interrupted) {
    kill_all(pids, o->jobs);
    s = cf_error_set(err, CF_EIO, "interrupted: %zu tasks not finished",
                     progress.running + progress.pending);
  }
  free(pids);
  free(slot_task);
  return s;
}
