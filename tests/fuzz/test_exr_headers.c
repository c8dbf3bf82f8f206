/* The OpenEXR files that made OpenEXR 3.1 allocate what their headers
 * declare, found by fuzz_image (tests/fuzz/regressions/fuzz_image/exr-*):
 * an attribute of 0.8 and of 1.6 GB, a box2i declared 4 bytes long (read
 * as 16, the rest misread into a 1.7 GB attribute), and a scan line 1.8 GB
 * wide, all from files of a few hundred bytes. They are refused before
 * OpenEXR reads them: cf_image_read_header says CF_EPARSE, "a corrupt
 * OpenEXR header", and names the file. Before, OpenEXR allocated the size
 * and the read failed later (CF_EIO).
 *   test_exr_headers REGRESSIONS_DIR */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/image.h"
#include "core/file.h"
#include "fuzz_files.h"

static int check(const char *dir, const char *name) {
  char input[4096], path[4096];
  snprintf(input, sizeof input, "%s/%s", dir, name);
  char *bytes;
  size_t size;
  cf_error err = {0};
  if (cf_read_file(input, 1 << 20, &bytes, &size, &err) != CF_OK || size < 2) {
    fprintf(stderr, "FAIL %s: %s\n", name, err.message);
    return 1;
  }
  fuzz_write("bomb.exr", bytes + 1, size - 1, path); /* after fuzz_image's selector byte */
  free(bytes);
  cf_image_header header;
  cf_status s = cf_image_read_header(path, &header, &err);
  int ok = s == CF_EPARSE && strstr(err.message, path) &&
           strstr(err.message, "a corrupt OpenEXR header");
  printf("%s %s: status %d, '%s'\n", ok ? "ok  " : "FAIL", name, (int)s, err.message);
  return !ok;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: test_exr_headers REGRESSIONS_DIR\n");
    return 2;
  }
  int failed = check(argv[1], "exr-attribute-size-1.6GB");
  failed |= check(argv[1], "exr-attribute-size-800MB");
  failed |= check(argv[1], "exr-box2i-declared-4-bytes");
  failed |= check(argv[1], "exr-scan-line-1.8GB");
  return failed;
}
