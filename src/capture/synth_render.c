/* The rendering of a synthetic capture's images (synth_internal.h): each
 * image's radiance with S×S samples per pixel near and on the sphere,
 * photon and read noise, the image and its mask written to their files;
 * and the reference card's region in image 0. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/image.h"
#include "core/file.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "synth_internal.h"

/* The reference card (--reference): a square on the ground between the
 * sphere and camera 0 (azimuth 0), where that camera sees the ground in
 * front of the sphere; its region in image 0 stays this many pixels inside
 * the card's edges. */
const double synth_card_center[2] = {0.7, 0.0}, synth_card_half = 0.3;
enum { CARD_MARGIN_PX = 2, MIN_CARD_PIXELS = 16 };

/* The scene as camera cam sees it, lit by the environment's lights or by
 * its flash (a point light kept in *flash). */
static void make_scene(const render_job *job, const synth_camera *cam, synth_scene *scene,
                       cf_light *flash) {
  const cf_synth_options *o = job->options;
  memset(scene, 0, sizeof *scene);
  scene->model = o->model;
  scene->params = o->params;
  scene->seed = o->seed;
  memset(flash, 0, sizeof *flash);
  flash->kind = CF_LIGHT_POINT;
  for (int i = 0; i < 3; ++i) { /* the flash: C + Rᵀ t_flash */
    flash->position[i] = cam->c[i] + cam->r[i] * o->flash_offset[0] +
                         cam->r[3 + i] * o->flash_offset[1] + cam->r[6 + i] * o->flash_offset[2];
    flash->intensity[i] = job->intensity;
  }
  scene->lights = job->environment ? job->environment : flash;
  scene->light_count = job->environment ? o->environment_lights : 1;
  scene->card_albedo = o->reference_albedo;
  scene->card_center[0] = synth_card_center[0];
  scene->card_center[1] = synth_card_center[1];
  scene->card_half = synth_card_half;
}

/* The world ray of pixel coordinates uv of camera cam. */
static void pixel_ray(const render_job *job, const synth_camera *cam, const double uv[2],
                      double d[3]) {
  double ray[3];
  cf_camera_unproject(&job->camera, uv, ray);
  for (int k = 0; k < 3; ++k)
    d[k] = cam->r[k] * ray[0] + cam->r[3 + k] * ray[1] + cam->r[6 + k] * ray[2];
}

/* The radiance of pixel (x, y): S×S samples on a centred grid where the
 * pixel is within 2 pixels of the sphere's silhouette or inside it, one
 * sample elsewhere (the background is never fitted). *covered is the
 * fraction of samples that hit the sphere. */
static void render_pixel(const render_job *job, const synth_scene *scene, const synth_camera *cam,
                         int x, int y, double radiance[3], double *covered) {
  const cf_synth_options *o = job->options;
  double centre[2] = {x + 0.5, y + 0.5}, ray[3], d[3];
  cf_camera_unproject(&job->camera, centre, ray);
  for (int k = 0; k < 3; ++k)
    d[k] = cam->r[k] * ray[0] + cam->r[3 + k] * ray[1] + cam->r[6 + k] * ray[2];
  /* angular distance of the centre ray from the silhouette, in pixels */
  double to_centre = sqrt(cam->c[0] * cam->c[0] + cam->c[1] * cam->c[1] + cam->c[2] * cam->c[2]);
  double cos_ray = -(d[0] * cam->c[0] + d[1] * cam->c[1] + d[2] * cam->c[2]) / to_centre;
  double outside_px = (acos(fmin(1.0, cos_ray)) - asin(1.0 / to_centre)) * o->focal_px;
  int s = outside_px > 2.0 ? 1 : o->supersample;
  double sum[3] = {0.0, 0.0, 0.0};
  int hits = 0;
  for (int j = 0; j < s; ++j) {
    for (int i = 0; i < s; ++i) {
      double uv[2] = {x + (i + 0.5) / s, y + (j + 0.5) / s}, sample[3];
      cf_camera_unproject(&job->camera, uv, ray);
      for (int k = 0; k < 3; ++k)
        d[k] = cam->r[k] * ray[0] + cam->r[3 + k] * ray[1] + cam->r[6 + k] * ray[2];
      hits += synth_shade(scene, cam->c, d, sample) == SYNTH_SPHERE;
      for (int c = 0; c < 3; ++c) sum[c] += sample[c];
    }
  }
  for (int c = 0; c < 3; ++c) radiance[c] = sum[c] / (s * s);
  *covered = (double)hits / (s * s);
}

/* Photon and read noise, then what the file stores: the noise is added in
 * radiance units (so the capture's noise block holds after decoding), then
 * the image's exposure, and for integer formats the clip to [0, 1] and the
 * response curve (the writer rounds). */
