/* The residual of every observation in units of σ, its marks and its
 * angles (report_internal.h). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/memory.h"
#include "core/parallel.h"
#include "core/vec.h"
#include "report_internal.h"

/* Degrees between the normal and the nearest half vector of a lit light
 * (NaN where no light reaches the observation). */
static double half_angle(const cf_observations *o, size_t i) {
  double best = cf_observation_specularity(o, i);
  return best < -0.5 ? NAN : acos(fmin(1.0, best)) * CF_DEGREES;
}

/* Is the capture the one the fit was made on? Its image count, its
 * observation count and its images' names (fit.json's per-image
 * residuals) must agree. */
static cf_status check_same_capture(const report_data *d, const char *fit_path, cf_error *err) {
  const cf_fit_file *fit = d->fit;
  const json_t *per_image =
      d->doc ? json_object_get(json_object_get(d->doc, "residuals"), "per_image") : NULL;
  if (fit->result.images != d->images)
    return cf_error_set(err, CF_EINVAL,
                        "%s: the fit has %zu images and the capture %zu: not this capture's fit",
                        fit_path, fit->result.images, d->images);
  if (fit->capture_observations != d->count)
    return cf_error_set(err, CF_EINVAL,
                        "%s: the fit was made on %zu observations and the capture has %zu: not "
                        "this capture's fit",
                        fit_path, fit->capture_observations, d->count);
  for (size_t k = 0; json_is_array(per_image) && k < json_array_size(per_image) && k < d->images;
       ++k) {
    const json_t *name = json_object_get(json_array_get(per_image, k), "name");
    const char *mine = cf_capture_image_at(d->capture, k)->name;
    if (json_is_string(name) && strcmp(json_string_value(name), mine) != 0)
      return cf_error_set(err, CF_EINVAL,
                          "%s: the fit's image %zu is %s and the capture's %s: not this "
                          "capture's fit",
                          fit_path, k, json_string_value(name), mine);
  }
  return CF_OK;
}

void report_data_free(report_data *d) {
  free(d->prediction);
  free(d->sigma);
  free(d->residual);
  free(d->mark);
  free(d->half_angle);
  free(d->view_angle);
  free(d->censored);
  free(d->rejected);
  free(d->observations);
  free(d->first);
  free(d->last);
  free(d->rms_sigma);
  free(d->rejected_region);
  free(d->rejected_clustered);
  memset(d, 0, sizeof *d);
}

/* The arrays of the observations and the images. */
static cf_status allocate(report_data *d, cf_error *err) {
  size_t n = d->count ? d->count : 1, k = d->images ? d->images : 1;
  d->prediction = cf_malloc_large(3 * n * sizeof *d->prediction);
  d->sigma = cf_malloc_large(3 * n * sizeof *d->sigma);
  d->residual = cf_malloc_large(n * sizeof *d->residual);
  d->mark = calloc(n, 1);
  d->half_angle = cf_malloc_large(n * sizeof *d->half_angle);
  d->view_angle = cf_malloc_large(n * sizeof *d->view_angle);
  d->censored = calloc(k, sizeof *d->censored);
  d->rejected = calloc(k, sizeof *d->rejected);
  d->observations = calloc(k, sizeof *d->observations);
  d->rms_sigma = calloc(k, sizeof *d->rms_sigma);
  d->rejected_region = calloc(k, sizeof *d->rejected_region);
  d->rejected_clustered = calloc(k, sizeof *d->rejected_clustered);
  d->first = malloc(k * sizeof *d->first);
  d->last = calloc(k, sizeof *d->last);
  if (!d->prediction || !d->sigma || !d->residual || !d->mark || !d->half_angle || !d->view_angle ||
      !d->censored || !d->rejected || !d->observations || !d->rms_sigma || !d->first || !d->last ||
      !d->rejected_region || !d->rejected_clustered)
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", d->count);
  return CF_OK;
}

/* Observations [begin, end)'s combined residual in σ, marks and angles. */
typedef struct observation_job {
  report_data *d;
  int parts;
} observation_job;

static void observation_part(void *user, int part) {
  const observation_job *job = user;
  report_data *d = job->d;
  const cf_observations *o = d->obs;
  size_t begin, end;
  cf_part_range(d->count, job->parts, part, &begin, &end);
  for (size_t i = begin; i < end; ++i) {
    double total = 0.0;
    int used = 0;
    for (int c = 0; c < 3; ++c) {
      double y = o->rgb[3 * i + c], mu = d->prediction[3 * i + c];
      double r = (mu - y) / d->sigma[3 * i + c];
      if ((o->flags[i] >> c & 1u) && mu >= y) { /* censored: no residual */
        d->mark[i] |= REPORT_CENSORED;
        continue;
      }
      if (fabs(r) > d->loss_scale) d->mark[i] |= REPORT_REJECTED;
      total += r;
      ++used;
    }
    d->residual[i] = used ? (float)(total / sqrt((double)used)) : NAN;
    d->half_angle[i] = (float)half_angle(o, i);
    d->view_angle[i] =
        (float)(acos(fmax(-1.0, fmin(1.0, cf_dot3(o->normal + 3 * i, o->view + 3 * i)))) *
                CF_DEGREES);
  }
}

