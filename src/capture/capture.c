/* Loading a capture (include/clayfit/capture.h): the capture file, then the
 * cameras, the sphere's surface, the lights, and every image's pixels into
 * observations. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"

void capture_warn(cf_capture *capture, const char *format, ...) {
  char message[CF_ERROR_MESSAGE_SIZE];
  va_list args;
  va_start(args, format);
  vsnprintf(message, sizeof message, format, args);
  va_end(args);
  char **grown = realloc(capture->warnings, (capture->num_warnings + 1) * sizeof *grown);
  if (!grown) return;
  capture->warnings = grown;
  size_t n = strlen(message) + 1;
  if ((grown[capture->num_warnings] = malloc(n))) {
    memcpy(grown[capture->num_warnings], message, n);
    ++capture->num_warnings;
  }
}

cf_decode capture_image_decode(const cf_capture *capture, const cf_image_info *info,
                               double exposure) {
  const cf_capture_spec *spec = &capture->spec;
  cf_decode d;
  d.transfer = spec->transfer;
  d.gamma = spec->gamma;
  d.black_level = spec->black_level;
  /* by default the largest code of an integer image is clipped; a float
   * image has no such level. A JPEG's coding spreads a clipped highlight's
   * error to the codes just below the top (its blocks' ringing, 4:2:0
   * chroma): CAPTURE_JPEG_CLIP_LEVEL counts them as clipped too. */
  double integer_clip = strcmp(info->format, "jpeg") == 0 ? CAPTURE_JPEG_CLIP_LEVEL : 1.0;
  d.clip_level =
      isnan(spec->clip_level) ? (info->is_float ? INFINITY : integer_clip) : spec->clip_level;
  d.exposure = exposure;
  return d;
}

/* colour.exposure "exif": the exposures' reference is their geometric mean
 * (docs/model.md (39): fix the reference, or exposures trade with ρ and F0). The
 * radiances were divided by the raw exposures; rescale them. */
static void normalise_exif_exposures(cf_capture *capture) {
  size_t n = capture->spec.num_images;
  double log_sum = 0.0;
  for (size_t k = 0; k < n; ++k) log_sum += log(capture->raw_exposures[k]);
  double reference = exp(log_sum / (double)n);
  for (size_t k = 0; k < n; ++k)
    capture->images[k].exposure = capture->raw_exposures[k] / reference;
  for (size_t i = 0; i < 3 * capture->obs.count; ++i) capture->obs.rgb[i] *= reference;
}

static cf_status check_sphere_seen(cf_capture *capture, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  for (size_t k = 0; k < spec->num_images; ++k)
    if (capture->images[k].sphere_pixels == 0)
      capture_warn(capture, "%s: no pixel of this image sees the sphere", spec->image_paths[k]);
  if (capture->obs.count > 0) return CF_OK;
  if (spec->camera == CF_CAMERA_KIND_COLMAP)
    return cf_error_set(err, CF_EINVAL,
                        "%s: geometry: the sphere (centre %g %g %g, radius %g) is seen by none "
                        "of the %zu cameras (clear of its silhouette and inside the masks)",
                        spec->path, capture->center[0], capture->center[1], capture->center[2],
                        capture->radius, spec->num_images);
  return cf_error_set(err, CF_EINVAL,
                      "%s: geometry: no pixel of the %zu images sees the sphere clear of its "
                      "silhouette and inside the masks",
                      spec->path, spec->num_images);
}

