/* The residual of every observation in units of σ, its marks and its
 * angles (report_internal.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "report_internal.h"

#define DEGREES (180.0 / 3.14159265358979323846)

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Degrees between the normal and the nearest half vector of a lit light
 * (NaN where no light reaches the observation). */
static double half_angle(const cf_observations *o, size_t i) {
  double best = cf_observation_specularity(o, i);
  return best < -0.5 ? NAN : acos(fmin(1.0, best)) * DEGREES;
}

/* Is the capture the one the fit was made on? Its image count, its
 * observation count and its images' names (fit.json's per-image
 * residuals) must agree. */
static cf_status check_same_capture(const report_data *d, const char *fit_path, cf_error *err) {
  const cf_fit_file *fit = d->fit;
  const json_t *capture = d->doc ? json_object_get(d->doc, "capture") : NULL;
  const json_t *observations = json_object_get(capture, "observations");
  const json_t *per_image =
      d->doc ? json_object_get(json_object_get(d->doc, "residuals"), "per_image") : NULL;
  if (fit->result.images != d->images)
    return cf_error_set(err, CF_EINVAL,
                        "%s: the fit has %zu images and the capture %zu: not this capture's fit",
                        fit_path, fit->result.images, d->images);
  if (json_is_integer(observations) && (size_t)json_integer_value(observations) != d->count)
    return cf_error_set(err, CF_EINVAL,
                        "%s: the fit was made on %lld observations and the capture has %zu: not "
                        "this capture's fit",
                        fit_path, (long long)json_integer_value(observations), d->count);
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
  if (d->doc) json_decref(d->doc);
  memset(d, 0, sizeof *d);
}

/* The arrays of the observations and the images. */
static cf_status allocate(report_data *d, cf_error *err) {
  size_t n = d->count ? d->count : 1, k = d->images ? d->images : 1;
  d->prediction = malloc(3 * n * sizeof *d->prediction);
  d->sigma = malloc(3 * n * sizeof *d->sigma);
  d->residual = malloc(n * sizeof *d->residual);
  d->mark = calloc(n, 1);
  d->half_angle = malloc(n * sizeof *d->half_angle);
  d->view_angle = malloc(n * sizeof *d->view_angle);
  d->censored = calloc(k, sizeof *d->censored);
  d->rejected = calloc(k, sizeof *d->rejected);
  d->observations = calloc(k, sizeof *d->observations);
  d->rms_sigma = calloc(k, sizeof *d->rms_sigma);
  d->first = malloc(k * sizeof *d->first);
  d->last = calloc(k, sizeof *d->last);
  if (!d->prediction || !d->sigma || !d->residual || !d->mark || !d->half_angle || !d->view_angle ||
      !d->censored || !d->rejected || !d->observations || !d->rms_sigma || !d->first || !d->last)
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", d->count);
  return CF_OK;
}

/* Each observation's combined residual in sigma, its marks and angles;
 * each image's range of observations, counts and RMS. */
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
  for (size_t i = 0; i < d->count; ++i) {
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
        (float)(acos(fmax(-1.0, fmin(1.0, dot3(o->normal + 3 * i, o->view + 3 * i)))) * DEGREES);
    uint32_t im = o->image[i];
    ++d->observations[im];
    d->censored[im] += (d->mark[i] & REPORT_CENSORED) != 0;
    d->rejected[im] += (d->mark[i] & REPORT_REJECTED) != 0;
    if (used) sum2[im] += (double)d->residual[i] * d->residual[i];
  }
  for (size_t im = 0; im < d->images; ++im)
    d->rms_sigma[im] = d->observations[im] ? sqrt(sum2[im] / d->observations[im]) : 0.0;
  free(sum2);
  return CF_OK;
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
  json_error_t parse;
  d->doc = json_load_file(fit_path, JSON_REJECT_DUPLICATES, &parse);
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
  s = cf_fit_predict(capture, &fit->result, &options, d->prediction, d->sigma, err);
  if (s != CF_OK) {
    report_data_free(d);
    return s;
  }
  s = residuals(d, err);
  if (s != CF_OK) report_data_free(d);
  return s;
}