/* Each observation's combined residual in sigma, its marks and angles (in
 * parts, on the threads); each image's range of observations, counts and
 * RMS (in the observations' order). */
static cf_status residuals(report_data *d, cf_error *err) {
  size_t k = d->images ? d->images : 1;
  const cf_observations *o = d->obs;
  for (size_t im = 0; im < d->images; ++im) d->first[im] = d->count;
  for (size_t i = 0; i < d->count; ++i) {
    uint32_t im = o->image[i];
    if (d->first[im] == d->count) d->first[im] = i;
    d->last[im] = i + 1;
  }
  double *sum2 = calloc(k, sizeof *sum2);
  if (!sum2) return cf_error_set(err, CF_ENOMEM, "out of memory for %zu images", k);
  observation_job job = {d, d->threads};
  cf_parallel_for(job.parts, d->threads, observation_part, &job);
  for (size_t i = 0; i < d->count; ++i) {
    uint32_t im = o->image[i];
    ++d->observations[im];
    d->censored[im] += (d->mark[i] & REPORT_CENSORED) != 0;
    d->rejected[im] += (d->mark[i] & REPORT_REJECTED) != 0;
    int used = 0; /* the channels not censored */
    for (int c = 0; c < 3; ++c)
      used += !((o->flags[i] >> c & 1u) && d->prediction[3 * i + c] >= o->rgb[3 * i + c]);
    if (used) sum2[im] += (double)d->residual[i] * d->residual[i];
  }
  for (size_t im = 0; im < d->images; ++im)
    d->rms_sigma[im] = d->observations[im] ? sqrt(sum2[im] / d->observations[im]) : 0.0;
  free(sum2);
  return CF_OK;
}

/* The size of the largest 8-connected region of the n marked cells of a
 * w × h grid, and into *clustered the cells in regions of at least
 * REPORT_CLUSTER_PX (marks cleared on the way); stack holds n cells. */
static size_t largest_region(uint8_t *grid, size_t w, size_t h, size_t *stack,
                             size_t *clustered) {
  size_t best = 0;
  *clustered = 0;
  for (size_t start = 0; start < w * h; ++start) {
    if (!grid[start]) continue;
    size_t top = 0, size = 0;
    grid[start] = 0;
    stack[top++] = start;
    while (top > 0) {
      size_t q = stack[--top], x = q % w, y = q / w;
      ++size;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if ((dx < 0 && x == 0) || (dy < 0 && y == 0) || (dx > 0 && x + 1 == w) ||
              (dy > 0 && y + 1 == h))
            continue;
          size_t n = (size_t)((ptrdiff_t)q + dy * (ptrdiff_t)w + dx);
          if (grid[n]) grid[n] = 0, stack[top++] = n; /* each cell pushed once */
        }
    }
    if (size > best) best = size;
    if (size >= REPORT_CLUSTER_PX) *clustered += size;
  }
  return best;
}

/* Per image, the largest 8-connected region of rejected observations in
 * the pixel grid, over the rejected observations' bounding box. */
static cf_status rejected_regions(report_data *d, cf_error *err) {
  const cf_observations *o = d->obs;
  for (size_t im = 0; im < d->images; ++im) {
    if (d->rejected[im] == 0) continue;
    size_t x0 = SIZE_MAX, y0 = SIZE_MAX, x1 = 0, y1 = 0;
    for (size_t i = d->first[im]; i < d->last[im]; ++i) {
      if (o->image[i] != im || !(d->mark[i] & REPORT_REJECTED)) continue;
      size_t x = (size_t)o->pixel[2 * i], y = (size_t)o->pixel[2 * i + 1];
      x0 = x < x0 ? x : x0, y0 = y < y0 ? y : y0, x1 = x > x1 ? x : x1, y1 = y > y1 ? y : y1;
    }
    size_t w = x1 - x0 + 1, h = y1 - y0 + 1; /* within the image: the capture checked */
    uint8_t *grid = calloc(w * h, 1);
    size_t *stack = malloc(d->rejected[im] * sizeof *stack);
    if (!grid || !stack) {
      free(grid);
      free(stack);
      return cf_error_set(err, CF_ENOMEM, "out of memory for image %zu's rejected regions", im);
    }
    for (size_t i = d->first[im]; i < d->last[im]; ++i)
      if (o->image[i] == im && (d->mark[i] & REPORT_REJECTED))
        grid[((size_t)o->pixel[2 * i + 1] - y0) * w + ((size_t)o->pixel[2 * i] - x0)] = 1;
    d->rejected_region[im] = largest_region(grid, w, h, stack, &d->rejected_clustered[im]);
    free(grid);
    free(stack);
  }
  return CF_OK;
}

