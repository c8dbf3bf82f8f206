/* clayfit batch: the captures of a manifest fitted into a material library
 * (docs/batch.md), only those missing, failed for other inputs, or stale. */
#define _DEFAULT_SOURCE /* sigaction's SA_ flags, realpath */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "args.h"
#include "clayfit/batch.h"
#include "cli.h"
#include "core/file.h"
#include "out_path.h"

static void batch_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit batch MANIFEST -o LIBRARY [--executor local|slurm] [--jobs N]\n"
          "                     [--threads T] [--force] [Slurm options]\n\n"
          "Fits every capture of MANIFEST (data_schema/manifest.schema.json) into\n"
          "LIBRARY/<name>/: fit.json, every preset (presets/), the report (report/) and\n"
          "entry.json; a failed capture leaves LIBRARY/<name>/failed.json and the others\n"
          "go on. LIBRARY/library.json lists the entries (data_schema/library.schema.json).\n"
          "Each entry is keyed by a hash of the files its capture reads, its options and\n"
          "clayfit's build: a run fits only the entries missing or whose key changed\n"
          "(docs/batch.md).\n\n"
          "  --executor local  (default) a pool of worker processes on this machine\n"
          "  --executor slurm  one Slurm job array (sbatch), waited for; the job script\n"
          "                    and the task logs go to LIBRARY/.slurm/\n"
          "  --jobs N          tasks at a time (default 1)\n"
          "  --threads T       solver threads per task (default: the CPUs / N, at least 1)\n"
          "  --force           re-fit every entry\n"
          "Slurm options (with --executor slurm):\n"
          "  --partition P, --time T, --mem M   sbatch's, passed on (default: the cluster's)\n"
          "  --cpus-per-task C  (default: --threads, else 1); without --threads each task\n"
          "                    runs C solver threads\n"
          "  --max-running K   array elements at a time (the array's %%K; default --jobs,\n"
          "                    else 16)\n"
          "  --sbatch-arg ARG  one more sbatch argument, verbatim (repeatable)\n"
          "  --dry-run         write and print the job script and the sbatch command,\n"
          "                    submit nothing\n"
          "  --task I          (internal) run entry I only, in this process: what each\n"
          "                    worker runs; the caller holds the library's lock; exit 2\n"
          "                    when the capture failed it, 1 for a failure while running\n\n"
          "exit status: 0 every entry fitted, 1 some failed (named on stderr) or the\n"
          "library is locked by another batch, 2 invalid command line (-o not a folder\n"
          "that can be written) or manifest\n");
}

typedef struct batch_command {
  const char *manifest, *library, *executor;
  long jobs, threads, task;
  int force, slurm, jobs_given, threads_given, dry_run, slurm_options;
  const char *partition, *time, *mem; /* Slurm's; NULL: the cluster's default */
  long cpus_per_task, max_running;    /* 0: from --threads, --jobs */
  char **sbatch_args;                 /* into argv */
  int sbatch_arg_count;
} batch_command;

enum {
  OPT_PARTITION = 256,
  OPT_TIME,
  OPT_MEM,
  OPT_CPUS,
  OPT_MAX_RUNNING,
  OPT_SBATCH_ARG,
  OPT_DRY_RUN
};

static const struct option batch_options[] = {
    {"output", required_argument, NULL, 'o'},
    {"executor", required_argument, NULL, 'e'},
    {"jobs", required_argument, NULL, 'j'},
    {"threads", required_argument, NULL, 't'},
    {"force", no_argument, NULL, 'f'},
    {"task", required_argument, NULL, 'T'},
    {"partition", required_argument, NULL, OPT_PARTITION},
    {"time", required_argument, NULL, OPT_TIME},
    {"mem", required_argument, NULL, OPT_MEM},
    {"cpus-per-task", required_argument, NULL, OPT_CPUS},
    {"max-running", required_argument, NULL, OPT_MAX_RUNNING},
    {"sbatch-arg", required_argument, NULL, OPT_SBATCH_ARG},
    {"dry-run", no_argument, NULL, OPT_DRY_RUN},
    {"help", no_argument, NULL, 'h'},
    {0}};

