/* Synthetic captures (include/clayfit/synth.h): orbit cameras, the scene
 * rendered by the image formation of docs/model.md §5 with S×S samples per pixel near
 * and on the sphere, photon and read noise, and everything a real capture
 * would have: images, a COLMAP model, a capture file (plus the truth). */
#include "clayfit/synth.h"

#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/colmap.h"
#include "clayfit/image.h"
#include "core/file.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "core/vec.h"
#include "envmap.h"
#include "synth_scene.h"

/* The reference card (--reference): a square on the ground between the
 * sphere and camera 0 (azimuth 0), where that camera sees the ground in
 * front of the sphere; its region in image 0 stays this many pixels inside
 * the card's edges. */
static const double card_center[2] = {0.7, 0.0}, card_half = 0.3;
enum { CARD_MARGIN_PX = 2, MIN_CARD_PIXELS = 16 };

void cf_synth_default_options(cf_synth_options *o) {
  memset(o, 0, sizeof *o);
  o->model = CF_MODEL_CLAY;
  cf_model_default_params(o->model, o->params);
  o->images = 16;
  o->width = 640;
  o->height = 480;
  o->focal_px = 1.2 * 640;
  o->distance = 5.0;
  o->flash_offset[0] = 0.3;  /* right */
  o->flash_offset[1] = -0.3; /* up (camera y points down) */
  o->read_noise = 0.002;
  o->shot_noise = 0.0005;
  o->supersample = 3;
  o->format = CF_SYNTH_PNG8;
  o->response = -1;
  o->jpeg_quality = CF_SYNTH_JPEG_QUALITY;
  o->seed = 1;
  o->sphere_radius_m = 0.04;
  o->environment_lights = 1024;
  static const double rotation[9] = CF_SYNTH_ENVIRONMENT_ROTATION;
  memcpy(o->environment_rotation, rotation, sizeof rotation);
}

/* ---- cameras ---- */

typedef struct synth_camera {
  double r[9], t[3], c[3]; /* world-to-camera rotation, translation; centre */
  double q[4];             /* r as a quaternion (qw, qx, qy, qz) */
} synth_camera;

/* A rotation matrix as a unit quaternion (Shepperd's method). */
static void matrix_to_quaternion(const double r[9], double q[4]) {
  double trace = r[0] + r[4] + r[8];
  if (trace > 0.0) {
    double s = 2.0 * sqrt(1.0 + trace);
    q[0] = 0.25 * s;
    q[1] = (r[7] - r[5]) / s;
    q[2] = (r[2] - r[6]) / s;
    q[3] = (r[3] - r[1]) / s;
  } else if (r[0] > r[4] && r[0] > r[8]) {
    double s = 2.0 * sqrt(1.0 + r[0] - r[4] - r[8]);
    q[0] = (r[7] - r[5]) / s;
    q[1] = 0.25 * s;
    q[2] = (r[1] + r[3]) / s;
    q[3] = (r[2] + r[6]) / s;
  } else if (r[4] > r[8]) {
    double s = 2.0 * sqrt(1.0 + r[4] - r[0] - r[8]);
    q[0] = (r[2] - r[6]) / s;
    q[1] = (r[1] + r[3]) / s;
    q[2] = 0.25 * s;
    q[3] = (r[5] + r[7]) / s;
  } else {
    double s = 2.0 * sqrt(1.0 + r[8] - r[0] - r[4]);
    q[0] = (r[3] - r[1]) / s;
    q[1] = (r[2] + r[6]) / s;
    q[2] = (r[5] + r[7]) / s;
    q[3] = 0.25 * s;
  }
  if (q[0] < 0.0)
    for (int k = 0; k < 4; ++k) q[k] = -q[k];
}

/* Camera k of the orbit: two rings (20 and 35 degrees of elevation,
 * alternating), evenly spaced in azimuth, looking at the sphere's centre.
 * COLMAP's axes: x right, y down, z forward. */