double report_rejected_share(const report_data *d, int clustered) {
  size_t rejected = 0, part = 0;
  for (size_t im = 0; im < d->images; ++im)
    rejected += d->rejected[im],
        part += clustered ? d->rejected_clustered[im] : d->rejected_region[im];
  return rejected ? (double)part / (double)rejected : NAN;
}

cf_status report_data_build(report_data *d, const cf_capture *capture, const cf_fit_file *fit,
                            const char *fit_path, cf_error *err) {
  memset(d, 0, sizeof *d);
  d->capture = capture;
  d->fit = fit;
  d->obs = cf_capture_observations(capture);
  d->count = d->obs->count;
  d->images = cf_capture_image_count(capture);
  d->loss_scale = strcmp(fit->loss, "none") == 0 ? INFINITY : fit->loss_scale;
  d->doc = fit->document; /* parsed once, under cf_fit_file_read's cap */
  cf_status s = check_same_capture(d, fit_path, err);
  if (s != CF_OK) {
    report_data_free(d);
    return s;
  }
  s = allocate(d, err);
  if (s != CF_OK) {
    report_data_free(d);
    return s;
  }
  cf_fit_options options;
  cf_fit_default_options(&options, fit->result.model);
  options.footprint = fit->footprint;
  options.footprint_tolerance = fit->footprint_tolerance;
  d->threads = options.threads > 1 ? options.threads : 1;
  report_srgb_init(&d->srgb);
  s = cf_fit_predict(capture, &fit->result, &options, d->prediction, d->sigma, err);
  if (s != CF_OK) {
    report_data_free(d);
    return s;
  }
  s = residuals(d, err);
  if (s == CF_OK) s = rejected_regions(d, err);
  if (s != CF_OK) report_data_free(d);
  return s;
}

/* ---- is another capture the fit's? ---- */

static int differ(double a, double b, double absolute) {
  double scale = absolute > 0.0 ? absolute : 1e-6 * fmax(fabs(a), fabs(b));
  return !(fabs(a - b) <= scale); /* NaN differs */
}

static int differ_n(const double *a, const double *b, size_t n, double absolute) {
  for (size_t k = 0; k < n; ++k)
    if (differ(a[k], b[k], absolute)) return 1;
  return 0;
}

/* The images, the noise model and the radiometry (what cf_capture_image
 * and the summary hold). */
static cf_status compare_images(const cf_capture *a, const cf_capture *b, char *what, size_t size) {
  size_t n = cf_capture_image_count(a);
  if (n != cf_capture_image_count(b)) {
    snprintf(what, size, "the fit has %zu images and the capture %zu", cf_capture_image_count(b),
             n);
    return CF_EINVAL;
  }
  for (size_t k = 0; k < n; ++k) {
    const cf_capture_image *x = cf_capture_image_at(a, k), *y = cf_capture_image_at(b, k);
    if (strcmp(x->name, y->name) != 0)
      snprintf(what, size, "image %zu is %s, in the fit's capture %s", k, x->name, y->name);
    else if (x->lights != y->lights)
      snprintf(what, size, "the lights differ: image %zu (%s) has %d lights, in the fit's capture %d",
               k, x->name, x->lights, y->lights);
    else if (differ(x->exposure, y->exposure, 0.0))
      snprintf(what, size,
               "the colours differ (the colour block's exposure): image %zu (%s) has exposure %.9g, "
               "in the fit's capture %.9g",
               k, x->name, x->exposure, y->exposure);
    else
      continue;
    return CF_EINVAL;
  }
  cf_capture_summary p, q;
  cf_capture_summarize(a, &p);
  cf_capture_summarize(b, &q);
  if (p.radiometry_relative != q.radiometry_relative ||
      p.radiometry_from_reference != q.radiometry_from_reference ||
      differ(p.reference_scale, q.reference_scale, 0.0))
    snprintf(what, size, "the radiometry differs (%s, in the fit's capture %s)",
             p.radiometry_relative ? "relative" : "absolute",
             q.radiometry_relative ? "relative" : "absolute");
  else if (p.tone_curve_unknown != q.tone_curve_unknown)
    snprintf(what, size, "the colours differ: the colour block's tone curve is %s, in the fit's "
             "capture %s", p.tone_curve_unknown ? "unknown" : "known",
             q.tone_curve_unknown ? "unknown" : "known");
  else if (p.has_noise != q.has_noise || differ(p.noise_read, q.noise_read, 0.0) ||
           differ(p.noise_shot, q.noise_shot, 0.0))
    snprintf(what, size, "the noise model differs");
  else
    return CF_OK;
  return CF_EINVAL;
}

