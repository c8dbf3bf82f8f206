/* clayfit batch: many captures fitted into a material library
 * (docs/batch.md). A manifest (data_schema/manifest.schema.json) lists the
 * captures; each is one task (fit, every preset, the report) whose results
 * go to LIBRARY/<name>/, written in a temporary folder and renamed into
 * place. Each entry is keyed by a hash of its inputs, its options and
 * clayfit's build, so that a re-run fits only what is missing or stale. */
#ifndef CLAYFIT_BATCH_H
#define CLAYFIT_BATCH_H

#include <stddef.h>
#include <sys/types.h>

#include "clayfit/fit.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

struct json_t; /* Jansson's */

/* Caps on what a manifest may hold (it is untrusted input). */
#define CF_BATCH_MANIFEST_MAX_SIZE ((size_t)16 << 20)
enum {
  CF_BATCH_MAX_ENTRIES = 100000,
  CF_BATCH_NAME_MAX = 64,  /* [A-Za-z0-9._-]{1,64}, not starting with '.' */
  CF_BATCH_MAX_HOLDS = 32, /* per entry */
  CF_BATCH_MAX_TAGS = 64,  /* per entry */
  CF_BATCH_TAG_MAX = 256   /* bytes of a tag's key or value */
};

typedef struct cf_batch_entry {
  char name[CF_BATCH_NAME_MAX + 1];
  char *capture;     /* the capture file: as given, joined to the manifest's folder */
  const char *model; /* "auto" or a model's code or name (checked) */
  int hold_count;
  cf_fit_hold hold[CF_BATCH_MAX_HOLDS]; /* names point into the manifest's document */
  size_t budget;                        /* observations; 0: all */
  int budget_given;                     /* 0: clayfit fit's default */
  int fit_exposures;
  const struct json_t *options; /* the entry's "options" object, or NULL */
  const struct json_t *tags;    /* its "tags" (an object of strings), or NULL */
} cf_batch_entry;

typedef struct cf_batch_manifest {
  char *path;
  size_t count;
  cf_batch_entry *entries;
  struct json_t *document; /* owned */
} cf_batch_manifest;

/* Read and check a manifest: every record, with errors naming the file and
 * the JSON path (CF_EPARSE, CF_EINVAL: bad input; CF_ENOTFOUND: a capture
 * file that does not exist; CF_ENOMEM). */
cf_status cf_batch_manifest_read(const char *path, cf_batch_manifest *manifest, cf_error *err);
void cf_batch_manifest_free(cf_batch_manifest *manifest);

/* 1 if name is an entry name: [A-Za-z0-9._-]{1,64}, not starting with '.'. */
int cf_batch_name_valid(const char *name);

/* Each model's fit options for an entry, as `clayfit fit` builds them from
 * the same options (--model, --hold, --budget, --fit-exposures, --threads):
 * *automatic is 1 for "auto" (ladder[] all filled), else *model is the
 * forced one (ladder[*model] filled). A hold applies, with auto, to every
 * model that has the parameter and must name one that some model has. */
cf_status cf_batch_fit_options(const cf_batch_entry *entry, int threads, int *automatic,
                               cf_model_id *model, cf_fit_options ladder[CF_MODEL_COUNT],
                               cf_error *err);

/* clayfit's build id: git describe plus the version, and a hash of the
 * source tree when it differs from the commit (computed at each build). */
const char *cf_batch_build_id(void);

/* ---- the key ---- */

enum { CF_BATCH_KEY_SIZE = 33 }; /* 32 hex digits of XXH3-128 and a NUL */

/* The entry's key: a hash of every file its capture reads (their contents;
 * a file that cannot be read counts as missing), its options and the build
 * id. XXH3-128, not cryptographic: it detects change, not tampering. */
cf_status cf_batch_entry_key(const cf_batch_entry *entry, char key[CF_BATCH_KEY_SIZE],
                             cf_error *err);

/* ---- the library folder ---- */

