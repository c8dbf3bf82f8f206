/* Synthetic captures (include/clayfit/synth.h): orbit cameras, the scene
 * rendered by the image formation of docs/model.md §5 with S×S samples per pixel near
 * and on the sphere, photon and read noise, and everything a real capture
 * would have: images, a COLMAP model, a capture file (plus the truth).
 * This file: the options and their check, the orbit's cameras, the images'
 * exposures, the environment's lights, and cf_synth_write, which renders
 * the images (synth_render.c) and writes the files around them
 * (synth_files.c). */
#include "clayfit/synth.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/image.h"
#include "core/file.h"
#include "core/parallel.h"
#include "core/vec.h"
#include "envmap.h"
#include "synth_internal.h"

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

/* ---- the images: names, response, exposures ---- */

const char *synth_extension(cf_synth_format format) {
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

/* ---- the environment, the options, the whole capture ---- */

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
  if (s == CF_OK && o->reference_albedo > 0.0) s = synth_card_region(&job, job.card_region, err);
  if (s != CF_OK) {
    free(job.environment);
    free(job.cameras);
    free(job.exposures);
    free(job.exif);
    return s;
  }
  pthread_mutex_init(&job.lock, NULL);
  cf_parallel_for(o->images, SYNTH_THREADS, synth_render_one, &job);
  pthread_mutex_destroy(&job.lock);
  s = job.status;
  if (s != CF_OK && err) *err = job.error;
  if (s == CF_OK) s = synth_write_files(dir, &job, err);
  free(job.environment);
  free(job.cameras);
  free(job.exposures);
  free(job.exif);
  return s;
}
