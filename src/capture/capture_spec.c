/* Reading a capture file into a cf_capture_spec (capture_spec.h), against
 * data_schema/capture.schema.json: types, ranges, unknown keys and the
 * rules between fields (a gamma for encoding "gamma", exposures for
 * exposure "given", ...), each error naming the JSON path. */
#include "capture_spec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "core/file.h"
#include "core/json_reader.h"
#include "envmap.h"

enum {
  MAX_CAPTURE_FILE = 64 << 20, /* bytes */
  MAX_LIST_FILE = 16 << 20,
  MAX_IMAGES = 1 << 20,
  MAX_PATH_LENGTH = 4096
};

static char *copy_string(const char *text) {
  size_t n = strlen(text) + 1;
  char *copy = malloc(n);
  if (copy) memcpy(copy, text, n);
  return copy;
}

/* A path from the file, resolved against `dir`. */
static cf_status resolve(const char *dir, const char *name, const json_at *at, char **out,
                         cf_error *err) {
  char buffer[MAX_PATH_LENGTH];
  if (cf_path_join(dir, name, buffer, sizeof buffer, err) != CF_OK)
    return json_fail(at, err, CF_ERANGE, "path too long");
  *out = copy_string(buffer);
  return *out ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
}

static cf_status out_of_memory(cf_error *err) {
  return cf_error_set(err, CF_ENOMEM, "out of memory reading the capture file");
}

/* ---- camera ---- */

static cf_status read_camera(const json_t *root, const json_at *at, cf_capture_spec *spec,
                             cf_error *err) {
  const json_t *camera;
  cf_status s = json_get_object(root, at, "camera", 1, &camera, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "camera");
  static const char *const kinds[] = {"colmap", "orthographic", NULL};
  int kind;
  s = json_get_choice(camera, &here, "type", 1, kinds, &kind, NULL, err);
  if (s != CF_OK) return s;
  spec->camera = (cf_camera_kind)kind;
  if (spec->camera == CF_CAMERA_KIND_COLMAP) {
    static const char *const keys[] = {"type", "model", NULL};
    const char *model;
    if ((s = json_check_keys(camera, &here, keys, err)) != CF_OK) return s;
    if ((s = json_get_string(camera, &here, "model", 1, &model, NULL, err)) != CF_OK) return s;
    json_at model_at = json_member_at(&here, "model");
    return resolve(spec->dir, model, &model_at, &spec->colmap_model, err);
  }
  static const char *const keys[] = {"type", "view", NULL};
  if ((s = json_check_keys(camera, &here, keys, err)) != CF_OK) return s;
  double view[3] = {0.0, 0.0, 1.0};
  if ((s = json_get_numbers(camera, &here, "view", 0, 3, -1e300, 1e300, view, NULL, err)) != CF_OK)
    return s;
  double length = sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
  json_at view_at = json_member_at(&here, "view");
  if (!(length > 0.0) || !isfinite(length))
    return json_fail(&view_at, err, CF_EPARSE,
                     "the view direction needs a finite, non-zero length");
  for (int k = 0; k < 3; ++k) spec->view[k] = view[k] / length;
  return CF_OK;
}

/* ---- images ---- */

/* Names from a list file: one per line, blank lines and '#' comments
 * skipped (as in the light files), spaces at either end removed. */
static cf_status read_list(const char *path, const json_at *at, cf_capture_spec *spec,
                           cf_error *err) {
  char *text;
  size_t size;
  cf_status s = cf_read_text_file(path, MAX_LIST_FILE, &text, &size, err);
  if (s != CF_OK) return json_fail(at, err, s, "%s", err->message);
  size_t capacity = 0, line = 0;
  for (char *cursor = text; *cursor;) {
    char *end = strchr(cursor, '\n');
    if (end) *end = '\0';
    ++line;
    size_t n = strlen(cursor);
    while (n && (cursor[n - 1] == '\r' || cursor[n - 1] == ' ' || cursor[n - 1] == '\t'))
      cursor[--n] = '\0';
    while (*cursor == ' ' || *cursor == '\t') ++cursor;
    if (*cursor && *cursor != '#') {
      if (spec->num_images == MAX_IMAGES) {
        free(text);
        return cf_error_set(err, CF_ERANGE, "%s: more than %d images", path, MAX_IMAGES);
      }
      if (spec->num_images == capacity) {
        capacity = capacity ? 2 * capacity : 64;
        char **grown = realloc(spec->image_names, capacity * sizeof *grown);
        if (!grown) {
          free(text);
          return out_of_memory(err);
        }
        spec->image_names = grown;
      }
      spec->image_names[spec->num_images] = copy_string(cursor);
      if (!spec->image_names[spec->num_images]) {
        free(text);
        return out_of_memory(err);
      }
      ++spec->num_images;
    }
    if (!end) break;
    cursor = end + 1;
  }
  free(text);
  if (spec->num_images == 0)
    return cf_error_set(err, CF_EPARSE, "%s: the image list is empty", path);
  return CF_OK;
}

