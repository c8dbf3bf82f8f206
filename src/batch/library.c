/* The library folder: entries and their state, the atomic replacement of
 * an entry, the lock, the clean-up of what dead tasks left, library.json. */
#define _XOPEN_SOURCE 700 /* nftw */
#define _DEFAULT_SOURCE   /* gethostname */
#include <dirent.h>
#include <errno.h>
#include <ftw.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "batch_internal.h"
#include "clayfit/fit_file.h"
#include "core/file.h"
#include "core/json_reader.h"

/* An entry.json, failed.json or lock owner is small; more is not ours. */
enum { SMALL_JSON_MAX = 1 << 20 };

const char *batch_preset_file(cf_export_format format) {
  static const char *const files[CF_EXPORT_FORMAT_COUNT] = {
      [CF_EXPORT_JSON] = "preset.json",
      [CF_EXPORT_MTLX] = "material.mtlx",
      [CF_EXPORT_MTLX_OPENPBR] = "material.openpbr.mtlx",
      [CF_EXPORT_GLTF] = "material.gltf",
      [CF_EXPORT_BLENDER] = "material.py",
      [CF_EXPORT_MITSUBA] = "material.xml",
      [CF_EXPORT_GLSL] = "material.three.js",
      [CF_EXPORT_UNITY] = "unity"};
  return files[format];
}

json_t *batch_object_or_empty(const json_t *object) {
  return object ? json_incref((json_t *)object) : json_object();
}

void batch_host_name(char *out, size_t size) {
  if (gethostname(out, size) != 0) out[0] = '\0';
  out[size - 1] = '\0';
}

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag, (void)ftw;
  return remove(path) == 0 || errno == ENOENT ? 0 : -1;
}

int batch_remove_tree(const char *path) {
  struct stat st;
  if (lstat(path, &st) != 0) return errno == ENOENT ? 0 : -1;
  return nftw(path, remove_one, 16, FTW_DEPTH | FTW_PHYS);
}

cf_status batch_tmp_path(const char *library, const char *name, pid_t pid, char *out, size_t size,
                         cf_error *err) {
  int n = snprintf(out, size, "%s/.tmp.%s.%ld", library, name, (long)pid);
  if (n < 0 || (size_t)n >= size) return cf_error_set(err, CF_ERANGE, "%s: path too long", library);
  return CF_OK;
}

cf_status batch_replace_entry(const char *library, const char *name, const char *tmp,
                              cf_error *err) {
  char entry[4096], old[4096];
  int n = snprintf(entry, sizeof entry, "%s/%s", library, name);
  int m = snprintf(old, sizeof old, "%s/.old.%s.%ld", library, name, (long)getpid());
  if (n < 0 || m < 0 || (size_t)n >= sizeof entry || (size_t)m >= sizeof old)
    return cf_error_set(err, CF_ERANGE, "%s: path too long", library);
  int had_old = rename(entry, old) == 0;
  if (!had_old && errno != ENOENT)
    return cf_error_set(err, CF_EIO, "%s: cannot move it aside: %s", entry, strerror(errno));
  if (rename(tmp, entry) != 0) {
    int e = errno;
    if (had_old) rename(old, entry);
    return cf_error_set(err, CF_EIO, "%s: cannot move %s into place: %s", entry, tmp, strerror(e));
  }
  if (had_old && batch_remove_tree(old) != 0)
    return cf_error_set(err, CF_EIO, "%s: cannot delete it: %s", old, strerror(errno));
  return CF_OK;
}

/* ---- an entry's state ---- */

/* The "key" of LIBRARY/<name>/<file>, 1 if it has one. */
static int read_key(const char *library, const char *name, const char *file,
                    char key[CF_BATCH_KEY_SIZE]) {
  char path[4096];
  if (snprintf(path, sizeof path, "%s/%s/%s", library, name, file) >= (int)sizeof path) return 0;
  if (!cf_path_exists(path)) return 0;
  json_t *root = NULL;
  cf_error ignored = {0};
  if (json_load_object(path, SMALL_JSON_MAX, &root, &ignored) != CF_OK) return 0;
  const char *text = json_string_value(json_object_get(root, "key"));
  int ok = text && strlen(text) == CF_BATCH_KEY_SIZE - 1;
  if (ok) strcpy(key, text);
  json_decref(root);
  return ok;
}

