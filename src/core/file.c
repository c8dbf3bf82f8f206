/* Whole-file reading and path handling (src/core/include/core/file.h). */
#define _XOPEN_SOURCE 700 /* POSIX 2008 with realpath (XSI) */
#include "core/file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

cf_status cf_open_regular_file(const char *path, FILE **file, long long *size, cf_error *err) {
  *file = NULL;
  *size = 0;
  int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC); /* a FIFO: no wait for a writer */
  if (fd < 0) {
    int failed = errno;
    char hidden[160];
    cf_path_hidden_characters(path, hidden, sizeof hidden);
    if (failed == ENOENT) return cf_error_set(err, CF_ENOTFOUND, "%s: no such file%s", path, hidden);
    return cf_error_set(err, CF_EIO, "%s: %s%s", path, strerror(failed), hidden);
  }
  struct stat st;
  int failed = fstat(fd, &st) != 0 ? errno : 0;
  if (failed || !S_ISREG(st.st_mode)) {
    close(fd);
    return cf_error_set(err, CF_EIO, "%s: %s", path,
                        failed ? strerror(failed) : "not a regular file");
  }
  int flags = fcntl(fd, F_GETFL);
  if (flags >= 0) fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  *file = fdopen(fd, "rb");
  if (!*file) {
    failed = errno;
    close(fd);
    return cf_error_set(err, CF_EIO, "%s: %s", path, strerror(failed));
  }
  *size = (long long)st.st_size;
  return CF_OK;
}

cf_status cf_read_file(const char *path, size_t max_size, char **data, size_t *size,
                       cf_error *err) {
  *data = NULL;
  *size = 0;
  FILE *file;
  long long file_size;
  cf_status s = cf_open_regular_file(path, &file, &file_size, err);
  if (s != CF_OK) return s;
  if ((unsigned long long)file_size > (unsigned long long)max_size) {
    fclose(file);
    return cf_error_set(err, CF_ERANGE, "%s: %lld bytes, more than the %zu this reader accepts",
                        path, file_size, max_size);
  }
  size_t expected = (size_t)file_size;
  char *buffer = malloc(expected + 1);
  if (!buffer) {
    fclose(file);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory for %zu bytes", path, expected);
  }
  size_t got = fread(buffer, 1, expected, file);
  int failed = ferror(file) || fgetc(file) != EOF; /* changed while reading */
  fclose(file);
  if (got != expected || failed) {
    free(buffer);
    return cf_error_set(err, CF_EIO, "%s: read %zu of %zu bytes", path, got, expected);
  }
  buffer[got] = '\0';
  *data = buffer;
  *size = got;
  return CF_OK;
}

void cf_path_hidden_characters(const char *path, char *out, size_t size) {
  if (size) out[0] = '\0';
  const unsigned char *p = (const unsigned char *)path;
  for (size_t i = 0; p[i]; ++i) {
    const char *what = NULL;
    if (p[i] == 0xEF && p[i + 1] == 0xBB && p[i + 2] == 0xBF)
      what = "a UTF-8 byte-order mark (U+FEFF, bytes EF BB BF)";
    else if (p[i] == 0xC2 && p[i + 1] == 0xA0)
      what = "a no-break space (U+00A0)";
    else if (p[i] == 0xE2 && p[i + 1] == 0x80 && p[i + 2] >= 0x8B && p[i + 2] <= 0x8F)
      what = "a zero-width character (U+200B to U+200F)";
    else if (p[i] < 0x20 || p[i] == 0x7F) {
      snprintf(out, size, " (the name holds the control character 0x%02X at byte %zu)", p[i], i);
      return;
    } else if (p[i] == ' ' && (i == 0 || p[i + 1] == '\0' || p[i - 1] == '/' || p[i + 1] == '/'))
      what = "a space at the start or end of a name";
    if (what) {
      snprintf(out, size, " (the name holds %s at byte %zu)", what, i);
      return;
    }
  }
}