/* The options only the Slurm executor takes. */
static cf_status parse_slurm_option(int c, batch_command *cmd, cf_error *err) {
  cmd->slurm_options = 1;
  if (c == OPT_PARTITION) cmd->partition = optarg;
  if (c == OPT_TIME) cmd->time = optarg;
  if (c == OPT_MEM) cmd->mem = optarg;
  if (c == OPT_DRY_RUN) cmd->dry_run = 1;
  if (c == OPT_SBATCH_ARG) cmd->sbatch_args[cmd->sbatch_arg_count++] = optarg;
  if ((c == OPT_PARTITION || c == OPT_TIME || c == OPT_MEM) && optarg[0] == '\0')
    return cf_error_set(err, CF_EINVAL, "an empty Slurm option value");
  if (c == OPT_CPUS)
    return cli_parse_count(optarg, "--cpus-per-task", 1, 4096, &cmd->cpus_per_task, err);
  if (c == OPT_MAX_RUNNING)
    return cli_parse_count(optarg, "--max-running", 1, 100000, &cmd->max_running, err);
  return CF_OK;
}

/* The executor and what it needs: the defaults of threads, CPUs per task
 * and the array's throttle. */
static cf_status check_executor(batch_command *cmd, cf_error *err) {
  cmd->slurm = strcmp(cmd->executor, "slurm") == 0;
  if (!cmd->slurm && strcmp(cmd->executor, "local") != 0)
    return cf_error_set(err, CF_EINVAL, "--executor: '%s' is neither local nor slurm",
                        cmd->executor);
  if (!cmd->slurm && cmd->slurm_options)
    return cf_error_set(err, CF_EINVAL, "a Slurm option without --executor slurm");
  if (cmd->slurm && strchr(cmd->library, '\\'))
    return cf_error_set(err, CF_EINVAL,
                        "--executor slurm: the library's path holds a "
                        "backslash, which turns off sbatch's %%A_%%a log names");
  if (!cmd->slurm) return CF_OK;
  if (cmd->cpus_per_task == 0) cmd->cpus_per_task = cmd->threads_given ? cmd->threads : 1;
  if (cmd->max_running == 0) cmd->max_running = cmd->jobs_given ? cmd->jobs : 16;
  if (!cmd->threads_given) cmd->threads = cmd->cpus_per_task;
  return CF_OK;
}

/* Returns -1 to go on, else the exit status. */
static int parse_command(int argc, char **argv, batch_command *cmd) {
  *cmd = (batch_command){0};
  cmd->executor = "local", cmd->jobs = 1, cmd->task = -1;
  cmd->sbatch_args = calloc((size_t)argc, sizeof *cmd->sbatch_args);
  if (!cmd->sbatch_args) return CLI_EXIT_FAILURE;
  cf_error err = {0};
  cf_status s = CF_OK;
  optind = 1;
  opterr = 0;
  for (int c; s == CF_OK && (c = getopt_long(argc, argv, "o:j:", batch_options, NULL)) != -1;) {
    if (c == 'o')
      cmd->library = optarg;
    else if (c == 'e')
      cmd->executor = optarg;
    else if (c == 'j')
      s = cli_parse_count(optarg, "--jobs", 1, 1024, &cmd->jobs, &err), cmd->jobs_given = 1;
    else if (c == 't')
      s = cli_parse_count(optarg, "--threads", 1, 256, &cmd->threads, &err), cmd->threads_given = 1;
    else if (c >= OPT_PARTITION && c <= OPT_DRY_RUN)
      s = parse_slurm_option(c, cmd, &err);
    else if (c == 'T')
      s = cli_parse_count(optarg, "--task", 0, CF_BATCH_MAX_ENTRIES - 1, &cmd->task, &err);
    else if (c == 'f')
      cmd->force = 1;
    else if (c == 'h') {
      batch_usage(stdout);
      return CLI_EXIT_OK;
    } else
      return cli_bad_option("batch", argv);
  }
  if (s == CF_OK && optind + 1 != argc)
    s = cf_error_set(&err, CF_EINVAL, "expected one manifest (see clayfit batch --help)");
  if (s == CF_OK && !cmd->library) s = cf_error_set(&err, CF_EINVAL, "-o LIBRARY is required");
  if (s == CF_OK) s = check_executor(cmd, &err);
  if (s == CF_OK && cmd->task < 0) s = cli_check_output("-o", cmd->library, CLI_OUT_FOLDER, &err);
  if (s != CF_OK) {
    cli_report("batch", err.message);
    return CLI_EXIT_USAGE;
  }
  cmd->manifest = argv[optind];
  if (cmd->threads == 0 && !cmd->slurm) {
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    cmd->threads = cpus / cmd->jobs > 1 ? cpus / cmd->jobs : 1;
  }
  return -1;
}

