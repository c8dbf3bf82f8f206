/* Light probes from chrome-ball photos (src/capture/include/capture/light_probe.h): an
 * exposure-bracket merge after P. Debevec and J. Malik, "Recovering High
 * Dynamic Range Radiance Maps from Photographs", SIGGRAPH 1997 (eq. 6 and
 * its hat weight; the response is the declared transfer, not recovered),
 * and the mirror-ball unwrap (Debevec 1998, "Rendering Synthetic Objects
 * into Real Scenes", §3: the ball reflects the whole sphere but −v). */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "capture/light_probe.h"
#include "core/order_statistics.h"
#include "core/vec.h"
#include "envmap.h"

#define MAX_BRACKETS CF_MAX_BRACKETS
/* 8 × 8 reads a map pixel cover balls up to r = 16 H / π (1300 px at the
 * default 512 × 256) without skipping a photo pixel; larger balls alias. */
#define MAX_SUPERSAMPLE 8

/* ---- brackets ---- */

static cf_status check_brackets(const cf_image *brackets, const double *exposures, int count,
                                const char *const *names, const cf_bracket_options *o,
                                cf_error *err) {
  if (count < 1 || count > MAX_BRACKETS)
    return cf_error_set(err, CF_EINVAL, "%d exposure brackets; give 1 to %d", count, MAX_BRACKETS);
  if (!(o->dark >= 0.0 && o->dark < o->saturated && o->saturated <= 1.0))
    return cf_error_set(err, CF_EINVAL,
                        "bracket codes: dark %g and saturated %g must satisfy 0 <= dark < "
                        "saturated <= 1",
                        o->dark, o->saturated);
  if (o->transfer == CF_TRANSFER_GAMMA && !(o->gamma > 0.0 && isfinite(o->gamma)))
    return cf_error_set(err, CF_EINVAL, "bracket gamma %g must be positive", o->gamma);
  for (int k = 0; k < count; ++k) {
    const char *name = names ? names[k] : "bracket";
    const cf_image *b = &brackets[k];
    if (!b->pixels || b->channels < 1 || b->channels > 4)
      return cf_error_set(err, CF_EINVAL, "%s (bracket %d): an empty image", name, k + 1);
    if (b->width != brackets[0].width || b->height != brackets[0].height)
      return cf_error_set(err, CF_EINVAL,
                          "%s (bracket %d) is %d x %d, but %s (bracket 1) is %d x %d: brackets "
                          "must be photos of one size",
                          name, k + 1, b->width, b->height, names ? names[0] : "bracket",
                          brackets[0].width, brackets[0].height);
    if (!(exposures[k] >= CF_BRACKET_MIN_EXPOSURE && exposures[k] <= CF_BRACKET_MAX_EXPOSURE))
      return cf_error_set(err, CF_EINVAL, "%s (bracket %d): exposure %g is outside [%g, %g]", name,
                          k + 1, exposures[k], CF_BRACKET_MIN_EXPOSURE, CF_BRACKET_MAX_EXPOSURE);
    if (k > 0 && !(exposures[k] > exposures[k - 1]))
      return cf_error_set(err, CF_EINVAL,
                          "exposures must increase strictly from bracket to bracket: %s (bracket "
                          "%d) has %g after %g",
                          name, k + 1, exposures[k], exposures[k - 1]);
    cf_status s = cf_image_check_finite(b, name, err);
    if (s != CF_OK) return s;
  }
  return CF_OK;
}

/* The stored code of channel `c` of pixel i, for 1..4 channels. */
static double code_at(const cf_image *b, size_t i, int c) {
  return b->pixels[i * (size_t)b->channels + (size_t)(b->channels >= 3 ? c : 0)];
}

/* Debevec & Malik's hat on the stored code: 0 at dark and saturated. */
static double hat_weight(double code, const cf_bracket_options *o) {
  const double w = fmin(code - o->dark, o->saturated - code);
  return w > 0.0 ? w : 0.0;
}