typedef enum cf_batch_state {
  CF_BATCH_MISSING, /* no entry (never fitted, or its task died) */
  CF_BATCH_FITTED,  /* entry.json */
  CF_BATCH_FAILED   /* failed.json */
} cf_batch_state;

/* The state of LIBRARY/<name> and the key it was made with ("" if none). */
cf_batch_state cf_batch_entry_state(const char *library, const char *name,
                                    char key[CF_BATCH_KEY_SIZE]);

/* Take LIBRARY/.lock (created atomically with its owner: host, pid, the
 * pid's start time). A lock whose owner is on this host and gone is stale:
 * taken over, and *taken_over says so. Another live owner: CF_EIO with a
 * message naming it. */
cf_status cf_batch_lock(const char *library, int *taken_over, cf_error *err);
void cf_batch_unlock(const char *library);

/* Remove what dead tasks left: LIBRARY/.tmp.<name>.<pid> folders, and
 * LIBRARY/.old.<name>.<pid> (moved back into place when the entry is
 * missing, so that a kill between the two renames of a replacement loses
 * nothing). Only names of exactly that pattern. Call with the lock held and
 * no task running. Returns how many were removed or restored. */
int cf_batch_clean(const char *library);

/* Write LIBRARY/library.json (data_schema/library.schema.json) for the
 * manifest's entries, atomically, then LIBRARY/index.html, the gallery of
 * the same records. */
cf_status cf_batch_library_write(const char *library, const cf_batch_manifest *manifest,
                                 cf_error *err);

/* The reason recorded in LIBRARY/<name>/failed.json ("" if none). */
void cf_batch_failed_reason(const char *library, const char *name, char *out, size_t size);

/* ---- one task ---- */

typedef struct cf_batch_task_options {
  int threads;               /* solver threads */
  const char *viewer_bundle; /* the report's three.js bundle
                                (cf_report_options.viewer_bundle); NULL: none */
} cf_batch_task_options;

/* Whose fault a task's failure is. */
typedef enum cf_batch_fault {
  CF_BATCH_FAULT_NONE,  /* the task succeeded */
  CF_BATCH_FAULT_INPUT, /* the capture's (what clayfit fit, export or report
                           refuse with exit 2): failed.json replaces the entry */
  CF_BATCH_FAULT_RUN    /* a failure while running (out of memory, disk full,
                           I/O): an earlier fitted entry is kept, else
                           failed.json with "retry": true */
} cf_batch_fault;

/* Run entry `index` in this process: load the capture, fit, write fit.json,
 * every preset and the report, and entry.json, into
 * LIBRARY/.tmp.<name>.<pid>, then replace LIBRARY/<name> with it. When a
 * step fails, the step's status is returned, err saying why, and *fault
 * whose fault it is: the capture's makes LIBRARY/<name> a folder holding
 * failed.json (the reason and the log); a failure while running keeps a
 * fitted LIBRARY/<name> as it was (err says so), else leaves failed.json
 * with "retry": true, which the next run fits again. CF_EIO (a failure
 * while running) when the library itself could not be written (the entry
 * is then as it was). */
cf_status cf_batch_task_run(const cf_batch_manifest *manifest, size_t index, const char *library,
                            const cf_batch_task_options *options, cf_batch_fault *fault,
                            cf_error *err);

/* 1 if LIBRARY/<name>/failed.json says its task ended without a result
 * for a reason that is not the capture's ("retry": true: a failure while
 * running, or a Slurm task cancelled, timed out or killed): the next run
 * fits it again although its key is the same. */
int cf_batch_failed_retry(const char *library, const char *name);

/* ---- the executors ---- */

typedef struct cf_batch_progress {
  size_t done, running, failed, pending;
} cf_batch_progress;

/* How a task ended. */
typedef enum cf_batch_outcome {
  CF_BATCH_TASK_FITTED, /* exited 0: its entry is fitted */
  CF_BATCH_TASK_FAILED, /* failed.json written by the task */
  CF_BATCH_TASK_KILLED  /* died without a result (signal, scancel, time limit) */
} cf_batch_outcome;