/* --task I: one entry in this process. */
static int run_task(const batch_command *cmd, const cf_batch_manifest *m, const cli_context *ctx) {
  cf_error err = {0};
  char bundle[4096];
  cli_viewer_bundle(bundle, sizeof bundle);
  cf_batch_task_options options = {(int)cmd->threads, bundle};
  if (cmd->task >= (long)m->count) {
    fprintf(stderr, "clayfit batch: --task %ld: the manifest has %zu captures\n", cmd->task,
            m->count);
    return CLI_EXIT_USAGE;
  }
  cf_batch_fault fault;
  cf_status s = cf_batch_task_run(m, (size_t)cmd->task, cmd->library, &options, &fault, &err);
  if (s == CF_OK) return CLI_EXIT_OK;
  if (!ctx->quiet || fault != CF_BATCH_FAULT_INPUT) /* else it is in failed.json */
    fprintf(stderr, "clayfit batch: %s: %s\n", m->entries[cmd->task].name, err.message);
  return fault == CF_BATCH_FAULT_INPUT ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE;
}

/* The entries to fit: missing, failed with another key or to be retried,
 * stale; all with --force. keys[i] is entry i's key. */
static size_t plan(const batch_command *cmd, const cf_batch_manifest *m, const char *keys,
                   size_t *todo, size_t *up_to_date) {
  size_t count = 0;
  *up_to_date = 0;
  for (size_t i = 0; i < m->count; ++i) {
    char have[CF_BATCH_KEY_SIZE];
    cf_batch_state state = cf_batch_entry_state(cmd->library, m->entries[i].name, have);
    int retry = state == CF_BATCH_FAILED && cf_batch_failed_retry(cmd->library, m->entries[i].name);
    if (!cmd->force && state != CF_BATCH_MISSING && !retry &&
        strcmp(keys + i * CF_BATCH_KEY_SIZE, have) == 0)
      (*up_to_date)++;
    else
      todo[count++] = i;
  }
  return count;
}

typedef struct progress_context {
  const cf_batch_manifest *manifest;
  const size_t *todo;
  int quiet;
} progress_context;

static void progress_line(void *user, const cf_batch_progress *p, size_t finished,
                          cf_batch_outcome outcome) {
  const progress_context *c = user;
  if (c->quiet) return;
  const char *name = c->manifest->entries[c->todo[finished]].name;
  const char *how = outcome == CF_BATCH_TASK_FITTED   ? "fitted"
                    : outcome == CF_BATCH_TASK_KILLED ? "killed"
                                                      : "failed";
  fprintf(stderr, "clayfit batch: %s %s; %zu done, %zu running, %zu failed, %zu pending\n", name,
          how, p->done, p->running, p->failed, p->pending);
  fflush(stderr);
}

static volatile int interrupted;
static void on_signal(int signal) {
  (void)signal;
  interrupted = 1;
}

/* SIGINT and SIGTERM set the flag, without restarting waitpid. */
static void catch_signals(void) {
  struct sigaction action;
  memset(&action, 0, sizeof action);
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, NULL);
  sigaction(SIGTERM, &action, NULL);
}

/* Every entry of the manifest that is not fitted, named with its reason
 * (this run's failures, and the failures of earlier runs whose inputs did
 * not change); how many. */
static size_t report_failures(const batch_command *cmd, const cf_batch_manifest *m,
                              const int *ran_bad) {
  size_t failed = 0;
  for (size_t i = 0; i < m->count; ++i) {
    char key[CF_BATCH_KEY_SIZE], reason[1024];
    cf_batch_state state = cf_batch_entry_state(cmd->library, m->entries[i].name, key);
    if (state == CF_BATCH_FITTED && ran_bad[i]) {
      failed++;
      fprintf(stderr,
              "clayfit batch: failed: %s: its task failed while running (its message above) "
              "or died (killed, or crashed); the earlier entry is kept, and re-fitted by the "
              "next run if its inputs changed\n",
              m->entries[i].name);
    }
    if (state == CF_BATCH_FITTED) continue;
    failed++;
    cf_batch_failed_reason(cmd->library, m->entries[i].name, reason, sizeof reason);
    fprintf(stderr, "clayfit batch: failed: %s: %s\n", m->entries[i].name,
            state == CF_BATCH_FAILED
                ? reason
                : "no entry: its task died (killed, or crashed) or did not run");
  }
  return failed;
}

