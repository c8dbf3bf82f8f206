#include "out_path.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum { PATH_CAP = 4096 };

/* The folder holding `path` ("a/b/" and "a/b" → "a", "b" → ".", "/b" → "/"). */
static void parent_of(const char *path, char out[PATH_CAP]) {
  size_t n = strlen(path);
  while (n > 1 && path[n - 1] == '/') --n; /* trailing slashes */
  while (n > 0 && path[n - 1] != '/') --n; /* the last name */
  while (n > 1 && path[n - 1] == '/') --n; /* the slashes before it */
  if (n == 0)
    snprintf(out, PATH_CAP, ".");
  else
    snprintf(out, PATH_CAP, "%.*s", (int)n, path);
}

/* CF_OK if a file can be created in the folder `dir`: access() first (a
 * clear reason for a normal user), then a real file created and removed,
 * since root passes access() on a read-only folder but not on a read-only
 * mount or in /proc. */
static cf_status probe_folder(const char *option, const char *path, const char *dir,
                              cf_error *err) {
  if (access(dir, W_OK | X_OK) != 0)
    return cf_error_set(err, CF_EINVAL, "%s '%s': cannot write into the folder '%s': %s", option,
                        path, dir, strerror(errno));
  char probe[PATH_CAP + 32];
  snprintf(probe, sizeof probe, "%s/.clayfit-probe-XXXXXX", dir);
  int fd = mkstemp(probe);
  if (fd < 0)
    return cf_error_set(err, CF_EINVAL, "%s '%s': cannot create a file in the folder '%s': %s",
                        option, path, dir, strerror(errno));
  close(fd);
  unlink(probe);
  return CF_OK;
}

/* The nearest folder that exists at or above `path` (a missing one is
 * created by cf_make_dirs), checked to be a writable folder. */
static cf_status check_nearest_folder(const char *option, const char *path, cf_error *err) {
  char at[PATH_CAP];
  snprintf(at, sizeof at, "%s", path);
  struct stat st;
  while (stat(at, &st) != 0) {
    if (errno != ENOENT && errno != ENOTDIR)
      return cf_error_set(err, CF_EINVAL, "%s '%s': cannot reach '%s': %s", option, path, at,
                          strerror(errno));
    char up[PATH_CAP];
    parent_of(at, up);
    if (strcmp(up, at) == 0) /* "." or "/" missing: nothing left to try */
      return cf_error_set(err, CF_EINVAL, "%s '%s': '%s' does not exist", option, path, at);
    memcpy(at, up, sizeof at);
  }
  if (!S_ISDIR(st.st_mode))
    return cf_error_set(err, CF_EINVAL, "%s '%s': '%s' is not a folder (%s)", option, path, at,
                        strerror(ENOTDIR));
  return probe_folder(option, path, at, err);
}

/* A FIFO is written only while a process reads it; with none, the write
 * would wait forever, so it is refused now, before any work. The probe's
 * descriptor stays open to the process's end: closing it would end the
 * reader's input (EOF) before the real output is written. */
static cf_status check_fifo_reader(const char *option, const char *path, cf_error *err) {
  int fd = open(path, O_WRONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0 && errno == ENXIO)
    return cf_error_set(err, CF_EINVAL,
                        "%s '%s': a FIFO that no process is reading; clayfit would wait for a "
                        "reader forever (start the reader first, or name a regular file)",
                        option, path);
  if (fd < 0)
    return cf_error_set(err, CF_EINVAL, "%s '%s': cannot write: %s", option, path,
                        strerror(errno));
  return CF_OK;
}

/* A file to create or replace (cf_write_file: a temporary file beside it,
 * renamed into place). */
static cf_status check_file(const char *option, const char *path, cf_error *err) {
  size_t n = strlen(path);
  if (path[n - 1] == '/')
    return cf_error_set(err, CF_EINVAL, "%s '%s': names a folder; a file is expected", option,
                        path);
  struct stat st;
  if (stat(path, &st) == 0) {
    if (S_ISDIR(st.st_mode))
      return cf_error_set(err, CF_EINVAL, "%s '%s': is a folder; a file is expected (%s)", option,
                          path, strerror(EISDIR));
    if (!S_ISREG(st.st_mode)) { /* /dev/stdout, a FIFO: written directly */
      if (access(path, W_OK) != 0)
        return cf_error_set(err, CF_EINVAL, "%s '%s': cannot write: %s", option, path,
                            strerror(errno));
      return S_ISFIFO(st.st_mode) ? check_fifo_reader(option, path, err) : CF_OK;
    }
  } else if (errno != ENOENT && errno != ENOTDIR) {
    return cf_error_set(err, CF_EINVAL, "%s '%s': %s", option, path, strerror(errno));
  }
  char dir[PATH_CAP];
  parent_of(path, dir);
  if (stat(dir, &st) != 0)
    return cf_error_set(err, CF_EINVAL, "%s '%s': the folder '%s' cannot be used: %s", option, path,
                        dir, strerror(errno));
  if (!S_ISDIR(st.st_mode))
    return cf_error_set(err, CF_EINVAL, "%s '%s': '%s' is not a folder (%s)", option, path, dir,
                        strerror(ENOTDIR));
  return probe_folder(option, path, dir, err);
}

/* A folder to write into, or (replaced) to swap for a new one. */
static cf_status check_folder(const char *option, const char *path, int replaced, cf_error *err) {
  struct stat st;
  if (stat(path, &st) != 0) return check_nearest_folder(option, path, err);
  if (!S_ISDIR(st.st_mode))
    return cf_error_set(err, CF_EINVAL, "%s '%s': exists and is not a folder (%s)", option, path,
                        strerror(ENOTDIR));
  if (!replaced) return probe_folder(option, path, path, err);
  char parent[PATH_CAP];
  parent_of(path, parent);
  return probe_folder(option, path, parent, err);
}

cf_status cli_check_output(const char *option, const char *path, cli_out_kind kind, cf_error *err) {
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "%s: the path is empty", option);
  if (strlen(path) >= PATH_CAP)
    return cf_error_set(err, CF_EINVAL, "%s: the path is longer than %d bytes", option,
                        PATH_CAP - 1);
  if (kind == CLI_OUT_FILE) return check_file(option, path, err);
  return check_folder(option, path, kind == CLI_OUT_FOLDER_REPLACED, err);
}

cf_status cli_check_output_in(const char *option, const char *dir, const char *name,
                              cf_error *err) {
  cf_status s = cli_check_output(option, dir, CLI_OUT_FOLDER, err);
  struct stat st;
  if (s != CF_OK || stat(dir, &st) != 0) return s;
  char path[2 * PATH_CAP];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  return cli_check_output(option, path, CLI_OUT_FILE, err);
}
