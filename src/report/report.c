/* The residual report of a fit (include/clayfit/report.h), written whole or
 * not at all: built in a sibling temporary folder DIR.tmp-PID, then
 * exchanged with DIR in one rename, so that DIR holds at every moment the
 * earlier report or the new one, complete. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* renameat2, nftw */
#endif
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/file.h"
#include "report_internal.h"

/* ---- the output folder ---- */

/* dir without trailing slashes (path: so that a link is not followed),
 * split into its folder and its name. */
static cf_status split_dir(const char *dir, char path[4096], char parent[4096], char base[1024],
                           cf_error *err) {
  size_t n = dir ? strlen(dir) : 0;
  while (n > 1 && dir[n - 1] == '/') --n;
  if (n == 0) return cf_error_set(err, CF_EINVAL, "the report's folder is an empty name");
  if (n >= 4096) return cf_error_set(err, CF_ERANGE, "the report's folder name is too long");
  memcpy(path, dir, n);
  path[n] = '\0';
  const char *slash = strrchr(path, '/');
  const char *name = slash ? slash + 1 : path;
  if (!*name || strcmp(name, ".") == 0 || strcmp(name, "..") == 0)
    return cf_error_set(err, CF_EINVAL,
                        "%s: the report replaces its folder as a whole, so the folder must be "
                        "given by its name (not /, . or ..)",
                        dir);
  if (strlen(name) >= 1000) return cf_error_set(err, CF_ERANGE, "%s: the name is too long", dir);
  snprintf(base, 1024, "%s", name);
  if (!slash)
    snprintf(parent, 4096, ".");
  else if (slash == path)
    snprintf(parent, 4096, "/");
  else
    snprintf(parent, 4096, "%.*s", (int)(slash - path), path);
  return CF_OK;
}

static int has_suffix(const char *name, const char *suffix) {
  size_t n = strlen(name), m = strlen(suffix);
  return n > m && strcmp(name + n - m, suffix) == 0;
}

/* The first entry of folder `path` that a report does not hold (into
 * `which`): in DIR only index.html, report.json, images/, plots/ and
 * viewer/, in images/ only .png files, in plots/ only .svg files, in viewer/
 * only .png, .js and .mjs files; none of them a
 * symbolic link. 1 when there is one, 0 when there is none, -1 when the
 * folder cannot be read. */
static int foreign_entry(const char *path, const char *sub, char *which, size_t size) {
  char folder[4200];
  snprintf(folder, sizeof folder, sub ? "%s/%s" : "%s", path, sub);
  DIR *d = opendir(folder);
  if (!d) return -1;
  int found = 0;
  for (struct dirent *e; !found && (e = readdir(d)) != NULL;) {
    const char *name = e->d_name;
    if (strcmp(name, ".") == 0 || strcmp(name, "..") == 0) continue;
    char full[4500];
    struct stat st;
    snprintf(full, sizeof full, "%s/%s", folder, name);
    int is_dir = lstat(full, &st) == 0 && S_ISDIR(st.st_mode);
    int is_file = lstat(full, &st) == 0 && S_ISREG(st.st_mode);
    int ours;
    if (!sub)
      ours = ((strcmp(name, "index.html") == 0 || strcmp(name, "report.json") == 0) && is_file) ||
             ((strcmp(name, "images") == 0 || strcmp(name, "plots") == 0 ||
               strcmp(name, "viewer") == 0) &&
              is_dir);
    else if (strcmp(sub, "viewer") == 0)
      ours = is_file &&
             (has_suffix(name, ".png") || has_suffix(name, ".js") || has_suffix(name, ".mjs"));
    else
      ours = is_file && has_suffix(name, strcmp(sub, "images") == 0 ? ".png" : ".svg");
    if (!ours) {
      snprintf(which, size, "%s%s%s", sub ? sub : "", sub ? "/" : "", name);
      found = 1;
    }
  }
  closedir(d);
  return found;
}

/* 1 if dir/report.json begins as clayfit's report.json does. */
static int is_report_json(const char *dir) {
  char path[4200], head[256] = {0};
  snprintf(path, sizeof path, "%s/report.json", dir);
  int fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) return 0;
  ssize_t got = read(fd, head, sizeof head - 1);
  close(fd);
  return got > 0 && strstr(head, "\"clayfit_report\"") != NULL;
}

/* The files in dir, dir/images, dir/plots and dir/viewer (an earlier
 * clayfit left the folders empty when it failed). */
static size_t count_files(const char *dir) {
  static const char *const subs[] = {"", "/images", "/plots", "/viewer"};
  size_t files = 0;
  for (int k = 0; k < 4; ++k) {
    char folder[4200];
    snprintf(folder, sizeof folder, "%s%s", dir, subs[k]);
    DIR *d = opendir(folder);
    for (struct dirent *e; d && (e = readdir(d)) != NULL;) {
      char full[4500];
      struct stat st;
      snprintf(full, sizeof full, "%s/%s", folder, e->d_name);
      files += lstat(full, &st) == 0 && !S_ISDIR(st.st_mode);
    }
    if (d) closedir(d);
  }
  return files;
}