/* realpath into out (size PATH_MAX). */
static cf_status absolute(const char *path, char *out, cf_error *err) {
  if (!realpath(path, out)) return cf_error_set(err, CF_EIO, "%s: %s", path, strerror(errno));
  return CF_OK;
}

/* The tasks as one Slurm job array, waited for; with --dry-run only its
 * script and sbatch command, printed. Absolute paths: the nodes run them
 * from the library folder. */
static cf_status run_slurm(const batch_command *cmd, const cf_batch_manifest *m, const size_t *todo,
                           size_t count, int *ok, progress_context *context, cf_error *err) {
  char exe[PATH_MAX], manifest[PATH_MAX], library[PATH_MAX];
  cf_status s = absolute("/proc/self/exe", exe, err);
  if (s == CF_OK) s = absolute(cmd->manifest, manifest, err);
  if (s == CF_OK) s = absolute(cmd->library, library, err);
  if (s != CF_OK) return s;
  cf_batch_slurm_options o = {exe,
                              manifest,
                              library,
                              m,
                              cmd->threads_given ? (int)cmd->threads : 0,
                              (int)cmd->cpus_per_task,
                              (int)cmd->max_running,
                              cmd->partition,
                              cmd->time,
                              cmd->mem,
                              cmd->sbatch_args,
                              cmd->sbatch_arg_count,
                              progress_line,
                              context,
                              &interrupted};
  cf_batch_slurm_job job;
  s = cf_batch_slurm_prepare(&o, todo, count, &job, err);
  if (s != CF_OK) return s;
  static char command[1 << 16];
  cf_batch_slurm_command(&job, command, sizeof command);
  if (cmd->dry_run) {
    char *script = NULL;
    size_t size = 0;
    s = cf_read_file(job.script, (size_t)1 << 26, &script, &size, err);
    if (s == CF_OK) printf("# %s\n%s\n# submit with:\n%s\n", job.script, script, command);
    free(script);
  }
  if (s == CF_OK && !cmd->dry_run) s = cf_batch_slurm_submit(&job, err);
  if (s == CF_OK && !cmd->dry_run) {
    printf("submitted Slurm job %s: %zu tasks, at most %ld at a time; logs in %s/.slurm/logs\n",
           job.id, count, cmd->max_running, library);
    fflush(stdout);
    s = cf_batch_slurm_wait(&o, &job, todo, count, ok, err);
  }
  cf_batch_slurm_job_free(&job);
  return s;
}

static void print_plan(const batch_command *cmd, size_t entries, size_t up_to_date, size_t count) {
  printf("%zu entries: %zu up to date, %zu to fit ", entries, up_to_date, count);
  if (cmd->slurm)
    printf("(Slurm, at most %ld at a time, %ld CPUs and %ld threads each)\n", cmd->max_running,
           cmd->cpus_per_task, cmd->threads);
  else
    printf("(%ld jobs, %ld threads each)\n", cmd->jobs, cmd->threads);
  fflush(stdout);
}

/* Every entry's key, m->count of CF_BATCH_KEY_SIZE bytes, before the lock
 * is taken: reading the captures' files (a file that is not a regular one
 * is not read: cf_batch_entry_key) is the slow part of planning, and
 * SIGINT or SIGTERM while it runs must not leave the lock behind. NULL when
 * interrupted or out of memory, err saying which. */
static char *key_all(const cf_batch_manifest *m, cf_error *err) {
  char *keys = calloc(m->count ? m->count : 1, CF_BATCH_KEY_SIZE);
  if (!keys) return cf_error_set(err, CF_ENOMEM, "out of memory"), NULL;
  for (size_t i = 0; i < m->count; ++i) {
    if (interrupted) {
      cf_error_set(err, CF_EIO, "interrupted while reading the captures, before any task");
      free(keys);
      return NULL;
    }
    if (cf_batch_entry_key(&m->entries[i], keys + i * CF_BATCH_KEY_SIZE, err) != CF_OK) {
      free(keys);
      return NULL;
    }
  }
  return keys;
}

