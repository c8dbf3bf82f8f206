/* The screen of a capture's observations (capture_internal.h): values that
 * cannot be radiance left out, and a capture with nothing lit and positive
 * to fit refused. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/order_statistics.h"
#include "core/parallel.h"
#include "core/vec.h"

/* Values that cannot be radiance (docs/captures.md):
 * A channel is not radiance when it is below −NOISE_SIGMAS σ₀, σ₀ the
 * photo's noise at radiance 0 (the capture's read noise, or without a
 * noise model FALLBACK_NOISE times the image's bright level), or above the
 * brightest radiance any material of the ladder can reflect there under the
 * capture's lights (MARGIN times capture_radiance_bound, plus NOISE_SIGMAS
 * σ₀). When the lights' level is not known (relative radiometry, an unknown
 * tone curve: the fit's scale is free) the upper bound is instead ABSURD
 * times the bright level, the BRIGHT_QUANTILE of the image's positive
 * values: robust to a tenth of them being wrong. */
#define NOISE_SIGMAS 5.0 /* Gaussian noise beyond 5 σ: 3e-7 of the values */
/* generous: raw photos' read noise is 0.1-1 % of full scale, so only values
 * far below any camera's noise are left out (-10 % of the bright level) */
#define FALLBACK_NOISE 0.02
#define BRIGHT_QUANTILE 0.9
/* the ladder's sharpest, strongest lobe (roughness 0.03, F0 0.25) peaks at
 * 7.7e4 times a white diffuse surface (clayfit eval): room for albedo 1e-4 */
#define ABSURD 1e9
/* two stops above the bound: the capture's exposures (EXIF's rounding) and
 * the fit's corrections to them (--fit-exposures), a footprint's samples
 * beside the pixel's centre; the patch of 1e6 of cli_fit_bright_patch is
 * 3.3 times above it, real highlights (roughness >= 0.1) far below */
#define MARGIN 4.0
/* π f c_i of the ladder over docs/model.md §1.6's ranges, searched by
 * test_radiance_bound: 8.2e4 at c_o = 1 (M4: r 0.03, F0 0.25 on both
 * lobes), 8.8e4 at 0.93, 3.0e5 at 0.33, 1.8e6 at 0.1, 8.7e6 at 0.03 (the
 * lobe's 1/(4 c_o) and the Fresnel's rise); PEAK / c_o^1.5 is above all */
#define PEAK 9e4
#define MOST 0.5 /* more than half of the capture: the decoding is wrong */

/* threads judging the images, 2 cores: the demo loaded in 0.68 of one
 * thread's wall time (5 alternating runs of a program loading it, busy
 * machine) */
enum { SCREENERS = 2 };

double capture_radiance_bound(double cos_o) {
  return cos_o > 0.0 ? PEAK / (CF_PI * cos_o * sqrt(cos_o)) : INFINITY;
}

/* The bounds of radiance for observations [begin, end) of one image. */
typedef struct radiance_bounds {
  double low, absurd, sigma, bright;
  int sigma_from_capture;
  int lights_known; /* the lights' level is known: the model's bound applies */
} radiance_bounds;

static cf_status bounds_of(const cf_capture *capture, size_t begin, size_t end, radiance_bounds *b,
                           cf_error *err) {
  const double *rgb = capture->obs.rgb;
  size_t n = 0;
  double *positive = malloc(3 * (end - begin) * sizeof *positive + 1);
  if (!positive) return cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 3 * begin; i < 3 * end; ++i)
    if (rgb[i] > 0.0) positive[n++] = rgb[i];
  b->bright =
      n ? order_kth_smallest(positive, n, (size_t)(BRIGHT_QUANTILE * (double)(n - 1))) : 0.0;
  free(positive);
  const cf_capture_spec *spec = &capture->spec;
  b->sigma_from_capture = spec->has_noise && spec->noise_read > 0.0;
  b->sigma = b->sigma_from_capture ? spec->noise_read : FALLBACK_NOISE * b->bright;
  b->low = -NOISE_SIGMAS * b->sigma;
  b->absurd = b->bright > 0.0 ? ABSURD * b->bright : INFINITY;
  b->lights_known = !spec->radiometry_relative && !spec->tone_curve_unknown;
  return CF_OK;
}

