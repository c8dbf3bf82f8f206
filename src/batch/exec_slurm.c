/* The Slurm executor: the tasks to fit as one job array whose element i
 * runs `clayfit batch MANIFEST -o LIBRARY --task todo[i]`, the command a
 * local worker runs. Everything goes through the library folder (the
 * cluster's shared file system): the job script, the task logs, the
 * results. Progress comes from squeue (pending, running) and from each
 * task's own result in the library (done, failed): no accounting needed. */
#define _DEFAULT_SOURCE /* nanosleep, realpath */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "batch_internal.h"
#include "core/clock.h"
#include "core/file.h"
#include "core/json_reader.h"

extern char **environ;

/* Seconds between looks at the tasks' results (a stat each), and between
 * squeue calls (one RPC to the controller: a real cluster's admins want
 * few). */
#define RESULT_POLL_S 0.5
#define SQUEUE_POLL_S 2.0
/* A task squeue calls ended is declared dead only after this long without
 * a result: on NFS another client's rename can show a few seconds late. */
#define RESULT_GRACE_S 3.0
/* squeue failing this long (the controller down): cancel, give up. */
#define SQUEUE_GIVE_UP_S 300.0
/* After scancel, how long to wait for the tasks to end (Slurm's KillWait,
 * 30 s by default, then SIGKILL). */
#define CANCEL_WAIT_S 90.0

/* ---- a growing string ---- */

typedef struct text {
  char *p;
  size_t n, cap;
  int failed;
} text;

static void text_add(text *t, const char *s, size_t len) {
  if (t->failed) return;
  if (t->n + len + 1 > t->cap) {
    size_t cap = t->cap ? t->cap : 256;
    while (cap < t->n + len + 1) cap *= 2;
    char *p = realloc(t->p, cap);
    if (!p) {
      t->failed = 1;
      return;
    }
    t->p = p, t->cap = cap;
  }
  memcpy(t->p + t->n, s, len);
  t->n += len;
  t->p[t->n] = '\0';
}

static void text_put(text *t, const char *s) {
  text_add(t, s, strlen(s));
}

static void text_clear(text *t) {
  t->n = 0;
  if (t->p) t->p[0] = '\0';
}

static void text_printf(text *t, const char *format, ...) __attribute__((format(printf, 2, 3)));
static void text_printf(text *t, const char *format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  int n = vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  if (n < 0 || (size_t)n >= sizeof buffer) {
    t->failed = 1;
    return;
  }
  text_add(t, buffer, (size_t)n);
}

/* One word for bash: 'single-quoted' ('\'' for a quote), or $'...' with
 * escapes when it holds a control character (a newline in a path would
 * otherwise end a comment line of the script). */
static void text_quote(text *t, const char *word) {
  int plain = *word != '\0', control = 0;
  for (const unsigned char *c = (const unsigned char *)word; *c; ++c) {
    if (*c < 0x20 || *c == 0x7f) control = 1;
    if (!strchr("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-./=%:,@+", *c))
      plain = 0;
  }
  if (plain) {
    text_put(t, word);
    return;
  }
  if (!control) {
    text_put(t, "'");
    for (const char *c = word; *c; ++c) *c == '\'' ? text_put(t, "'\\''") : text_add(t, c, 1);
    text_put(t, "'");
    return;
  }
  text_put(t, "$'");
  for (const unsigned char *c = (const unsigned char *)word; *c; ++c) {
    if (*c == '\'' || *c == '\\')
      text_printf(t, "\\%c", *c);
    else if (*c < 0x20 || *c == 0x7f)
      text_printf(t, "\\x%02x", *c);
    else
      text_add(t, (const char *)c, 1);
  }
  text_put(t, "'");
}

/* ---- running a command ---- */

/* Read fd to its end into t. */
static void read_all(int fd, text *t) {
  char buffer[4096];
  for (;;) {
    ssize_t n = read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    text_add(t, buffer, (size_t)n);
  }
  close(fd);
}

/* Run argv[0] from PATH (no shell), its stdout and stderr into out and
 * errors; its exit status, or -1 with errors saying why it could not
 * run. The output of sbatch and squeue is small (stderr is read after
 * stdout: it fits a pipe's buffer). */