/* Under the lock: plan, run, library.json. */
static int run_locked(const batch_command *cmd, const cf_batch_manifest *m, const char *keys,
                      const cli_context *ctx) {
  cf_error err = {0};
  int cleaned = cf_batch_clean(cmd->library);
  if (cleaned && !ctx->quiet)
    fprintf(stderr, "clayfit batch: cleaned %d leftover%s of interrupted tasks\n", cleaned,
            cleaned == 1 ? "" : "s");
  size_t *todo = calloc(m->count, sizeof *todo);
  int *ok = calloc(m->count, sizeof *ok);
  size_t up_to_date = 0, count = todo && ok ? plan(cmd, m, keys, todo, &up_to_date) : 0;
  cf_status s = !todo || !ok  ? cf_error_set(&err, CF_ENOMEM, "out of memory")
                : interrupted ? cf_error_set(&err, CF_EIO, "interrupted before any task")
                              : CF_OK;
  progress_context context = {m, todo, ctx->quiet};
  if (s == CF_OK) print_plan(cmd, m->count, up_to_date, count);
  if (s == CF_OK && cmd->dry_run) { /* nothing run, nothing written but the script */
    s = count ? run_slurm(cmd, m, todo, count, ok, &context, &err) : CF_OK;
    if (s == CF_OK && !count) printf("nothing to submit\n");
    if (s != CF_OK) cli_report("batch", err.message);
    free(todo);
    free(ok);
    return s == CF_OK ? CLI_EXIT_OK : CLI_EXIT_FAILURE;
  }
  if (s == CF_OK) {
    cf_batch_local_options options = {"/proc/self/exe", cmd->manifest,     cmd->library,
                                      (int)cmd->jobs,   (int)cmd->threads, progress_line,
                                      &context,         &interrupted};
    if (cmd->slurm)
      s = count ? run_slurm(cmd, m, todo, count, ok, &context, &err) : CF_OK;
    else
      s = cf_batch_run_local(&options, todo, count, ok, &err);
    if (s != CF_OK) cf_batch_clean(cmd->library); /* the killed tasks' folders */
  }
  size_t failed = 0, ran_ok = 0;
  int *ran_bad = s == CF_OK ? calloc(m->count, sizeof *ran_bad) : NULL;
  if (s == CF_OK && !ran_bad) s = cf_error_set(&err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; s == CF_OK && i < count; ++i) {
    ran_ok += ok[i] != 0;
    ran_bad[todo[i]] = !ok[i];
  }
  if (s == CF_OK) cf_batch_clean(cmd->library); /* what died tasks left */
  if (s == CF_OK) failed = report_failures(cmd, m, ran_bad);
  free(ran_bad);
  cf_error write_err = {0};
  cf_status written = cf_batch_library_write(cmd->library, m, &write_err);
  if (written != CF_OK) cli_report("batch", write_err.message);
  if (s != CF_OK) cli_report("batch", err.message);
  if (s == CF_OK)
    printf("fitted %zu of %zu; %zu of the %zu entries failed\n", ran_ok, count, failed, m->count);
  free(todo);
  free(ok);
  return s == CF_OK && written == CF_OK && failed == 0 ? CLI_EXIT_OK : CLI_EXIT_FAILURE;
}

static int batch_main(batch_command *command, int argc, char **argv, cli_context *ctx) {
  batch_command cmd;
  int exit_status = parse_command(argc, argv, &cmd);
  *command = cmd;
  if (exit_status >= 0) return exit_status;
  cf_batch_manifest m;
  cf_error err = {0};
  cf_status s = cf_batch_manifest_read(cmd.manifest, &m, &err);
  if (s != CF_OK) {
    cli_report("batch", err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  if (cmd.task >= 0) {
    exit_status = run_task(&cmd, &m, ctx);
    cf_batch_manifest_free(&m);
    return exit_status;
  }
  catch_signals(); /* from here on SIGINT and SIGTERM end the batch in order */
  int taken_over = 0;
  char *keys = key_all(&m, &err);
  s = keys ? cf_make_dirs(cmd.library, &err) : CF_EIO;
  if (s == CF_OK) s = cf_batch_lock(cmd.library, &taken_over, &err);
  if (s != CF_OK) {
    cli_report("batch", err.message);
    cf_batch_manifest_free(&m);
    free(keys);
    return CLI_EXIT_FAILURE;
  }
  if (taken_over && !ctx->quiet)
    fprintf(stderr, "clayfit batch: took over the stale lock of a batch that is gone\n");
  exit_status = run_locked(&cmd, &m, keys, ctx);
  cf_batch_unlock(cmd.library);
  cf_batch_manifest_free(&m);
  free(keys);
  return exit_status;
}

int cmd_batch(int argc, char **argv, cli_context *ctx) {
  batch_command cmd = {0};
  int exit_status = batch_main(&cmd, argc, argv, ctx);
  free(cmd.sbatch_args);
  return exit_status;
}