static float stored_value(const render_job *job, double exposure, double radiance, cf_rng *rng) {
  const cf_synth_options *o = job->options;
  double variance = o->shot_noise * fmax(radiance, 0.0) + o->read_noise * o->read_noise;
  double noisy = radiance + (variance > 0.0 ? sqrt(variance) * cf_rng_gaussian(rng) : 0.0);
  noisy *= exposure;
  if (o->format == CF_SYNTH_EXR) return (float)noisy;
  return (float)cf_response_encode(job->response, fmin(1.0, fmax(0.0, noisy)));
}

/* Image k into its file: JPEG at the options' quality with 4:2:0 chroma
 * (as cameras write it) and its EXIF, the other formats as they are. */
static cf_status write_photo(const render_job *job, int k, const char *path, const cf_image *image,
                             cf_error *err) {
  const cf_synth_options *o = job->options;
  if (o->format == CF_SYNTH_JPEG)
    return cf_image_write_jpeg(path, image, o->jpeg_quality, CF_CHROMA_420,
                               job->exif ? &job->exif[k] : NULL, err);
  int bits = o->format == CF_SYNTH_PNG8 ? 8 : o->format == CF_SYNTH_PNG16 ? 16 : 32;
  return cf_image_write(path, image, bits, err);
}

/* Camera cam's image in `parts` bands of interleaved rows: radiance (3
 * per pixel) and the sphere's coverage (1 per pixel). */
typedef struct row_bands {
  const render_job *job;
  const synth_scene *scene;
  const synth_camera *cam;
  int parts;
  double *radiance, *covered;
} row_bands;

/* Rows part, part + parts, ... */
static void render_rows(void *user, int part) {
  const row_bands *b = user;
  const int w = b->job->options->width;
  for (int y = part; y < b->job->options->height; y += b->parts)
    for (int x = 0; x < w; ++x) {
      size_t i = (size_t)y * (size_t)w + (size_t)x;
      render_pixel(b->job, b->scene, b->cam, x, y, b->radiance + 3 * i, b->covered + i);
    }
}

/* The radiance of every pixel: with fewer images than threads (one
 * fidelity image under 1024 lights: 20 s on one thread), the image's rows
 * interleaved over the threads; else on this image's thread. */
static void render_radiance(const render_job *job, const synth_scene *scene,
                            const synth_camera *cam, double *radiance, double *covered) {
  const int parts = job->options->images < SYNTH_THREADS ? SYNTH_THREADS : 1;
  row_bands bands = {job, scene, cam, parts, radiance, covered};
  cf_parallel_for(parts, parts, render_rows, &bands);
}

static cf_status render_image(render_job *job, int k, cf_error *err) {
  const cf_synth_options *o = job->options;
  synth_camera *cam = &job->cameras[k];
  synth_scene scene;
  cf_light flash;
  make_scene(job, cam, &scene, &flash);
  cf_image image = {0}, mask = {0};
  const size_t n = (size_t)o->width * (size_t)o->height;
  double *radiance = malloc(3 * n * sizeof *radiance), *covered = malloc(n * sizeof *covered);
  cf_status s = radiance && covered ? cf_image_alloc(&image, o->width, o->height, 3, err)
                                    : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK && o->write_masks) s = cf_image_alloc(&mask, o->width, o->height, 1, err);
  if (s == CF_OK) render_radiance(job, &scene, cam, radiance, covered);
  /* the noise in pixel order, so the draws do not depend on the threads */
  cf_rng rng = cf_rng_seed(o->seed * 1000003u + (uint64_t)k);
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    for (int c = 0; c < 3; ++c)
      image.pixels[3 * i + c] = stored_value(job, job->exposures[k], radiance[3 * i + c], &rng);
    if (mask.pixels) mask.pixels[i] = covered[i] == 1.0;
  }
  free(radiance);
  free(covered);
  char name[64], path[4096];
  snprintf(name, sizeof name, "images/%03d.%s", k, synth_extension(o->format));
  if (s == CF_OK) s = cf_path_join(job->dir, name, path, sizeof path, err);
  if (s == CF_OK) s = write_photo(job, k, path, &image, err);
  /* a mask has its image's file name (the capture format looks it up so) */
  snprintf(name, sizeof name, "masks/%03d.%s", k, synth_extension(o->format));
  if (s == CF_OK && mask.pixels) s = cf_path_join(job->dir, name, path, sizeof path, err);
  if (s == CF_OK && mask.pixels)
    s = cf_image_write(path, &mask, o->format == CF_SYNTH_EXR ? 16 : 8, err);
  cf_image_free(&image);
  cf_image_free(&mask);
  return s;
}

