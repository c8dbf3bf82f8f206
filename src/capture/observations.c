/* The pixel loop of a capture: for every pixel of image k that sees the
 * sphere clear of its silhouette (and is inside the mask, if any), decode
 * the photo's value to linear radiance and record the observation: normal,
 * view, every light's direction and irradiance, RGB, flags. Then the
 * screen of the whole capture: values that cannot be radiance left out,
 * and a capture with nothing lit and positive to fit refused. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/order_statistics.h"
#include "core/vec.h"

/* Make room for `extra` more observations (doubling). */
static cf_status reserve(cf_capture *capture, size_t extra, cf_error *err) {
  cf_observations *o = &capture->obs;
  if (o->count + extra <= capture->obs_capacity) return CF_OK;
  size_t capacity = capture->obs_capacity ? capture->obs_capacity : 4096;
  while (capacity < o->count + extra) capacity *= 2;
  size_t slots = (size_t)(o->lights > 0 ? o->lights : 1);
#define GROW(field, per)                                                                   \
  do {                                                                                     \
    void *grown = realloc(o->field, capacity * (per) * sizeof *o->field);                  \
    if (!grown)                                                                            \
      return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", capacity); \
    o->field = grown;                                                                      \
  } while (0)
  GROW(normal, 3);
  GROW(view, 3);
  GROW(light_dir, 3 * slots);
  GROW(irradiance, 3 * slots);
  GROW(rgb, 3);
  GROW(flags, 1);
  GROW(image, 1);
  GROW(pixel, 2);
#undef GROW
  capture->obs_capacity = capacity;
  return CF_OK;
}

/* Is pixel (x, y) inside the mask (first channel > 0.5)? */
static int in_mask(const cf_image *mask, int x, int y) {
  if (!mask || !mask->pixels) return 1;
  return capture_mask_usable(
      mask->pixels[((size_t)y * (size_t)mask->width + (size_t)x) * (size_t)mask->channels]);
}

/* Every light slot's direction and irradiance at a surface point seen in
 * image k (zero for the slots the image does not use); 1 if some light
 * reaches it (n·l > 0 and some irradiance). */
static int lights_at(const cf_capture *capture, size_t k, const surface_point *point,
                     double *light_dir, double *irradiance) {
  const capture_view *view = &capture->views[k];
  const int lights = capture->light_counts[k];
  const cf_light *image_lights = capture->lights + k * (size_t)capture->max_lights;
  int lit = 0;
  for (int j = 0; j < capture->obs.lights; ++j) {
    double *l = light_dir + 3 * (size_t)j, *e = irradiance + 3 * (size_t)j;
    memset(l, 0, 3 * sizeof *l);
    memset(e, 0, 3 * sizeof *e);
    if (j >= lights || !cf_light_at(&image_lights[j], view->r, view->c, point->position, l, e))
      continue;
    lit |= l[0] * point->normal[0] + l[1] * point->normal[1] + l[2] * point->normal[2] > 0.0 &&
           e[0] + e[1] + e[2] > 0.0;
  }
  return lit;
}

int cf_capture_footprint_at(const cf_capture *capture, size_t i, double du, double dv,
                            double normal[3], double view[3], double *light_dir,
                            double *irradiance) {
  const cf_observations *o = &capture->obs;
  if (i >= o->count || !isfinite(du) || !isfinite(dv)) return 0;
  size_t k = o->image[i];
  surface_point point;
  double u = (double)o->pixel[2 * i] + du, v = (double)o->pixel[2 * i + 1] + dv;
  if (capture_surface_at_uv(capture, k, u, v, &point) == SURFACE_MISS) return 0;
  memcpy(normal, point.normal, sizeof point.normal);
  memcpy(view, point.view, sizeof point.view);
  lights_at(capture, k, &point, light_dir, irradiance);
  return 1;
}

double cf_observation_specularity(const cf_observations *obs, size_t k) {
  const double *n = obs->normal + 3 * k, *v = obs->view + 3 * k;
  double best = -1.0;
  for (int j = 0; j < obs->lights; ++j) {
    size_t slot = k * (size_t)obs->lights + (size_t)j;
    const double *l = obs->light_dir + 3 * slot, *e = obs->irradiance + 3 * slot;
    if (e[0] + e[1] + e[2] <= 0.0 || n[0] * l[0] + n[1] * l[1] + n[2] * l[2] <= 0.0) continue;
    double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
    double length = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (length > 0.0) best = fmax(best, (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / length);
  }
  return best;
}

cf_status capture_add_observations(cf_capture *capture, size_t k, const cf_image *image,
                                   const cf_image *mask, const cf_decode *decode, cf_error *err) {
  cf_observations *o = &capture->obs;
  cf_capture_image *info = &capture->images[k];
  const size_t slots = (size_t)o->lights;
  int bounds[4];
  capture_surface_bounds(capture, k, image->width, image->height, bounds);
  cf_status s =
      reserve(capture, (size_t)(bounds[2] - bounds[0]) * (size_t)(bounds[3] - bounds[1]), err);
  if (s != CF_OK) return s;
  for (int y = bounds[1]; y < bounds[3]; ++y) {
    for (int x = bounds[0]; x < bounds[2]; ++x) {
      surface_point point;
      surface_hit hit = capture_surface_at(capture, k, x, y, &point);
      if (hit == SURFACE_MISS) continue;
      ++info->sphere_pixels;
      if (hit == SURFACE_MARGIN || !in_mask(mask, x, y)) continue;

      size_t i = o->count;
      const float *stored =
          image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
      unsigned clipped = cf_decode_pixel(decode, stored, image->channels, o->rgb + 3 * i);
      int lit = lights_at(capture, k, &point, o->light_dir + 3 * slots * i,
                          o->irradiance + 3 * slots * i);
      memcpy(o->normal + 3 * i, point.normal, sizeof point.normal);
      memcpy(o->view + 3 * i, point.view, sizeof point.view);
      o->flags[i] = (uint8_t)(clipped | (lit ? 0u : CF_OBS_UNLIT));
      o->image[i] = (uint32_t)k;
      o->pixel[2 * i] = (float)(x + 0.5);
      o->pixel[2 * i + 1] = (float)(y + 0.5);
      ++o->count;
      ++info->observations;
      info->clipped += clipped != 0;
    }
  }
  return CF_OK;
}

/* ---- The screen: values that cannot be radiance (docs/captures.md) ----
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

/* Copy observation `from` over `to` (to < from). */
static void move_observation(cf_observations *o, size_t to, size_t from) {
  const size_t slots = (size_t)(o->lights > 0 ? o->lights : 1);
  memcpy(o->normal + 3 * to, o->normal + 3 * from, 3 * sizeof *o->normal);
  memcpy(o->view + 3 * to, o->view + 3 * from, 3 * sizeof *o->view);
  memcpy(o->light_dir + 3 * slots * to, o->light_dir + 3 * slots * from,
         3 * slots * sizeof *o->light_dir);
  memcpy(o->irradiance + 3 * slots * to, o->irradiance + 3 * slots * from,
         3 * slots * sizeof *o->irradiance);
  memcpy(o->rgb + 3 * to, o->rgb + 3 * from, 3 * sizeof *o->rgb);
  o->flags[to] = o->flags[from];
  o->image[to] = o->image[from];
  memcpy(o->pixel + 2 * to, o->pixel + 2 * from, 2 * sizeof *o->pixel);
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

/* Leave out image k's observations [begin, end) that hold a value that is
 * not radiance, moving the rest down to *kept; add its counts to *all. */
static cf_status screen_image(cf_capture *capture, size_t k, size_t begin, size_t end, size_t *kept,
                              left_out_counts *all, cf_error *err) {
  cf_observations *o = &capture->obs;
  cf_capture_image *info = &capture->images[k];
  radiance_bounds b = {0};
  cf_status s = bounds_of(capture, begin, end, &b, err);
  if (s != CF_OK) return s;
  left_out_counts out = {0};
  for (size_t i = begin; i < end; ++i) {
    int low = 0, high = 0;
    double brightest = b.lights_known ? brightest_at(o, i) : INFINITY;
    double limit = fmin(b.absurd, MARGIN * brightest + NOISE_SIGMAS * b.sigma);
    for (int c = 0; c < 3; ++c) {
      double v = o->rgb[3 * i + c];
      if (v < b.low) low = 1, out.lowest = fmin(out.lowest, v);
      if (v > limit) high = 1;
      if (v > limit && v > out.highest) out.highest = v, out.limit = limit;
    }
    if (low || high) {
      if (out.low + out.high == 0) memcpy(out.at, o->pixel + 2 * i, sizeof out.at);
      out.low += (size_t)low;
      out.high += (size_t)(high && !low);
      info->clipped -= (o->flags[i] & CF_OBS_CLIPPED) != 0;
      continue;
    }
    if (*kept != i) move_observation(o, *kept, i);
    ++*kept;
    double z = brightest / b.sigma;
    all->signal += b.sigma > 0.0 ? z * z : INFINITY;
  }
  all->sigma = fmax(all->sigma, b.sigma);
  info->not_radiance = out.low + out.high;
  info->observations -= info->not_radiance;
  if ((double)info->not_radiance > CF_NOT_RADIANCE_TRACE * (double)(end - begin))
    warn_left_out(capture, k, &b, &out);
  all->low += out.low;
  all->high += out.high;
  if (out.highest > all->highest) all->highest = out.highest, all->limit = out.limit;
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

/* How many observations some light reaches with some irradiance, how many
 * are lit (n·l > 0 as well) and of those how many measure a positive value. */
typedef struct usable {
  size_t irradiated, lit, positive;
} usable;

static usable count_usable(const cf_observations *o) {
  usable u = {0, 0, 0};
  const size_t slots = (size_t)(o->lights > 0 ? o->lights : 1);
  for (size_t i = 0; i < o->count; ++i) {
    const double *e = o->irradiance + 3 * slots * i;
    int irradiated = 0;
    for (size_t j = 0; j < 3 * slots; ++j) irradiated |= e[j] > 0.0;
    u.irradiated += (size_t)irradiated;
    if (o->flags[i] & CF_OBS_UNLIT) continue;
    ++u.lit;
    const double *y = o->rgb + 3 * i;
    u.positive += y[0] > 0.0 || y[1] > 0.0 || y[2] > 0.0;
  }
  return u;
}

/* Refuse a capture that no light reaches (before the screen: with no
 * light every value is above what the lights can give). */
static cf_status check_reached(const cf_capture *capture, cf_error *err) {
  const cf_observations *o = &capture->obs;
  if (count_usable(o).irradiated > 0) return CF_OK;
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
  usable u = count_usable(o);
  size_t k = 0;
  int j = 0;
  double distance = 0.0;
  if (u.lit == 0 && light_inside(capture, &k, &j, &distance))
    return cf_error_set(err, CF_EINVAL,
                        "%s: lights: no observation is lit: at all %zu observations every light "
                        "is behind the surface; light %d of %s is inside the sphere (%g from "
                        "its centre, radius %g)",
                        spec->path, o->count, j + 1, spec->image_names[k], distance,
                        capture->radius);
  if (u.lit == 0)
    return cf_error_set(err, CF_EINVAL,
                        "%s: lights: no observation is lit: at all %zu observations of the %zu "
                        "images every light is behind the surface (n.l <= 0)",
                        spec->path, o->count, spec->num_images);
  if (u.positive == 0)
    return cf_error_set(err, CF_EINVAL,
                        "%s: colour: none of the %zu lit observations measures a positive value "
                        "(after black_level %g is subtracted): nothing to fit",
                        spec->path, u.lit, spec->black_level);
  return CF_OK;
}

cf_status capture_screen_observations(cf_capture *capture, cf_error *err) {
  cf_observations *o = &capture->obs;
  size_t total = o->count, kept = 0, begin = 0;
  left_out_counts all = {0};
  cf_status s = check_reached(capture, err);
  while (s == CF_OK && begin < total) {
    size_t k = o->image[begin], end = begin;
    while (end < total && o->image[end] == k) ++end;
    s = screen_image(capture, k, begin, end, &kept, &all, err);
    begin = end;
  }
  if (s != CF_OK) return s;
  o->count = kept;
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
