/* COLMAP 3.8's binary model files (cameras.bin, images.bin, points3D.bin)
 * parsed from memory. The layouts are those of Reconstruction::Read*Binary
 * and Write*Binary in src/base/reconstruction.cc, little-endian:
 *
 *   cameras.bin   uint64 count; per camera: uint32 camera_id, int32 model_id,
 *                 uint64 width, uint64 height, double params[model's count]
 *   images.bin    uint64 count; per image: uint32 image_id, double qw qx qy qz,
 *                 double tx ty tz, uint32 camera_id, name + NUL,
 *                 uint64 num_points2D, per point: double x, double y,
 *                 uint64 point3D_id (UINT64_MAX = none)
 *   points3D.bin  uint64 count; per point: uint64 point3D_id, double x y z,
 *                 uint8 r g b, double error, uint64 track_length,
 *                 per element: uint32 image_id, uint32 point2D_idx
 *
 * COLMAP trusts these bytes; here every count is checked against the bytes
 * that remain before anything is allocated, every value as it is read, and
 * an error names the file, the byte offset, the record and the field. The
 * records are parsed into arrays of their own and appended to the model
 * only when the whole file is good, so a failure leaves the model as it
 * was. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "colmap_internal.h"
#include "clayfit/colmap.h"

/* Record sizes without their variable parts, for the count checks. */
enum {
  CAMERA_MIN_BYTES = 4 + 4 + 8 + 8 + 3 * 8, /* the smallest model has 3 parameters */
  IMAGE_MIN_BYTES = 4 + 7 * 8 + 4 + 2 + 8,  /* a one-byte name and its NUL */
  POINT2D_BYTES = 8 + 8 + 8,
  POINT3D_MIN_BYTES = 8 + 3 * 8 + 3 + 8 + 8,
  TRACK_ELEMENT_BYTES = 4 + 4
};

typedef struct reader {
  const uint8_t *data;
  size_t size, pos;
  const char *name;  /* the file, for messages */
  char record[96];   /* "image record 5 of 9 (image_id 12)" */
  const char *array; /* "points2D" while inside a record's array, else NULL */
  size_t item;       /* the element of that array */
  cf_error *err;
} reader;

static size_t remaining(const reader *r) {
  return r->size - r->pos;
}

/* "qw", or "points2D[17].x" inside an array. */
static const char *field_label(const reader *r, const char *field, char *buf, size_t size) {
  if (r->array)
    snprintf(buf, size, "%s[%zu].%s", r->array, r->item, field);
  else
    snprintf(buf, size, "%s", field);
  return buf;
}

/* A message about the field at byte offset `at`. */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
static cf_status
field_error(reader *r, size_t at, const char *field, const char *format, ...);

static cf_status field_error(reader *r, size_t at, const char *field, const char *format, ...) {
  char what[512], label[96];
  va_list args;
  va_start(args, format);
  vsnprintf(what, sizeof what, format, args);
  va_end(args);
  return cf_error_set(r->err, CF_EPARSE, "%s: byte %zu: %s: field %s: %s", r->name, at, r->record,
                      field_label(r, field, label, sizeof label), what);
}

/* Make sure `bytes` more can be read for `field`. */
static cf_status need(reader *r, size_t bytes, const char *field) {
  if (remaining(r) >= bytes) return CF_OK;
  return field_error(r, r->pos, field, "the file ends here; %zu bytes needed but %zu remain", bytes,
                     remaining(r));
}

static uint64_t load_le(const uint8_t *p, int bytes) {
  uint64_t v = 0;
  for (int k = bytes - 1; k >= 0; --k) v = (v << 8) | p[k];
  return v;
}

static cf_status read_u8(reader *r, const char *field, uint8_t *v) {
  cf_status s = need(r, 1, field);
  if (s != CF_OK) return s;
  *v = r->data[r->pos++];
  return CF_OK;
}

static cf_status read_u32(reader *r, const char *field, uint32_t *v) {
  cf_status s = need(r, 4, field);
  if (s != CF_OK) return s;
  *v = (uint32_t)load_le(r->data + r->pos, 4);
  r->pos += 4;
  return CF_OK;
}

static cf_status read_i32(reader *r, const char *field, int32_t *v) {
  uint32_t bits;
  cf_status s = read_u32(r, field, &bits);
  if (s != CF_OK) return s;
  *v = bits <= INT32_MAX ? (int32_t)bits : -(int32_t)(UINT32_MAX - bits) - 1;
  return CF_OK;
}

static cf_status read_u64(reader *r, const char *field, uint64_t *v) {
  cf_status s = need(r, 8, field);
  if (s != CF_OK) return s;
  *v = load_le(r->data + r->pos, 8);
  r->pos += 8;
  return CF_OK;
}

