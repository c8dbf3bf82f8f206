/* The lights each image of a capture sees: the capture file's flash, point
 * and directional lights, one directional light per image from text files
 * (DiLiGenT), and environment maps reduced to directional lights. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/file.h"
#include "envmap.h"

enum { MAX_ROWS_FILE = 64 << 20 };

/* Rows of 3 finite numbers, one per image ('#' comments and blank lines
 * skipped). Errors name the file and the line. */
static cf_status read_rows(const char *path, size_t rows, double *out, cf_error *err) {
  char *text;
  size_t size, line = 0, row = 0;
  cf_status s = cf_read_file(path, MAX_ROWS_FILE, &text, &size, err);
  if (s != CF_OK) return s;
  for (char *cursor = text; s == CF_OK && *cursor;) {
    char *end = strchr(cursor, '\n');
    if (end) *end = '\0';
    ++line;
    char *p = cursor;
    while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
    if (*p && *p != '#') {
      if (row == rows) {
        s = cf_error_set(err, CF_EPARSE, "%s:%zu: more rows than the %zu images", path, line, rows);
        break;
      }
      for (int k = 0; k < 3 && s == CF_OK; ++k) {
        errno = 0;
        char *stop;
        double x = strtod(p, &stop);
        if (stop == p || !isfinite(x) || errno == ERANGE)
          s = cf_error_set(err, CF_EPARSE, "%s:%zu: value %d of the row is not a finite number",
                           path, line, k + 1);
        out[3 * row + k] = x;
        p = stop;
      }
      while (s == CF_OK && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
      if (s == CF_OK && *p)
        s = cf_error_set(err, CF_EPARSE, "%s:%zu: expected 3 numbers, found more", path, line);
      ++row;
    }
    if (!end) break;
    cursor = end + 1;
  }
  free(text);
  if (s == CF_OK && row != rows)
    s = cf_error_set(err, CF_EPARSE, "%s: %zu rows for %zu images", path, row, rows);
  return s;
}

static cf_status per_image_lights(cf_capture *capture, const cf_light_spec *spec_light, size_t slot,
                                  cf_error *err) {
  size_t n = capture->spec.num_images;
  double *directions = malloc(3 * n * sizeof(double));
  double *intensities = malloc(3 * n * sizeof(double));
  cf_status s = directions && intensities ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) s = read_rows(spec_light->directions, n, directions, err);
  if (s == CF_OK) s = read_rows(spec_light->intensities, n, intensities, err);
  for (size_t k = 0; s == CF_OK && k < n; ++k) {
    double *d = directions + 3 * k, *e = intensities + 3 * k;
    double length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(length > 0.0))
      s = cf_error_set(err, CF_EPARSE, "%s: row %zu: the direction has zero length",
                       spec_light->directions, k + 1);
    else if (e[0] < 0.0 || e[1] < 0.0 || e[2] < 0.0)
      s = cf_error_set(err, CF_EPARSE, "%s: row %zu: a negative intensity", spec_light->intensities,
                       k + 1);
    if (s != CF_OK) break;
    cf_light *light = &capture->lights[k * (size_t)capture->max_lights + slot];
    light->kind = CF_LIGHT_DIRECTIONAL;
    for (int c = 0; c < 3; ++c) {
      light->direction[c] = d[c] / length;
      light->intensity[c] = e[c];
    }
  }
  free(directions);
  free(intensities);
  return s;
}

static cf_status environment_lights(cf_capture *capture, const cf_light_spec *spec_light,
                                    size_t slot, cf_error *err) {
  cf_image map = {0};
  cf_status s = cf_image_read(spec_light->file, &map, NULL, err);
  if (s != CF_OK) return s;
  if (map.channels < 3) {
    cf_image_free(&map);
    return cf_error_set(err, CF_EINVAL, "%s: an environment map needs RGB, it has %d channel%s",
                        spec_light->file, map.channels, map.channels == 1 ? "" : "s");
  }
  cf_directional_light *reduced = malloc((size_t)spec_light->count * sizeof *reduced);
  cf_envmap_report report = {0};
  s = reduced ? cf_envmap_median_cut(&map, spec_light->rotation, spec_light->count, reduced,
                                     &report, err)
              : cf_error_set(err, CF_ENOMEM, "out of memory");
  cf_image_free(&map);
  if (s != CF_OK) cf_error_prefix(err, "%s", spec_light->file);
  if (s == CF_OK && report.clamped)
    capture_warn(capture, "%s: %zu negative or non-finite values clamped to 0", spec_light->file,
                 report.clamped);
  for (size_t k = 0; s == CF_OK && k < capture->spec.num_images; ++k)
    for (int j = 0; j < spec_light->count; ++j) {
      cf_light *light = &capture->lights[k * (size_t)capture->max_lights + slot + (size_t)j];
      light->kind = CF_LIGHT_DIRECTIONAL;
      for (int c = 0; c < 3; ++c) {
        light->direction[c] = reduced[j].direction[c];
        light->intensity[c] = reduced[j].irradiance[c] * spec_light->scale;
      }
    }
  free(reduced);
  return s;
}

cf_status capture_load_lights(cf_capture *capture, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  int slots = 0;
  for (size_t i = 0; i < spec->num_lights; ++i)
    slots += spec->lights[i].kind == CF_LIGHT_SPEC_ENVIRONMENT ? spec->lights[i].count : 1;
  capture->max_lights = slots;
  capture->lights = calloc(spec->num_images * (size_t)slots, sizeof *capture->lights);
  capture->light_counts = calloc(spec->num_images, sizeof *capture->light_counts);
  if (!capture->lights || !capture->light_counts)
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu x %d lights", spec->num_images,
                        slots);
  size_t slot = 0;
  cf_status s = CF_OK;
  for (size_t i = 0; s == CF_OK && i < spec->num_lights; ++i) {
    const cf_light_spec *light = &spec->lights[i];
    switch (light->kind) {
      case CF_LIGHT_SPEC_SINGLE: {
        cf_light single = light->light;
        if (light->offset_in_metres) /* world units per metre = radius / radius_m */
          for (int c = 0; c < 3; ++c) single.position[c] *= capture->radius / spec->sphere_radius_m;
        for (size_t k = 0; k < spec->num_images; ++k)
          capture->lights[k * (size_t)slots + slot] = single;
        slot += 1;
        break;
      }
      case CF_LIGHT_SPEC_PER_IMAGE:
        s = per_image_lights(capture, light, slot, err);
        slot += 1;
        break;
      case CF_LIGHT_SPEC_ENVIRONMENT:
        s = environment_lights(capture, light, slot, err);
        slot += (size_t)light->count;
        break;
    }
  }
  for (size_t k = 0; k < spec->num_images; ++k) {
    capture->light_counts[k] = slots;
    capture->images[k].lights = slots;
  }
  return s;
}