/* Called as each task ends: finished indexes todo[]. */
typedef void (*cf_batch_progress_fn)(void *user, const cf_batch_progress *progress, size_t finished,
                                     cf_batch_outcome outcome);

typedef struct cf_batch_local_options {
  const char *exe;      /* the clayfit executable (/proc/self/exe) */
  const char *manifest; /* as given on the command line */
  const char *library;
  int jobs, threads;
  cf_batch_progress_fn progress; /* may be NULL */
  void *progress_user;
  volatile int *interrupted; /* set by a signal handler: kill the workers */
} cf_batch_local_options;

/* Run the tasks todo[0..count) (manifest indices), at most jobs at a
 * time, each as `exe --quiet batch MANIFEST -o LIBRARY --task I --threads
 * T` (stdout to /dev/null). ok[i] (for todo[i]) is 1 when the task exited
 * 0. CF_OK when every task ran (fitted or not); CF_EIO when a worker could
 * not start or *interrupted was set (every worker is then killed). */
cf_status cf_batch_run_local(const cf_batch_local_options *options, const size_t *todo,
                             size_t count, int *ok, cf_error *err);

/* ---- the Slurm executor (docs/batch.md) ---- */

typedef struct cf_batch_slurm_options {
  const char *exe;      /* the clayfit executable, absolute (the nodes run it) */
  const char *manifest; /* absolute */
  const char *library;  /* absolute: the shared file system */
  const cf_batch_manifest *entries;
  int threads; /* solver threads per task; 0: $SLURM_CPUS_PER_TASK */
  int cpus_per_task, max_running;
  const char *partition, *time, *mem; /* NULL: the cluster's default */
  char *const *sbatch_args;           /* passed verbatim, each one argument */
  int sbatch_arg_count;
  cf_batch_progress_fn progress; /* may be NULL */
  void *progress_user;
  volatile int *interrupted; /* set by a signal handler: scancel the job */
} cf_batch_slurm_options;

/* The job of one run: its script and the sbatch command that submits it. */
typedef struct cf_batch_slurm_job {
  char script[4096]; /* LIBRARY/.slurm/job-<UTC time>.sh */
  char **argv;       /* sbatch's, NULL-terminated */
  int argc;
  char id[64];                /* the job id once submitted */
  unsigned long long *before; /* per task: LIBRARY/<name>'s inode before, 0 if none */
} cf_batch_slurm_job;

/* Write the job script of the tasks todo[0..count) (manifest indices:
 * array index i runs entry todo[i]) into LIBRARY/.slurm/ and build the
 * sbatch command. count > 0. */
cf_status cf_batch_slurm_prepare(const cf_batch_slurm_options *options, const size_t *todo,
                                 size_t count, cf_batch_slurm_job *job, cf_error *err);
void cf_batch_slurm_job_free(cf_batch_slurm_job *job);

/* The command, each word shell-quoted, into out (truncated to size). */
void cf_batch_slurm_command(const cf_batch_slurm_job *job, char *out, size_t size);

/* Run sbatch (posix_spawnp, no shell): job->id set. CF_EIO with sbatch's
 * stderr when it fails or cannot run. */
cf_status cf_batch_slurm_submit(cf_batch_slurm_job *job, cf_error *err);

/* Wait for the submitted job: squeue for pending and running, each entry's
 * own result (a new LIBRARY/<name>) for done and failed. A task that
 * squeue no longer lists as pending or running and that left no result
 * died: LIBRARY/<name>/failed.json records why (unless an earlier entry
 * is there, which is kept). ok[i] (for todo[i]) is 1 when fitted. CF_EIO
 * when squeue keeps failing or *interrupted was set (the job is then
 * cancelled and its tasks waited for). */
cf_status cf_batch_slurm_wait(const cf_batch_slurm_options *options, const cf_batch_slurm_job *job,
                              const size_t *todo, size_t count, int *ok, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_BATCH_H */