/* The image names: exactly one of 'files' (the names) and 'list' (a list
 * file, read_list). */
static cf_status read_image_names(const json_t *images, const json_at *here, cf_capture_spec *spec,
                                  cf_error *err) {
  const json_t *files = NULL;
  const char *list = NULL;
  int has_files = 0, has_list = 0;
  cf_status s = json_get_array(images, here, "files", 0, &files, &has_files, err);
  if (s == CF_OK) s = json_get_string(images, here, "list", 0, &list, &has_list, err);
  if (s == CF_OK && has_files == has_list)
    s = json_fail(here, err, CF_EPARSE, "give exactly one of 'files' and 'list'");
  if (s != CF_OK) return s;
  if (has_list) {
    json_at list_at = json_member_at(here, "list");
    char *list_path = NULL;
    s = resolve(spec->dir, list, &list_at, &list_path, err);
    if (s == CF_OK) s = read_list(list_path, &list_at, spec, err);
    spec->image_list = list_path;
    return s;
  }
  json_at files_at = json_member_at(here, "files");
  spec->num_images = json_array_size(files);
  if (spec->num_images == 0 || spec->num_images > MAX_IMAGES)
    s = json_fail(&files_at, err, CF_EPARSE, "needs 1 to %d image names, has %zu", MAX_IMAGES,
                  spec->num_images);
  if (s == CF_OK && !(spec->image_names = calloc(spec->num_images, sizeof(char *))))
    s = out_of_memory(err);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i) {
    json_at element = json_element_at(&files_at, i);
    const char *name;
    s = json_as_string(json_array_get(files, i), &element, &name, err);
    if (s == CF_OK && !name[0]) s = json_fail(&element, err, CF_EPARSE, "empty file name");
    if (s == CF_OK && !(spec->image_names[i] = copy_string(name))) s = out_of_memory(err);
  }
  return s;
}

/* exposures: one per image, when given */
static cf_status read_exposures(const json_t *images, const json_at *here, cf_capture_spec *spec,
                                cf_error *err) {
  const json_t *exposures = NULL;
  int has_exposures = 0;
  cf_status s = json_get_array(images, here, "exposures", 0, &exposures, &has_exposures, err);
  if (s != CF_OK || !has_exposures) return s;
  json_at exp_at = json_member_at(here, "exposures");
  if (json_array_size(exposures) != spec->num_images)
    s = json_fail(&exp_at, err, CF_EPARSE, "has %zu exposures for %zu images",
                  json_array_size(exposures), spec->num_images);
  if (s == CF_OK && !(spec->exposures = malloc(spec->num_images * sizeof(double))))
    s = out_of_memory(err);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i) {
    json_at element = json_element_at(&exp_at, i);
    s = json_as_number(json_array_get(exposures, i), &element, 1e-300, 1e300, &spec->exposures[i],
                       err);
  }
  return s;
}

/* masks: one for all images, or a folder with the images' names */
static cf_status read_masks(const json_t *images, const json_at *here, cf_capture_spec *spec,
                            cf_error *err) {
  const char *mask = NULL, *masks = NULL;
  int has_mask = 0, has_masks = 0;
  cf_status s = json_get_string(images, here, "mask", 0, &mask, &has_mask, err);
  if (s == CF_OK) s = json_get_string(images, here, "masks", 0, &masks, &has_masks, err);
  if (s == CF_OK && has_mask && has_masks)
    s = json_fail(here, err, CF_EPARSE, "give at most one of 'mask' and 'masks'");
  if (s != CF_OK || !(has_mask || has_masks)) return s;
  if (!(spec->mask_paths = calloc(spec->num_images, sizeof(char *)))) s = out_of_memory(err);
  char *mask_dir = NULL;
  json_at mask_at = json_member_at(here, has_mask ? "mask" : "masks");
  if (s == CF_OK && has_masks) s = resolve(spec->dir, masks, &mask_at, &mask_dir, err);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i)
    s = has_mask ? resolve(spec->dir, mask, &mask_at, &spec->mask_paths[i], err)
                 : resolve(mask_dir, spec->image_names[i], &mask_at, &spec->mask_paths[i], err);
  free(mask_dir);
  return s;
}