cf_status cf_read_text_file(const char *path, size_t max_size, char **data, size_t *size,
                            cf_error *err) {
  cf_status s = cf_read_file(path, max_size, data, size, err);
  if (s != CF_OK) return s;
  const char *nul = memchr(*data, '\0', *size);
  if (nul) {
    size_t offset = (size_t)(nul - *data), line = 1;
    for (const char *p = *data; p < nul; ++p) line += *p == '\n';
    free(*data);
    *data = NULL;
    *size = 0;
    return cf_error_set(err, CF_EPARSE,
                        "%s:%zu: a NUL byte at byte offset %zu; a text file holds none (is it "
                        "UTF-16, or not text?)",
                        path, line, offset);
  }
  if (*size >= 3 && memcmp(*data, "\xEF\xBB\xBF", 3) == 0) { /* a UTF-8 byte-order mark */
    memmove(*data, *data + 3, *size - 3 + 1);
    *size -= 3;
  }
  return CF_OK;
}

/* All of data to the open descriptor fd, then to the disk (fsync, when
 * flush); 0, or the errno of the first failure. */
static int write_all(int fd, const char *data, size_t size, int flush) {
  while (size > 0) {
    ssize_t put = write(fd, data, size);
    if (put < 0 && errno == EINTR) continue;
    if (put < 0) return errno;
    data += put;
    size -= (size_t)put;
  }
  return flush && fsync(fd) != 0 ? errno : 0;
}

/* A path that exists and is not a regular file: written as it is. Opened
 * without waiting, so that a FIFO no process reads is refused (ENXIO)
 * instead of blocking forever; then written with blocking writes. */
static cf_status write_in_place(const char *path, const void *data, size_t size, cf_error *err) {
  int fd = open(path, O_WRONLY | O_TRUNC | O_NONBLOCK);
  if (fd < 0 && errno == ENXIO)
    return cf_error_set(err, CF_EINVAL,
                        "%s: a FIFO that no process is reading; clayfit would wait for a reader "
                        "forever (start the reader first, or name a regular file)",
                        path);
  if (fd < 0) return cf_error_set(err, CF_EIO, "%s: %s", path, strerror(errno));
  int flags = fcntl(fd, F_GETFL);
  if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
    int failed = errno;
    close(fd);
    return cf_error_set(err, CF_EIO, "%s: %s", path, strerror(failed));
  }
  int failed = write_all(fd, data, size, 0);
  if (close(fd) != 0 && !failed) failed = errno;
  if (failed) return cf_error_set(err, CF_EIO, "%s: %s", path, strerror(failed));
  return CF_OK;
}

cf_status cf_write_file(const char *path, const void *data, size_t size, cf_error *err) {
  struct stat st;
  if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) return write_in_place(path, data, size, err);
  char temporary[4200];
  int n = snprintf(temporary, sizeof temporary, "%s.tmp-%ld", path, (long)getpid());
  if (n < 0 || (size_t)n >= sizeof temporary)
    return cf_error_set(err, CF_EINVAL, "%s: the path is too long", path);
  int fd = open(temporary, O_WRONLY | O_CREAT | O_TRUNC, 0666);
  if (fd < 0) return cf_error_set(err, CF_EIO, "%s: %s", temporary, strerror(errno));
  int failed = write_all(fd, data, size, 1);
  if (close(fd) != 0 && !failed) failed = errno;
  if (!failed && rename(temporary, path) != 0) failed = errno;
  if (!failed) return CF_OK;
  unlink(temporary);
  return cf_error_set(err, CF_EIO, "%s: could not write %zu bytes: %s", path, size,
                      strerror(failed));
}

cf_status cf_path_join(const char *dir, const char *name, char *out, size_t size, cf_error *err) {
  int n;
  if (!dir || !dir[0] || name[0] == '/')
    n = snprintf(out, size, "%s", name);
  else
    n = snprintf(out, size, "%s%s%s", dir, dir[strlen(dir) - 1] == '/' ? "" : "/", name);
  if (n < 0 || (size_t)n >= size)
    return cf_error_set(err, CF_ERANGE, "path too long: %s/%s", dir ? dir : "", name);
  return CF_OK;
}