static void orbit_camera(const cf_synth_options *o, int k, synth_camera *cam) {
  double azimuth = 2.0 * CF_PI * k / o->images;
  double elevation = (k % 2 ? 35.0 : 20.0) * CF_PI / 180.0;
  double c[3] = {o->distance * cos(elevation) * cos(azimuth),
                 o->distance * cos(elevation) * sin(azimuth), o->distance * sin(elevation)};
  double forward[3] = {-c[0] / o->distance, -c[1] / o->distance, -c[2] / o->distance};
  /* right = forward × up, down = forward × right */
  double right[3] = {forward[1], -forward[0], 0.0};
  double length = sqrt(right[0] * right[0] + right[1] * right[1]);
  for (int i = 0; i < 3; ++i) right[i] /= length;
  double down[3];
  cf_cross3(forward, right, down);
  for (int i = 0; i < 3; ++i) {
    cam->r[i] = right[i];
    cam->r[3 + i] = down[i];
    cam->r[6 + i] = forward[i];
    cam->c[i] = c[i];
  }
  for (int i = 0; i < 3; ++i)
    cam->t[i] = -(cam->r[3 * i] * c[0] + cam->r[3 * i + 1] * c[1] + cam->r[3 * i + 2] * c[2]);
  matrix_to_quaternion(cam->r, cam->q);
}

static cf_camera pinhole(const cf_synth_options *o) {
  cf_camera camera = {1, CF_CAMERA_PINHOLE, (uint64_t)o->width, (uint64_t)o->height, 4, {0}};
  camera.params[0] = camera.params[1] = o->focal_px;
  camera.params[2] = 0.5 * o->width;
  camera.params[3] = 0.5 * o->height;
  return camera;
}

/* ---- rendering ---- */

enum { SYNTH_THREADS = 2 };

typedef struct render_job {
  const cf_synth_options *options;
  const char *dir;
  cf_camera camera;
  synth_camera *cameras;
  double intensity;
  cf_light *environment;       /* the map's lights (options->environment_lights), or NULL */
  char environment_file[4096]; /* the map relative to the capture's folder */
  cf_envmap_report environment_report;
  cf_response response;
  double *exposures;   /* e_k per image (geometric mean 1) */
  cf_image_info *exif; /* per image with exif_exposures, else NULL */
  int card_region[4];  /* the reference card's pixels in image 0 */
  /* over done, status, error and the progress */
  pthread_mutex_t lock;
  int done;
  cf_status status;
  cf_error error;
} render_job;

static const char *extension(cf_synth_format format) {
  return format == CF_SYNTH_EXR ? "exr" : format == CF_SYNTH_JPEG ? "jpg" : "png";
}

/* The curve the photos are coded with. */
static cf_response synth_response(const cf_synth_options *o) {
  if (o->response >= 0) return (cf_response)o->response;
  return o->format == CF_SYNTH_PNG8 || o->format == CF_SYNTH_JPEG ? CF_RESPONSE_SRGB
                                                                  : CF_RESPONSE_LINEAR;
}

/* The EXIF settings exif_exposures cycles through: exposure time (s), ISO,
 * f-number; exposure time x ISO / f-number^2 spans a factor of 1.95. The
 * times were chosen when OpenImageIO 2.4 wrote the EXIF (it wrote 1/50 s
 * as 0.019999 s and 1/64 s as infinity); clayfit's writer (image_exif.c)
 * keeps any 1/N s, and these stay so that the test captures do not move. */
static const double exif_settings[][3] = {{1.0 / 80, 100, 4.0},
                                          {1.0 / 125, 200, 4.0},
                                          {1.0 / 40, 100, 4.5},
                                          {1.0 / 160, 400, 5.6},
                                          {1.0 / 125, 400, 7.1}};
enum { EXIF_SETTINGS = sizeof exif_settings / sizeof exif_settings[0] };

/* Each image's exposure e_k, and with exif_exposures its EXIF: the
 * settings' exposure (as the file stores them: float) over their geometric
 * mean, as the capture reads "exposure": "exif". */
static void image_exposures(const cf_synth_options *o, double *exposures, cf_image_info *exif) {
  double log_sum = 0.0;
  for (int k = 0; k < o->images; ++k) {
    exposures[k] = 1.0;
    if (!exif) continue;
    const double *setting = exif_settings[k % EXIF_SETTINGS];
    memset(&exif[k], 0, sizeof exif[k]);
    exif[k].exposure_time = (float)setting[0];
    exif[k].iso = setting[1];
    exif[k].f_number = (float)setting[2];
    exposures[k] = exif[k].exposure_time * exif[k].iso / (exif[k].f_number * exif[k].f_number);
    log_sum += log(exposures[k]);
  }
  for (int k = 0; exif && k < o->images; ++k) exposures[k] /= exp(log_sum / o->images);
}

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
  scene->card_center[0] = card_center[0];
  scene->card_center[1] = card_center[1];
  scene->card_half = card_half;
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
  snprintf(name, sizeof name, "images/%03d.%s", k, extension(o->format));
  if (s == CF_OK) s = cf_path_join(job->dir, name, path, sizeof path, err);
  if (s == CF_OK) s = write_photo(job, k, path, &image, err);
  /* a mask has its image's file name (the capture format looks it up so) */
  snprintf(name, sizeof name, "masks/%03d.%s", k, extension(o->format));
  if (s == CF_OK && mask.pixels) s = cf_path_join(job->dir, name, path, sizeof path, err);
  if (s == CF_OK && mask.pixels)
    s = cf_image_write(path, &mask, o->format == CF_SYNTH_EXR ? 16 : 8, err);
  cf_image_free(&image);
  cf_image_free(&mask);
  return s;
}