cf_batch_state cf_batch_entry_state(const char *library, const char *name,
                                    char key[CF_BATCH_KEY_SIZE]) {
  key[0] = '\0';
  if (read_key(library, name, "entry.json", key)) return CF_BATCH_FITTED;
  if (read_key(library, name, "failed.json", key)) return CF_BATCH_FAILED;
  return CF_BATCH_MISSING;
}

void cf_batch_failed_reason(const char *library, const char *name, char *out, size_t size) {
  char path[4096];
  out[0] = '\0';
  if (snprintf(path, sizeof path, "%s/%s/failed.json", library, name) >= (int)sizeof path) return;
  json_t *root = NULL;
  cf_error ignored = {0};
  if (json_load_object(path, SMALL_JSON_MAX, &root, &ignored) != CF_OK) return;
  const char *reason = json_string_value(json_object_get(root, "reason"));
  snprintf(out, size, "%s", reason ? reason : "");
  json_decref(root);
}

int cf_batch_failed_retry(const char *library, const char *name) {
  char path[4096];
  if (snprintf(path, sizeof path, "%s/%s/failed.json", library, name) >= (int)sizeof path) return 0;
  if (!cf_path_exists(path)) return 0;
  json_t *root = NULL;
  cf_error ignored = {0};
  if (json_load_object(path, SMALL_JSON_MAX, &root, &ignored) != CF_OK) return 0;
  int retry = json_is_true(json_object_get(root, "retry"));
  json_decref(root);
  return retry;
}

/* ---- the lock ---- */

/* A process's start time in clock ticks since boot (/proc/PID/stat, field
 * 22), which tells a pid reused by another process from the owner; 0 when
 * the process does not exist. */
static unsigned long long process_start(long pid) {
  char path[64], text[1024];
  snprintf(path, sizeof path, "/proc/%ld/stat", pid);
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = '\0';
  const char *p = strrchr(text, ')'); /* the name may hold spaces and ')' */
  if (!p) return 0;
  unsigned long long start = 0;
  /* after ')': state is field 3, starttime field 22 */
  if (sscanf(p + 1,
             " %*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %*u %*u %*d %*d %*d %*d %*d "
             "%*d %llu",
             &start) != 1)
    return 0;
  return start;
}

static cf_status write_owner(const char *dir, cf_error *err) {
  char host[256], path[4096];
  batch_host_name(host, sizeof host);
  json_t *owner = json_pack("{s:o, s:I, s:I}", "host", json_text(host), "pid", (json_int_t)getpid(),
                            "start_ticks", (json_int_t)process_start((long)getpid()));
  if (!owner) return cf_error_set(err, CF_ENOMEM, "out of memory");
  cf_status s = cf_path_join(dir, "owner.json", path, sizeof path, err);
  if (s == CF_OK) s = json_write_file(owner, path, JSON_INDENT(2), err);
  json_decref(owner);
  return s;
}

/* 1 if the lock at `lock` is stale (its owner on this host and gone), -1
 * if it is ours, else 0 with a message naming who holds it. */
static int lock_stale(const char *lock, char *holder, size_t size) {
  char path[4200], host[256];
  snprintf(path, sizeof path, "%s/owner.json", lock);
  json_t *root = NULL;
  cf_error why = {0};
  if (json_load_object(path, SMALL_JSON_MAX, &root, &why) != CF_OK) {
    snprintf(holder, size, "an owner that did not record itself (%.400s)", why.message);
    return 0;
  }
  const char *owner_host = json_string_value(json_object_get(root, "host"));
  long pid = (long)json_integer_value(json_object_get(root, "pid"));
  unsigned long long start =
      (unsigned long long)json_integer_value(json_object_get(root, "start_ticks"));
  batch_host_name(host, sizeof host);
  int here = owner_host && strcmp(owner_host, host) == 0;
  int stale = here && pid > 0 && process_start(pid) != start;
  /* our own (NFSv3 may answer a retried rename that succeeded with EEXIST) */
  if (here && pid == (long)getpid() && process_start(pid) == start) stale = -1;
  if (pid > 0)
    snprintf(holder, size, "process %ld on host %s", pid, owner_host ? owner_host : "?");
  else /* not ours, and nothing to check whether its batch is gone */
    snprintf(holder, size,
             "a lock whose owner.json holds no process id (host %s): remove the lock by hand "
             "once no batch uses the library",
             owner_host ? owner_host : "not recorded either");
  json_decref(root);
  return stale;
}

