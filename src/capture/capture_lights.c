/* The lights each image of a capture sees: the capture file's flash, point
 * and directional lights, one directional light per image from text files
 * (DiLiGenT), and environment maps reduced to directional lights. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/file.h"
#include "envmap.h"

enum { MAX_ROWS_FILE = 64 << 20 };

/* Where the images' count comes from, for messages: "the 96 images of
 * filenames.txt" or "the 96 images of images.files". */
static void images_source(const cf_capture_spec *spec, char *out, size_t size) {
  snprintf(out, size, "the %zu images of %s", spec->num_images,
           spec->image_list ? spec->image_list : "images.files");
}

/* One number of a row at p: CF_OK, or CF_EPARSE naming the token. A
 * subnormal (1e-320) is finite and kept; strtod's ERANGE counts only when
 * the value overflowed. */
static cf_status read_number(const char *path, size_t line, int k, char **p, double *x,
                             cf_error *err) {
  errno = 0;
  char *stop;
  *x = strtod(*p, &stop);
  int length = 0;
  while ((*p)[length] && (*p)[length] != ' ' && (*p)[length] != '\t' && (*p)[length] != '\r' &&
         length < 40)
    ++length;
  if (stop == *p)
    return cf_error_set(err, CF_EPARSE, "%s:%zu: value %d of the row, '%.*s', is not a number",
                        path, line, k + 1, length, *p);
  if (!isfinite(*x))
    return cf_error_set(err, CF_EPARSE,
                        "%s:%zu: value %d of the row, '%.*s', is not a finite number (beyond "
                        "+-1.8e308, or inf or nan)",
                        path, line, k + 1, length, *p);
  *p = stop;
  return CF_OK;
}

/* Rows of 3 finite numbers, one per image ('#' comments and blank lines
 * skipped). Errors name the file and the line. */
static cf_status read_rows(const char *path, const cf_capture_spec *spec, double *out,
                           cf_error *err) {
  const size_t rows = spec->num_images;
  char *text, source[CF_ERROR_MESSAGE_SIZE / 2];
  size_t size, line = 0, row = 0;
  images_source(spec, source, sizeof source);
  cf_status s = cf_read_text_file(path, MAX_ROWS_FILE, &text, &size, err);
  if (s != CF_OK) return s;
  for (char *cursor = text; s == CF_OK && *cursor;) {
    char *end = strchr(cursor, '\n');
    if (end) *end = '\0';
    ++line;
    char *p = cursor;
    while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
    if (*p && *p != '#') {
      if (row == rows) {
        s = cf_error_set(err, CF_EPARSE, "%s:%zu: more rows than %s", path, line, source);
        break;
      }
      for (int k = 0; k < 3 && s == CF_OK; ++k)
        s = read_number(path, line, k, &p, &out[3 * row + k], err);
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
    s = cf_error_set(err, CF_EPARSE, "%s: %zu rows (lines not blank and not '#' comments) for %s",
                     path, row, source);
  return s;
}

static cf_status per_image_lights(cf_capture *capture, const cf_light_spec *spec_light, size_t slot,
                                  cf_error *err) {
  size_t n = capture->spec.num_images;
  double *directions = malloc(3 * n * sizeof(double));
  double *intensities = malloc(3 * n * sizeof(double));
  cf_status s = directions && intensities ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) s = read_rows(spec_light->directions, &capture->spec, directions, err);
  if (s == CF_OK && spec_light->intensities_equal)
    for (size_t k = 0; k < 3 * n; ++k) intensities[k] = 1.0; /* unknown and equal */
  else if (s == CF_OK)
    s = read_rows(spec_light->intensities, &capture->spec, intensities, err);
  for (size_t k = 0; s == CF_OK && k < n; ++k) {
    double *d = directions + 3 * k, *e = intensities + 3 * k;
    /* scaled by its largest component first: the squares of 1e200 overflow
     * (an infinite length made the direction 0, 0, 0), those of 1e-200
     * underflow (refused as zero length) */
    double big = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2])));
    for (int c = 0; c < 3 && big > 0.0; ++c) d[c] /= big;
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
  cf_directional_light *reduced = malloc((size_t)spec_light->count * sizeof *reduced);
  cf_envmap_report report = {0};
  cf_status s = reduced ? cf_envmap_load(spec_light->file, spec_light->rotation, spec_light->count,
                                         reduced, &report, err)
                        : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK && report.clamped)
    capture_warn(capture, "%s: %zu negative values clamped to 0", spec_light->file,
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