/* Image k, unless an image has failed (the first failure is kept). */
void synth_render_one(void *user, int k) {
  render_job *job = user;
  pthread_mutex_lock(&job->lock);
  const int failed = job->status != CF_OK;
  pthread_mutex_unlock(&job->lock);
  if (failed) return;
  cf_error err = {0};
  cf_status s = render_image(job, k, &err);
  pthread_mutex_lock(&job->lock);
  if (s != CF_OK && job->status == CF_OK) {
    job->status = s;
    job->error = err;
  }
  ++job->done;
  if (job->options->progress)
    job->options->progress(job->options->progress_user, "rendering images", (size_t)job->done,
                           (size_t)job->options->images);
  pthread_mutex_unlock(&job->lock);
}

/* ---- the reference card's region in image 0 ---- */

/* Does the ray through pixel coordinates (u, v) of camera 0 see the card? */
static int sees_card(const render_job *job, const synth_scene *scene, double u, double v) {
  double uv[2] = {u, v}, d[3], radiance[3];
  pixel_ray(job, &job->cameras[0], uv, d);
  return synth_shade(scene, job->cameras[0].c, d, radiance) == SYNTH_CARD;
}

/* Pixel (x, y) with CARD_MARGIN_PX around it inside the card's image (the
 * card's image is convex, so its corners decide). */
static int card_pixel(const render_job *job, const synth_scene *scene, int x, int y) {
  const double m = CARD_MARGIN_PX;
  const cf_synth_options *o = job->options;
  if (x < 0 || y < 0 || x >= o->width || y >= o->height) return 0;
  return sees_card(job, scene, x - m, y - m) && sees_card(job, scene, x + 1 + m, y - m) &&
         sees_card(job, scene, x - m, y + 1 + m) && sees_card(job, scene, x + 1 + m, y + 1 + m);
}

/* The region [x0, x1) x [y0, y1) of image 0 inside the card: from the
 * pixel of the card's centre, grown one row or column at a time while the
 * new pixels stay inside; then every pixel's point of the card checked to
 * be lit by flash 0 (not in the sphere's shadow). */
cf_status synth_card_region(const render_job *job, int region[4], cf_error *err) {
  const synth_camera *cam = &job->cameras[0];
  synth_scene scene;
  cf_light flash;
  make_scene(job, cam, &scene, &flash);
  double centre[3] = {synth_card_center[0], synth_card_center[1], SYNTH_GROUND_Z}, xc[3],
         uv[2] = {-1, -1};
  for (int i = 0; i < 3; ++i)
    xc[i] = cam->r[3 * i] * centre[0] + cam->r[3 * i + 1] * centre[1] +
            cam->r[3 * i + 2] * centre[2] + cam->t[i];
  cf_camera_project(&job->camera, xc, uv);
  int x = (int)floor(uv[0]), y = (int)floor(uv[1]);
  if (!card_pixel(job, &scene, x, y))
    return cf_error_set(err, CF_EINVAL,
                        "--reference: image 0 (%d x %d pixels) does not see the card's centre "
                        "clear of its edges",
                        job->options->width, job->options->height);
  int r[4] = {x, y, x + 1, y + 1};
  for (int grown = 1; grown;) {
    grown = 0;
    int ok = 1; /* left, right: a column; top, bottom: a row */
    for (int j = r[1]; ok && j < r[3]; ++j) ok = card_pixel(job, &scene, r[0] - 1, j);
    if (ok) --r[0], grown = 1;
    ok = 1;
    for (int j = r[1]; ok && j < r[3]; ++j) ok = card_pixel(job, &scene, r[2], j);
    if (ok) ++r[2], grown = 1;
    ok = 1;
    for (int i = r[0]; ok && i < r[2]; ++i) ok = card_pixel(job, &scene, i, r[1] - 1);
    if (ok) --r[1], grown = 1;
    ok = 1;
    for (int i = r[0]; ok && i < r[2]; ++i) ok = card_pixel(job, &scene, i, r[3]);
    if (ok) ++r[3], grown = 1;
  }
  int pixels = (r[2] - r[0]) * (r[3] - r[1]);
  if (pixels < MIN_CARD_PIXELS)
    return cf_error_set(err, CF_EINVAL,
                        "--reference: the card covers only %d pixels of image 0 clear of its "
                        "edges, fewer than %d: use a larger --size",
                        pixels, MIN_CARD_PIXELS);
  for (int j = r[1]; j < r[3]; ++j)
    for (int i = r[0]; i < r[2]; ++i) {
      double pixel[2] = {i + 0.5, j + 0.5}, d[3];
      pixel_ray(job, cam, pixel, d);
      double t = (SYNTH_GROUND_Z - cam->c[2]) / d[2];
      double point[3] = {cam->c[0] + t * d[0], cam->c[1] + t * d[1], SYNTH_GROUND_Z};
      if (synth_in_shadow(point, &flash))
        return cf_error_set(err, CF_EINVAL,
                            "--reference: pixel (%d, %d) of the card in image 0 is in the "
                            "sphere's shadow",
                            i, j);
    }
  memcpy(region, r, sizeof r);
  return CF_OK;
}
