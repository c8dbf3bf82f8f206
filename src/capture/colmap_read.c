/* Reading a COLMAP sparse model folder (the thin path wrapper around the
 * memory cores of colmap_text.c and colmap_binary.c, after
 * Reconstruction::Read in src/base/reconstruction.cc), the checks across
 * its files, releasing it, and the look-ups. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "colmap_internal.h"
#include "clayfit/colmap.h"
#include "core/file.h"

/* The largest model file read: 4 GiB (or half the address space). */
#define COLMAP_MAX_FILE_SIZE (SIZE_MAX > 0xFFFFFFFFu ? (size_t)0x100000000ull : SIZE_MAX / 2)

void cf_colmap_model_free(cf_colmap_model *model) {
  if (!model) return;
  free(model->cameras);
  cf__free_images(model->images, model->num_images);
  cf__free_points3d(model->points3d, model->num_points3d);
  memset(model, 0, sizeof *model);
}

const cf_camera *cf_colmap_find_camera(const cf_colmap_model *model, uint32_t camera_id) {
  for (size_t i = 0; i < model->num_cameras; ++i)
    if (model->cameras[i].camera_id == camera_id) return &model->cameras[i];
  return NULL;
}

const cf_colmap_image *cf_colmap_find_image_by_name(const cf_colmap_model *model,
                                                    const char *name) {
  for (size_t i = 0; i < model->num_images; ++i)
    if (model->images[i].name && strcmp(model->images[i].name, name) == 0) return &model->images[i];
  return NULL;
}

typedef cf_status (*text_parser)(const char *, size_t, const char *, cf_colmap_model *, cf_error *);
typedef cf_status (*binary_parser)(const uint8_t *, size_t, const char *, cf_colmap_model *,
                                   cf_error *);

/* Read dir/file and parse it with the text or the binary core. */
static cf_status read_one(const char *dir, const char *file, text_parser text, binary_parser binary,
                          cf_colmap_model *model, char *path, size_t path_size, cf_error *err) {
  cf_status s = cf_path_join(dir, file, path, path_size, err);
  if (s != CF_OK) return s;
  char *data;
  size_t size;
  if ((s = cf_read_file(path, COLMAP_MAX_FILE_SIZE, &data, &size, err)) != CF_OK) return s;
  s = text ? text(data, size, path, model, err)
           : binary((const uint8_t *)data, size, path, model, err);
  free(data);
  return s;
}

static int exists_in(const char *dir, const char *file) {
  char path[4096];
  return cf_path_join(dir, file, path, sizeof path, NULL) == CF_OK && cf_path_exists(path);
}

static int compare_names(const void *a, const void *b) {
  const cf_colmap_image *x = *(const cf_colmap_image *const *)a;
  const cf_colmap_image *y = *(const cf_colmap_image *const *)b;
  int c = strcmp(x->name, y->name);
  if (c) return c;
  return x->image_id < y->image_id ? -1 : x->image_id > y->image_id;
}

/* Two images of one name would make look-ups by name ambiguous. */
static cf_status check_unique_names(const cf_colmap_model *model, const char *images_path,
                                    cf_error *err) {
  if (model->num_images < 2) return CF_OK;
  const cf_colmap_image **sorted = malloc(model->num_images * sizeof *sorted);
  if (!sorted) return cf_error_set(err, CF_ENOMEM, "%s: out of memory", images_path);
  for (size_t i = 0; i < model->num_images; ++i) sorted[i] = &model->images[i];
  qsort(sorted, model->num_images, sizeof *sorted, compare_names);
  cf_status s = CF_OK;
  for (size_t i = 1; i < model->num_images && s == CF_OK; ++i) {
    if (strcmp(sorted[i - 1]->name, sorted[i]->name) == 0)
      s = cf_error_set(err, CF_EPARSE, "%s: images %u and %u have the same name '%s'", images_path,
                       sorted[i - 1]->image_id, sorted[i]->image_id, sorted[i]->name);
  }
  free(sorted);
  return s;
}