static cf_status read_images(const json_t *root, const json_at *at, cf_capture_spec *spec,
                             cf_error *err) {
  const json_t *images;
  cf_status s = json_get_object(root, at, "images", 1, &images, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "images");
  static const char *const keys[] = {"directory", "files", "list", "exposures",
                                     "masks",     "mask",  NULL};
  if ((s = json_check_keys(images, &here, keys, err)) != CF_OK) return s;

  const char *directory = ".";
  if ((s = json_get_string(images, &here, "directory", 0, &directory, NULL, err)) != CF_OK)
    return s;
  char *image_dir = NULL;
  json_at dir_at = json_member_at(&here, "directory");
  if ((s = resolve(spec->dir, directory, &dir_at, &image_dir, err)) != CF_OK) return s;

  s = read_image_names(images, &here, spec, err);
  if (s == CF_OK && !(spec->image_paths = calloc(spec->num_images, sizeof(char *))))
    s = out_of_memory(err);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i)
    s = resolve(image_dir, spec->image_names[i], &here, &spec->image_paths[i], err);
  if (s == CF_OK) s = read_exposures(images, &here, spec, err);
  if (s == CF_OK) s = read_masks(images, &here, spec, err);
  free(image_dir);
  return s;
}

/* ---- colour, radiometry, noise ---- */

static cf_status read_colour(const json_t *root, const json_at *at, cf_capture_spec *spec,
                             cf_error *err) {
  const json_t *colour;
  cf_status s = json_get_object(root, at, "colour", 1, &colour, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "colour");
  static const char *const keys[] = {"encoding", "gamma",      "black_level", "clip_level",
                                     "exposure", "tone_curve", NULL};
  static const char *const encodings[] = {"linear", "srgb", "gamma", NULL};
  static const char *const exposures[] = {"none", "given", "exif", NULL};
  static const char *const curves[] = {"known", "unknown", NULL};
  int encoding = 0, exposure = 0, curve = 0, has_gamma = 0, has_clip = 0;
  spec->gamma = 1.0;
  spec->black_level = 0.0;
  if ((s = json_check_keys(colour, &here, keys, err)) != CF_OK) return s;
  if ((s = json_get_choice(colour, &here, "encoding", 1, encodings, &encoding, NULL, err)) != CF_OK)
    return s;
  if ((s = json_get_number(colour, &here, "gamma", 0, 1e-3, 1e3, &spec->gamma, &has_gamma, err)) !=
      CF_OK)
    return s;
  if ((s = json_get_number(colour, &here, "black_level", 0, -1e300, 1e300, &spec->black_level, NULL,
                           err)) != CF_OK)
    return s;
  if ((s = json_get_number(colour, &here, "clip_level", 0, 1e-300, 1e300, &spec->clip_level,
                           &has_clip, err)) != CF_OK)
    return s;
  if ((s = json_get_choice(colour, &here, "exposure", 0, exposures, &exposure, NULL, err)) != CF_OK)
    return s;
  if ((s = json_get_choice(colour, &here, "tone_curve", 0, curves, &curve, NULL, err)) != CF_OK)
    return s;
  spec->transfer = (cf_transfer)encoding;
  if (spec->transfer == CF_TRANSFER_GAMMA && !has_gamma)
    return json_fail(&here, err, CF_EPARSE, "encoding \"gamma\" needs 'gamma'");
  if (spec->transfer != CF_TRANSFER_GAMMA && has_gamma)
    return json_fail(&here, err, CF_EPARSE, "'gamma' is only for encoding \"gamma\"");
  if (!has_clip) spec->clip_level = NAN;
  spec->exposure = (cf_exposure_kind)exposure;
  spec->tone_curve_unknown = curve == 1;
  json_at exp_at = json_member_at(&here, "exposure");
  if (spec->exposure == CF_EXPOSURE_GIVEN && !spec->exposures)
    return json_fail(&exp_at, err, CF_EPARSE, "\"given\" needs images.exposures");
  if (spec->exposure != CF_EXPOSURE_GIVEN && spec->exposures)
    return json_fail(&exp_at, err, CF_EPARSE,
                     "images.exposures are given, so this must be \"given\"");
  return CF_OK;
}

