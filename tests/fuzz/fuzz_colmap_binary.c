/* libFuzzer target for the COLMAP model readers (built and run by
 * scripts/fuzz.sh): the bytes go to the three binary parsers and, as text,
 * to the three text parsers, all appending to one model (so that ids
 * already present are exercised too); the cameras that pass
 * cf_camera_check are then projected and unprojected. Besides crashes and
 * sanitizer reports, a broken promise of the readers aborts: a failure
 * must leave the model as it was and name the file in its message. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/colmap.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef cf_status (*parser)(const uint8_t *, size_t, const char *, cf_colmap_model *, cf_error *);

static cf_status cameras_text(const uint8_t *d, size_t n, const char *name, cf_colmap_model *m,
                              cf_error *e) {
  return cf_colmap_parse_cameras_text((const char *)d, n, name, m, e);
}
static cf_status images_text(const uint8_t *d, size_t n, const char *name, cf_colmap_model *m,
                             cf_error *e) {
  return cf_colmap_parse_images_text((const char *)d, n, name, m, e);
}
static cf_status points3d_text(const uint8_t *d, size_t n, const char *name, cf_colmap_model *m,
                               cf_error *e) {
  return cf_colmap_parse_points3d_text((const char *)d, n, name, m, e);
}

static size_t records(const cf_colmap_model *m) {
  return m->num_cameras + m->num_images + m->num_points3d;
}

/* Projection and unprojection of a valid camera: no crash, and a pixel
 * that unprojects comes back: to the promised 1e-12 in normalised
 * coordinates (1e-12 focal lengths), plus the rounding of f x + c, which
 * grows with the size of the principal point and the pixel. */
static void exercise_camera(const cf_camera *c) {
  const double w = (double)c->width, h = (double)c->height;
  const double pixels[5][2] = {{0.5, 0.5}, {w / 2, h / 2}, {w, h}, {0, h}, {w * 0.3, h * 0.8}};
  for (int k = 0; k < 5; ++k) {
    double ray[3], uv[2];
    if (!cf_camera_unproject(c, pixels[k], ray)) continue;
    if (!cf_camera_project(c, ray, uv)) continue;
    double intrinsics = fabs(c->params[0]) + fabs(c->params[1]) + fabs(c->params[2]) +
                        (c->num_params > 3 ? fabs(c->params[3]) : 0.0);
    double tolerance = 2e-12 * intrinsics + 1e-9 * (1.0 + fabs(pixels[k][0]) + fabs(pixels[k][1]));
    if (!(fabs(uv[0] - pixels[k][0]) <= tolerance && fabs(uv[1] - pixels[k][1]) <= tolerance))
      abort();
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static const parser parsers[6] = {cf_colmap_parse_cameras_binary,
                                    cf_colmap_parse_images_binary,
                                    cf_colmap_parse_points3d_binary,
                                    cameras_text,
                                    images_text,
                                    points3d_text};
  static const char *const names[6] = {"cameras.bin", "images.bin", "points3D.bin",
                                       "cameras.txt", "images.txt", "points3D.txt"};
  cf_colmap_model model = {0};
  for (int k = 0; k < 6; ++k) {
    cf_error err = {0};
    size_t before = records(&model);
    cf_status s = parsers[k](data, size, names[k], &model, &err);
    if (s != CF_OK &&
        (records(&model) != before || strncmp(err.message, names[k], strlen(names[k])) != 0))
      abort();
  }
  for (size_t i = 0; i < model.num_cameras; ++i)
    if (cf_camera_check(&model.cameras[i], NULL) == CF_OK) exercise_camera(&model.cameras[i]);
  cf_colmap_model_free(&model);
  return 0;
}
