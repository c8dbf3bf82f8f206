/* Private helpers shared by the COLMAP readers and writers
 * (colmap_text.c, colmap_binary.c, colmap_read.c, colmap_write.c,
 * camera_model.c). Not part of the public interface. */
#ifndef CLAYFIT_CAPTURE_COLMAP_INTERNAL_H
#define CLAYFIT_CAPTURE_COLMAP_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "clayfit/colmap.h"

/* The longest image name accepted, in bytes (terminating NUL excluded). */
enum { CF_COLMAP_MAX_NAME = 4096 };

/* The name of parameter k of a model ("fx"), copied into buf; "params[k]"
 * when the model or k is unknown. Returns buf. */
const char *cf__camera_param_name(cf_camera_model model, int k, char *buf, size_t size);

/* "SIMPLE_PINHOLE, PINHOLE, ..." (with_ids = 0) or "0 (SIMPLE_PINHOLE),
 * 1 (PINHOLE), ..." (with_ids = 1), for messages. Returns buf. */
const char *cf__camera_model_list(int with_ids, char *buf, size_t size);

/* Grow *array (of elem_size-byte elements, *capacity of them) to hold at
 * least `needed`; doubling, with every product checked for overflow.
 * CF_ENOMEM (err untouched) when it cannot. */
cf_status cf__grow(void **array, size_t *capacity, size_t needed, size_t elem_size);

/* Append n elements to *array (holding *count), reallocating it to exactly
 * *count + n. CF_ENOMEM (err untouched, *array intact) when it cannot. */
cf_status cf__append(void **array, size_t *count, const void *items, size_t n, size_t elem_size);

/* Look for an id used twice among ids[0..total), of which the first
 * `existing` are already in the model and the rest are new. Returns 1 and
 * the pair (*first < *second, *second >= existing, the smallest such
 * *second) when there is one, 0 when there is none, -1 when out of memory. */
int cf__find_duplicate_id(const uint64_t *ids, size_t existing, size_t total, size_t *first,
                          size_t *second);

/* Release the names, points and tracks of n records and the array. */
void cf__free_images(cf_colmap_image *images, size_t n);
void cf__free_points3d(cf_point3d *points, size_t n);

#endif /* CLAYFIT_CAPTURE_COLMAP_INTERNAL_H */
