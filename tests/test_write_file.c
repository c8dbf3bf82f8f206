/* cf_write_file, the one way clayfit writes an output file (fit.json, the
 * presets, report.json, captures): whole or not at all.
 *   - a written file holds exactly the bytes, and no temporary is left;
 *   - a write that fails part way (the disk full: here a file size limit,
 *     RLIMIT_FSIZE, whose writes fail with EFBIG) leaves the earlier file
 *     as it was, removes its temporary, and says why (before, the earlier
 *     file was truncated and the message had no reason);
 *   - a folder that does not exist, and /dev/full, fail with the system's
 *     reason; /dev/null is written in place (not replaced by a file);
 *   - a FIFO that no process reads is refused, not waited on (before, the
 *     write blocked forever); cf_open_regular_file refuses a FIFO and
 *     /dev/zero at once, and opens a regular file with its size. */
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/file.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static size_t files_in(const char *dir) {
  DIR *d = opendir(dir);
  size_t count = 0;
  for (struct dirent *e; d && (e = readdir(d));) count += e->d_name[0] != '.';
  if (d) closedir(d);
  return count;
}

static int holds(const char *path, const char *text) {
  char *data = NULL;
  size_t size = 0;
  cf_error err = {0};
  int same = cf_read_file(path, 1 << 20, &data, &size, &err) == CF_OK && size == strlen(text) &&
             memcmp(data, text, size) == 0;
  free(data);
  return same;
}

int main(void) {
  char dir[] = "/tmp/clayfit_write_XXXXXX";
  CHECK(mkdtemp(dir) != NULL, "mkdtemp: %s", strerror(errno));
  char path[256];
  snprintf(path, sizeof path, "%s/fit.json", dir);
  cf_error err = {0};

  CHECK(cf_write_file(path, "old", 3, &err) == CF_OK, "write: %s", err.message);
  CHECK(holds(path, "old"), "the file does not hold what was written");
  CHECK(files_in(dir) == 1, "%zu files in the folder, expected 1 (a temporary left?)",
        files_in(dir));

  /* a full disk, part way through 100 000 bytes */
  static char big[100000];
  memset(big, 'x', sizeof big);
  struct rlimit limit, before;
  getrlimit(RLIMIT_FSIZE, &before);
  limit = before;
  limit.rlim_cur = 4096;
  signal(SIGXFSZ, SIG_IGN);
  CHECK(setrlimit(RLIMIT_FSIZE, &limit) == 0, "setrlimit: %s", strerror(errno));
  cf_status s = cf_write_file(path, big, sizeof big, &err);
  setrlimit(RLIMIT_FSIZE, &before);
  CHECK(s == CF_EIO, "a write past the limit: status %d", s);
  CHECK(strstr(err.message, strerror(EFBIG)) != NULL && strstr(err.message, path) != NULL,
        "the message names neither the file nor the reason: %s", err.message);
  CHECK(holds(path, "old"), "the earlier file was changed by a failed write");
  CHECK(files_in(dir) == 1, "%zu files in the folder after a failed write, expected 1",
        files_in(dir));

  char missing[300];
  snprintf(missing, sizeof missing, "%s/no/such/folder/fit.json", dir);
  s = cf_write_file(missing, "x", 1, &err);
  CHECK(s == CF_EIO && strstr(err.message, strerror(ENOENT)) != NULL,
        "a missing folder: status %d, %s", s, err.message);

  s = cf_write_file("/dev/full", big, sizeof big, &err);
  CHECK(s == CF_EIO && strstr(err.message, strerror(ENOSPC)) != NULL, "/dev/full: status %d, %s", s,
        err.message);
  struct stat st;
  CHECK(cf_write_file("/dev/null", "x", 1, &err) == CF_OK, "/dev/null: %s", err.message);
  CHECK(stat("/dev/null", &st) == 0 && S_ISCHR(st.st_mode), "/dev/null is no longer a device");

  /* a FIFO that no process reads or writes: refused at once, never waited on */
  char fifo[300];
  snprintf(fifo, sizeof fifo, "%s/fifo", dir);
  CHECK(mkfifo(fifo, 0600) == 0, "mkfifo: %s", strerror(errno));
  s = cf_write_file(fifo, "x", 1, &err);
  CHECK(s == CF_EINVAL && strstr(err.message, "no process is reading"), "a FIFO written: %d, %s", s,
        err.message);
  FILE *file = NULL;
  long long size = -1;
  s = cf_open_regular_file(fifo, &file, &size, &err);
  CHECK(s == CF_EIO && !file && strstr(err.message, "not a regular file"), "a FIFO read: %d, %s",
        s, err.message);
  CHECK(cf_open_regular_file("/dev/zero", &file, &size, &err) == CF_EIO && !file,
        "/dev/zero read: %s", err.message);
  CHECK(cf_open_regular_file(path, &file, &size, &err) == CF_OK && file && size == 3,
        "a regular file: %s", err.message);
  if (file) fclose(file);
  unlink(fifo);

  unlink(path);
  rmdir(dir);
  return check_finish("test_write_file");
}