static cf_status read_radiometry_and_noise(const json_t *root, const json_at *at,
                                           cf_capture_spec *spec, cf_error *err) {
  static const char *const radiometry[] = {"absolute", "relative", NULL};
  int relative = 0;
  cf_status s = json_get_choice(root, at, "radiometry", 0, radiometry, &relative,
                                &spec->radiometry_given, err);
  if (s != CF_OK) return s;
  spec->radiometry_relative = relative;
  const json_t *noise;
  if ((s = json_get_object(root, at, "noise", 0, &noise, &spec->has_noise, err)) != CF_OK) return s;
  if (!spec->has_noise) return CF_OK;
  json_at here = json_member_at(at, "noise");
  static const char *const keys[] = {"read", "shot", NULL};
  if ((s = json_check_keys(noise, &here, keys, err)) != CF_OK) return s;
  if ((s = json_get_number(noise, &here, "read", 1, 0.0, 1e300, &spec->noise_read, NULL, err)) !=
      CF_OK)
    return s;
  return json_get_number(noise, &here, "shot", 1, 0.0, 1e300, &spec->noise_shot, NULL, err);
}

/* ---- geometry and scale ---- */

static cf_status read_geometry(const json_t *root, const json_at *at, cf_capture_spec *spec,
                               cf_error *err) {
  const json_t *geometry;
  cf_status s = json_get_object(root, at, "geometry", 1, &geometry, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "geometry");
  static const char *const keys[] = {"type", "center", "radius", "file", "margin_px", NULL};
  static const char *const kinds[] = {"sphere", "sphere_from_silhouettes", "normal_map", NULL};
  int kind, has_center = 0, has_radius = 0, has_file = 0;
  if ((s = json_check_keys(geometry, &here, keys, err)) != CF_OK) return s;
  if ((s = json_get_choice(geometry, &here, "type", 1, kinds, &kind, NULL, err)) != CF_OK) return s;
  spec->geometry = (cf_geometry_kind)kind;
  spec->margin_px = 2.0;
  const char *file = NULL;
  if ((s = json_get_numbers(geometry, &here, "center", 0, 3, -1e300, 1e300, spec->center,
                            &has_center, err)) != CF_OK ||
      (s = json_get_number(geometry, &here, "radius", 0, 1e-300, 1e300, &spec->radius, &has_radius,
                           err)) != CF_OK ||
      (s = json_get_string(geometry, &here, "file", 0, &file, &has_file, err)) != CF_OK ||
      (s = json_get_number(geometry, &here, "margin_px", 0, 0.0, 1e4, &spec->margin_px, NULL,
                           err)) != CF_OK)
    return s;
  int is_sphere = spec->geometry == CF_GEOMETRY_SPHERE;
  if (is_sphere && !(has_center && has_radius))
    return json_fail(&here, err, CF_EPARSE, "type \"sphere\" needs 'center' and 'radius'");
  if (!is_sphere && (has_center || has_radius))
    return json_fail(&here, err, CF_EPARSE, "'center' and 'radius' are only for type \"sphere\"");
  if (spec->geometry == CF_GEOMETRY_NORMAL_MAP) {
    if (!has_file) return json_fail(&here, err, CF_EPARSE, "type \"normal_map\" needs 'file'");
    if (spec->camera != CF_CAMERA_KIND_ORTHOGRAPHIC)
      return json_fail(&here, err, CF_EPARSE, "type \"normal_map\" needs an orthographic camera");
    json_at file_at = json_member_at(&here, "file");
    return resolve(spec->dir, file, &file_at, &spec->normal_map, err);
  }
  if (has_file) return json_fail(&here, err, CF_EPARSE, "'file' is only for type \"normal_map\"");
  if (is_sphere && spec->camera == CF_CAMERA_KIND_ORTHOGRAPHIC)
    return json_fail(&here, err, CF_EPARSE,
                     "an orthographic camera has no world positions: use "
                     "\"sphere_from_silhouettes\" or \"normal_map\"");
  return CF_OK;
}

static cf_status read_scale(const json_t *root, const json_at *at, cf_capture_spec *spec,
                            cf_error *err) {
  const json_t *scale;
  int found = 0;
  spec->sphere_radius_m = NAN;
  cf_status s = json_get_object(root, at, "scale", 0, &scale, &found, err);
  if (s != CF_OK || !found) return s;
  json_at here = json_member_at(at, "scale");
  static const char *const keys[] = {"sphere_radius_m", NULL};
  if ((s = json_check_keys(scale, &here, keys, err)) != CF_OK) return s;
  return json_get_number(scale, &here, "sphere_radius_m", 1, 1e-300, 1e300, &spec->sphere_radius_m,
                         NULL, err);
}