static cf_status load(cf_capture *capture, const char *path, const cf_capture_options *options,
                      cf_error *err) {
  cf_status s = cf_capture_spec_read(path, &capture->spec, err);
  if (s != CF_OK) return s;
  size_t n = capture->spec.num_images;
  capture->views = calloc(n, sizeof *capture->views);
  capture->images = calloc(n, sizeof *capture->images);
  capture->raw_exposures = calloc(n, sizeof *capture->raw_exposures);
  if (!capture->views || !capture->images || !capture->raw_exposures)
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu images", n);
  if ((s = capture_load_views(capture, err)) != CF_OK) return s;
  if ((s = capture_read_headers(capture, options, err)) != CF_OK) return s;
  if ((s = capture_load_surface(capture, options, err)) != CF_OK) return s;
  if ((s = capture_load_lights(capture, err)) != CF_OK) return s;
  capture->obs.lights = capture->max_lights;
  if ((s = capture_read_images(capture, options, err)) != CF_OK) return s;
  if (capture->spec.exposure == CF_EXPOSURE_EXIF) {
    if ((s = capture_check_exposure_spread(capture, err)) != CF_OK) return s;
    normalise_exif_exposures(capture);
  }
  if ((s = check_sphere_seen(capture, err)) != CF_OK) return s;
  if ((s = capture_screen_observations(capture, err)) != CF_OK) return s;
  capture_measure_adjacent_turn(capture);
  /* the observations' irradiance in absolute units from the reference */
  return capture->spec.has_reference ? capture_apply_reference(capture, err) : CF_OK;
}

cf_status cf_capture_load(const char *path, const cf_capture_options *options, cf_capture **capture,
                          cf_error *err) {
  *capture = calloc(1, sizeof **capture);
  if (!*capture) return cf_error_set(err, CF_ENOMEM, "out of memory");
  cf_status s = load(*capture, path, options, err);
  if (s != CF_OK) {
    cf_capture_free(*capture);
    *capture = NULL;
  }
  return s;
}

void cf_capture_free(cf_capture *capture) {
  if (!capture) return;
  capture_free_observations(&capture->obs);
  for (size_t i = 0; i < capture->num_warnings; ++i) free(capture->warnings[i]);
  free(capture->warnings);
  free(capture->views);
  free(capture->images);
  free(capture->raw_exposures);
  free(capture->lights);
  free(capture->light_counts);
  cf_image_free(&capture->normal_map);
  free(capture->map_class);
  cf_colmap_model_free(&capture->colmap);
  cf_capture_spec_free(&capture->spec);
  free(capture);
}

const cf_observations *cf_capture_observations(const cf_capture *capture) {
  return &capture->obs;
}

size_t cf_capture_image_count(const cf_capture *capture) {
  return capture->spec.num_images;
}

const cf_capture_image *cf_capture_image_at(const cf_capture *capture, size_t index) {
  return index < capture->spec.num_images ? &capture->images[index] : NULL;
}

const char *cf_capture_warning(const cf_capture *capture, size_t index) {
  return index < capture->num_warnings ? capture->warnings[index] : NULL;
}

void cf_capture_summarize(const cf_capture *capture, cf_capture_summary *summary) {
  static const char *const geometries[] = {"sphere", "sphere_from_silhouettes", "normal_map"};
  const cf_capture_spec *spec = &capture->spec;
  memset(summary, 0, sizeof *summary);
  summary->name = spec->name;
  summary->camera = spec->camera == CF_CAMERA_KIND_COLMAP ? "colmap" : "orthographic";
  summary->geometry = geometries[spec->geometry];
  memcpy(summary->sphere_center, capture->center, sizeof capture->center);
  summary->sphere_radius = capture->radius;
  summary->sphere_rms_px = capture->rms_px;
  summary->silhouette_kept = capture->silhouette_kept;
  summary->radiometry_relative = spec->radiometry_relative && !capture->from_reference;
  summary->tone_curve_unknown = spec->tone_curve_unknown;
  summary->transfer = (int)spec->transfer;
  summary->transfer_gamma = spec->gamma;
  summary->has_noise = spec->has_noise;
  summary->noise_read = spec->noise_read;
  summary->noise_shot = spec->noise_shot;
  summary->warnings = capture->num_warnings;
  summary->radiometry_from_reference = capture->from_reference;
  summary->reference_scale = capture->reference_scale;
  summary->reference_spread = capture->reference_spread;
  memcpy(summary->reference_channel_scales, capture->reference_channel_scales,
         sizeof capture->reference_channel_scales);
  summary->reference_pixels = capture->reference_pixels;
  summary->has_circle = capture->circle_source != NULL;
  summary->circle_center_px[0] = capture->circle.cx;
  summary->circle_center_px[1] = capture->circle.cy;
  summary->circle_axes_px[0] = capture->circle.a;
  summary->circle_axes_px[1] = capture->circle.b;
  summary->circle_angle = capture->circle.angle;
  summary->circle_source = capture->circle_source;
}