/* Normalise q unless it is already of unit length to rounding (then it is
 * left bit for bit, so that reading what was written gives it back). */
static cf_status normalise_quaternion(cf_colmap_image *image, const char *images_path,
                                      cf_error *err) {
  double *q = image->qvec;
  double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (!isfinite(n2) || !(n2 > 0.0))
    return cf_error_set(err, CF_EPARSE,
                        "%s: image %u (%s): quaternion (%g, %g, %g, %g) %s; it must be finite and "
                        "of non-zero length",
                        images_path, image->image_id, image->name, q[0], q[1], q[2], q[3],
                        isfinite(n2) ? "has zero length" : "is not finite");
  if (fabs(n2 - 1.0) > 8.0 * 2.220446049250313e-16) {
    double n = sqrt(n2);
    for (int k = 0; k < 4; ++k) q[k] /= n;
  }
  return CF_OK;
}

/* The checks across files: cameras valid, every image's camera present,
 * quaternions usable (and normalised), names unique. */
static cf_status check_model(cf_colmap_model *model, const char *cameras_path,
                             const char *images_path, cf_error *err) {
  for (size_t i = 0; i < model->num_cameras; ++i) {
    cf_status s = cf_camera_check(&model->cameras[i], err);
    if (s != CF_OK) {
      cf_error_prefix(err, "%s", cameras_path);
      return s;
    }
  }
  for (size_t i = 0; i < model->num_images; ++i) {
    cf_colmap_image *image = &model->images[i];
    if (!cf_colmap_find_camera(model, image->camera_id))
      return cf_error_set(err, CF_EPARSE, "%s: image %u (%s): camera_id %u names no camera in %s",
                          images_path, image->image_id, image->name, image->camera_id,
                          cameras_path);
    cf_status s = normalise_quaternion(image, images_path, err);
    if (s != CF_OK) return s;
  }
  return check_unique_names(model, images_path, err);
}

cf_status cf_colmap_read(const char *dir, int with_points, cf_colmap_model *model, cf_error *err) {
  memset(model, 0, sizeof *model);
  if (!cf_path_exists(dir)) return cf_error_set(err, CF_ENOTFOUND, "%s: no such folder", dir);
  int binary = exists_in(dir, "cameras.bin") && exists_in(dir, "images.bin") &&
               (!with_points || exists_in(dir, "points3D.bin"));
  if (!binary && !exists_in(dir, "cameras.txt") && !exists_in(dir, "images.txt"))
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: no COLMAP sparse model here (neither cameras.bin, images.bin, "
                        "points3D.bin nor cameras.txt, images.txt, points3D.txt)",
                        dir);
  char cameras_path[4096], images_path[4096], points_path[4096];
  cf_status s;
  if (binary) {
    s = read_one(dir, "cameras.bin", NULL, cf_colmap_parse_cameras_binary, model, cameras_path,
                 sizeof cameras_path, err);
    if (s == CF_OK)
      s = read_one(dir, "images.bin", NULL, cf_colmap_parse_images_binary, model, images_path,
                   sizeof images_path, err);
    if (s == CF_OK && with_points)
      s = read_one(dir, "points3D.bin", NULL, cf_colmap_parse_points3d_binary, model, points_path,
                   sizeof points_path, err);
  } else {
    s = read_one(dir, "cameras.txt", cf_colmap_parse_cameras_text, NULL, model, cameras_path,
                 sizeof cameras_path, err);
    if (s == CF_OK)
      s = read_one(dir, "images.txt", cf_colmap_parse_images_text, NULL, model, images_path,
                   sizeof images_path, err);
    if (s == CF_OK && with_points)
      s = read_one(dir, "points3D.txt", cf_colmap_parse_points3d_text, NULL, model, points_path,
                   sizeof points_path, err);
  }
  if (s == CF_OK) s = check_model(model, cameras_path, images_path, err);
  if (s != CF_OK) cf_colmap_model_free(model);
  return s;
}
