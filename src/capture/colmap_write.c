/* Writing a COLMAP sparse model in the text and the binary format, after
 * Reconstruction::Write*Text and Write*Binary in src/base/reconstruction.cc:
 * the same comment headers and layouts, doubles with 17 significant
 * digits (COLMAP's precision(17)) so that a text round trip is exact, and
 * records in the model's order. Unlike COLMAP, quaternions are written as
 * they are (COLMAP normalises them on the way out). */
#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "colmap_internal.h"
#include "clayfit/colmap.h"
#include "core/file.h"

/* A file being written, and whether a write failed. */
typedef struct writer {
  FILE *file;
  char path[4096];
  int failed;
} writer;

static cf_status open_writer(writer *w, const char *dir, const char *name, int binary,
                             cf_error *err) {
  w->file = NULL;
  w->failed = 0;
  cf_status s = cf_path_join(dir, name, w->path, sizeof w->path, err);
  if (s != CF_OK) return s;
  w->file = fopen(w->path, binary ? "wb" : "w");
  if (!w->file) return cf_error_set(err, CF_EIO, "%s: %s", w->path, strerror(errno));
  return CF_OK;
}

/* Close, and say whether everything reached the file. */
static cf_status close_writer(writer *w, cf_status status, cf_error *err) {
  if (!w->file) return status;
  int failed = ferror(w->file) || w->failed;
  if (fclose(w->file) != 0) failed = 1;
  w->file = NULL;
  if (status == CF_OK && failed) return cf_error_set(err, CF_EIO, "%s: could not write", w->path);
  return status;
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void
put_text(writer *w, const char *format, ...);

static void put_text(writer *w, const char *format, ...) {
  va_list args;
  va_start(args, format);
  if (vfprintf(w->file, format, args) < 0) w->failed = 1;
  va_end(args);
}

/* ---- checks before writing ---- */

/* What the text layout cannot hold: unknown models, wrong parameter
 * counts, empty names, names with line breaks or around blanks, ids
 * below −1. */
static cf_status check_writable(const cf_colmap_model *model, cf_error *err) {
  for (size_t i = 0; i < model->num_cameras; ++i) {
    const cf_camera *c = &model->cameras[i];
    int count = cf_camera_model_param_count(c->model);
    if (count < 0 || c->num_params != count)
      return cf_error_set(err, CF_EINVAL,
                          "camera %u: model id %d with %d parameters cannot be written",
                          c->camera_id, (int)c->model, c->num_params);
  }
  for (size_t i = 0; i < model->num_images; ++i) {
    const cf_colmap_image *image = &model->images[i];
    const char *name = image->name;
    size_t length = name ? strlen(name) : 0;
    if (length == 0 || length > CF_COLMAP_MAX_NAME || strpbrk(name, "\r\n") ||
        strchr(" \t", name[0]) || strchr(" \t", name[length - 1]))
      return cf_error_set(err, CF_EINVAL,
                          "image %u: name '%s' cannot be written (empty, longer than %d bytes, "
                          "or with a line break or blanks around it)",
                          image->image_id, name ? name : "", CF_COLMAP_MAX_NAME);
    for (size_t j = 0; j < image->num_points2d; ++j)
      if (image->points2d[j].point3d_id < -1)
        return cf_error_set(err, CF_EINVAL,
                            "image %u: points2D[%zu].point3D_id is %" PRId64
                            "; it must be -1 (none) or >= 0",
                            image->image_id, j, image->points2d[j].point3d_id);
  }
  for (size_t i = 0; i < model->num_points3d; ++i)
    if (model->points3d[i].point3d_id > (uint64_t)INT64_MAX)
      return cf_error_set(err, CF_EINVAL, "point %" PRIu64 ": id above %" PRId64,
                          model->points3d[i].point3d_id, INT64_MAX);
  return CF_OK;
}

/* ---- text ---- */

static void write_cameras_text(writer *w, const cf_colmap_model *model) {
  put_text(w, "# Camera list with one line of data per camera:\n");
  put_text(w, "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n");
  put_text(w, "# Number of cameras: %zu\n", model->num_cameras);
  for (size_t i = 0; i < model->num_cameras; ++i) {
    const cf_camera *c = &model->cameras[i];
    put_text(w, "%u %s %" PRIu64 " %" PRIu64, c->camera_id, cf_camera_model_name(c->model),
             c->width, c->height);
    for (int k = 0; k < c->num_params; ++k) put_text(w, " %.17g", c->params[k]);
    put_text(w, "\n");
  }
}

/* Reconstruction::ComputeNumObservations: keypoints with a 3D point. */
static size_t count_observations(const cf_colmap_model *model) {
  size_t observations = 0;
  for (size_t i = 0; i < model->num_images; ++i)
    for (size_t j = 0; j < model->images[i].num_points2d; ++j)
      observations += model->images[i].points2d[j].point3d_id >= 0;
  return observations;
}

static void write_images_text(writer *w, const cf_colmap_model *model) {
  /* Reconstruction::ComputeMeanObservationsPerRegImage */
  size_t observations = count_observations(model);
  double mean = model->num_images ? (double)observations / (double)model->num_images : 0.0;
  put_text(w, "# Image list with two lines of data per image:\n");
  put_text(w, "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n");
  put_text(w, "#   POINTS2D[] as (X, Y, POINT3D_ID)\n");
  put_text(w, "# Number of images: %zu, mean observations per image: %.17g\n", model->num_images,
           mean);
  for (size_t i = 0; i < model->num_images; ++i) {
    const cf_colmap_image *image = &model->images[i];
    put_text(w, "%u %.17g %.17g %.17g %.17g %.17g %.17g %.17g %u %s\n", image->image_id,
             image->qvec[0], image->qvec[1], image->qvec[2], image->qvec[3], image->tvec[0],
             image->tvec[1], image->tvec[2], image->camera_id, image->name);
    for (size_t j = 0; j < image->num_points2d; ++j) {
      const cf_point2d *p = &image->points2d[j];
      put_text(w, "%s%.17g %.17g %" PRId64, j ? " " : "", p->x, p->y, p->point3d_id);
    }
    put_text(w, "\n");
  }
}

static void write_points3d_text(writer *w, const cf_colmap_model *model) {
  /* Reconstruction::ComputeMeanTrackLength: the images' observations per
   * point (the mean track length when tracks and images agree) */
  size_t observations = count_observations(model);
  double mean = model->num_points3d ? (double)observations / (double)model->num_points3d : 0.0;
  put_text(w, "# 3D point list with one line of data per point:\n");
  put_text(w, "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n");
  put_text(w, "# Number of points: %zu, mean track length: %.17g\n", model->num_points3d, mean);
  for (size_t i = 0; i < model->num_points3d; ++i) {
    const cf_point3d *p = &model->points3d[i];
    /* COLMAP ends ERROR with a blank even when the track is empty */
    put_text(w, "%" PRIu64 " %.17g %.17g %.17g %d %d %d %.17g ", p->point3d_id, p->xyz[0],
             p->xyz[1], p->xyz[2], p->rgb[0], p->rgb[1], p->rgb[2], p->error);
    for (size_t j = 0; j < p->track_length; ++j)
      put_text(w, "%s%u %u", j ? " " : "", p->track[j].image_id, p->track[j].point2d_idx);
    put_text(w, "\n");
  }
}

typedef void (*content_writer)(writer *, const cf_colmap_model *);

static cf_status write_file(const char *dir, const char *name, int binary, content_writer content,
                            const cf_colmap_model *model, cf_error *err) {
  writer w;
  cf_status s = open_writer(&w, dir, name, binary, err);
  if (s != CF_OK) return s;
  content(&w, model);
  return close_writer(&w, CF_OK, err);
}

cf_status cf_colmap_write_text(const char *dir, const cf_colmap_model *model, cf_error *err) {
  cf_status s = check_writable(model, err);
  if (s == CF_OK) s = write_file(dir, "cameras.txt", 0, write_cameras_text, model, err);
  if (s == CF_OK) s = write_file(dir, "images.txt", 0, write_images_text, model, err);
  if (s == CF_OK) s = write_file(dir, "points3D.txt", 0, write_points3d_text, model, err);
  return s;
}

/* ---- binary (little-endian whatever the machine) ---- */

static void put_bytes(writer *w, const void *data, size_t size) {
  if (size && fwrite(data, 1, size, w->file) != size) w->failed = 1;
}

static void put_le(writer *w, uint64_t v, int bytes) {
  unsigned char buf[8];
  for (int k = 0; k < bytes; ++k) buf[k] = (unsigned char)(v >> (8 * k));
  put_bytes(w, buf, (size_t)bytes);
}

static void put_u8(writer *w, uint8_t v) {
  put_le(w, v, 1);
}
static void put_u32(writer *w, uint32_t v) {
  put_le(w, v, 4);
}
static void put_u64(writer *w, uint64_t v) {
  put_le(w, v, 8);
}
static void put_f64(writer *w, double v) {
  uint64_t bits;
  memcpy(&bits, &v, sizeof bits);
  put_le(w, bits, 8);
}

static void write_cameras_binary(writer *w, const cf_colmap_model *model) {
  put_u64(w, model->num_cameras);
  for (size_t i = 0; i < model->num_cameras; ++i) {
    const cf_camera *c = &model->cameras[i];
    put_u32(w, c->camera_id);
    put_u32(w, (uint32_t)c->model); /* int32 model_id, non-negative */
    put_u64(w, c->width);
    put_u64(w, c->height);
    for (int k = 0; k < c->num_params; ++k) put_f64(w, c->params[k]);
  }
}

static void write_images_binary(writer *w, const cf_colmap_model *model) {
  put_u64(w, model->num_images);
  for (size_t i = 0; i < model->num_images; ++i) {
    const cf_colmap_image *image = &model->images[i];
    put_u32(w, image->image_id);
    for (int k = 0; k < 4; ++k) put_f64(w, image->qvec[k]);
    for (int k = 0; k < 3; ++k) put_f64(w, image->tvec[k]);
    put_u32(w, image->camera_id);
    put_bytes(w, image->name, strlen(image->name) + 1);
    put_u64(w, image->num_points2d);
    for (size_t j = 0; j < image->num_points2d; ++j) {
      const cf_point2d *p = &image->points2d[j];
      put_f64(w, p->x);
      put_f64(w, p->y);
      put_u64(w, p->point3d_id < 0 ? UINT64_MAX : (uint64_t)p->point3d_id);
    }
  }
}

static void write_points3d_binary(writer *w, const cf_colmap_model *model) {
  put_u64(w, model->num_points3d);
  for (size_t i = 0; i < model->num_points3d; ++i) {
    const cf_point3d *p = &model->points3d[i];
    put_u64(w, p->point3d_id);
    for (int k = 0; k < 3; ++k) put_f64(w, p->xyz[k]);
    for (int k = 0; k < 3; ++k) put_u8(w, p->rgb[k]);
    put_f64(w, p->error);
    put_u64(w, p->track_length);
    for (size_t j = 0; j < p->track_length; ++j) {
      put_u32(w, p->track[j].image_id);
      put_u32(w, p->track[j].point2d_idx);
    }
  }
}

cf_status cf_colmap_write_binary(const char *dir, const cf_colmap_model *model, cf_error *err) {
  cf_status s = check_writable(model, err);
  if (s == CF_OK) s = write_file(dir, "cameras.bin", 1, write_cameras_binary, model, err);
  if (s == CF_OK) s = write_file(dir, "images.bin", 1, write_images_binary, model, err);
  if (s == CF_OK) s = write_file(dir, "points3D.bin", 1, write_points3d_binary, model, err);
  return s;
}