/* One pixel of the merge, all channels; returns bit 0 if a channel was
 * clipped in every bracket, bit 1 if one was dark in every bracket. */
static unsigned merge_pixel(const cf_image *brackets, const double *exposures, int count,
                            const cf_bracket_options *o, size_t index, float out[3]) {
  double sum[3] = {0, 0, 0}, weight[3] = {0, 0, 0}, longest[3] = {0, 0, 0};
  for (int k = 0; k < count; ++k) {
    const cf_image *b = &brackets[k];
    const float *stored = b->pixels + index * (size_t)b->channels;
    const cf_decode decode = {o->transfer, o->gamma, 0.0, INFINITY, exposures[k]};
    double radiance[3];
    cf_decode_pixel(&decode, stored, b->channels, radiance);
    for (int c = 0; c < 3; ++c) {
      const double code = code_at(b, index, c);
      const double w = code >= o->saturated ? 0.0 : hat_weight(code, o);
      sum[c] += w * radiance[c];
      weight[c] += w;
      longest[c] = radiance[c]; /* the last bracket is the longest */
    }
  }
  unsigned flags = 0;
  for (int c = 0; c < 3; ++c) {
    if (weight[c] > 0.0) {
      out[c] = (float)(sum[c] / weight[c]);
      continue;
    }
    if (code_at(&brackets[0], index, c) >= o->saturated) {
      const cf_decode decode = {o->transfer, o->gamma, 0.0, INFINITY, exposures[0]};
      const float clip[1] = {(float)o->saturated};
      double bound[3];
      cf_decode_pixel(&decode, clip, 1, bound);
      out[c] = (float)bound[0];
      flags |= 1u;
    } else {
      out[c] = (float)longest[c];
      flags |= 2u;
    }
  }
  return flags;
}

/* Bracket k+1 over bracket k, measured (report) and compared with the
 * declared exposures. */
static cf_status check_ratio(const cf_image *brackets, const double *exposures, int k,
                             const char *const *names, const cf_bracket_options *o, double *samples,
                             cf_bracket_report *report, cf_error *err) {
  const cf_image *a = &brackets[k], *b = &brackets[k + 1];
  const size_t pixels = (size_t)a->width * (size_t)a->height;
  const cf_decode da = {o->transfer, o->gamma, 0.0, INFINITY, 1.0};
  size_t n = 0;
  for (size_t i = 0; i < pixels; ++i) {
    double la[3], lb[3];
    cf_decode_pixel(&da, a->pixels + i * (size_t)a->channels, a->channels, la);
    cf_decode_pixel(&da, b->pixels + i * (size_t)b->channels, b->channels, lb);
    for (int c = 0; c < 3; ++c) {
      const double ca = code_at(a, i, c), cb = code_at(b, i, c);
      if (ca >= 0.1 && ca <= 0.9 && cb >= 0.1 && cb <= 0.9 && la[c] > 0.0)
        samples[n++] = lb[c] / la[c];
    }
  }
  report->ratio_samples[k] = n;
  report->measured_ratio[k] = n >= CF_BRACKET_MIN_SAMPLES ? order_median(samples, n) : NAN;
  const double declared = exposures[k + 1] / exposures[k], measured = report->measured_ratio[k];
  if (isnan(measured) || fabs(log(measured / declared)) <= log(CF_BRACKET_RATIO_TOLERANCE))
    return CF_OK;
  return cf_error_set(err, CF_EINVAL,
                      "%s (bracket %d) measures %.3g times as bright as %s (bracket %d), but its "
                      "exposure says %.3g times: brackets out of order, one missing, a wrong "
                      "exposure or a wrong tone curve",
                      names ? names[k + 1] : "bracket", k + 2, measured,
                      names ? names[k] : "bracket", k + 1, declared);
}