/* The first image, at most `index`, whose slot `slot` holds the same light
 * as image `index`'s (direction and intensity). */
static size_t first_same_light(const cf_capture *capture, size_t index, size_t slot) {
  size_t slots = (size_t)capture->max_lights;
  const cf_light *mine = &capture->lights[index * slots + slot];
  for (size_t k = 0; k < index; ++k) {
    const cf_light *other = &capture->lights[k * slots + slot];
    if (!memcmp(other->direction, mine->direction, sizeof mine->direction) &&
        !memcmp(other->intensity, mine->intensity, sizeof mine->intensity))
      return k;
  }
  return index;
}

/* The capture file's light (its index in spec->lights) of light slot
 * `slot` (capture_load_lights' layout: an environment's `count` slots,
 * one for any other light); num_lights past the last. */
static size_t spec_light_of_slot(const cf_capture_spec *spec, size_t slot) {
  size_t at = 0;
  for (size_t i = 0; i < spec->num_lights; ++i) {
    at += spec->lights[i].kind == CF_LIGHT_SPEC_ENVIRONMENT ? (size_t)spec->lights[i].count : 1;
    if (slot < at) return i;
  }
  return spec->num_lights;
}

/* The capture file's lights at most (capture_spec.c refuses more). */
enum { FILE_LIGHTS_MAX = 64 };

size_t cf_capture_light_ids(const cf_capture *capture, long *ids) {
  const cf_capture_spec *spec = &capture->spec;
  size_t slots = (size_t)capture->max_lights, count = 0;
  long whole[FILE_LIGHTS_MAX]; /* the id of each of the file's lights but directional_per_image */
  for (size_t i = 0; i < FILE_LIGHTS_MAX; ++i) whole[i] = -1;
  for (size_t k = 0; k < spec->num_images; ++k)
    for (size_t j = 0; j < slots; ++j) {
      const double *e = capture->lights[k * slots + j].intensity;
      size_t i = spec_light_of_slot(spec, j);
      long *id = &ids[k * slots + j];
      if ((e[0] == 0.0 && e[1] == 0.0 && e[2] == 0.0) || i >= FILE_LIGHTS_MAX) {
        *id = -1; /* no light: no gain */
      } else if (spec->lights[i].kind == CF_LIGHT_SPEC_PER_IMAGE) {
        size_t same = first_same_light(capture, k, j);
        *id = same < k ? ids[same * slots + j] : (long)count++;
      } else {
        if (whole[i] < 0) whole[i] = (long)count++;
        *id = whole[i];
      }
    }
  return count;
}

void cf_capture_light_name(const cf_capture *capture, size_t image, int slot, char *text,
                           size_t size) {
  const cf_capture_spec *spec = &capture->spec;
  size_t i = spec_light_of_slot(spec, (size_t)slot);
  if (i >= spec->num_lights || image >= spec->num_images) {
    snprintf(text, size, "no light");
  } else if (spec->lights[i].kind == CF_LIGHT_SPEC_PER_IMAGE) {
    size_t same = first_same_light(capture, image, (size_t)slot);
    snprintf(text, size, "light %zu, row of %s", i + 1, capture->images[same].name);
  } else {
    snprintf(text, size, "light %zu%s", i + 1,
             spec->lights[i].kind == CF_LIGHT_SPEC_ENVIRONMENT ? " (environment)" : "");
  }
}