/* The brightest radiance any material can reflect at observation i under
 * its lights (with every light's irradiance, at the brightest channel). */
static double brightest_at(const cf_observations *o, size_t i) {
  const double *n = o->normal + 3 * i, *v = o->view + 3 * i;
  const size_t slots = (size_t)(o->lights > 0 ? o->lights : 1);
  const double *e = o->irradiance + 3 * slots * i;
  double channel[3] = {0.0, 0.0, 0.0};
  for (size_t j = 0; j < slots; ++j)
    for (int c = 0; c < 3; ++c) channel[c] += e[3 * j + c];
  double irradiance = fmax(channel[0], fmax(channel[1], channel[2]));
  return capture_radiance_bound(n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) * irradiance;
}

/* What was left out of one image (for its warning), or of the capture. */
typedef struct left_out_counts {
  size_t low, high;
  double lowest, highest;
  double limit;  /* the upper bound where the highest value is */
  float at[2];   /* the first such pixel's centre */
  double signal; /* capture: Σ (brightest / σ₀)² over the values kept */
  double sigma;  /* capture: the largest image's σ₀ */
} left_out_counts;

static void warn_left_out(cf_capture *capture, size_t k, const radiance_bounds *b,
                          const left_out_counts *out) {
  const cf_capture_image *info = &capture->images[k];
  size_t total = info->observations + info->not_radiance;
  char low[256] = "", high[256] = "";
  if (out->low && b->sigma_from_capture)
    snprintf(low, sizeof low,
             "; %zu with a value below %g (%g sigma, the capture's read noise %g; lowest %g)",
             out->low, b->low, NOISE_SIGMAS, b->sigma, out->lowest);
  else if (out->low)
    snprintf(low, sizeof low,
             "; %zu with a value below %g (%g sigma, sigma %g %% of the image's bright level %g; "
             "lowest %g)",
             out->low, b->low, NOISE_SIGMAS, 100.0 * FALLBACK_NOISE, b->bright, out->lowest);
  if (out->high && b->lights_known)
    snprintf(high, sizeof high,
             "; %zu above the brightest radiance any material can reflect there under the "
             "capture's lights (%g times the model's bound; highest %g where that is %g)",
             out->high, MARGIN, out->highest, out->limit);
  else if (out->high)
    snprintf(high, sizeof high, "; %zu above %g (%g times the bright level; highest %g)", out->high,
             b->absurd, ABSURD, out->highest);
  capture_warn(capture,
               "%s: %zu of its %zu pixels on the sphere (%.2g %%) hold values that cannot be "
               "radiance and are left out of the fit%s%s; the first at pixel (%.0f, %.0f). "
               "Check the black level, the encoding, the lights and the file",
               capture->spec.image_paths[k], info->not_radiance, total,
               100.0 * (double)info->not_radiance / (double)total, low, high, out->at[0] - 0.5,
               out->at[1] - 0.5);
}

/* 1 when observation i holds a value that is not radiance (out not NULL:
 * counted there); else its brightest radiance (brightest_at) in
 * *brightest. */
static int not_radiance(const cf_observations *o, size_t i, const radiance_bounds *b,
                        double *brightest, left_out_counts *out) {
  int low = 0, high = 0;
  *brightest = b->lights_known ? brightest_at(o, i) : INFINITY;
  const double limit = fmin(b->absurd, MARGIN * *brightest + NOISE_SIGMAS * b->sigma);
  for (int c = 0; c < 3; ++c) {
    double v = o->rgb[3 * i + c];
    if (v < b->low) low = 1;
    if (v > limit) high = 1;
    if (!out) continue;
    if (v < b->low) out->lowest = fmin(out->lowest, v);
    if (v > limit && v > out->highest) out->highest = v, out->limit = limit;
  }
  if (out && (low || high)) {
    if (out->low + out->high == 0) memcpy(out->at, o->pixel + 2 * i, sizeof out->at);
    out->low += (size_t)low;
    out->high += (size_t)(high && !low);
  }
  return low || high;
}