/* A double that must be finite. */
static cf_status read_finite(reader *r, const char *field, double *v) {
  size_t at = r->pos;
  uint64_t bits;
  cf_status s = read_u64(r, field, &bits);
  if (s != CF_OK) return s;
  memcpy(v, &bits, sizeof *v);
  if (!isfinite(*v)) return field_error(r, at, field, "%g is not a finite number", *v);
  return CF_OK;
}

/* A count of `unit`-byte elements that must fit in the bytes that remain
 * (each element at least `unit` bytes), checked before any allocation. */
static cf_status read_count(reader *r, const char *field, size_t unit, const char *what,
                            size_t *count) {
  size_t at = r->pos;
  uint64_t n;
  cf_status s = read_u64(r, field, &n);
  if (s != CF_OK) return s;
  if (n > remaining(r) / unit)
    return field_error(
        r, at, field, "%llu %s of at least %zu bytes each need more than the %zu bytes that remain",
        (unsigned long long)n, what, unit, remaining(r));
  *count = (size_t)n;
  return CF_OK;
}

/* Trailing bytes mean the counts and the data disagree. */
static cf_status check_end(reader *r, const char *what) {
  if (r->pos == r->size) return CF_OK;
  return cf_error_set(r->err, CF_EPARSE, "%s: byte %zu: %zu bytes follow the last %s", r->name,
                      r->pos, remaining(r), what);
}

static cf_status out_of_memory(reader *r) {
  return cf_error_set(r->err, CF_ENOMEM, "%s: out of memory", r->name);
}

/* An id used twice, in this file or already in the model. */
static cf_status check_duplicates(reader *r, const uint64_t *ids, size_t existing, size_t total,
                                  const size_t *offsets, const char *kind, const char *id_field) {
  size_t first, second;
  int found = cf__find_duplicate_id(ids, existing, total, &first, &second);
  if (found < 0) return out_of_memory(r);
  if (!found) return CF_OK;
  size_t record = second - existing;
  if (first < existing)
    return cf_error_set(
        r->err, CF_EPARSE, "%s: byte %zu: %s record %zu: %s %llu is already in the model", r->name,
        offsets[record], kind, record + 1, id_field, (unsigned long long)ids[second]);
  return cf_error_set(r->err, CF_EPARSE,
                      "%s: byte %zu: %s record %zu: %s %llu is used twice (first by %s record %zu "
                      "at byte %zu)",
                      r->name, offsets[record], kind, record + 1, id_field,
                      (unsigned long long)ids[second], kind, first - existing + 1,
                      offsets[first - existing]);
}

/* ---- cameras.bin ---- */

static cf_status read_camera(reader *r, size_t index, size_t count, cf_camera *camera) {
  snprintf(r->record, sizeof r->record, "camera record %zu of %zu", index + 1, count);
  cf_status s = read_u32(r, "camera_id", &camera->camera_id);
  if (s != CF_OK) return s;
  snprintf(r->record, sizeof r->record, "camera record %zu of %zu (camera_id %u)", index + 1, count,
           camera->camera_id);
  size_t at = r->pos;
  int32_t model_id;
  if ((s = read_i32(r, "model_id", &model_id)) != CF_OK) return s;
  if (model_id < 0 || model_id >= CF_CAMERA_MODEL_COUNT) {
    char known[512];
    return field_error(r, at, "model_id", "unknown camera model id %d; the known ids are %s",
                       (int)model_id, cf__camera_model_list(1, known, sizeof known));
  }
  camera->model = (cf_camera_model)model_id;
  camera->num_params = cf_camera_model_param_count(camera->model);
  if ((s = read_u64(r, "width", &camera->width)) != CF_OK) return s;
  if ((s = read_u64(r, "height", &camera->height)) != CF_OK) return s;
  for (int k = 0; k < camera->num_params; ++k) {
    char name[32];
    cf__camera_param_name(camera->model, k, name, sizeof name);
    if ((s = read_finite(r, name, &camera->params[k])) != CF_OK) return s;
  }
  return CF_OK;
}

cf_status cf_colmap_parse_cameras_binary(const uint8_t *data, size_t size, const char *name,
                                         cf_colmap_model *model, cf_error *err) {
  reader r = {.data = data, .size = size, .name = name, .err = err};
  snprintf(r.record, sizeof r.record, "header");
  size_t count;
  cf_status s = read_count(&r, "num_cameras", CAMERA_MIN_BYTES, "cameras", &count);
  if (s != CF_OK) return s;
  cf_camera *cameras = calloc(count ? count : 1, sizeof *cameras);
  size_t *offsets = calloc(count ? count : 1, sizeof *offsets);
  uint64_t *ids = calloc(model->num_cameras + count + 1, sizeof *ids);
  if (!cameras || !offsets || !ids) s = out_of_memory(&r);
  for (size_t i = 0; s == CF_OK && i < count; ++i) {
    offsets[i] = r.pos;
    s = read_camera(&r, i, count, &cameras[i]);
  }
  if (s == CF_OK) s = check_end(&r, "camera");
  if (s == CF_OK) {
    for (size_t i = 0; i < model->num_cameras; ++i) ids[i] = model->cameras[i].camera_id;
    for (size_t i = 0; i < count; ++i) ids[model->num_cameras + i] = cameras[i].camera_id;
    s = check_duplicates(&r, ids, model->num_cameras, model->num_cameras + count, offsets, "camera",
                         "camera_id");
  }
  if (s == CF_OK && cf__append((void **)&model->cameras, &model->num_cameras, cameras, count,
                               sizeof *cameras) != CF_OK)
    s = out_of_memory(&r);
  free(cameras);
  free(offsets);
  free(ids);
  return s;
}

