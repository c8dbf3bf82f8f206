/* The files a capture reads (cf_capture_files, include/clayfit/capture.h:
 * clayfit batch's keys): the capture file, the image list, images and
 * masks, the COLMAP model's files, the normal map and the light files, as
 * the capture file (capture_spec.c) names them. */
#include <stdlib.h>

#include "capture_spec.h"
#include "capture_spec_internal.h"
#include "clayfit/capture.h"
#include "core/file.h"

typedef struct file_list {
  char **files;
  size_t count, capacity;
} file_list;

static cf_status list_add(file_list *l, const char *path) {
  if (!path) return CF_OK;
  if (l->count == l->capacity) {
    size_t capacity = l->capacity ? 2 * l->capacity : 16;
    char **grown = realloc(l->files, capacity * sizeof *grown);
    if (!grown) return CF_ENOMEM;
    l->files = grown;
    l->capacity = capacity;
  }
  if (!(l->files[l->count] = cf__spec_copy_string(path))) return CF_ENOMEM;
  l->count++;
  return CF_OK;
}

/* The COLMAP model's files that exist (the reader takes .bin when the set
 * is there, else .txt: listing both follows either). */
static cf_status list_colmap(file_list *l, const char *dir) {
  static const char *const names[] = {"cameras.bin", "images.bin", "points3D.bin",
                                      "cameras.txt", "images.txt", "points3D.txt"};
  char path[MAX_PATH_LENGTH];
  cf_status s = CF_OK;
  for (size_t k = 0; s == CF_OK && k < sizeof names / sizeof names[0]; ++k) {
    cf_error ignored;
    if (cf_path_join(dir, names[k], path, sizeof path, &ignored) == CF_OK && cf_path_exists(path))
      s = list_add(l, path);
  }
  return s;
}

static cf_status list_spec_files(const cf_capture_spec *spec, file_list *l) {
  cf_status s = list_add(l, spec->path);
  if (s == CF_OK) s = list_add(l, spec->image_list);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i) {
    s = list_add(l, spec->image_paths[i]);
    if (s == CF_OK && spec->mask_paths) s = list_add(l, spec->mask_paths[i]);
  }
  if (s == CF_OK && spec->camera == CF_CAMERA_KIND_COLMAP && spec->colmap_model)
    s = list_colmap(l, spec->colmap_model);
  if (s == CF_OK) s = list_add(l, spec->normal_map);
  for (size_t i = 0; s == CF_OK && i < spec->num_lights; ++i) {
    s = list_add(l, spec->lights[i].directions);
    if (s == CF_OK) s = list_add(l, spec->lights[i].intensities);
    if (s == CF_OK) s = list_add(l, spec->lights[i].file);
  }
  return s;
}

cf_status cf_capture_files(const char *path, char ***files, size_t *count, cf_error *err) {
  *files = NULL;
  *count = 0;
  cf_capture_spec spec;
  cf_status s = cf_capture_spec_read(path, &spec, err);
  if (s != CF_OK) return s;
  file_list l = {0};
  s = list_spec_files(&spec, &l);
  cf_capture_spec_free(&spec);
  if (s != CF_OK) {
    cf_capture_files_free(l.files, l.count);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory listing its files", path);
  }
  *files = l.files;
  *count = l.count;
  return CF_OK;
}

void cf_capture_files_free(char **files, size_t count) {
  cf__spec_free_strings(files, count);
}