/* One image's screen, images side by side: its bounds of radiance, what
 * it leaves out, the kept values' part of the signal (in order within the
 * image) and how many clipped observations it leaves out. */
typedef struct image_screen {
  radiance_bounds bounds;
  left_out_counts out;
  size_t clipped_out;
  cf_status status;
  cf_error err;
} image_screen;

typedef struct screen_work {
  const cf_capture *capture;
  const size_t *begin; /* image k's observations: [begin[k], begin[k + 1]) */
  image_screen *images;
} screen_work;

static void judge_image(void *user, int k) {
  const screen_work *w = user;
  const cf_observations *o = &w->capture->obs;
  image_screen *m = &w->images[k];
  const size_t begin = w->begin[k], end = w->begin[k + 1];
  if (end == begin) return;
  m->status = bounds_of(w->capture, begin, end, &m->bounds, &m->err);
  if (m->status != CF_OK) return;
  const radiance_bounds *b = &m->bounds;
  for (size_t i = begin; i < end; ++i) {
    double brightest;
    if (not_radiance(o, i, b, &brightest, &m->out)) {
      m->clipped_out += (o->flags[i] & CF_OBS_CLIPPED) != 0;
      continue;
    }
    double z = brightest / b->sigma;
    m->out.signal += b->sigma > 0.0 ? z * z : INFINITY;
  }
}

/* Image k's kept observations moved down to *kept (runs between the
 * values left out). */
static void keep_image(cf_observations *o, size_t begin, size_t end, const image_screen *m,
                       size_t *kept) {
  size_t run = begin; /* the kept observations [run, i) go to *kept on */
  for (size_t i = begin; m->out.low + m->out.high > 0 && i < end; ++i) {
    double brightest;
    if (!not_radiance(o, i, &m->bounds, &brightest, NULL)) continue;
    capture_move_observations(o, *kept, o, run, i - run);
    *kept += i - run;
    run = i + 1;
  }
  capture_move_observations(o, *kept, o, run, end - run);
  *kept += end - run;
}

/* Image k's counts, its warning, its part of the capture's counts, in
 * image order. */
static void count_image(cf_capture *capture, size_t k, size_t observations,
                        const image_screen *m, left_out_counts *all) {
  cf_capture_image *info = &capture->images[k];
  const left_out_counts *out = &m->out;
  info->clipped -= m->clipped_out;
  all->sigma = fmax(all->sigma, m->bounds.sigma);
  info->not_radiance = out->low + out->high;
  info->observations -= info->not_radiance;
  if ((double)info->not_radiance > CF_NOT_RADIANCE_TRACE * (double)observations)
    warn_left_out(capture, k, &m->bounds, out);
  all->low += out->low;
  all->high += out->high;
  if (out->highest > all->highest) all->highest = out->highest, all->limit = out->limit;
}

/* Σ (brightest / σ₀)² over the kept values in the capture's order, as one
 * sum (before the kept are moved down). */
static double signal_in_order(const cf_capture *capture, const size_t *begin,
                              const image_screen *images) {
  const cf_observations *o = &capture->obs;
  double signal = 0.0;
  for (size_t k = 0; k < capture->spec.num_images; ++k)
    for (size_t i = begin[k]; i < begin[k + 1]; ++i) {
      const radiance_bounds *b = &images[k].bounds;
      double brightest;
      if (not_radiance(o, i, b, &brightest, NULL)) continue;
      double z = brightest / b->sigma;
      signal += b->sigma > 0.0 ? z * z : INFINITY;
    }
  return signal;
}

/* Every image judged side by side (SCREENERS threads), then in image
 * order: the first error, the counts and warnings, the signal, and the
 * kept observations moved down (o->count then the kept). */