/* The owner is recorded in a private folder first, which one rename makes
 * the lock: the lock never exists without its owner. */
cf_status cf_batch_lock(const char *library, int *taken_over, cf_error *err) {
  char lock[4096], fresh[4096], stale[4096], holder[512];
  *taken_over = 0;
  snprintf(lock, sizeof lock, "%s/.lock", library);
  snprintf(fresh, sizeof fresh, "%s/.lock.new.%ld", library, (long)getpid());
  snprintf(stale, sizeof stale, "%s/.lock.stale.%ld", library, (long)getpid());
  batch_remove_tree(fresh);
  if (mkdir(fresh, 0777) != 0)
    return cf_error_set(err, CF_EIO, "%s: cannot create: %s", fresh, strerror(errno));
  cf_status s = write_owner(fresh, err);
  for (int attempt = 0; s == CF_OK && attempt < 3; ++attempt) {
    if (rename(fresh, lock) == 0) return CF_OK;
    if (errno != EEXIST && errno != ENOTEMPTY) {
      s = cf_error_set(err, CF_EIO, "%s: cannot create: %s", lock, strerror(errno));
      break;
    }
    int state = lock_stale(lock, holder, sizeof holder);
    if (state < 0) return batch_remove_tree(fresh), CF_OK;
    if (state == 0) {
      s = cf_error_set(err, CF_EIO, "%s: the library is locked by %s", lock, holder);
      break;
    }
    if (rename(lock, stale) == 0) { /* one taker wins; the others retry */
      batch_remove_tree(stale);
      *taken_over = 1;
    }
  }
  if (s == CF_OK) s = cf_error_set(err, CF_EIO, "%s: could not take the lock", lock);
  batch_remove_tree(fresh);
  return s;
}

void cf_batch_unlock(const char *library) {
  char lock[4096], path[4200];
  snprintf(lock, sizeof lock, "%s/.lock", library);
  snprintf(path, sizeof path, "%s/owner.json", lock);
  json_t *root = NULL;
  cf_error ignored = {0};
  if (json_load_object(path, SMALL_JSON_MAX, &root, &ignored) != CF_OK) return;
  long pid = (long)json_integer_value(json_object_get(root, "pid"));
  json_decref(root);
  if (pid == (long)getpid()) batch_remove_tree(lock);
}

/* ---- clean-up ---- */

/* ".tmp.<name>.<pid>" or ".old.<name>.<pid>" exactly: the name into
 * `name`, 1 for .old. -1 when the text is neither. */
static int leftover_kind(const char *file, char name[CF_BATCH_NAME_MAX + 1]) {
  int old = strncmp(file, ".old.", 5) == 0;
  if (!old && strncmp(file, ".tmp.", 5) != 0) return -1;
  const char *rest = file + 5, *dot = strrchr(rest, '.');
  if (!dot || dot == rest || dot[1] == '\0' || (size_t)(dot - rest) > CF_BATCH_NAME_MAX) return -1;
  for (const char *d = dot + 1; *d; ++d)
    if (*d < '0' || *d > '9') return -1;
  memcpy(name, rest, (size_t)(dot - rest));
  name[dot - rest] = '\0';
  return cf_batch_name_valid(name) ? old : -1;
}

int cf_batch_clean(const char *library) {
  DIR *dir = opendir(library);
  if (!dir) return 0;
  int cleaned = 0;
  char name[CF_BATCH_NAME_MAX + 1], path[4096], entry[4096];
  for (struct dirent *d; (d = readdir(dir));) {
    int kind = leftover_kind(d->d_name, name);
    if (kind < 0) continue;
    snprintf(path, sizeof path, "%s/%s", library, d->d_name);
    snprintf(entry, sizeof entry, "%s/%s", library, name);
    if (kind == 1 && !cf_path_exists(entry) && rename(path, entry) == 0)
      cleaned++; /* a kill between the two renames: the old entry back */
    else if (batch_remove_tree(path) == 0)
      cleaned++;
  }
  closedir(dir);
  return cleaned;
}