static cf_status check_ratios(const cf_image *brackets, const double *exposures, int count,
                              const char *const *names, const cf_bracket_options *o,
                              cf_bracket_report *report, cf_error *err) {
  if (count < 2) return CF_OK;
  const size_t values = 3 * (size_t)brackets[0].width * (size_t)brackets[0].height;
  double *samples = malloc(values * sizeof *samples);
  if (!samples) return cf_error_set(err, CF_ENOMEM, "out of memory checking the exposures");
  cf_status s = CF_OK;
  for (int k = 0; s == CF_OK && k + 1 < count; ++k)
    s = check_ratio(brackets, exposures, k, names, o, samples, report, err);
  free(samples);
  return s;
}

cf_status cf_brackets_merge(const cf_image *brackets, const double *exposures, int count,
                            const char *const *names, const cf_bracket_options *options,
                            cf_image *radiance, cf_bracket_report *report, cf_error *err) {
  if (!brackets || !exposures || !options || !radiance)
    return cf_error_set(err, CF_EINVAL, "cf_brackets_merge: a required argument is NULL");
  cf_bracket_report local = {0};
  cf_status s = check_brackets(brackets, exposures, count, names, options, err);
  if (s == CF_OK) s = check_ratios(brackets, exposures, count, names, options, &local, err);
  if (s == CF_OK) s = cf_image_alloc(radiance, brackets[0].width, brackets[0].height, 3, err);
  if (s != CF_OK) return s;
  const size_t pixels = (size_t)brackets[0].width * (size_t)brackets[0].height;
  for (size_t i = 0; i < pixels; ++i) {
    const unsigned flags =
        merge_pixel(brackets, exposures, count, options, i, radiance->pixels + 3 * i);
    local.saturated_everywhere += flags & 1u;
    local.dark_everywhere += (flags >> 1) & 1u;
  }
  if (report) *report = local;
  return CF_OK;
}

/* ---- unwrap ---- */

void cf_probe_reflect(const double n[3], double d[3]) {
  const double nv = n[2];
  d[0] = 2.0 * nv * n[0];
  d[1] = 2.0 * nv * n[1];
  d[2] = 2.0 * nv * n[2] - 1.0;
}

void cf_envmap_pixel(int width, int height, const double d[3], double *x, double *y) {
  /* cf_envmap_direction: d = (−sin θ cos φ, cos θ, −sin θ sin φ) */
  const double theta = acos(fmax(-1.0, fmin(1.0, d[1])));
  double phi = atan2(-d[2], -d[0]);
  if (phi < 0.0) phi += 2.0 * CF_PI;
  *x = phi / (2.0 * CF_PI) * width - 0.5;
  *y = theta / CF_PI * height - 0.5;
}

typedef struct unwrap_ctx {
  const cf_image *photo;
  const cf_probe_ball *ball;
  const cf_probe_options *o;
  double max_offset; /* r − margin: the farthest usable point from the centre */
} unwrap_ctx;

static int on_mask(const cf_image *mask, int x, int y) {
  return mask->pixels[((size_t)y * (size_t)mask->width + (size_t)x) * (size_t)mask->channels] !=
         0.0f;
}

static void pixel_rgb(const cf_image *im, int x, int y, double rgb[3]) {
  const float *p = im->pixels + ((size_t)y * (size_t)im->width + (size_t)x) * (size_t)im->channels;
  for (int c = 0; c < 3; ++c) rgb[c] = p[im->channels >= 3 ? c : 0];
}

/* The photo's radiance reflected into map direction d; 0 when d is not
 * observable. */