/* ---- lights ---- */

static cf_status read_unit_vector(const json_t *object, const json_at *at, const char *key,
                                  double out[3], cf_error *err) {
  cf_status s = json_get_numbers(object, at, key, 1, 3, -1e300, 1e300, out, NULL, err);
  if (s != CF_OK) return s;
  double length = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
  json_at here = json_member_at(at, key);
  if (!(length > 0.0) || !isfinite(length))
    return json_fail(&here, err, CF_EPARSE, "a direction needs a finite, non-zero length");
  for (int k = 0; k < 3; ++k) out[k] /= length;
  return CF_OK;
}

static cf_status read_flash(const json_t *item, const json_at *at, cf_capture_spec *spec,
                            cf_light_spec *light, cf_error *err) {
  static const char *const keys[] = {"type", "offset", "offset_m", "intensity", NULL};
  int has_offset = 0, has_metres = 0;
  cf_status s;
  light->kind = CF_LIGHT_SPEC_SINGLE;
  light->light.kind = CF_LIGHT_FLASH;
  if ((s = json_check_keys(item, at, keys, err)) != CF_OK ||
      (s = json_get_numbers(item, at, "offset", 0, 3, -1e300, 1e300, light->light.position,
                            &has_offset, err)) != CF_OK ||
      (s = json_get_numbers(item, at, "offset_m", 0, 3, -1e300, 1e300, light->light.position,
                            &has_metres, err)) != CF_OK ||
      (s = json_get_numbers(item, at, "intensity", 1, 3, 0.0, 1e300, light->light.intensity, NULL,
                            err)) != CF_OK)
    return s;
  if (has_offset == has_metres)
    return json_fail(at, err, CF_EPARSE, "give exactly one of 'offset' and 'offset_m'");
  if (has_metres && !isfinite(spec->sphere_radius_m))
    return json_fail(at, err, CF_EPARSE, "'offset_m' needs scale.sphere_radius_m");
  light->offset_in_metres = has_metres;
  return CF_OK;
}

static cf_status read_point(const json_t *item, const json_at *at, cf_light_spec *light,
                            cf_error *err) {
  static const char *const keys[] = {"type", "position", "intensity", NULL};
  cf_status s;
  light->kind = CF_LIGHT_SPEC_SINGLE;
  light->light.kind = CF_LIGHT_POINT;
  if ((s = json_check_keys(item, at, keys, err)) != CF_OK ||
      (s = json_get_numbers(item, at, "position", 1, 3, -1e300, 1e300, light->light.position, NULL,
                            err)) != CF_OK)
    return s;
  return json_get_numbers(item, at, "intensity", 1, 3, 0.0, 1e300, light->light.intensity, NULL,
                          err);
}

static cf_status read_directional(const json_t *item, const json_at *at, cf_light_spec *light,
                                  cf_error *err) {
  static const char *const keys[] = {"type", "direction", "irradiance", NULL};
  cf_status s;
  light->kind = CF_LIGHT_SPEC_SINGLE;
  light->light.kind = CF_LIGHT_DIRECTIONAL;
  if ((s = json_check_keys(item, at, keys, err)) != CF_OK ||
      (s = read_unit_vector(item, at, "direction", light->light.direction, err)) != CF_OK)
    return s;
  return json_get_numbers(item, at, "irradiance", 1, 3, 0.0, 1e300, light->light.intensity, NULL,
                          err);
}

