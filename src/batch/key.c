/* An entry's key: XXH3-128 over every file its capture reads, its options
 * and clayfit's build id. XXH3 is not a cryptographic hash: it detects
 * change (a collision by accident has a chance of 2^-128), not an
 * adversary forging one, which a library folder the user controls does
 * not need; it runs at memory speed (GB/s), so keying 16 large photos costs
 * little next to their fit. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "build_id.h"
#include "clayfit/batch.h"
#include "clayfit/capture.h"
#include "core/file.h"
#include "core/json_reader.h"

const char *cf_batch_build_id(void) { return CLAYFIT_BUILD_ID; }

/* A labelled field: its length first, so that fields cannot run into one
 * another ("ab" + "c" differs from "a" + "bc"). */
static void hash_field(XXH3_state_t *h, const char *label, const void *data, size_t size) {
  unsigned long long n = size;
  XXH3_128bits_update(h, label, strlen(label) + 1);
  XXH3_128bits_update(h, &n, sizeof n);
  XXH3_128bits_update(h, data, size);
}

/* A file's contents, in chunks (images are large); a file that cannot be
 * read is hashed as missing, so that the key exists and changes when the
 * file appears. Only a regular file is read: a FIFO would block and
 * /dev/zero never end, so anything else (opened without blocking, then
 * looked at) is hashed as such, and the task refuses it as clayfit fit
 * does. Its role in the list (the index) is hashed, its path not: a
 * capture moved with its files keeps its key. */
static cf_status hash_file(XXH3_state_t *h, const char *path, char *buffer, size_t size) {
  FILE *f;
  long long file_size;
  cf_error err;
  cf_status opened = cf_open_regular_file(path, &f, &file_size, &err);
  if (opened != CF_OK) {
    hash_field(h, opened == CF_ENOTFOUND ? "missing" : "not readable", "", 0);
    return CF_OK;
  }
  hash_field(h, "file", "", 0);
  size_t n;
  while ((n = fread(buffer, 1, size, f)) > 0) XXH3_128bits_update(h, buffer, n);
  int failed = ferror(f);
  fclose(f);
  if (failed) hash_field(h, "unreadable", "", 0);
  return CF_OK;
}

static cf_status hash_files(XXH3_state_t *h, const char *capture) {
  char **files = NULL;
  size_t count = 0;
  cf_error ignored = {0};
  /* a capture file that does not parse: its bytes alone (the task fails
   * and says why; the key changes when the file is fixed) */
  if (cf_capture_files(capture, &files, &count, &ignored) != CF_OK) files = NULL, count = 0;
  enum { CHUNK = 1 << 20 };
  char *buffer = malloc(CHUNK);
  if (!buffer) {
    cf_capture_files_free(files, count);
    return CF_ENOMEM;
  }
  if (!files) hash_file(h, capture, buffer, CHUNK);
  for (size_t i = 0; i < count; ++i) hash_file(h, files[i], buffer, CHUNK);
  unsigned long long n = count;
  hash_field(h, "file count", &n, sizeof n);
  free(buffer);
  cf_capture_files_free(files, count);
  return CF_OK;
}

cf_status cf_batch_entry_key(const cf_batch_entry *e, char key[CF_BATCH_KEY_SIZE],
                             cf_error *err) {
  XXH3_state_t *h = XXH3_createState();
  if (!h) return cf_error_set(err, CF_ENOMEM, "out of memory");
  XXH3_128bits_reset(h);
  const char *build = cf_batch_build_id();
  hash_field(h, "clayfit batch key 1", "", 0);
  hash_field(h, "build", build, strlen(build));
  /* the options as canonical JSON (sorted keys, shortest exact numbers) */
  char *options = e->options ? json_dumps(e->options, JSON_COMPACT | JSON_SORT_KEYS |
                                                          JSON_REAL_PRECISION(17))
                             : strdup("{}");
  cf_status s = options ? CF_OK : CF_ENOMEM;
  if (s == CF_OK) hash_field(h, "options", options, strlen(options));
  free(options);
  if (s == CF_OK) s = hash_files(h, e->capture);
  XXH128_hash_t digest = XXH3_128bits_digest(h);
  XXH3_freeState(h);
  if (s != CF_OK) return cf_error_set(err, s, "%s: out of memory hashing its files", e->name);
  snprintf(key, CF_BATCH_KEY_SIZE, "%016llx%016llx", (unsigned long long)digest.high64,
           (unsigned long long)digest.low64);
  return CF_OK;
}
