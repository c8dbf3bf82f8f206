/* cf_report_write replaces its folder whole or not at all (issue 16, item 5):
 *   - a run killed (SIGKILL) at every step the report reports through its
 *     progress callback leaves the folder holding the earlier report or the
 *     new one, whole (every file byte-equal to a reference run's, every
 *     picture the page names present), and at most one leftover, which the
 *     next run removes;
 *   - one picture's write pointed at /dev/full fails the run (CF_EIO, the
 *     file named) and leaves the earlier report as it was, and no leftover
 *     (before: exit 0, the page naming a picture never written);
 *   - the next run removes leftovers of dead runs, and nothing else: not a
 *     live run's, not a name that merely resembles ours, not what a link
 *     of that name points to;
 *   - cf_report_check_dir refuses a file, a link, a folder holding anything
 *     but a report, and a folder of a report's names without report.json,
 *     and touches none of them.
 * Every report is written in a child process (fork before any use of
 * OpenImageIO), so that a kill can be exact.
 * usage: test_report_atomic CAPTURE FIT_A FIT_B WORKDIR */
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "clayfit/report.h"
#include "core/file.h"
#include "support/check.h"

#pragma GCC diagnostic ignored "-Wformat-truncation" /* paths in a test's folder */

CHECK_MAIN_STATE;

static const char *capture_path, *work;
static char out[1024];

/* ---- the child: one report ---- */

typedef struct hook {
  int kill_at;  /* raise SIGKILL at this progress call (1-based); 0: never */
  int calls;
  int full_at;  /* before any image is written (at "predicting": the images are written
                   side by side, in no fixed order), point image full_at's photo's
                   temporary at /dev/full; -1: never */
  char dir[1100];
} hook;

static void on_progress(void *user, const char *stage, size_t done, size_t total) {
  hook *h = user;
  (void)total;
  if (++h->calls == h->kill_at) raise(SIGKILL);
  if (h->full_at >= 0 && strcmp(stage, "predicting") == 0 && done == 0) {
    char link[1400];
    /* the image's own temporary (cf_image_write: PATH.tmp-PID.EXT) */
    snprintf(link, sizeof link, "%s.tmp-%ld/images/%03d_photo.png.tmp-%ld.png", h->dir,
             (long)getpid(), h->full_at, (long)getpid());
    if (symlink("/dev/full", link) != 0) _exit(5);
  }
}

/* Write the report of fit into out in a child; its exit status (0 ok, 1
 * failed, 3 failed as expect_error says) or 128 + the signal. */
static int report_child(const char *fit_path, const char *dir, int kill_at, int full_at,
                        const char *expect_error) {
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    hook h = {kill_at, 0, full_at, {0}};
    snprintf(h.dir, sizeof h.dir, "%s", dir);
    cf_error err = {0};
    cf_fit_file fit;
    cf_capture *capture = NULL;
    cf_status s = cf_fit_file_read(fit_path, &fit, &err);
    if (s == CF_OK) s = cf_capture_load(capture_path, NULL, &capture, &err);
    if (s == CF_OK) {
      cf_report_options o = {fit_path, "test", on_progress, &h, NULL, NULL, NULL};
      s = cf_report_write(capture, &fit, dir, &o, &err);
    }
    if (s != CF_OK && expect_error && strstr(err.message, expect_error)) _exit(3);
    if (s != CF_OK) fprintf(stderr, "report: %s\n", err.message);
    _exit(s == CF_OK ? 0 : 1);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
}

/* ---- comparing folders ---- */

static char *slurp(const char *path, size_t *size) {
  char *data = NULL;
  cf_error err = {0};
  *size = 0;
  if (cf_read_file(path, 64 << 20, &data, size, &err) != CF_OK) return NULL;
  /* report.json's "created" is the one line that differs between runs */
  char *created = strstr(data, "\"created\":");
  if (created && strstr(path, "report.json"))
    for (char *p = created; *p && *p != '\n'; ++p) *p = ' ';
  return data;
}

static int same_file(const char *a, const char *b) {
  size_t n = 0, m = 0;
  char *x = slurp(a, &n), *y = slurp(b, &m);
  int same = x && y && n == m && memcmp(x, y, n) == 0;
  free(x);
  free(y);
  return same;
}

/* Are the folders a and b (a report: files, images/, plots/) the same, file
 * for file? */
static int same_tree(const char *a, const char *b) {
  static const char *const subs[] = {"", "/images", "/plots"};
  for (int pass = 0; pass < 2; ++pass) /* a's files in b, then b's in a */
    for (int k = 0; k < 3; ++k) {
      char folder[1400];
      snprintf(folder, sizeof folder, "%s%s", pass ? b : a, subs[k]);
      DIR *d = opendir(folder);
      if (!d) return 0;
      for (struct dirent *e; (e = readdir(d)) != NULL;) {
        char x[1700], y[1700];
        struct stat st;
        snprintf(x, sizeof x, "%s/%s", folder, e->d_name);
        if (lstat(x, &st) != 0 || S_ISDIR(st.st_mode)) continue;
        snprintf(y, sizeof y, "%s%s/%s", pass ? a : b, subs[k], e->d_name);
        if (!same_file(x, y)) {
          closedir(d);
          return 0;
        }
      }
      closedir(d);
    }
  return 1;
}