/* Observation i of both (the same image, pixel and surface): its lights,
 * then its colours. */
static cf_status compare_observation(const cf_capture *a, const cf_capture *b, size_t i,
                                     char *what, size_t size) {
  const cf_observations *x = cf_capture_observations(a), *y = cf_capture_observations(b);
  const char *name = x->image[i] < cf_capture_image_count(a)
                         ? cf_capture_image_at(a, x->image[i])->name
                         : "?";
  char where[400];
  snprintf(where, sizeof where, "image %u (%s), pixel (%.1f, %.1f)", (unsigned)x->image[i], name,
           (double)x->pixel[2 * i], (double)x->pixel[2 * i + 1]);
  if (x->image[i] != y->image[i] || x->pixel[2 * i] != y->pixel[2 * i] ||
      x->pixel[2 * i + 1] != y->pixel[2 * i + 1]) {
    snprintf(what, size, "the observations differ: %s is at another place in the fit's capture",
             where);
    return CF_EINVAL;
  }
  if (differ_n(x->normal + 3 * i, y->normal + 3 * i, 3, 1e-6) ||
      differ_n(x->view + 3 * i, y->view + 3 * i, 3, 1e-6)) {
    snprintf(what, size, "the sphere or the cameras differ: %s has another normal or view", where);
    return CF_EINVAL;
  }
  for (int j = 0; j < x->lights; ++j) {
    size_t at = 3 * ((size_t)x->lights * i + (size_t)j);
    const double *p = x->light_dir + at, *q = y->light_dir + at;
    const double *e = x->irradiance + at, *f = y->irradiance + at;
    if (differ_n(p, q, 3, 1e-6)) {
      snprintf(what, size,
               "the lights differ (a direction or position): %s, light %d comes from (%.6f, "
               "%.6f, %.6f), in the fit's capture from (%.6f, %.6f, %.6f)",
               where, j, p[0], p[1], p[2], q[0], q[1], q[2]);
      return CF_EINVAL;
    }
    if (differ_n(e, f, 3, 0.0)) {
      snprintf(what, size,
               "the lights differ (an intensity or distance): %s, light %d gives irradiance "
               "(%.6g, %.6g, %.6g), in the fit's capture (%.6g, %.6g, %.6g)",
               where, j, e[0], e[1], e[2], f[0], f[1], f[2]);
      return CF_EINVAL;
    }
  }
  const double *u = x->rgb + 3 * i, *v = y->rgb + 3 * i;
  if (differ_n(u, v, 3, 0.0) || x->flags[i] != y->flags[i]) {
    snprintf(what, size,
             "the colours differ (the colour block: encoding, black and clip levels, exposure; "
             "or the photos): %s is (%.6g, %.6g, %.6g)%s, in the fit's capture (%.6g, %.6g, "
             "%.6g)%s",
             where, u[0], u[1], u[2], x->flags[i] & CF_OBS_CLIPPED ? " clipped" : "", v[0], v[1],
             v[2], y->flags[i] & CF_OBS_CLIPPED ? " clipped" : "");
    return CF_EINVAL;
  }
  return CF_OK;
}

cf_status cf_report_compare_captures(const cf_capture *capture, const char *capture_path,
                                     const cf_capture *fit_capture, const char *fit_capture_path,
                                     cf_error *err) {
  char what[700];
  cf_status s = compare_images(capture, fit_capture, what, sizeof what);
  const cf_observations *x = cf_capture_observations(capture);
  const cf_observations *y = cf_capture_observations(fit_capture);
  if (s == CF_OK && (x->count != y->count || x->lights != y->lights)) {
    snprintf(what, sizeof what,
             "it has %zu observations with %d light slots, the fit's capture %zu with %d",
             x->count, x->lights, y->count, y->lights);
    s = CF_EINVAL;
  }
  for (size_t i = 0; s == CF_OK && i < x->count; ++i)
    s = compare_observation(capture, fit_capture, i, what, sizeof what);
  if (s == CF_OK) return CF_OK;
  return cf_error_set(err, CF_EINVAL,
                      "%s is not the capture the fit was made on (%s): %s; report on the fit's "
                      "own capture, or fit this one",
                      capture_path, fit_capture_path, what);
}
