/* The lights and the reference target of a capture file (the rest of the
 * reader is capture_spec.c): each light's type and keys, the per-image
 * light files and environment map resolved, and the reference target's
 * image, region, albedo and plane checked against the capture's
 * radiometry, camera and lights. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_spec_internal.h"
#include "clayfit/capture.h"
#include "core/json_reader.h"
#include "envmap.h"

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
  if ((s = cf__spec_resolve(spec->dir, directions, &d_at, &light->directions, err)) != CF_OK)
    return s;
  if (strcmp(intensities, "equal") != 0)
    return cf__spec_resolve(spec->dir, intensities, &i_at, &light->intensities, err);
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
  return cf__spec_resolve(spec->dir, file, &f_at, &light->file, err);
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

cf_status cf__spec_read_lights(const json_t *root, const json_at *at, cf_capture_spec *spec,
                               cf_error *err) {
  const json_t *lights;
  cf_status s = json_get_array(root, at, "lights", 1, &lights, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "lights");
  spec->num_lights = json_array_size(lights);
  if (spec->num_lights == 0 || spec->num_lights > 64)
    return json_fail(&here, err, CF_EPARSE, "needs 1 to 64 lights, has %zu", spec->num_lights);
  if (!(spec->lights = calloc(spec->num_lights, sizeof *spec->lights)))
    return cf__spec_out_of_memory(err);
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

cf_status cf__spec_read_reference(const json_t *root, const json_at *at, cf_capture_spec *spec,
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
