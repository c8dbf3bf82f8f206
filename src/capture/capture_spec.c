/* Reading a capture file into a cf_capture_spec (capture_spec.h), against
 * data_schema/capture.schema.json: types, ranges, unknown keys and the
 * rules between fields (a gamma for encoding "gamma", exposures for
 * exposure "given", ...), each error naming the JSON path. This file: the
 * helpers the reader shares (capture_spec_internal.h), the camera, the
 * images, colour, radiometry and noise, geometry and scale, the whole file
 * and freeing it. The lights and the reference target are read in
 * capture_spec_lights.c; the files a capture reads are listed in
 * capture_files.c. */
#include "capture_spec.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_spec_internal.h"
#include "core/file.h"
#include "core/json_reader.h"

enum {
  MAX_CAPTURE_FILE = 64 << 20, /* bytes */
  MAX_LIST_FILE = 16 << 20,
  MAX_IMAGES = 1 << 20
};

char *cf__spec_copy_string(const char *text) {
  size_t n = strlen(text) + 1;
  char *copy = malloc(n);
  if (copy) memcpy(copy, text, n);
  return copy;
}

/* A path from the file, resolved against `dir`. */
cf_status cf__spec_resolve(const char *dir, const char *name, const json_at *at, char **out,
                           cf_error *err) {
  char buffer[MAX_PATH_LENGTH];
  if (cf_path_join(dir, name, buffer, sizeof buffer, err) != CF_OK)
    return json_fail(at, err, CF_ERANGE, "path too long");
  *out = cf__spec_copy_string(buffer);
  return *out ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
}

cf_status cf__spec_out_of_memory(cf_error *err) {
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
    return cf__spec_resolve(spec->dir, model, &model_at, &spec->colmap_model, err);
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
          return cf__spec_out_of_memory(err);
        }
        spec->image_names = grown;
      }
      spec->image_names[spec->num_images] = cf__spec_copy_string(cursor);
      if (!spec->image_names[spec->num_images]) {
        free(text);
        return cf__spec_out_of_memory(err);
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
    s = cf__spec_resolve(spec->dir, list, &list_at, &list_path, err);
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
    s = cf__spec_out_of_memory(err);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i) {
    json_at element = json_element_at(&files_at, i);
    const char *name;
    s = json_as_string(json_array_get(files, i), &element, &name, err);
    if (s == CF_OK && !name[0]) s = json_fail(&element, err, CF_EPARSE, "empty file name");
    if (s == CF_OK && !(spec->image_names[i] = cf__spec_copy_string(name)))
      s = cf__spec_out_of_memory(err);
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
    s = cf__spec_out_of_memory(err);
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
  if (!(spec->mask_paths = calloc(spec->num_images, sizeof(char *))))
    s = cf__spec_out_of_memory(err);
  char *mask_dir = NULL;
  json_at mask_at = json_member_at(here, has_mask ? "mask" : "masks");
  if (s == CF_OK && has_masks) s = cf__spec_resolve(spec->dir, masks, &mask_at, &mask_dir, err);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i)
    s = has_mask
            ? cf__spec_resolve(spec->dir, mask, &mask_at, &spec->mask_paths[i], err)
            : cf__spec_resolve(mask_dir, spec->image_names[i], &mask_at, &spec->mask_paths[i], err);
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
  if ((s = cf__spec_resolve(spec->dir, directory, &dir_at, &image_dir, err)) != CF_OK) return s;

  s = read_image_names(images, &here, spec, err);
  if (s == CF_OK && !(spec->image_paths = calloc(spec->num_images, sizeof(char *))))
    s = cf__spec_out_of_memory(err);
  for (size_t i = 0; s == CF_OK && i < spec->num_images; ++i)
    s = cf__spec_resolve(image_dir, spec->image_names[i], &here, &spec->image_paths[i], err);
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
    return cf__spec_resolve(spec->dir, file, &file_at, &spec->normal_map, err);
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
      (!(spec->path = cf__spec_copy_string(path)) || !(spec->dir = cf__spec_copy_string(dir))))
    s = cf__spec_out_of_memory(err);
  if (s == CF_OK) s = json_check_keys(root, &at, keys, err);
  if (s == CF_OK) s = json_get_integer(root, &at, "clayfit_capture", 1, 1, 1, &version, NULL, err);
  if (s == CF_OK) s = json_get_string(root, &at, "name", 0, &name, NULL, err);
  if (s == CF_OK && !(spec->name = cf__spec_copy_string(name))) s = cf__spec_out_of_memory(err);
  if (s == CF_OK) s = read_camera(root, &at, spec, err);
  if (s == CF_OK) s = read_images(root, &at, spec, err);
  if (s == CF_OK) s = read_colour(root, &at, spec, err);
  if (s == CF_OK) s = read_radiometry_and_noise(root, &at, spec, err);
  if (s == CF_OK) s = read_scale(root, &at, spec, err);
  if (s == CF_OK) s = read_geometry(root, &at, spec, err);
  if (s == CF_OK) s = cf__spec_read_lights(root, &at, spec, err);
  if (s == CF_OK) s = cf__spec_read_reference(root, &at, spec, err);
  json_decref(root);
  if (s != CF_OK) cf_capture_spec_free(spec);
  return s;
}

void cf__spec_free_strings(char **strings, size_t count) {
  if (!strings) return;
  for (size_t i = 0; i < count; ++i) free(strings[i]);
  free(strings);
}

void cf_capture_spec_free(cf_capture_spec *spec) {
  free(spec->path);
  free(spec->dir);
  free(spec->name);
  free(spec->colmap_model);
  cf__spec_free_strings(spec->image_names, spec->num_images);
  free(spec->image_list);
  cf__spec_free_strings(spec->image_paths, spec->num_images);
  cf__spec_free_strings(spec->mask_paths, spec->num_images);
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
