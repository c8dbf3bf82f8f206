/* Helpers shared by the COLMAP readers: checked growth of arrays, the
 * duplicate-id search, releasing partly built records
 * (src/capture/colmap_internal.h). */
#include <stdlib.h>
#include <string.h>

#include "colmap_internal.h"

cf_status cf__grow(void **array, size_t *capacity, size_t needed, size_t elem_size) {
  if (needed <= *capacity) return CF_OK;
  size_t grown = *capacity ? *capacity : 16;
  while (grown < needed) {
    if (grown > SIZE_MAX / 2) {
      grown = needed;
      break;
    }
    grown *= 2;
  }
  if (elem_size && grown > SIZE_MAX / elem_size) return CF_ENOMEM;
  void *bigger = realloc(*array, grown * elem_size);
  if (!bigger) return CF_ENOMEM;
  *array = bigger;
  *capacity = grown;
  return CF_OK;
}

cf_status cf__append(void **array, size_t *count, const void *items, size_t n, size_t elem_size) {
  if (n == 0) return CF_OK;
  if (n > SIZE_MAX - *count) return CF_ENOMEM;
  size_t total = *count + n;
  if (elem_size && total > SIZE_MAX / elem_size) return CF_ENOMEM;
  void *bigger = realloc(*array, total * elem_size);
  if (!bigger) return CF_ENOMEM;
  memcpy((char *)bigger + *count * elem_size, items, n * elem_size);
  *array = bigger;
  *count = total;
  return CF_OK;
}

typedef struct id_entry {
  uint64_t id;
  size_t index;
} id_entry;

static int compare_id_entries(const void *a, const void *b) {
  const id_entry *x = a, *y = b;
  if (x->id != y->id) return x->id < y->id ? -1 : 1;
  return x->index < y->index ? -1 : x->index > y->index;
}

int cf__find_duplicate_id(const uint64_t *ids, size_t existing, size_t total, size_t *first,
                          size_t *second) {
  if (total < 2) return 0;
  id_entry *entries = malloc(total * sizeof *entries);
  if (!entries) return -1;
  for (size_t i = 0; i < total; ++i) entries[i] = (id_entry){ids[i], i};
  qsort(entries, total, sizeof *entries, compare_id_entries);
  int found = 0;
  for (size_t run = 0; run < total;) {
    size_t end = run + 1;
    while (end < total && entries[end].id == entries[run].id) ++end;
    /* within a run, indices ascend: the first is the earliest use, the
     * first new one after it the duplicate to report */
    for (size_t k = run + 1; k < end; ++k) {
      if (entries[k].index < existing) continue;
      if (!found || entries[k].index < *second) {
        *first = entries[run].index;
        *second = entries[k].index;
        found = 1;
      }
      break;
    }
    run = end;
  }
  free(entries);
  return found;
}

void cf__free_images(cf_colmap_image *images, size_t n) {
  if (!images) return;
  for (size_t i = 0; i < n; ++i) {
    free(images[i].name);
    free(images[i].points2d);
  }
  free(images);
}

void cf__free_points3d(cf_point3d *points, size_t n) {
  if (!points) return;
  for (size_t i = 0; i < n; ++i) free(points[i].track);
  free(points);
}
