/* The helpers the capture file's reader shares among its files:
 * capture_spec.c (the reader and the whole file), capture_spec_lights.c
 * (the lights and the reference target) and capture_files.c (the files a
 * capture reads). Private to src/capture. */
#ifndef CLAYFIT_CAPTURE_SPEC_INTERNAL_H
#define CLAYFIT_CAPTURE_SPEC_INTERNAL_H

#include <stddef.h>

#include "capture_spec.h"
#include "clayfit/status.h"
#include "core/json_reader.h"

/* The longest path the reader builds, in bytes. */
enum { MAX_PATH_LENGTH = 4096 };

/* A copy of text (malloc'd), or NULL when out of memory. */
char *cf__spec_copy_string(const char *text);

/* A path from the file, resolved against `dir`. */
cf_status cf__spec_resolve(const char *dir, const char *name, const json_at *at, char **out,
                           cf_error *err);

/* CF_ENOMEM, "out of memory reading the capture file". */
cf_status cf__spec_out_of_memory(cf_error *err);

/* Free count strings and their array (NULL: nothing). */
void cf__spec_free_strings(char **strings, size_t count);

/* The capture file's "lights" (1 to 64) into spec->lights: needs the
 * camera, scale and radiometry read first. */
cf_status cf__spec_read_lights(const json_t *root, const json_at *at, cf_capture_spec *spec,
                               cf_error *err);

/* The capture file's optional "reference" target: needs the images,
 * radiometry and lights read first. */
cf_status cf__spec_read_reference(const json_t *root, const json_at *at, cf_capture_spec *spec,
                                  cf_error *err);

#endif /* CLAYFIT_CAPTURE_SPEC_INTERNAL_H */