cf_status cf_report_check_dir(const char *dir, cf_error *err) {
  char path[4096], parent[4096], base[1024];
  cf_status s = split_dir(dir, path, parent, base, err);
  if (s != CF_OK) return s;
  struct stat st;
  if (lstat(path, &st) != 0) {
    if (errno == ENOENT) return CF_OK;
    return cf_error_set(err, CF_EINVAL, "%s: %s", dir, strerror(errno));
  }
  if (S_ISLNK(st.st_mode))
    return cf_error_set(err, CF_EINVAL,
                        "%s is a symbolic link: the report replaces its folder as a whole; give "
                        "the folder it points to, or a new name",
                        dir);
  if (!S_ISDIR(st.st_mode))
    return cf_error_set(err, CF_EINVAL,
                        "%s exists and is not a folder: give a new name (the folder is created) "
                        "or an earlier report's folder",
                        dir);
  char which[1100];
  int foreign = foreign_entry(path, NULL, which, sizeof which);
  static const char *const subs[] = {"images", "plots", "viewer"};
  for (int k = 0; foreign == 0 && k < 3; ++k) {
    const char *sub = subs[k];
    char folder[4200];
    snprintf(folder, sizeof folder, "%s/%s", path, sub);
    if (cf_path_exists(folder)) foreign = foreign_entry(path, sub, which, sizeof which);
  }
  if (foreign < 0) return cf_error_set(err, CF_EINVAL, "%s: %s", dir, strerror(errno));
  if (foreign > 0)
    return cf_error_set(err, CF_EINVAL,
                        "%s is a folder that is not a clayfit report (it holds '%s'): the report "
                        "replaces its folder as a whole, so it writes only into a new or empty "
                        "folder or over an earlier report; choose another -o, or move that "
                        "folder's contents away",
                        dir, which);
  if (count_files(path) > 0 && !is_report_json(path))
    return cf_error_set(err, CF_EINVAL,
                        "%s holds no clayfit report.json (an interrupted or foreign folder): the "
                        "report replaces its folder as a whole and does so only over an earlier "
                        "report; choose another -o, or remove that folder first",
                        dir);
  return CF_OK;
}

/* ---- temporary folders ---- */

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag, (void)ftw;
  return remove(path) == 0 ? 0 : errno;
}

/* Remove the folder `path` and everything in it, following no symbolic
 * link and crossing into no other file system. */
static int remove_tree(const char *path) {
  return nftw(path, remove_entry, 8, FTW_DEPTH | FTW_PHYS | FTW_MOUNT);
}

/* The process id of a leftover of ours: NAME.tmp-PID or NAME.old-PID
 * exactly, PID decimal; 0 for any other name. */
static long leftover_pid(const char *entry, const char *base) {
  size_t n = strlen(base);
  if (strncmp(entry, base, n) != 0) return 0;
  entry += n;
  if (strncmp(entry, ".tmp-", 5) != 0 && strncmp(entry, ".old-", 5) != 0) return 0;
  entry += 5;
  long pid = 0;
  size_t digits = 0;
  for (; entry[digits]; ++digits) {
    if (entry[digits] < '0' || entry[digits] > '9' || digits >= 9) return 0;
    pid = 10 * pid + (entry[digits] - '0');
  }
  return digits && entry[0] != '0' ? pid : 0;
}

/* Remove the leftovers of runs that were killed while writing a report
 * into the same folder: folders (not links) named by leftover_pid whose
 * process is gone. Best effort: what cannot be removed stays. */
static void remove_leftovers(const char *parent, const char *base) {
  DIR *d = opendir(parent);
  if (!d) return;
  for (struct dirent *e; (e = readdir(d)) != NULL;) {
    long pid = leftover_pid(e->d_name, base);
    if (pid <= 0) continue;
    if (pid != (long)getpid() && (kill((pid_t)pid, 0) == 0 || errno != ESRCH)) continue;
    char path[5200];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", parent, e->d_name);
    if (lstat(path, &st) == 0 && S_ISDIR(st.st_mode)) remove_tree(path);
  }
  closedir(d);
}

/* ---- writing ---- */

static void progress(const cf_report_options *options, const char *stage, size_t done,
                     size_t total) {
  if (options && options->progress) options->progress(options->progress_user, stage, done, total);
}