static cf_status read_per_image(const json_t *item, const json_at *at, cf_capture_spec *spec,
                                cf_light_spec *light, cf_error *err) {
  static const char *const keys[] = {"type", "directions", "intensities", NULL};
  const char *directions, *intensities;
  cf_status s;
  light->kind = CF_LIGHT_SPEC_PER_IMAGE;
  if ((s = json_check_keys(item, at, keys, err)) != CF_OK ||
      (s = json_get_string(item, at, "directions", 1, &directions, NULL, err)) != CF_OK ||
      (s = json_get_string(item, at, "intensities", 1, &intensities, NULL, err)) != CF_OK)
    return s;
  json_at d_at = json_member_at(at, "directions"), i_at = json_member_at(at, "intensities");
  if ((s = resolve(spec->dir, directions, &d_at, &light->directions, err)) != CF_OK) return s;
  if (strcmp(intensities, "equal") != 0)
    return resolve(spec->dir, intensities, &i_at, &light->intensities, err);
  /* unknown and equal (a chrome ball gives directions only): 1 each, and
   * the capture's lights known up to one common factor */
  if (spec->radiometry_given && !spec->radiometry_relative)
    return json_fail(&i_at, err, CF_EPARSE,
                     "\"equal\" intensities are known only up to a common factor: the "
                     "capture's radiometry must be \"relative\" (or left out), not "
                     "\"absolute\"");
  light->intensities_equal = 1;
  spec->radiometry_relative = 1;
  return CF_OK;
}

static cf_status read_environment(const json_t *item, const json_at *at, cf_capture_spec *spec,
                                  cf_light_spec *light, cf_error *err) {
  static const char *const keys[] = {"type", "file", "rotation", "scale", "count", NULL};
  static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const char *file;
  long long count = 32;
  cf_status s;
  light->kind = CF_LIGHT_SPEC_ENVIRONMENT;
  light->scale = 1.0;
  memcpy(light->rotation, identity, sizeof identity);
  if ((s = json_check_keys(item, at, keys, err)) != CF_OK ||
      (s = json_get_string(item, at, "file", 1, &file, NULL, err)) != CF_OK ||
      (s = json_get_numbers(item, at, "rotation", 0, 9, -1e300, 1e300, light->rotation, NULL,
                            err)) != CF_OK ||
      (s = json_get_number(item, at, "scale", 0, 1e-300, 1e300, &light->scale, NULL, err)) !=
          CF_OK ||
      (s = json_get_integer(item, at, "count", 0, 1, CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS, &count,
                            NULL, err)) != CF_OK)
    return s;
  light->count = (int)count;
  if (cf_envmap_check_rotation(light->rotation, err) != CF_OK) {
    json_at r_at = json_member_at(at, "rotation");
    char why[sizeof err->message];
    snprintf(why, sizeof why, "%s", err->message);
    return json_fail(&r_at, err, CF_EPARSE, "%s", why);
  }
  json_at f_at = json_member_at(at, "file");
  return resolve(spec->dir, file, &f_at, &light->file, err);
}

static cf_status read_light(const json_t *item, const json_at *at, cf_capture_spec *spec,
                            cf_light_spec *light, cf_error *err) {
  if (!json_is_object(item))
    return json_fail(at, err, CF_EPARSE, "expected an object, got %s", json_type_name(item));
  static const char *const kinds[] = {
      "flash", "point", "directional", "directional_per_image", "environment", NULL};
  int kind;
  cf_status s = json_get_choice(item, at, "type", 1, kinds, &kind, NULL, err);
  if (s != CF_OK) return s;
  switch (kind) {
    case 0:
      return read_flash(item, at, spec, light, err);
    case 1:
      return read_point(item, at, light, err);
    case 2:
      return read_directional(item, at, light, err);
    case 3:
      return read_per_image(item, at, spec, light, err);
    default:
      return read_environment(item, at, spec, light, err);
  }
}

static cf_status read_lights(const json_t *root, const json_at *at, cf_capture_spec *spec,
                             cf_error *err) {
  const json_t *lights;
  cf_status s = json_get_array(root, at, "lights", 1, &lights, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "lights");
  spec->num_lights = json_array_size(lights);
  if (spec->num_lights == 0 || spec->num_lights > 64)
    return json_fail(&here, err, CF_EPARSE, "needs 1 to 64 lights, has %zu", spec->num_lights);
  if (!(spec->lights = calloc(spec->num_lights, sizeof *spec->lights))) return out_of_memory(err);
  for (size_t i = 0; i < spec->num_lights; ++i) {
    json_at element = json_element_at(&here, i);
    s = read_light(json_array_get(lights, i), &element, spec, &spec->lights[i], err);
    if (s != CF_OK) return s;
    int ortho = spec->camera == CF_CAMERA_KIND_ORTHOGRAPHIC;
    int positional = spec->lights[i].kind == CF_LIGHT_SPEC_SINGLE &&
                     spec->lights[i].light.kind != CF_LIGHT_DIRECTIONAL;
    if (ortho && positional)
      return json_fail(&element, err, CF_EPARSE,
                       "an orthographic camera has no world positions: only directional "
                       "lights and environment maps work with it");
  }
  return CF_OK;
}