/* ---- images.bin ---- */

/* The NUL-terminated name at the reader's position. */
static cf_status read_name(reader *r, char **name) {
  size_t at = r->pos;
  size_t window = remaining(r) < CF_COLMAP_MAX_NAME + 1 ? remaining(r) : CF_COLMAP_MAX_NAME + 1;
  const uint8_t *nul = memchr(r->data + r->pos, 0, window);
  if (!nul) {
    if (window <= CF_COLMAP_MAX_NAME)
      return field_error(r, at, "name", "no terminating NUL before the end of the file (%zu bytes)",
                         window);
    return field_error(r, at, "name", "longer than %d bytes (no NUL among them)",
                       CF_COLMAP_MAX_NAME);
  }
  size_t length = (size_t)(nul - (r->data + r->pos));
  if (length == 0) return field_error(r, at, "name", "the name is empty");
  *name = malloc(length + 1);
  if (!*name) return out_of_memory(r);
  memcpy(*name, r->data + r->pos, length + 1);
  r->pos += length + 1;
  return CF_OK;
}

static cf_status read_point2d(reader *r, cf_point2d *point) {
  cf_status s;
  if ((s = read_finite(r, "x", &point->x)) != CF_OK) return s;
  if ((s = read_finite(r, "y", &point->y)) != CF_OK) return s;
  size_t at = r->pos;
  uint64_t id;
  if ((s = read_u64(r, "point3D_id", &id)) != CF_OK) return s;
  if (id == UINT64_MAX) {
    point->point3d_id = -1;
  } else if (id > (uint64_t)INT64_MAX) {
    return field_error(r, at, "point3D_id",
                       "%llu is above %lld, the largest point id supported (UINT64_MAX means none)",
                       (unsigned long long)id, (long long)INT64_MAX);
  } else {
    point->point3d_id = (int64_t)id;
  }
  return CF_OK;
}

static cf_status read_image(reader *r, size_t index, size_t count, cf_colmap_image *image) {
  snprintf(r->record, sizeof r->record, "image record %zu of %zu", index + 1, count);
  r->array = NULL;
  cf_status s = read_u32(r, "image_id", &image->image_id);
  if (s != CF_OK) return s;
  snprintf(r->record, sizeof r->record, "image record %zu of %zu (image_id %u)", index + 1, count,
           image->image_id);
  static const char *const pose_fields[7] = {"qw", "qx", "qy", "qz", "tx", "ty", "tz"};
  for (int k = 0; k < 4; ++k)
    if ((s = read_finite(r, pose_fields[k], &image->qvec[k])) != CF_OK) return s;
  for (int k = 0; k < 3; ++k)
    if ((s = read_finite(r, pose_fields[4 + k], &image->tvec[k])) != CF_OK) return s;
  if ((s = read_u32(r, "camera_id", &image->camera_id)) != CF_OK) return s;
  if ((s = read_name(r, &image->name)) != CF_OK) return s;
  if ((s = read_count(r, "num_points2D", POINT2D_BYTES, "points", &image->num_points2d)) != CF_OK)
    return s;
  image->points2d = calloc(image->num_points2d ? image->num_points2d : 1, sizeof *image->points2d);
  if (!image->points2d) return out_of_memory(r);
  r->array = "points2D";
  for (size_t j = 0; j < image->num_points2d; ++j) {
    r->item = j;
    if ((s = read_point2d(r, &image->points2d[j])) != CF_OK) return s;
  }
  r->array = NULL;
  return CF_OK;
}