static int sample_direction(const unwrap_ctx *u, const double d[3], double rgb[3]) {
  double h[3] = {d[0], d[1], d[2] + 1.0};
  const double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
  if (len < 1e-9) return 0; /* d = −v exactly */
  const double r = u->ball->radius;
  const double ox = r * h[0] / len, oy = -r * h[1] / len;
  if (ox * ox + oy * oy > u->max_offset * u->max_offset) return 0;
  /* bilinear on pixel centres (x + 0.5, y + 0.5) */
  const double fx = u->ball->cx + ox - 0.5, fy = u->ball->cy + oy - 0.5;
  const int x0 = (int)floor(fx), y0 = (int)floor(fy);
  const double ax = fx - x0, ay = fy - y0;
  const cf_image *im = u->photo;
  if (x0 < 0 || y0 < 0 || x0 + 1 >= im->width || y0 + 1 >= im->height) return 0;
  const cf_image *m = u->o->mask;
  if (m && (!on_mask(m, x0, y0) || !on_mask(m, x0 + 1, y0) || !on_mask(m, x0, y0 + 1) ||
            !on_mask(m, x0 + 1, y0 + 1)))
    return 0;
  double p00[3], p10[3], p01[3], p11[3];
  pixel_rgb(im, x0, y0, p00);
  pixel_rgb(im, x0 + 1, y0, p10);
  pixel_rgb(im, x0, y0 + 1, p01);
  pixel_rgb(im, x0 + 1, y0 + 1, p11);
  for (int c = 0; c < 3; ++c)
    rgb[c] = ((1 - ax) * (1 - ay) * p00[c] + ax * (1 - ay) * p10[c] + (1 - ax) * ay * p01[c] +
              ax * ay * p11[c]) /
             u->o->reflectance;
  return 1;
}

/* One map pixel: the mean of its S × S observable directions, alpha their
 * share. */
static void unwrap_pixel(const unwrap_ctx *u, int width, int height, int x, int y, int s,
                         float out[4]) {
  double sum[3] = {0, 0, 0};
  int valid = 0;
  for (int j = 0; j < s; ++j)
    for (int i = 0; i < s; ++i) {
      double d[3], rgb[3];
      cf_envmap_direction(width, height, x + (i + 0.5) / s - 0.5, y + (j + 0.5) / s - 0.5, d);
      if (!sample_direction(u, d, rgb)) continue;
      for (int c = 0; c < 3; ++c) sum[c] += rgb[c];
      ++valid;
    }
  for (int c = 0; c < 3; ++c) out[c] = valid ? (float)(sum[c] / valid) : 0.0f;
  out[3] = (float)valid / (float)(s * s);
}

static cf_status check_unwrap(const cf_image *photo, const cf_probe_ball *b,
                              const cf_probe_options *o, cf_error *err) {
  if (!photo->pixels || photo->channels < 1 || photo->channels > 4)
    return cf_error_set(err, CF_EINVAL, "light probe: the photo is empty");
  if (o->width < 8 || o->width > 16384 || o->width % 2)
    return cf_error_set(err, CF_EINVAL, "light probe: map width %d; give an even width in 8..16384",
                        o->width);
  if (!(o->margin_px >= 0.0 && isfinite(o->margin_px)))
    return cf_error_set(err, CF_EINVAL, "light probe: margin %g px must be >= 0", o->margin_px);
  if (!(o->reflectance >= CF_PROBE_MIN_REFLECTANCE && o->reflectance <= 1.0))
    return cf_error_set(err, CF_EINVAL, "light probe: reflectance %g is outside [%g, 1]",
                        o->reflectance, CF_PROBE_MIN_REFLECTANCE);
  if (!(isfinite(b->cx) && isfinite(b->cy) && b->radius > o->margin_px + 1.0 &&
        isfinite(b->radius)))
    return cf_error_set(err, CF_EINVAL,
                        "light probe: the ball (centre %g, %g, radius %g px) must have a radius "
                        "above the margin (%g px) + 1",
                        b->cx, b->cy, b->radius, o->margin_px);
  if (b->cx - b->radius < 0.0 || b->cy - b->radius < 0.0 || b->cx + b->radius > photo->width ||
      b->cy + b->radius > photo->height)
    return cf_error_set(err, CF_EINVAL,
                        "light probe: the ball (centre %g, %g, radius %g px) is not wholly inside "
                        "the %d x %d photo",
                        b->cx, b->cy, b->radius, photo->width, photo->height);
  if (o->mask && (o->mask->width != photo->width || o->mask->height != photo->height ||
                  !o->mask->pixels || o->mask->channels < 1))
    return cf_error_set(err, CF_EINVAL, "light probe: the mask is %d x %d, the photo %d x %d",
                        o->mask->width, o->mask->height, photo->width, photo->height);
  return cf_image_check_finite(photo, "light probe photo", err);
}