static int run_command(char *const argv[], text *out, text *errors) {
  int out_pipe[2], err_pipe[2];
  if (pipe(out_pipe) != 0) return text_printf(errors, "pipe: %s", strerror(errno)), -1;
  if (pipe(err_pipe) != 0) {
    close(out_pipe[0]), close(out_pipe[1]);
    return text_printf(errors, "pipe: %s", strerror(errno)), -1;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  posix_spawn_file_actions_addclose(&actions, out_pipe[0]);
  posix_spawn_file_actions_addclose(&actions, err_pipe[0]);
  pid_t pid;
  int e = posix_spawnp(&pid, argv[0], &actions, NULL, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  close(out_pipe[1]), close(err_pipe[1]);
  if (e != 0) {
    close(out_pipe[0]), close(err_pipe[0]);
    text_printf(errors, "cannot run %s: %s", argv[0], strerror(e));
    return -1;
  }
  read_all(out_pipe[0], out);
  read_all(err_pipe[0], errors);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  text_printf(errors, "%s killed by signal %d", argv[0], WTERMSIG(status));
  return -1;
}

/* ---- the job script and the sbatch command ---- */

/* a b c joined, malloc'ed (NULL when out of memory). */
static char *concat(const char *a, const char *b, const char *c) {
  size_t n = strlen(a) + strlen(b) + strlen(c) + 1;
  char *s = malloc(n);
  if (s) snprintf(s, n, "%s%s%s", a, b, c);
  return s;
}

/* sbatch's file name patterns take %A, %a...: a literal % is %%. */
static char *pattern_escaped(const char *path) {
  text t = {0};
  for (const char *c = path; *c; ++c) *c == '%' ? text_put(&t, "%%") : text_add(&t, c, 1);
  if (t.failed) free(t.p);
  return t.failed ? NULL : t.p;
}

static cf_status build_argv(const cf_batch_slurm_options *o, size_t count, cf_batch_slurm_job *job,
                            cf_error *err) {
  int cap = 16 + o->sbatch_arg_count;
  job->argv = calloc((size_t)cap, sizeof *job->argv);
  if (!job->argv) return cf_error_set(err, CF_ENOMEM, "out of memory");
  char array[64], cpus[32];
  snprintf(array, sizeof array, "--array=0-%zu%%%d", count - 1, o->max_running);
  snprintf(cpus, sizeof cpus, "--cpus-per-task=%d", o->cpus_per_task);
  char *escaped = pattern_escaped(o->library);
  char **a = job->argv;
  int n = 0;
  a[n++] = strdup("sbatch");
  a[n++] = strdup("--parsable");
  a[n++] = strdup("--job-name=clayfit-batch");
  a[n++] = strdup(array);
  a[n++] = escaped ? concat("--output=", escaped, "/.slurm/logs/%A_%a.out") : NULL;
  a[n++] = concat("--chdir=", o->library, "");
  a[n++] = strdup(cpus);
  if (o->partition) a[n++] = concat("--partition=", o->partition, "");
  if (o->time) a[n++] = concat("--time=", o->time, "");
  if (o->mem) a[n++] = concat("--mem=", o->mem, "");
  for (int i = 0; i < o->sbatch_arg_count; ++i) a[n++] = strdup(o->sbatch_args[i]);
  a[n++] = strdup(job->script);
  job->argc = n;
  free(escaped);
  for (int i = 0; i < n; ++i)
    if (!a[i]) return cf_error_set(err, CF_ENOMEM, "out of memory");
  return CF_OK;
}

void cf_batch_slurm_command(const cf_batch_slurm_job *job, char *out, size_t size) {
  text t = {0};
  for (int i = 0; i < job->argc; ++i) {
    if (i) text_put(&t, " ");
    text_quote(&t, job->argv[i]);
  }
  snprintf(out, size, "%s", t.failed || !t.p ? "" : t.p);
  free(t.p);
}

/* The script: array index -> manifest entry, then the task. Every path
 * shell-quoted; nothing under /tmp. */
static cf_status write_script(const cf_batch_slurm_options *o, const size_t *todo, size_t count,
                              const cf_batch_slurm_job *job, cf_error *err) {
  text t = {0};
  char command[8192];
  cf_batch_slurm_command(job, command, sizeof command);
  text_put(&t,
           "#!/bin/bash\n"
           "# clayfit batch, the Slurm executor (docs/batch.md): array element i fits\n"
           "# manifest entry entries[i] into the library. Submitted as:\n#   ");
  text_put(&t, command);
  text_put(&t, "\n# Run `clayfit batch` again afterwards to write library.json.\n");
  text_put(&t, "entries=(");
  for (size_t i = 0; i < count; ++i) {
    text_printf(&t, "%s%zu", i ? " " : "", todo[i]);
    if (i % 16 == 15 && i + 1 < count) text_put(&t, "\n  ");
  }
  text_put(&t, ")\n");
  text_put(&t,
           "entry=${entries[${SLURM_ARRAY_TASK_ID:?not a Slurm array task}]:?no such array "
           "index}\ncd ");
  text_quote(&t, o->library);
  text_put(&t, " || exit 1\nexec ");
  text_quote(&t, o->exe);
  text_put(&t, " batch ");
  text_quote(&t, o->manifest);
  text_put(&t, " -o ");
  text_quote(&t, o->library);
  text_put(&t, " --task \"$entry\" --threads ");
  if (o->threads > 0)
    text_printf(&t, "%d\n", o->threads);
  else
    text_printf(&t, "\"${SLURM_CPUS_PER_TASK:-%d}\"\n", o->cpus_per_task);
  if (t.failed) {
    free(t.p);
    return cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  cf_status s = cf_write_file(job->script, t.p, t.n, err);
  if (s == CF_OK) chmod(job->script, 0755);
  free(t.p);
  return s;
}

/* LIBRARY/<name>'s inode, 0 when there is none: a new one is a result. */
static unsigned long long entry_inode(const char *library, const char *name) {
  char path[4096];
  struct stat st;
  snprintf(path, sizeof path, "%s/%s", library, name);
  return stat(path, &st) == 0 ? (unsigned long long)st.st_ino : 0;
}

cf_status cf_batch_slurm_prepare(const cf_batch_slurm_options *o, const size_t *todo, size_t count,
                                 cf_batch_slurm_job *job, cf_error *err) {
  memset(job, 0, sizeof *job);
  if (count == 0) return cf_error_set(err, CF_EINVAL, "no task to submit");
  char logs[4096], stamp[32];
  time_t now = time(NULL);
  struct tm tm;
  gmtime_r(&now, &tm);
  strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  int n = snprintf(logs, sizeof logs, "%s/.slurm/logs", o->library);
  int m = snprintf(job->script, sizeof job->script, "%s/.slurm/job-%s.sh", o->library, stamp);
  if (n < 0 || m < 0 || (size_t)n >= sizeof logs || (size_t)m >= sizeof job->script)
    return cf_error_set(err, CF_ERANGE, "%s: path too long", o->library);
  cf_status s = cf_make_dirs(logs, err);
  if (s == CF_OK) s = build_argv(o, count, job, err);
  if (s == CF_OK) s = write_script(o, todo, count, job, err);
  if (s == CF_OK && !(job->before = calloc(count, sizeof *job->before)))
    s = cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; s == CF_OK && i < count; ++i)
    job->before[i] = entry_inode(o->library, o->entries->entries[todo[i]].name);
  if (s != CF_OK) cf_batch_slurm_job_free(job);
  return s;
}

void cf_batch_slurm_job_free(cf_batch_slurm_job *job) {
  for (int i = 0; job->argv && i < job->argc; ++i) free(job->argv[i]);
  free(job->argv);
  free(job->before);
  job->argv = NULL, job->before = NULL, job->argc = 0;
}

/* ---- submitting ---- */

static void trim(text *t) {
  while (t->p && t->n && strchr(" \t\r\n", t->p[t->n - 1])) t->p[--t->n] = '\0';
}

cf_status cf_batch_slurm_submit(cf_batch_slurm_job *job, cf_error *err) {
  text out = {0}, errors = {0};
  int status = run_command(job->argv, &out, &errors);
  trim(&out), trim(&errors);
  cf_status s = CF_OK;
  if (status < 0)
    s = cf_error_set(err, CF_EIO, "%s", errors.p ? errors.p : "cannot run sbatch");
  else if (status != 0)
    s = cf_error_set(err, CF_EIO, "sbatch failed (exit status %d): %s", status,
                     errors.p ? errors.p : "no message");
  /* --parsable: "JOBID" or "JOBID;CLUSTER" */
  size_t digits = out.p ? strspn(out.p, "0123456789") : 0;
  if (s == CF_OK && (digits == 0 || digits >= sizeof job->id))
    s = cf_error_set(err, CF_EIO, "sbatch printed no job id: '%.200s' %s", out.p ? out.p : "",
                     errors.p ? errors.p : "");
  if (s == CF_OK) memcpy(job->id, out.p, digits), job->id[digits] = '\0';
  free(out.p), free(errors.p);
  return s;
}

/* ---- waiting ---- */

typedef enum { WAITING, ENDED } task_phase;

typedef struct task_view {
  task_phase phase;
  char state[24];     /* squeue's last word on it ("" when not listed) */
  double ended_since; /* when squeue first said it ended without a result; 0 */
} task_view;

/* squeue's states in which a task may still write its result. */
static int state_live(const char *state) {
  static const char *const live[] = {"PENDING",   "CONFIGURING", "RUNNING",      "COMPLETING",
                                     "SUSPENDED", "REQUEUED",    "REQUEUE_HOLD", "REQUEUE_FED",
                                     "RESIZING",  "SIGNALING",   "STAGE_OUT",    "STOPPED"};
  for (size_t i = 0; i < sizeof live / sizeof *live; ++i)
    if (strcmp(state, live[i]) == 0) return 1;
  return 0;
}

/* squeue's view of every array element into views[].state. 0 on success
 * (a job squeue no longer knows lists nothing), -1 with errors. */
static int squeue_states(const char *id, task_view *views, size_t count, text *errors) {
  char *argv[] = {"squeue", "-h", "-r", "-t", "all", "-j", (char *)id, "-o", "%K %T", NULL};
  text out = {0};
  int status = run_command(argv, &out, errors);
  int unknown = status == 1 && errors->p && strstr(errors->p, "Invalid job id");
  if (status != 0 && !unknown) return free(out.p), -1;
  for (size_t i = 0; i < count; ++i) views[i].state[0] = '\0';
  for (char *line = out.p, *next; line && *line; line = next) {
    next = strchr(line, '\n');
    if (next) *next++ = '\0';
    char *end = NULL, state[24];
    unsigned long index = strtoul(line, &end, 10);
    if (end == line || *end != ' ' || sscanf(end, " %23s", state) != 1 || index >= count) continue;
    snprintf(views[index].state, sizeof views[index].state, "%s", state);
  }
  free(out.p);
  return 0;
}

static void sleep_seconds(double seconds) {
  struct timespec ts = {(time_t)seconds, (long)((seconds - (double)(time_t)seconds) * 1e9)};
  nanosleep(&ts, NULL); /* a signal cuts it short: the flag is looked at next */
}

/* The last lines of a task's log, for its failed.json. */
static json_t *log_tail(const char *path) {
  json_t *lines = json_array();
  char *data = NULL;
  size_t size = 0;
  cf_error ignored = {0};
  if (cf_read_file(path, (size_t)1 << 24, &data, &size, &ignored) != CF_OK) return lines;
  size_t start = size > 4000 ? size - 4000 : 0;
  for (char *line = data + start, *next; line < data + size; line = next) {
    next = memchr(line, '\n', (size_t)(data + size - line));
    if (next)
      *next++ = '\0';
    else
      next = data + size;
    if (*line) json_array_append_new(lines, json_text(line));
  }
  free(data);
  return lines;
}

/* failed.json for a task that ended without a result, unless an earlier
 * fitted entry is there (kept whole: stale, it is re-fitted next run). */
static void record_died(const cf_batch_slurm_options *o, const cf_batch_slurm_job *job, size_t i,
                        const cf_batch_entry *e, const char *state) {
  char have[CF_BATCH_KEY_SIZE], key[CF_BATCH_KEY_SIZE], log[4200], reason[6000], tmp[4096],
      path[4200];
  if (cf_batch_entry_state(o->library, e->name, have) == CF_BATCH_FITTED) return;
  snprintf(log, sizeof log, "%s/.slurm/logs/%s_%zu.out", o->library, job->id, i);
  snprintf(reason, sizeof reason, "the Slurm task %s_%zu ended%s%s%s without a result: see %s",
           job->id, i, state[0] ? " (" : "", state, state[0] ? ")" : "", log);
  cf_error err = {0};
  if (cf_batch_entry_key(e, key, &err) != CF_OK) key[0] = '\0';
  json_t *doc =
      json_pack("{s:s, s:s, s:s, s:o, s:o, s:s, s:s, s:s, s:b, s:o}", "name", e->name, "key", key,
                "capture", e->capture, "options", batch_object_or_empty(e->options), "tags",
                batch_object_or_empty(e->tags), "build", cf_batch_build_id(), "slurm_job", job->id,
                "reason", reason, "retry", 1, "log", log_tail(log));
  if (!doc) return;
  if (batch_tmp_path(o->library, e->name, getpid(), tmp, sizeof tmp, &err) == CF_OK &&
      cf_make_dirs(tmp, &err) == CF_OK &&
      cf_path_join(tmp, "failed.json", path, sizeof path, &err) == CF_OK &&
      json_write_file(doc, path, JSON_INDENT(2), &err) == CF_OK &&
      entry_inode(o->library, e->name) == job->before[i]) /* no result meanwhile */
    batch_replace_entry(o->library, e->name, tmp, &err);
  batch_remove_tree(tmp);
  json_decref(doc);
}

/* Look at task i: its result, or its death. 1 when it just ended. */
static int update_task(const cf_batch_slurm_options *o, const cf_batch_slurm_job *job, task_view *v,
                       size_t i, size_t entry, int *ok, cf_batch_outcome *how) {
  const cf_batch_entry *e = &o->entries->entries[entry];
  unsigned long long inode = entry_inode(o->library, e->name);
  char key[CF_BATCH_KEY_SIZE];
  cf_batch_state state = inode && inode != job->before[i]
                             ? cf_batch_entry_state(o->library, e->name, key)
                             : CF_BATCH_MISSING;
  if (state != CF_BATCH_MISSING) {
    ok[i] = state == CF_BATCH_FITTED;
    *how = ok[i] ? CF_BATCH_TASK_FITTED : CF_BATCH_TASK_FAILED;
    return 1;
  }
  if (state_live(v->state)) return v->ended_since = 0, 0;
  double now = cf_now_seconds();
  if (v->ended_since == 0) v->ended_since = now;
  if (now - v->ended_since < RESULT_GRACE_S) return 0;
  record_died(o, job, i, e, v->state);
  ok[i] = 0;
  *how = CF_BATCH_TASK_KILLED;
  return 1;
}

/* scancel the job, then wait (bounded) until none of its tasks runs, so
 * that the caller's clean-up does not race a task still writing. */
static void cancel(const cf_batch_slurm_job *job, task_view *views, size_t count) {
  char *argv[] = {"scancel", (char *)job->id, NULL};
  text out = {0}, errors = {0};
  run_command(argv, &out, &errors);
  double start = cf_now_seconds();
  for (int live = 1; live && cf_now_seconds() - start < CANCEL_WAIT_S;) {
    sleep_seconds(RESULT_POLL_S);
    text_clear(&errors);
    if (squeue_states(job->id, views, count, &errors) != 0) continue;
    live = 0;
    for (size_t i = 0; i < count; ++i) live |= state_live(views[i].state);
  }
  free(out.p), free(errors.p);
}

cf_status cf_batch_slurm_wait(const cf_batch_slurm_options *o, const cf_batch_slurm_job *job,
                              const size_t *todo, size_t count, int *ok, cf_error *err) {
  task_view *views = calloc(count, sizeof *views);
  cf_batch_outcome *outcomes = calloc(count, sizeof *outcomes);
  size_t *ended_now = calloc(count, sizeof *ended_now);
  if (!views || !outcomes || !ended_now) {
    free(views), free(outcomes), free(ended_now);
    return cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  for (size_t i = 0; i < count; ++i) snprintf(views[i].state, sizeof views[i].state, "PENDING");
  cf_batch_progress p = {0, 0, 0, count};
  double last_squeue = 0, last_ok = cf_now_seconds();
  text errors = {0};
  cf_status s = CF_OK;
  while (p.done + p.failed < count && !*o->interrupted) {
    double now = cf_now_seconds();
    if (now - last_squeue >= SQUEUE_POLL_S) {
      last_squeue = now;
      text_clear(&errors);
      if (squeue_states(job->id, views, count, &errors) == 0)
        last_ok = now;
      else if (now - last_ok > SQUEUE_GIVE_UP_S) {
        s = cf_error_set(err, CF_EIO, "squeue has failed for %.0f s: %s", now - last_ok,
                         errors.p ? errors.p : "");
        break;
      }
    }
    cf_batch_outcome *how = outcomes;
    size_t ended = 0;
    for (size_t i = 0; i < count; ++i)
      if (views[i].phase == WAITING && update_task(o, job, &views[i], i, todo[i], ok, &how[i]))
        views[i].phase = ENDED, ended_now[ended++] = i;
    p.running = p.pending = 0;
    for (size_t i = 0; i < count; ++i)
      if (views[i].phase == WAITING)
        strcmp(views[i].state, "PENDING") == 0 ? p.pending++ : p.running++;
    for (size_t k = 0; k < ended; ++k)
      how[ended_now[k]] == CF_BATCH_TASK_FITTED ? p.done++ : p.failed++;
    for (size_t k = 0; k < ended && o->progress; ++k) /* a line each, the counts as of now */
      o->progress(o->progress_user, &p, ended_now[k], how[ended_now[k]]);
    if (p.done + p.failed < count) sleep_seconds(RESULT_POLL_S);
  }
  if (s != CF_OK) /* no task may run on while the caller cleans up */
    cancel(job, views, count);
  if (s == CF_OK && *o->interrupted) {
    cancel(job, views, count);
    s = cf_error_set(err, CF_EIO, "interrupted: Slurm job %s cancelled; %zu tasks not finished",
                     job->id, count - p.done - p.failed);
  }
  free(errors.p);
  free(views), free(outcomes), free(ended_now);
  return s;
}