/* ---- the reference target ---- */

/* reference.region: four integers x0, y0, x1, y1 with x1 > x0 >= 0 and
 * y1 > y0 >= 0 (the image's size is checked when it is read). */
static cf_status read_region(const json_t *reference, const json_at *at, int region[4],
                             cf_error *err) {
  const json_t *array;
  cf_status s = json_get_array(reference, at, "region", 1, &array, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "region");
  if (json_array_size(array) != 4)
    return json_fail(&here, err, CF_EPARSE, "expected 4 integers [x0, y0, x1, y1], got %zu values",
                     json_array_size(array));
  for (size_t i = 0; i < 4; ++i) {
    json_at element = json_element_at(&here, i);
    const json_t *value = json_array_get(array, i);
    if (!json_is_integer(value))
      return json_fail(&element, err, CF_EPARSE, "expected an integer (pixels), got %s",
                       json_is_real(value) ? "a fractional number" : json_type_name(value));
    json_int_t x = json_integer_value(value);
    if (x < 0 || x > 1 << 20)
      return json_fail(&element, err, CF_ERANGE, "%lld is outside [0, %d]", (long long)x, 1 << 20);
    region[i] = (int)x;
  }
  if (region[2] <= region[0] || region[3] <= region[1])
    return json_fail(&here, err, CF_EPARSE,
                     "[%d, %d, %d, %d] is empty: it needs x1 > x0 and y1 > y0", region[0],
                     region[1], region[2], region[3]);
  return CF_OK;
}

/* reference.albedo: one number or [r, g, b], each in (0, 1]. */
static cf_status read_albedo(const json_t *reference, const json_at *at, double albedo[3],
                             cf_error *err) {
  const json_t *value = json_object_get(reference, "albedo");
  json_at here = json_member_at(at, "albedo");
  if (!value) return json_fail(at, err, CF_EPARSE, "missing required key 'albedo'");
  cf_status s;
  if (json_is_array(value)) {
    s = json_get_numbers(reference, at, "albedo", 1, 3, -1e300, 1e300, albedo, NULL, err);
  } else if (json_is_number(value)) {
    s = json_as_number(value, &here, -1e300, 1e300, &albedo[0], err);
    albedo[1] = albedo[2] = albedo[0];
  } else {
    return json_fail(&here, err, CF_EPARSE, "expected a number or [r, g, b], got %s",
                     json_type_name(value));
  }
  if (s != CF_OK) return s;
  for (int c = 0; c < 3; ++c)
    if (!(albedo[c] > 0.0 && albedo[c] <= 1.0)) {
      json_at element = json_element_at(&here, (size_t)c);
      return json_fail(json_is_array(value) ? &element : &here, err, CF_ERANGE,
                       "%.17g is outside (0, 1]: an albedo is a fraction of the light", albedo[c]);
    }
  return CF_OK;
}

static cf_status read_reference(const json_t *root, const json_at *at, cf_capture_spec *spec,
                                cf_error *err) {
  const json_t *reference;
  cf_status s = json_get_object(root, at, "reference", 0, &reference, &spec->has_reference, err);
  if (s != CF_OK || !spec->has_reference) return s;
  json_at here = json_member_at(at, "reference");
  cf_reference_spec *r = &spec->reference;
  if (!spec->radiometry_relative)
    return json_fail(&here, err, CF_EPARSE,
                     "a reference target sets the scale of lights known only up to a factor: "
                     "it needs \"radiometry\": \"relative\"");
  static const char *const keys[] = {"image", "region", "albedo", "normal", "point", NULL};
  const char *image;
  if ((s = json_check_keys(reference, &here, keys, err)) != CF_OK ||
      (s = json_get_string(reference, &here, "image", 1, &image, NULL, err)) != CF_OK)
    return s;
  r->image = spec->num_images;
  for (size_t k = 0; k < spec->num_images; ++k)
    if (strcmp(spec->image_names[k], image) == 0) {
      r->image = k;
      break;
    }
  if (r->image == spec->num_images) {
    json_at image_at = json_member_at(&here, "image");
    return json_fail(&image_at, err, CF_EPARSE,
                     "'%s' is not one of the capture's %zu images (the first is '%s')", image,
                     spec->num_images, spec->image_names[0]);
  }
  if ((s = read_region(reference, &here, r->region, err)) != CF_OK ||
      (s = read_albedo(reference, &here, r->albedo, err)) != CF_OK ||
      (s = read_unit_vector(reference, &here, "normal", r->normal, err)) != CF_OK ||
      (s = json_get_numbers(reference, &here, "point", 0, 3, -1e300, 1e300, r->point, &r->has_point,
                            err)) != CF_OK)
    return s;
  int positional = 0;
  for (size_t i = 0; i < spec->num_lights; ++i)
    positional |= spec->lights[i].kind == CF_LIGHT_SPEC_SINGLE &&
                  spec->lights[i].light.kind != CF_LIGHT_DIRECTIONAL;
  if (r->has_point && spec->camera == CF_CAMERA_KIND_ORTHOGRAPHIC) {
    json_at point_at = json_member_at(&here, "point");
    return json_fail(&point_at, err, CF_EPARSE,
                     "an orthographic camera has no world positions: give no 'point'");
  }
  if (positional && !r->has_point)
    return json_fail(&here, err, CF_EPARSE,
                     "the lights include a point light or a flash, whose irradiance depends on "
                     "where the target is: give 'point', a point on the target's plane (world)");
  return CF_OK;
}