/* The map as light: every texel finite, and some texel at least a float's
 * smallest normal value. */
static cf_status check_map(const cf_image *map, double reflectance, cf_error *err) {
  const size_t texels = (size_t)map->width * (size_t)map->height;
  size_t bad = 0, first = 0;
  double brightest = 0.0;
  for (size_t i = 0; i < texels; ++i) {
    const float *rgb = map->pixels + 4 * i;
    if (!isfinite(rgb[0]) || !isfinite(rgb[1]) || !isfinite(rgb[2])) {
      if (bad++ == 0) first = i;
      continue;
    }
    brightest = fmax(brightest, fmax(rgb[0], fmax(rgb[1], rgb[2])));
  }
  if (bad)
    return cf_error_set(err, CF_EINVAL,
                        "light probe: %zu texels of the map are not finite (the first at (%zu, "
                        "%zu)): the photo's radiance over the reflectance %g is beyond a float's "
                        "range (%g)",
                        bad, first % (size_t)map->width, first / (size_t)map->width, reflectance,
                        (double)FLT_MAX);
  if (!(brightest >= FLT_MIN))
    return cf_error_set(err, CF_EINVAL,
                        "light probe: the map is black (its brightest value %g is below a float's "
                        "smallest normal value %g): the ball's radiance is 0 or too small for a "
                        "light",
                        brightest, (double)FLT_MIN);
  return CF_OK;
}

cf_status cf_probe_unwrap(const cf_image *photo, const cf_probe_ball *ball,
                          const cf_probe_options *options, cf_image *map, cf_probe_report *report,
                          cf_error *err) {
  if (!photo || !ball || !options || !map)
    return cf_error_set(err, CF_EINVAL, "cf_probe_unwrap: a required argument is NULL");
  cf_status s = check_unwrap(photo, ball, options, err);
  if (s != CF_OK) return s;
  const int width = options->width, height = width / 2;
  s = cf_image_alloc(map, width, height, 4, err);
  if (s != CF_OK) return s;
  const unwrap_ctx u = {photo, ball, options, ball->radius - options->margin_px};
  int ss = (int)ceil(CF_PI * ball->radius / (2.0 * height));
  ss = ss < 1 ? 1 : ss > MAX_SUPERSAMPLE ? MAX_SUPERSAMPLE : ss;
  double invalid = 0.0, valid_pixels = 0.0;
  for (int y = 0; y < height; ++y) {
    const double d_omega =
        (2.0 * CF_PI / width) * (CF_PI / height) * sin(CF_PI * (y + 0.5) / height);
    for (int x = 0; x < width; ++x) {
      float *out = map->pixels + 4 * ((size_t)y * (size_t)width + (size_t)x);
      unwrap_pixel(&u, width, height, x, y, ss, out);
      invalid += (1.0 - out[3]) * d_omega;
      valid_pixels += out[3];
    }
  }
  if (valid_pixels == 0.0) {
    cf_image_free(map);
    return cf_error_set(err, CF_EINVAL,
                        "light probe: no direction of the map is observable on the ball");
  }
  if ((s = check_map(map, options->reflectance, err)) != CF_OK) {
    cf_image_free(map);
    return s;
  }
  if (report) {
    const double sin_alpha = u.max_offset / ball->radius; /* α: normal's angle from v */
    report->invalid_fraction = invalid / (4.0 * CF_PI);
    report->max_reflection_deg = 2.0 * asin(fmin(1.0, sin_alpha)) * 180.0 / CF_PI;
    report->supersample = ss;
  }
  return CF_OK;
}