static cf_status screen_images(cf_capture *capture, size_t *begin, image_screen *images,
                               left_out_counts *all, cf_error *err) {
  cf_observations *o = &capture->obs;
  const size_t n = capture->spec.num_images;
  begin[0] = 0;
  for (size_t k = 0; k < n; ++k) begin[k + 1] = begin[k] + capture->images[k].observations;
  screen_work w = {capture, begin, images};
  if (n > 0) cf_parallel_for((int)n, SCREENERS, judge_image, &w);
  for (size_t k = 0; k < n; ++k)
    if (images[k].status != CF_OK) {
      if (err) *err = images[k].err;
      return images[k].status;
    }
  for (size_t k = 0; k < n; ++k) {
    if (begin[k + 1] == begin[k]) continue;
    count_image(capture, k, begin[k + 1] - begin[k], &images[k], all);
    all->signal += images[k].out.signal;
  }
  /* the images' sums added differ from the one sum by rounding (1e-16
   * relative a value): the one sum is needed only near the check's 1 */
  if (!(all->signal >= 2.0)) all->signal = signal_in_order(capture, begin, images);
  size_t kept = 0;
  for (size_t k = 0; k < n; ++k) keep_image(o, begin[k], begin[k + 1], &images[k], &kept);
  o->count = kept;
  return CF_OK;
}

/* A point light or flash closer to the sphere's centre than its radius:
 * its image's name, its index and that distance (0 when there is none). */
static int light_inside(const cf_capture *capture, size_t *image, int *light, double *distance) {
  if (!(capture->radius > 0.0)) return 0;
  for (size_t k = 0; k < capture->spec.num_images; ++k)
    for (int j = 0; j < capture->light_counts[k]; ++j) {
      const cf_light *l = &capture->lights[k * (size_t)capture->max_lights + (size_t)j];
      if (l->kind == CF_LIGHT_DIRECTIONAL) continue;
      double p[3];
      for (int a = 0; a < 3; ++a) {
        p[a] = l->position[a];
        if (l->kind == CF_LIGHT_FLASH) { /* C + Rᵀ t */
          const double *r = capture->views[k].r;
          p[a] = capture->views[k].c[a] + r[a] * l->position[0] + r[3 + a] * l->position[1] +
                 r[6 + a] * l->position[2];
        }
      }
      double d = sqrt((p[0] - capture->center[0]) * (p[0] - capture->center[0]) +
                      (p[1] - capture->center[1]) * (p[1] - capture->center[1]) +
                      (p[2] - capture->center[2]) * (p[2] - capture->center[2]));
      if (d < capture->radius) {
        *image = k, *light = j, *distance = d;
        return 1;
      }
    }
  return 0;
}

/* Is observation i reached by some light with some irradiance? */
static int irradiated(const cf_observations *o, size_t i) {
  const size_t slots = (size_t)(o->lights > 0 ? o->lights : 1);
  const double *e = o->irradiance + 3 * slots * i;
  int any = 0;
  for (size_t j = 0; j < 3 * slots; ++j) any |= e[j] > 0.0;
  return any;
}

/* How many observations are lit (n·l > 0 and some irradiance), counted up
 * to the first lit one that measures a positive value (*positive 1; the
 * count is whole only when there is none, the one case it is reported). */
static size_t lit_until_positive(const cf_observations *o, int *positive) {
  size_t lit = 0;
  *positive = 0;
  for (size_t i = 0; i < o->count && !*positive; ++i) {
    if (o->flags[i] & CF_OBS_UNLIT) continue;
    ++lit;
    const double *y = o->rgb + 3 * i;
    *positive = y[0] > 0.0 || y[1] > 0.0 || y[2] > 0.0;
  }
  return lit;
}

/* Refuse a capture that no light reaches (before the screen: with no
 * light every value is above what the lights can give). */
static cf_status check_reached(const cf_capture *capture, cf_error *err) {
  const cf_observations *o = &capture->obs;
  for (size_t i = 0; i < o->count; ++i)
    if (irradiated(o, i)) return CF_OK;
  return cf_error_set(err, CF_EINVAL,
                      "%s: lights: no light reaches the sphere: every light gives zero "
                      "irradiance at all %zu observations of the %zu images (are the lights' "
                      "intensities 0?)",
                      capture->spec.path, o->count, capture->spec.num_images);
}