cf_status cf_path_dirname(const char *path, char *out, size_t size, cf_error *err) {
  const char *slash = strrchr(path, '/');
  int n;
  if (!slash)
    n = snprintf(out, size, ".");
  else if (slash == path)
    n = snprintf(out, size, "/");
  else
    n = snprintf(out, size, "%.*s", (int)(slash - path), path);
  if (n < 0 || (size_t)n >= size) return cf_error_set(err, CF_ERANGE, "path too long: %s", path);
  return CF_OK;
}

/* The real path of a folder, into out (size bytes). */
static cf_status real_folder(const char *folder, char *out, size_t size, cf_error *err) {
  char *real = realpath(folder, NULL);
  if (!real) return cf_error_set(err, CF_ENOTFOUND, "%s: %s", folder, strerror(errno));
  int n = snprintf(out, size, "%s", real);
  free(real);
  if (n < 0 || (size_t)n >= size) return cf_error_set(err, CF_ERANGE, "path too long: %s", folder);
  return CF_OK;
}

/* The length of the leading folders that the absolute paths a and b share
 * ("/x/y" and "/x/yz": "/x"), up to a '/' or the end of a and b. */
static size_t shared_folders(const char *a, const char *b) {
  size_t shared = 0;
  for (size_t i = 0;; ++i) {
    int a_end = a[i] == '/' || a[i] == '\0', b_end = b[i] == '/' || b[i] == '\0';
    if (a_end && b_end) shared = i;
    if (a[i] != b[i] || a[i] == '\0') return a_end && b_end ? i : shared;
  }
}

cf_status cf_path_relative(const char *from, const char *target, char *out, size_t size,
                           cf_error *err) {
  char folder[4096], from_real[4096], target_real[4096];
  cf_status s = cf_path_dirname(target, folder, sizeof folder, err);
  if (s == CF_OK) s = real_folder(from, from_real, sizeof from_real, err);
  if (s == CF_OK) s = real_folder(folder, target_real, sizeof target_real, err);
  if (s != CF_OK) return s;
  const char *name = strrchr(target, '/') ? strrchr(target, '/') + 1 : target;
  size_t n = strlen(target_real);
  if (snprintf(target_real + n, sizeof target_real - n, "%s%s", n > 1 ? "/" : "", name) >=
      (int)(sizeof target_real - n))
    return cf_error_set(err, CF_ERANGE, "path too long: %s", target);
  size_t shared = shared_folders(from_real, target_real);
  char relative[8192] = "";
  size_t used = 0;
  for (const char *p = from_real + shared; *p; ++p) /* one ../ per folder left in from */
    if (*p == '/' && p[1]) used += (size_t)snprintf(relative + used, sizeof relative - used, "../");
  const char *rest = target_real + shared + (target_real[shared] == '/');
  int n_out = snprintf(out, size, "%s%s", relative, rest);
  if (n_out < 0 || (size_t)n_out >= size)
    return cf_error_set(err, CF_ERANGE, "path too long: %s", target);
  return CF_OK;
}

int cf_path_exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

cf_status cf_make_dirs(const char *path, cf_error *err) {
  char buffer[4096];
  if (snprintf(buffer, sizeof buffer, "%s", path) >= (int)sizeof buffer)
    return cf_error_set(err, CF_ERANGE, "path too long: %s", path);
  for (char *p = buffer + 1;; ++p) {
    if (*p == '/' || *p == '\0') {
      char saved = *p;
      *p = '\0';
      if (mkdir(buffer, 0777) != 0 && errno != EEXIST)
        return cf_error_set(err, CF_EIO, "cannot create folder %s: %s", buffer, strerror(errno));
      *p = saved;
      if (saved == '\0') break;
    }
  }
  return CF_OK;
}
