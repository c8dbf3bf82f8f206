/* A fuzz target's code as a ctest test (tests/fuzz/fuzz.cmake): compiled
 * normally with the target (Release, or the ASan+UBSan build), it feeds
 * every file of the folders given through LLVMFuzzerTestOneInput as
 * libFuzzer runs them, in name order. A broken promise of the reader or a
 * crash fails the test. The folders: the target's seeds and the inputs
 * that once found a bug (tests/fuzz/regressions/TARGET).
 *   fuzz_run_TARGET DIR... */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv) __attribute__((weak));

/* Run the file at path; 0, or 1 when it cannot be read. */
static int run_file(const char *path) {
  FILE *file = fopen(path, "rb");
  if (!file) {
    perror(path);
    return 1;
  }
  size_t capacity = 4096, size = 0;
  uint8_t *data = malloc(capacity);
  size_t n;
  while (data && (n = fread(data + size, 1, capacity - size, file)) > 0) {
    size += n;
    if (size == capacity) {
      uint8_t *grown = realloc(data, capacity *= 2);
      if (!grown) free(data);
      data = grown;
    }
  }
  fclose(file);
  if (!data) {
    fprintf(stderr, "%s: out of memory\n", path);
    return 1;
  }
  fprintf(stderr, "input %s (%zu bytes)\n", path, size);
  LLVMFuzzerTestOneInput(data, size);
  free(data);
  return 0;
}

static int skip_entry(const struct dirent *entry) {
  return entry->d_name[0] != '.';
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s DIR...\n", argv[0]);
    return 2;
  }
  if (LLVMFuzzerInitialize) LLVMFuzzerInitialize(&argc, &argv);
  size_t inputs = 0;
  for (int a = 1; a < argc; ++a) {
    struct dirent **entries;
    int count = scandir(argv[a], &entries, skip_entry, alphasort);
    if (count < 0) {
      perror(argv[a]);
      return 1;
    }
    for (int i = 0; i < count; ++i) {
      char path[8192];
      snprintf(path, sizeof path, "%s/%s", argv[a], entries[i]->d_name);
      if (run_file(path) != 0) return 1;
      ++inputs;
      free(entries[i]);
    }
    free(entries);
  }
  printf("%zu inputs, every promise kept\n", inputs);
  return inputs > 0 ? 0 : 1;
}
