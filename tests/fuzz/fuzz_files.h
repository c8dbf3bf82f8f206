/* Files for the fuzz targets whose reader takes a path (the capture file,
 * its text files, fit.json, images): one scratch folder per process,
 * $TMPDIR/clayfit-fuzz-XXXXXX (scripts/fuzz.sh points TMPDIR into
 * build/fuzz), emptied and removed at exit. Header-only, C and C++. */
#ifndef CLAYFIT_FUZZ_FILES_H
#define CLAYFIT_FUZZ_FILES_H

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char fuzz_folder_path[4096];

static inline void fuzz_folder_remove(void) {
  DIR *dir = opendir(fuzz_folder_path);
  if (dir) {
    struct dirent *entry;
    char path[8192];
    while ((entry = readdir(dir)))
      if (strcmp(entry->d_name, ".") != 0 && strcmp(entry->d_name, "..") != 0) {
        int n = snprintf(path, sizeof path, "%s/%s", fuzz_folder_path, entry->d_name);
        if (n > 0 && (size_t)n < sizeof path) unlink(path);
      }
    closedir(dir);
  }
  rmdir(fuzz_folder_path);
}

/* The process's scratch folder, made on first use. */
static inline const char *fuzz_folder(void) {
  if (!fuzz_folder_path[0]) {
    const char *tmp = getenv("TMPDIR");
    int n = snprintf(fuzz_folder_path, sizeof fuzz_folder_path, "%s/clayfit-fuzz-XXXXXX",
                     tmp && tmp[0] ? tmp : "/tmp");
    if (n < 0 || (size_t)n >= sizeof fuzz_folder_path || !mkdtemp(fuzz_folder_path)) {
      perror(fuzz_folder_path);
      abort();
    }
    atexit(fuzz_folder_remove);
  }
  return fuzz_folder_path;
}

/* Write `size` bytes to file `name` of the scratch folder; its path goes to
 * `path` (4096 bytes). A failure to write is the harness's, not the
 * reader's: abort with a message. */
static inline void fuzz_write(const char *name, const void *data, size_t size, char *path) {
  int n = snprintf(path, 4096, "%s/%s", fuzz_folder(), name);
  FILE *file = n > 0 && n < 4096 ? fopen(path, "wb") : NULL;
  if (!file || (size && fwrite(data, 1, size, file) != size) || fclose(file) != 0) {
    perror(path);
    abort();
  }
}

/* The same for a NUL-terminated text. */
static inline void fuzz_write_text(const char *name, const char *text, char *path) {
  fuzz_write(name, text, strlen(text), path);
}

/* Abort with a message when a promise of the reader is broken (a crash for
 * libFuzzer, a failure for the regression run). */
static inline void fuzz_require(int condition, const char *what, const char *message) {
  if (condition) return;
  fprintf(stderr, "fuzz: broken promise: %s (message: '%s')\n", what, message ? message : "");
  abort();
}

#endif /* CLAYFIT_FUZZ_FILES_H */