/* Image k, unless an image has failed (the first failure is kept). */
static void render_one(void *user, int k) {
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

/* ---- the files around the images ---- */

static cf_status write_colmap(const char *dir, const render_job *job, cf_error *err) {
  const cf_synth_options *o = job->options;
  char path[4096];
  cf_status s = cf_path_join(dir, "sparse/0", path, sizeof path, err);
  if (s == CF_OK) s = cf_make_dirs(path, err);
  if (s != CF_OK) return s;
  cf_colmap_image *images = calloc((size_t)o->images, sizeof *images);
  char(*names)[32] = calloc((size_t)o->images, sizeof *names);
  cf_camera camera = job->camera;
  if (!images || !names) s = cf_error_set(err, CF_ENOMEM, "out of memory");
  for (int k = 0; s == CF_OK && k < o->images; ++k) {
    snprintf(names[k], sizeof names[k], "%03d.%s", k, extension(o->format));
    images[k].image_id = (uint32_t)k + 1;
    memcpy(images[k].qvec, job->cameras[k].q, sizeof images[k].qvec);
    memcpy(images[k].tvec, job->cameras[k].t, sizeof images[k].tvec);
    images[k].camera_id = camera.camera_id;
    images[k].name = names[k];
  }
  cf_colmap_model model = {1, &camera, (size_t)o->images, images, 0, NULL};
  if (s == CF_OK) s = cf_colmap_write_text(path, &model, err);
  free(images);
  free(names);
  return s;
}

static json_t *rgb_json(double r, double g, double b) {
  return json_pack("[f, f, f]", r, g, b);
}

static cf_status write_json(const char *dir, const char *name, json_t *doc, cf_error *err) {
  char path[4096];
  cf_status s = cf_path_join(dir, name, path, sizeof path, err);
  if (s == CF_OK) s = json_write_file(doc, path, JSON_INDENT(2) | JSON_REAL_PRECISION(17), err);
  json_decref(doc);
  return s;
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
static cf_status card_region(const render_job *job, int region[4], cf_error *err) {
  const synth_camera *cam = &job->cameras[0];
  synth_scene scene;
  cf_light flash;
  make_scene(job, cam, &scene, &flash);
  double centre[3] = {card_center[0], card_center[1], SYNTH_GROUND_Z}, xc[3], uv[2] = {-1, -1};
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

/* The environment light as the capture format declares it (with key_type
 * "type") and as truth.json records it (NULL: no type, and the map's
 * total Σ L dω and its clamped values). The file is relative to the
 * capture's folder. */
static json_t *environment_json(const render_job *job, const char *key_type) {
  const cf_synth_options *o = job->options;
  json_t *rotation = json_array();
  for (int i = 0; i < 9; ++i)
    json_array_append_new(rotation, json_real(o->environment_rotation[i]));
  /* a capture file holds at most CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS (the fit
   * keeps every light of every observation): its count says what the fit
   * will use, truth.json's what rendered the photos (cf_synth_write warns) */
  const int count = key_type && o->environment_lights > CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS
                        ? CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS
                        : o->environment_lights;
  json_t *light = json_pack("{s:s, s:i, s:o}", "file", job->environment_file, "count", count,
                            "rotation", rotation);
  if (key_type) {
    json_object_set_new(light, key_type, json_string("environment"));
  } else {
    const double *total = job->environment_report.total;
    json_object_set_new(light, "total", rgb_json(total[0], total[1], total[2]));
    json_object_set_new(light, "clamped",
                        json_integer((json_int_t)job->environment_report.clamped));
  }
  return light;
}

static cf_status write_capture_file(const char *dir, const render_job *job, cf_error *err) {
  const cf_synth_options *o = job->options;
  const cf_model_info *m = cf_model_info_get(o->model);
  json_t *files = json_array();
  for (int k = 0; k < o->images; ++k) {
    char name[32];
    snprintf(name, sizeof name, "%03d.%s", k, extension(o->format));
    json_array_append_new(files, json_string(name));
  }
  json_t *images = json_pack("{s:s, s:o}", "directory", "images", "files", files);
  if (o->write_masks) json_object_set_new(images, "masks", json_string("masks"));
  /* JPEG's 4:2:0 chroma carries the background about 3 pixels into the
   * sphere (the upsampling's reach): 2 more pixels of margin */
  const double margin = o->format == CF_SYNTH_JPEG ? 4.0 : 2.0;
  json_t *geometry =
      o->silhouette_geometry
          ? json_pack("{s:s, s:f}", "type", "sphere_from_silhouettes", "margin_px", margin)
          : json_pack("{s:s, s:[f, f, f], s:f, s:f}", "type", "sphere", "center", 0.0, 0.0, 0.0,
                      "radius", 1.0, "margin_px", margin);
  /* with a reference card, the lights are given wrong by a known factor */
  const int reference = o->reference_albedo > 0.0;
  const double intensity = reference ? CF_SYNTH_REFERENCE_FACTOR * job->intensity : job->intensity;
  json_t *flash = job->environment
                      ? environment_json(job, "type")
                      : json_pack("{s:s, s:[f, f, f], s:o}", "type", "flash", "offset",
                                  o->flash_offset[0], o->flash_offset[1], o->flash_offset[2],
                                  "intensity", rgb_json(intensity, intensity, intensity));
  char name[128];
  snprintf(name, sizeof name, "synthetic %s (%s), %d images", m->name, m->code, o->images);
  json_t *doc = json_pack(
      "{s:i, s:s, s:{s:s, s:s}, s:o, s:{s:s}, s:s, s:o, s:{s:f}, s:[o]}", "clayfit_capture", 1,
      "name", name, "camera", "type", "colmap", "model", "sparse/0", "images", images, "colour",
      "encoding", o->format == CF_SYNTH_PNG8 || o->format == CF_SYNTH_JPEG ? "srgb" : "linear",
      "radiometry", reference ? "relative" : "absolute", "geometry", geometry, "scale",
      "sphere_radius_m", o->sphere_radius_m, "lights", flash);
  /* the colour block declares the format's own encoding whatever the
   * response (truth.json has the true curve: a test declares it, or not) */
  if (o->exif_exposures)
    json_object_set_new(json_object_get(doc, "colour"), "exposure", json_string("exif"));
  /* the noise model, when there is noise (without one the fit estimates σ
   * from its residuals) */
  if (o->read_noise > 0.0 || o->shot_noise > 0.0)
    json_object_set_new(doc, "noise",
                        json_pack("{s:f, s:f}", "read", o->read_noise, "shot", o->shot_noise));
  if (reference) {
    char image[32];
    snprintf(image, sizeof image, "%03d.%s", 0, extension(o->format));
    json_object_set_new(
        doc, "reference",
        json_pack("{s:s, s:[i, i, i, i], s:f, s:[f, f, f], s:[f, f, f]}", "image", image, "region",
                  job->card_region[0], job->card_region[1], job->card_region[2],
                  job->card_region[3], "albedo", o->reference_albedo, "normal", 0.0, 0.0, 1.0,
                  "point", 0.0, 0.0, SYNTH_GROUND_Z));
  }
  return write_json(dir, "capture.json", doc, err);
}

static cf_status write_truth(const char *dir, const render_job *job, cf_error *err) {
  const cf_synth_options *o = job->options;
  const cf_model_info *m = cf_model_info_get(o->model);
  json_t *params = json_object();
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *p = cf_param_info_get(m->params[j]);
    const double *x = o->params + m->offsets[j];
    json_object_set_new(params, p->name,
                        p->components == 3 ? rgb_json(x[0], x[1], x[2]) : json_real(x[0]));
  }
  static const char *const formats[] = {"png8", "png16", "exr", "jpg"};
  json_t *flash = job->environment ? json_null()
                                   : json_pack("{s:[f, f, f], s:f}", "offset", o->flash_offset[0],
                                               o->flash_offset[1], o->flash_offset[2], "intensity",
                                               job->intensity);
  json_t *doc = json_pack(
      "{s:s, s:s, s:o, s:{s:[f, f, f], s:f}, s:o, s:f, s:i, s:s, s:{s:f, "
      "s:f}, s:I, s:i, s:i, s:f, s:f}",
      "model", m->name, "code", m->code, "params", params, "sphere", "center", 0.0, 0.0, 0.0,
      "radius", 1.0, "flash", flash, "exposure", 1.0, "supersample", o->supersample, "format",
      formats[o->format], "noise", "read", o->read_noise, "shot", o->shot_noise, "seed",
      (json_int_t)o->seed, "width", o->width, "height", o->height, "focal_px", o->focal_px,
      "distance", o->distance);
  json_object_set_new(doc, "response", json_string(cf_response_name(job->response)));
  if (job->environment) json_object_set_new(doc, "environment", environment_json(job, NULL));
  if (o->format == CF_SYNTH_JPEG)
    json_object_set_new(
        doc, "jpeg", json_pack("{s:i, s:s}", "quality", o->jpeg_quality, "subsampling", "4:2:0"));
  if (job->exif) {
    json_t *exposures = json_array();
    for (int k = 0; k < o->images; ++k)
      json_array_append_new(exposures, json_real(job->exposures[k]));
    json_object_set_new(doc, "exposures", exposures);
  }
  if (o->reference_albedo > 0.0)
    json_object_set_new(
        doc, "reference",
        json_pack("{s:f, s:[f, f, f], s:f, s:f, s:[i, i, i, i]}", "albedo", o->reference_albedo,
                  "center", card_center[0], card_center[1], SYNTH_GROUND_Z, "size", 2.0 * card_half,
                  "intensity_factor", CF_SYNTH_REFERENCE_FACTOR, "region", job->card_region[0],
                  job->card_region[1], job->card_region[2], job->card_region[3]));
  return write_json(dir, "truth.json", doc, err);
}

/* The environment's lights (median cut of the map, as a capture's
 * `environment` light loads it) and the map's path relative to dir. */
static cf_status load_environment(const char *dir, render_job *job, cf_error *err) {
  const cf_synth_options *o = job->options;
  if (!o->environment) return CF_OK;
  int k = o->environment_lights;
  cf_directional_light *reduced = malloc((size_t)k * sizeof *reduced);
  job->environment = calloc((size_t)k, sizeof *job->environment);
  if (!reduced || !job->environment) {
    free(reduced);
    return cf_error_set(err, CF_ENOMEM, "out of memory for %d lights", k);
  }
  cf_status s = cf_envmap_load(o->environment, o->environment_rotation, k, reduced,
                               &job->environment_report, err);
  for (int j = 0; s == CF_OK && j < k; ++j) {
    job->environment[j].kind = CF_LIGHT_DIRECTIONAL;
    memcpy(job->environment[j].direction, reduced[j].direction, sizeof reduced[j].direction);
    memcpy(job->environment[j].intensity, reduced[j].irradiance, sizeof reduced[j].irradiance);
  }
  free(reduced);
  if (s == CF_OK)
    s = cf_path_relative(dir, o->environment, job->environment_file, sizeof job->environment_file,
                         err);
  return s;
}

static cf_status check_options(const cf_synth_options *o, cf_error *err) {
  cf_status s = cf_params_check(o->model, o->params, err);
  if (s != CF_OK) return s;
  if (o->images < 1 || o->images > 10000)
    return cf_error_set(err, CF_ERANGE, "images: %d is outside [1, 10000]", o->images);
  if (o->width < 16 || o->height < 16 || o->width > 16384 || o->height > 16384)
    return cf_error_set(err, CF_ERANGE, "image size %d x %d is outside [16, 16384]", o->width,
                        o->height);
  if (!(o->focal_px > 0.0) || !(o->distance > 1.5) || o->distance > 5.5)
    return cf_error_set(err, CF_ERANGE,
                        "focal length %g must be > 0 and the distance %g in (1.5, 5.5] (inside "
                        "the backdrop)",
                        o->focal_px, o->distance);
  if (o->supersample < 1 || o->supersample > 16)
    return cf_error_set(err, CF_ERANGE, "supersample: %d is outside [1, 16]", o->supersample);
  if (!(o->read_noise >= 0.0) || !(o->shot_noise >= 0.0) || !(o->flash_intensity >= 0.0) ||
      !isfinite(o->read_noise + o->shot_noise + o->flash_intensity))
    return cf_error_set(err, CF_ERANGE, "noise and flash intensity must be finite and >= 0");
  if (o->response < -1 || o->response >= CF_RESPONSE_COUNT)
    return cf_error_set(err, CF_EINVAL, "response: %d is not a response curve", o->response);
  if (o->format == CF_SYNTH_EXR && o->response > CF_RESPONSE_LINEAR)
    return cf_error_set(err, CF_EINVAL,
                        "response %s: exr stores linear floats; use png8, png16 or jpg",
                        cf_response_name((cf_response)o->response));
  if (o->format == CF_SYNTH_JPEG && (o->jpeg_quality < 1 || o->jpeg_quality > 100))
    return cf_error_set(err, CF_ERANGE, "JPEG quality: %d is outside [1, 100]", o->jpeg_quality);
  if (o->exif_exposures && o->format != CF_SYNTH_JPEG)
    return cf_error_set(err, CF_EINVAL, "EXIF exposures need the jpg format (PNG keeps no EXIF)");
  if (!(o->reference_albedo >= 0.0 && o->reference_albedo <= 1.0))
    return cf_error_set(err, CF_ERANGE, "reference albedo: %g is outside (0, 1] (0: no card)",
                        o->reference_albedo);
  if (o->environment && (o->environment_lights < 1 || o->environment_lights > CF_ENVMAP_MAX_LIGHTS))
    return cf_error_set(err, CF_ERANGE, "--environment-lights: %d is outside [1, %d]",
                        o->environment_lights, CF_ENVMAP_MAX_LIGHTS);
  if (o->environment && o->reference_albedo > 0.0)
    return cf_error_set(err, CF_EINVAL,
                        "a reference card needs the flash (its region is checked against the "
                        "flash's shadow): not with an environment");
  return CF_OK;
}

cf_status cf_synth_write(const char *dir, const cf_synth_options *o, cf_error *err) {
  cf_status s = check_options(o, err);
  if (s != CF_OK) return s;
  char path[4096];
  const char *folders[] = {"images", o->write_masks ? "masks" : NULL};
  for (int i = 0; s == CF_OK && i < 2; ++i)
    if (folders[i] && (s = cf_path_join(dir, folders[i], path, sizeof path, err)) == CF_OK)
      s = cf_make_dirs(path, err);
  if (s != CF_OK) return s;

  render_job job;
  memset(&job, 0, sizeof job);
  job.options = o;
  job.dir = dir;
  job.camera = pinhole(o);
  /* a white Lambert surface facing the flash at the orbit's distance has
   * radiance 0.5: I/(π D²) = 0.5 */
  job.intensity =
      o->flash_intensity > 0.0 ? o->flash_intensity : 0.5 * CF_PI * o->distance * o->distance;
  job.response = synth_response(o);
  job.cameras = calloc((size_t)o->images, sizeof *job.cameras);
  job.exposures = calloc((size_t)o->images, sizeof *job.exposures);
  if (o->exif_exposures) job.exif = calloc((size_t)o->images, sizeof *job.exif);
  if (!job.cameras || !job.exposures || (o->exif_exposures && !job.exif))
    s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) {
    image_exposures(o, job.exposures, job.exif);
    for (int k = 0; k < o->images; ++k) orbit_camera(o, k, &job.cameras[k]);
  }
  /* an unreadable map is bad input like a bad option (CF_EINVAL), the
   * message kept */
  if (s == CF_OK && (s = load_environment(dir, &job, err)) != CF_OK && s != CF_ENOMEM)
    s = CF_EINVAL;
  if (s == CF_OK && o->reference_albedo > 0.0) s = card_region(&job, job.card_region, err);
  if (s != CF_OK) {
    free(job.environment);
    free(job.cameras);
    free(job.exposures);
    free(job.exif);
    return s;
  }
  pthread_mutex_init(&job.lock, NULL);
  cf_parallel_for(o->images, SYNTH_THREADS, render_one, &job);
  pthread_mutex_destroy(&job.lock);
  s = job.status;
  if (s != CF_OK && err) *err = job.error;
  if (s == CF_OK) s = write_colmap(dir, &job, err);
  if (s == CF_OK) s = write_capture_file(dir, &job, err);
  if (s == CF_OK) s = write_truth(dir, &job, err);
  free(job.environment);
  free(job.cameras);
  free(job.exposures);
  free(job.exif);
  return s;
}