/* Does every picture index.html names exist? */
static int pictures_exist(const char *dir) {
  char path[1200];
  size_t size;
  snprintf(path, sizeof path, "%s/index.html", dir);
  char *page = slurp(path, &size);
  if (!page) return 0;
  int all = 1, count = 0;
  for (const char *p = page; (p = strstr(p, "src=\"")) != NULL;) {
    p += 5;
    const char *end = strchr(p, '"');
    if (!end) break;
    snprintf(path, sizeof path, "%s/%.*s", dir, (int)(end - p), p);
    all &= cf_path_exists(path);
    ++count;
  }
  free(page);
  return all && count >= 8 * 3;
}

/* The leftovers beside out (out.tmp-*, out.old-*). */
static int leftovers(void) {
  DIR *d = opendir(work);
  int count = 0;
  const char *base = strrchr(out, '/') + 1;
  size_t n = strlen(base);
  for (struct dirent *e; d && (e = readdir(d)) != NULL;)
    count += strncmp(e->d_name, base, n) == 0 &&
             (strncmp(e->d_name + n, ".tmp-", 5) == 0 || strncmp(e->d_name + n, ".old-", 5) == 0);
  if (d) closedir(d);
  return count;
}

static int run(const char *command) {
  fflush(NULL);
  return system(command);
}

static void reset_out(const char *ref) {
  char command[4000];
  snprintf(command, sizeof command, "rm -rf '%s' && cp -a '%s' '%s'", out, ref, out);
  CHECK(run(command) == 0, "%s", command);
}

/* ---- the cases ---- */

static void killed_at_every_step(const char *fit_b, const char *ref_a, const char *ref_b) {
  int old_whole = 0, new_whole = 0, new_with_leftover = 0, finished = 0;
  for (int at = 1; at < 100 && !finished; ++at) {
    reset_out(ref_a);
    int status = report_child(fit_b, out, at, -1, NULL);
    finished = status == 0;
    CHECK(status == 0 || status == 128 + SIGKILL, "kill at step %d: status %d", at, status);
    int is_a = same_tree(out, ref_a), is_b = same_tree(out, ref_b);
    CHECK(is_a || is_b, "killed at step %d: %s is neither report whole", at, out);
    CHECK(pictures_exist(out), "killed at step %d: a picture of the page is missing", at);
    CHECK(leftovers() <= (finished ? 0 : 1), "killed at step %d: %d leftovers", at, leftovers());
    CHECK(!finished || is_b, "the finished run did not leave the new report");
    old_whole += is_a;
    new_whole += is_b;
    new_with_leftover += is_b && leftovers() == 1;
    if (new_with_leftover == 1 && is_b && leftovers() == 1) { /* the next run cleans up */
      CHECK(report_child(fit_b, out, 0, -1, NULL) == 0, "the run after a kill failed");
      CHECK(leftovers() == 0, "the run after a kill left %d leftovers", leftovers());
      CHECK(same_tree(out, ref_b), "the run after a kill did not leave its report");
    }
  }
  CHECK(finished, "the report never finished");
  CHECK(old_whole >= 10, "only %d kills left the earlier report", old_whole);
  CHECK(new_with_leftover >= 1, "no kill fell between the exchange and the removal");
  printf("kills: %d left the earlier report, %d the new one (%d with a leftover)\n", old_whole,
         new_whole - 1, new_with_leftover);
}

static void dev_full(const char *fit_b, const char *ref_a) {
  reset_out(ref_a);
  int status = report_child(fit_b, out, 0, 1, "001_photo.png: could not write the image");
  CHECK(status == 3, "a picture written to /dev/full: status %d (3: failed, naming it)", status);
  CHECK(same_tree(out, ref_a), "a failed run changed the earlier report");
  CHECK(leftovers() == 0, "a failed run left %d leftovers", leftovers());
}

static void make_dir(const char *path, const char *file) {
  char p[1400];
  CHECK(mkdir(path, 0777) == 0 || errno == EEXIST, "mkdir %s", path);
  if (!file) return;
  snprintf(p, sizeof p, "%s/%s", path, file);
  FILE *f = fopen(p, "w");
  CHECK(f != NULL, "%s", p);
  if (f) fputs("keep me\n", f), fclose(f);
}