/* ---- the whole file ---- */

cf_status cf_capture_spec_read(const char *path, cf_capture_spec *spec, cf_error *err) {
  memset(spec, 0, sizeof *spec);
  spec->clip_level = NAN;
  spec->sphere_radius_m = NAN;
  json_t *root = NULL;
  cf_status s = json_load_object(path, MAX_CAPTURE_FILE, &root, err);
  if (s != CF_OK) return s;
  char dir[MAX_PATH_LENGTH];
  json_at at = {path, NULL, NULL, 0};
  static const char *const keys[] = {"clayfit_capture", "name",       "camera",    "images",
                                     "colour",          "radiometry", "noise",     "geometry",
                                     "scale",           "lights",     "reference", NULL};
  long long version = 0;
  const char *name = "";
  if ((s = cf_path_dirname(path, dir, sizeof dir, err)) == CF_OK &&
      (!(spec->path = copy_string(path)) || !(spec->dir = copy_string(dir))))
    s = out_of_memory(err);
  if (s == CF_OK) s = json_check_keys(root, &at, keys, err);
  if (s == CF_OK) s = json_get_integer(root, &at, "clayfit_capture", 1, 1, 1, &version, NULL, err);
  if (s == CF_OK) s = json_get_string(root, &at, "name", 0, &name, NULL, err);
  if (s == CF_OK && !(spec->name = copy_string(name))) s = out_of_memory(err);
  if (s == CF_OK) s = read_camera(root, &at, spec, err);
  if (s == CF_OK) s = read_images(root, &at, spec, err);
  if (s == CF_OK) s = read_colour(root, &at, spec, err);
  if (s == CF_OK) s = read_radiometry_and_noise(root, &at, spec, err);
  if (s == CF_OK) s = read_scale(root, &at, spec, err);
  if (s == CF_OK) s = read_geometry(root, &at, spec, err);
  if (s == CF_OK) s = read_lights(root, &at, spec, err);
  if (s == CF_OK) s = read_reference(root, &at, spec, err);
  json_decref(root);
  if (s != CF_OK) cf_capture_spec_free(spec);
  return s;
}

static void free_strings(char **strings, size_t count) {
  if (!strings) return;
  for (size_t i = 0; i < count; ++i) free(strings[i]);
  free(strings);
}

void cf_capture_spec_free(cf_capture_spec *spec) {
  free(spec->path);
  free(spec->dir);
  free(spec->name);
  free(spec->colmap_model);
  free_strings(spec->image_names, spec->num_images);
  free(spec->image_list);
  free_strings(spec->image_paths, spec->num_images);
  free_strings(spec->mask_paths, spec->num_images);
  free(spec->exposures);
  free(spec->normal_map);
  for (size_t i = 0; spec->lights && i < spec->num_lights; ++i) {
    free(spec->lights[i].directions);
    free(spec->lights[i].intensities);
    free(spec->lights[i].file);
  }
  free(spec->lights);
  memset(spec, 0, sizeof *spec);
}

/* ---- the files a capture reads (clayfit batch's keys) ---- */

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
  if (!(l->files[l->count] = copy_string(path))) return CF_ENOMEM;
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
    if (cf_path_join(dir, names[k], path, sizeof path, &ignored) == CF_OK &&
        cf_path_exists(path))
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

void cf_capture_files_free(char **files, size_t count) { free_strings(files, count); }