cf_status cf_colmap_parse_images_binary(const uint8_t *data, size_t size, const char *name,
                                        cf_colmap_model *model, cf_error *err) {
  reader r = {.data = data, .size = size, .name = name, .err = err};
  snprintf(r.record, sizeof r.record, "header");
  size_t count;
  cf_status s = read_count(&r, "num_images", IMAGE_MIN_BYTES, "images", &count);
  if (s != CF_OK) return s;
  cf_colmap_image *images = calloc(count ? count : 1, sizeof *images);
  size_t *offsets = calloc(count ? count : 1, sizeof *offsets);
  uint64_t *ids = calloc(model->num_images + count + 1, sizeof *ids);
  if (!images || !offsets || !ids) s = out_of_memory(&r);
  for (size_t i = 0; s == CF_OK && i < count; ++i) {
    offsets[i] = r.pos;
    s = read_image(&r, i, count, &images[i]);
  }
  if (s == CF_OK) s = check_end(&r, "image");
  if (s == CF_OK) {
    for (size_t i = 0; i < model->num_images; ++i) ids[i] = model->images[i].image_id;
    for (size_t i = 0; i < count; ++i) ids[model->num_images + i] = images[i].image_id;
    s = check_duplicates(&r, ids, model->num_images, model->num_images + count, offsets, "image",
                         "image_id");
  }
  if (s == CF_OK && cf__append((void **)&model->images, &model->num_images, images, count,
                               sizeof *images) != CF_OK)
    s = out_of_memory(&r);
  if (s == CF_OK)
    free(images); /* the records now belong to the model */
  else
    cf__free_images(images, count);
  free(offsets);
  free(ids);
  return s;
}

/* ---- points3D.bin ---- */

static cf_status read_point3d(reader *r, size_t index, size_t count, cf_point3d *point) {
  snprintf(r->record, sizeof r->record, "point record %zu of %zu", index + 1, count);
  r->array = NULL;
  size_t at = r->pos;
  cf_status s = read_u64(r, "point3D_id", &point->point3d_id);
  if (s != CF_OK) return s;
  if (point->point3d_id > (uint64_t)INT64_MAX)
    return field_error(r, at, "point3D_id", "%llu is above %lld, the largest point id supported",
                       (unsigned long long)point->point3d_id, (long long)INT64_MAX);
  snprintf(r->record, sizeof r->record, "point record %zu of %zu (point3D_id %llu)", index + 1,
           count, (unsigned long long)point->point3d_id);
  static const char *const xyz[3] = {"x", "y", "z"}, *const rgb[3] = {"r", "g", "b"};
  for (int k = 0; k < 3; ++k)
    if ((s = read_finite(r, xyz[k], &point->xyz[k])) != CF_OK) return s;
  for (int k = 0; k < 3; ++k)
    if ((s = read_u8(r, rgb[k], &point->rgb[k])) != CF_OK) return s;
  if ((s = read_finite(r, "error", &point->error)) != CF_OK) return s;
  if ((s = read_count(r, "track_length", TRACK_ELEMENT_BYTES, "track elements",
                      &point->track_length)) != CF_OK)
    return s;
  point->track = calloc(point->track_length ? point->track_length : 1, sizeof *point->track);
  if (!point->track) return out_of_memory(r);
  r->array = "track";
  for (size_t j = 0; j < point->track_length; ++j) {
    r->item = j;
    if ((s = read_u32(r, "image_id", &point->track[j].image_id)) != CF_OK) return s;
    if ((s = read_u32(r, "point2D_idx", &point->track[j].point2d_idx)) != CF_OK) return s;
  }
  r->array = NULL;
  return CF_OK;
}

cf_status cf_colmap_parse_points3d_binary(const uint8_t *data, size_t size, const char *name,
                                          cf_colmap_model *model, cf_error *err) {
  reader r = {.data = data, .size = size, .name = name, .err = err};
  snprintf(r.record, sizeof r.record, "header");
  size_t count;
  cf_status s = read_count(&r, "num_points3D", POINT3D_MIN_BYTES, "points", &count);
  if (s != CF_OK) return s;
  cf_point3d *points = calloc(count ? count : 1, sizeof *points);
  size_t *offsets = calloc(count ? count : 1, sizeof *offsets);
  uint64_t *ids = calloc(model->num_points3d + count + 1, sizeof *ids);
  if (!points || !offsets || !ids) s = out_of_memory(&r);
  for (size_t i = 0; s == CF_OK && i < count; ++i) {
    offsets[i] = r.pos;
    s = read_point3d(&r, i, count, &points[i]);
  }
  if (s == CF_OK) s = check_end(&r, "point");
  if (s == CF_OK) {
    for (size_t i = 0; i < model->num_points3d; ++i) ids[i] = model->points3d[i].point3d_id;
    for (size_t i = 0; i < count; ++i) ids[model->num_points3d + i] = points[i].point3d_id;
    s = check_duplicates(&r, ids, model->num_points3d, model->num_points3d + count, offsets,
                         "point", "point3D_id");
  }
  if (s == CF_OK && cf__append((void **)&model->points3d, &model->num_points3d, points, count,
                               sizeof *points) != CF_OK)
    s = out_of_memory(&r);
  if (s == CF_OK)
    free(points);
  else
    cf__free_points3d(points, count);
  free(offsets);
  free(ids);
  return s;
}