/* Refuse a capture of which more than half of the values cannot be
 * radiance: mostly too bright for the lights, or mostly far below 0. */
static cf_status check_left_out(const cf_capture *capture, size_t total, const left_out_counts *out,
                                cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  size_t left_out = out->low + out->high;
  if (!((double)left_out > MOST * (double)total)) return CF_OK;
  double share = 100.0 * (double)left_out / (double)total;
  if (out->high > out->low && isfinite(out->limit))
    return cf_error_set(err, CF_EINVAL,
                        "%s: lights: %zu of the %zu pixels on the sphere (%.3g %%) are brighter "
                        "than any material can reflect under the capture's lights (the highest, "
                        "%g, where %g is the most the lights allow): the lights are too weak to "
                        "give these values (their intensities, or the photos' exposures or "
                        "units, are wrong): nothing to fit",
                        spec->path, left_out, total, share, out->highest, out->limit);
  return cf_error_set(err, CF_EINVAL,
                      "%s: colour: %zu of the %zu pixels on the sphere (%.3g %%) hold values "
                      "that cannot be radiance (far below 0, or absurdly large; each image's "
                      "count is in the warnings): the decoding is wrong (black_level %g?) or "
                      "the photos are not radiance",
                      spec->path, left_out, total, share, spec->black_level);
}

/* Refuse a capture whose observations leave nothing to fit, saying why. */
static cf_status check_usable(const cf_capture *capture, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  const cf_observations *o = &capture->obs;
  int positive = 0;
  const size_t lit = lit_until_positive(o, &positive);
  size_t k = 0;
  int j = 0;
  double distance = 0.0;
  if (lit == 0 && light_inside(capture, &k, &j, &distance))
    return cf_error_set(err, CF_EINVAL,
                        "%s: lights: no observation is lit: at all %zu observations every light "
                        "is behind the surface; light %d of %s is inside the sphere (%g from "
                        "its centre, radius %g)",
                        spec->path, o->count, j + 1, spec->image_names[k], distance,
                        capture->radius);
  if (lit == 0)
    return cf_error_set(err, CF_EINVAL,
                        "%s: lights: no observation is lit: at all %zu observations of the %zu "
                        "images every light is behind the surface (n.l <= 0)",
                        spec->path, o->count, spec->num_images);
  if (!positive)
    return cf_error_set(err, CF_EINVAL,
                        "%s: colour: none of the %zu lit observations measures a positive value "
                        "(after black_level %g is subtracted): nothing to fit",
                        spec->path, lit, spec->black_level);
  return CF_OK;
}

cf_status capture_screen_observations(cf_capture *capture, cf_error *err) {
  cf_observations *o = &capture->obs;
  const size_t n = capture->spec.num_images, total = o->count;
  left_out_counts all = {0};
  cf_status s = check_reached(capture, err);
  size_t *begin = malloc((n + 1) * sizeof *begin);
  image_screen *images = calloc(n ? n : 1, sizeof *images);
  if (s == CF_OK && (!begin || !images)) s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) s = screen_images(capture, begin, images, &all, err);
  const size_t kept = o->count;
  free(begin);
  free(images);
  if (s != CF_OK) return s;
  s = check_left_out(capture, total, &all, err);
  if (s == CF_OK && all.signal < 1.0) /* (infinite when the lights' level is not known) */
    s = cf_error_set(err, CF_EINVAL,
                     "%s: lights: the lights are too weak to move any value beyond the noise: "
                     "the brightest material the model allows would differ from a black one "
                     "by chi2 %.3g over all %zu observations (below 1; the noise's sigma %g at "
                     "radiance 0): nothing to fit",
                     capture->spec.path, all.signal, kept, all.sigma);
  return s == CF_OK ? check_usable(capture, err) : s;
}