static void leftovers_removed(const char *fit_b, const char *ref_a) {
  reset_out(ref_a);
  fflush(NULL);
  pid_t dead = fork();
  if (dead == 0) _exit(0);
  waitpid(dead, NULL, 0);
  char p[1400], victim[1400];
  const char *gone[] = {"tmp", "old"};
  for (int k = 0; k < 2; ++k) {
    snprintf(p, sizeof p, "%s.%s-%ld", out, gone[k], (long)dead);
    make_dir(p, "index.html");
  }
  /* not ours: a live process's, look-alike names, a link to a user's folder */
  char kept[6][64];
  snprintf(kept[0], 64, ".tmp-%ld", (long)getpid());
  snprintf(kept[1], 64, ".tmp-0%ld", (long)dead);
  snprintf(kept[2], 64, ".tmp-%ldx", (long)dead);
  snprintf(kept[3], 64, ".tmpx-%ld", (long)dead);
  snprintf(kept[4], 64, ".tmp-");
  snprintf(kept[5], 64, "x.tmp-%ld", (long)dead);
  for (int k = 0; k < 6; ++k) {
    snprintf(p, sizeof p, "%s%s", out, kept[k]);
    make_dir(p, "notes.txt");
  }
  snprintf(victim, sizeof victim, "%s/victim", work);
  make_dir(victim, "notes.txt");
  snprintf(p, sizeof p, "%s.old-%ld", out, (long)dead + 1);
  CHECK(symlink(victim, p) == 0, "symlink %s", p);
  CHECK(report_child(fit_b, out, 0, -1, NULL) == 0, "the run over leftovers failed");
  for (int k = 0; k < 2; ++k) {
    snprintf(p, sizeof p, "%s.%s-%ld", out, gone[k], (long)dead);
    CHECK(!cf_path_exists(p), "the leftover %s was not removed", p);
  }
  for (int k = 0; k < 6; ++k) {
    snprintf(p, sizeof p, "%s%s/notes.txt", out, kept[k]);
    CHECK(cf_path_exists(p), "%s was removed: not a leftover of ours", p);
  }
  snprintf(p, sizeof p, "%s/notes.txt", victim);
  CHECK(cf_path_exists(p), "a link's target lost %s", p);
}

static void refused(const char *dir, const char *message) {
  cf_error err = {0};
  CHECK(cf_report_check_dir(dir, &err) == CF_EINVAL && strstr(err.message, message),
        "%s: '%s' lacks '%s'", dir, err.message, message);
}

static void folders_refused(const char *fit_b) {
  char p[1400], q[1400];
  snprintf(p, sizeof p, "%s/user", work);
  make_dir(p, "notes.txt");
  refused(p, "is a folder that is not a clayfit report (it holds 'notes.txt')");
  CHECK(report_child(fit_b, p, 0, -1, "not a clayfit report") == 3, "a user's folder: not refused");
  snprintf(q, sizeof q, "%s/notes.txt", p);
  CHECK(cf_path_exists(q), "a refused folder lost its file");
  refused(q, "exists and is not a folder");
  snprintf(p, sizeof p, "%s/site", work);
  make_dir(p, "index.html");
  refused(p, "holds no clayfit report.json");
  snprintf(q, sizeof q, "%s/images", p);
  make_dir(q, "holiday.jpg");
  refused(p, "it holds 'images/holiday.jpg'");
  snprintf(q, sizeof q, "%s/link", work);
  CHECK(symlink(p, q) == 0, "symlink");
  refused(q, "is a symbolic link");
  strcat(q, "/"); /* a trailing slash would follow it */
  refused(q, "is a symbolic link");
  refused(".", "must be given by its name");
  refused("a/..", "must be given by its name");
  refused("", "an empty name");
  cf_error err = {0};
  snprintf(p, sizeof p, "%s/empty", work);
  make_dir(p, NULL);
  CHECK(cf_report_check_dir(p, &err) == CF_OK, "an empty folder: %s", err.message);
  snprintf(q, sizeof q, "%s/images", p);
  make_dir(q, NULL); /* what an earlier clayfit left when it failed */
  CHECK(cf_report_check_dir(p, &err) == CF_OK, "a folder of empty images/: %s", err.message);
  snprintf(p, sizeof p, "%s/not/yet", work);
  CHECK(cf_report_check_dir(p, &err) == CF_OK, "a new folder: %s", err.message);
}

int main(int argc, char **argv) {
  if (argc != 5) {
    fprintf(stderr, "usage: test_report_atomic CAPTURE FIT_A FIT_B WORKDIR\n");
    return 2;
  }
  capture_path = argv[1];
  work = argv[4];
  char ref_a[1100], ref_b[1100], command[1400];
  snprintf(command, sizeof command, "rm -rf '%s' && mkdir -p '%s'", work, work);
  CHECK(run(command) == 0, "%s", command);
  snprintf(ref_a, sizeof ref_a, "%s/reference_a", work);
  snprintf(ref_b, sizeof ref_b, "%s/reference_b", work);
  snprintf(out, sizeof out, "%s/report", work);
  CHECK(report_child(argv[2], ref_a, 0, -1, NULL) == 0, "the report of %s failed", argv[2]);
  CHECK(report_child(argv[3], ref_b, 0, -1, NULL) == 0, "the report of %s failed", argv[3]);
  CHECK(!same_tree(ref_a, ref_b), "the two fits' reports cannot be told apart");
  if (check_global.failures) return check_finish("test_report_atomic");
  killed_at_every_step(argv[3], ref_a, ref_b);
  dev_full(argv[3], ref_a);
  leftovers_removed(argv[3], ref_a);
  folders_refused(argv[3]);
  return check_finish("test_report_atomic");
}
