/* The files of a synthetic capture around its images (synth_internal.h):
 * the COLMAP model, the capture file and truth.json. */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/colmap.h"
#include "core/file.h"
#include "core/json_reader.h"
#include "synth_internal.h"

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
    snprintf(names[k], sizeof names[k], "%03d.%s", k, synth_extension(o->format));
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
    snprintf(name, sizeof name, "%03d.%s", k, synth_extension(o->format));
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
    snprintf(image, sizeof image, "%03d.%s", 0, synth_extension(o->format));
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
                  "center", synth_card_center[0], synth_card_center[1], SYNTH_GROUND_Z, "size",
                  2.0 * synth_card_half, "intensity_factor", CF_SYNTH_REFERENCE_FACTOR, "region",
                  job->card_region[0], job->card_region[1], job->card_region[2],
                  job->card_region[3]));
  return write_json(dir, "truth.json", doc, err);
}

cf_status synth_write_files(const char *dir, const render_job *job, cf_error *err) {
  cf_status s = write_colmap(dir, job, err);
  if (s == CF_OK) s = write_capture_file(dir, job, err);
  if (s == CF_OK) s = write_truth(dir, job, err);
  return s;
}