/* Every file of the report into the folder dir (which exists, empty). */
static cf_status write_parts(const cf_capture *capture, const cf_fit_file *fit, const char *dir,
                             const cf_report_options *options, cf_error *err) {
  const char *fit_path = options && options->fit_path ? options->fit_path : "fit.json";
  const char *version = options && options->version ? options->version : "";
  char sub[4200];
  snprintf(sub, sizeof sub, "%s/images", dir);
  if (mkdir(sub, 0777) != 0) return cf_error_set(err, CF_EIO, "%s: %s", sub, strerror(errno));
  snprintf(sub, sizeof sub, "%s/plots", dir);
  if (mkdir(sub, 0777) != 0) return cf_error_set(err, CF_EIO, "%s: %s", sub, strerror(errno));
  report_data d;
  progress(options, "predicting", 0, 1);
  cf_status s = report_data_build(&d, capture, fit, fit_path, err);
  if (s != CF_OK) return s;
  d.capture_path = options && options->capture_path ? options->capture_path : fit->capture_path;
  d.capture_check = options && options->capture_check ? options->capture_check : "";
  char(*files)[3][64] = calloc(d.images ? d.images : 1, sizeof *files);
  if (!files) s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK)
    s = report_images(&d, dir, files, options ? options->progress : NULL,
                      options ? options->progress_user : NULL, err);
  report_view view;
  if (s == CF_OK) progress(options, "writing the material's view", 0, 1);
  if (s == CF_OK) s = report_view_scene(&d, &view, err);
  if (s == CF_OK)
    s = report_view_write(&d, dir, fit_path, options ? options->viewer_bundle : NULL, &view, err);
  if (s == CF_OK) progress(options, "writing plots and the page", 0, 3);
  if (s == CF_OK) s = report_write_plots(&d, dir, err);
  if (s == CF_OK) progress(options, "writing plots and the page", 1, 3);
  if (s == CF_OK) s = report_write_json(&d, dir, fit_path, version, files, err);
  if (s == CF_OK) progress(options, "writing plots and the page", 2, 3);
  if (s == CF_OK) s = report_write_html(&d, dir, fit_path, version, files, &view, err);
  if (s == CF_OK) progress(options, "writing plots and the page", 3, 3);
  free(files);
  report_data_free(&d);
  return s;
}

/* Put the complete report `fresh` in the place of dir. With an earlier
 * report there, the two are exchanged in one rename (RENAME_EXCHANGE) and
 * the earlier one, now at `fresh`, removed; where the file system cannot
 * exchange, the earlier one is first moved aside to `aside`. */
static cf_status install(const char *fresh, const char *dir, const char *aside,
                         const cf_report_options *options, cf_error *err) {
  progress(options, "replacing the earlier report", 0, 2);
  struct stat st;
  if (lstat(dir, &st) != 0 && errno == ENOENT) {
    if (rename(fresh, dir) != 0)
      return cf_error_set(err, CF_EIO, "cannot rename %s to %s: %s", fresh, dir, strerror(errno));
    progress(options, "replacing the earlier report", 2, 2);
    return CF_OK;
  }
  cf_status s = cf_report_check_dir(dir, err); /* it may have changed while the report was made */
  if (s != CF_OK) return s;
  const char *old = fresh;
#ifdef RENAME_EXCHANGE
  int exchanged = renameat2(AT_FDCWD, fresh, AT_FDCWD, dir, RENAME_EXCHANGE) == 0;
  if (!exchanged && errno != EINVAL && errno != ENOSYS && errno != ENOTSUP)
    return cf_error_set(err, CF_EIO, "cannot exchange %s and %s: %s", fresh, dir, strerror(errno));
#else
  int exchanged = 0;
#endif
  if (!exchanged) {
    if (rename(dir, aside) != 0)
      return cf_error_set(err, CF_EIO, "cannot move %s aside to %s: %s", dir, aside,
                          strerror(errno));
    if (rename(fresh, dir) != 0) {
      int why = errno;
      rename(aside, dir);
      return cf_error_set(err, CF_EIO, "cannot rename %s to %s: %s", fresh, dir, strerror(why));
    }
    old = aside;
  }
  progress(options, "replacing the earlier report", 1, 2);
  remove_tree(old); /* a failure leaves a leftover that the next run removes */
  progress(options, "replacing the earlier report", 2, 2);
  return CF_OK;
}

cf_status cf_report_write(const cf_capture *capture, const cf_fit_file *fit, const char *dir,
                          const cf_report_options *options, cf_error *err) {
  char path[4096], parent[4096], base[1024], fresh[4096], aside[4096];
  cf_status s = cf_report_check_dir(dir, err);
  if (s == CF_OK) s = split_dir(dir, path, parent, base, err);
  if (s == CF_OK) s = cf_make_dirs(parent, err);
  if (s != CF_OK) return s;
  remove_leftovers(parent, base);
  int n = snprintf(fresh, sizeof fresh, "%s/%s.tmp-%ld", parent, base, (long)getpid());
  if (n < 0 || (size_t)n >= sizeof fresh)
    return cf_error_set(err, CF_ERANGE, "%s: the folder's name is too long", dir);
  n = snprintf(aside, sizeof aside, "%s/%s.old-%ld", parent, base, (long)getpid());
  if (n < 0 || (size_t)n >= sizeof aside)
    return cf_error_set(err, CF_ERANGE, "%s: the folder's name is too long", dir);
  if (mkdir(fresh, 0777) != 0)
    return cf_error_set(err, CF_EIO, "cannot create the folder %s: %s", fresh, strerror(errno));
  s = write_parts(capture, fit, fresh, options, err);
  if (s == CF_OK) s = install(fresh, path, aside, options, err);
  if (s != CF_OK) remove_tree(fresh);
  return s;
}
