/* The pixel loop of a capture: for every pixel of image k that sees the
 * sphere clear of its silhouette (and is inside the mask, if any), decode
 * the photo's value to linear radiance and record the observation: normal,
 * view, every light's direction and irradiance, RGB, flags. Then the
 * screen of the whole capture: values that cannot be radiance left out,
 * and a capture with nothing lit and positive to fit refused. */
#define _DEFAULT_SOURCE /* madvise */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "capture_internal.h"
#include "core/order_statistics.h"
#include "core/parallel.h"
#include "image_codec.h"
#include "core/vec.h"

/* The arrays of n observations (o->lights set) as they are: `field`,
 * its values per observation. */
#define EACH_ARRAY(o, slots, DO) \
  DO(normal, 3);                 \
  DO(view, 3);                   \
  DO(light_dir, 3 * (slots));    \
  DO(irradiance, 3 * (slots));   \
  DO(rgb, 3);                    \
  DO(flags, 1);                  \
  DO(image, 1);                  \
  DO(pixel, 2)

static size_t slots_of(const cf_observations *o) {
  return (size_t)(o->lights > 0 ? o->lights : 1);
}

/* Huge pages for a large array: first touching its pages (zeroing them)
 * is most of the kernel's part of loading, 4 KiB at a time otherwise. */
static void advise_huge(void *p, size_t bytes) {
#ifdef MADV_HUGEPAGE
  const uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE), huge = (uintptr_t)2 << 20;
  uintptr_t begin = ((uintptr_t)p + page - 1) / page * page, end = (uintptr_t)p + bytes;
  if (end > begin + huge) madvise((void *)begin, (end - begin) / page * page, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}

cf_status capture_allocate_observations(cf_observations *o, size_t n, cf_error *err) {
  const size_t slots = slots_of(o), room = n ? n : 1;
#define ALLOCATE(field, per)                                                   \
  if (!(o->field = malloc(room * (per) * sizeof *o->field)))                   \
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", n); \
  advise_huge(o->field, room * (per) * sizeof *o->field)
  EACH_ARRAY(o, slots, ALLOCATE);
#undef ALLOCATE
  return CF_OK;
}

void capture_shrink_observations(cf_observations *o) {
  const size_t slots = slots_of(o), room = o->count ? o->count : 1;
  void *shrunk;
#define SHRINK(field, per)                                         \
  if ((shrunk = realloc(o->field, room * (per) * sizeof *o->field))) \
  o->field = shrunk /* (on failure the larger block stays) */
  EACH_ARRAY(o, slots, SHRINK);
#undef SHRINK
}

void capture_free_observations(cf_observations *o) {
  const size_t slots = slots_of(o);
#define FREE(field, per) \
  free(o->field);        \
  o->field = NULL
  EACH_ARRAY(o, slots, FREE);
#undef FREE
  (void)slots;
}

void capture_move_observations(cf_observations *to, size_t at, const cf_observations *from,
                               size_t first, size_t count) {
  if ((to == from && at == first) || count == 0) return;
  const size_t slots = slots_of(to);
#define MOVE(field, per) \
  memmove(to->field + (per) * at, from->field + (per) * first, (per) * count * sizeof *to->field)
  EACH_ARRAY(to, slots, MOVE);
#undef MOVE
}

/* An 8-bit image's 256 values (image_scale_u8's) decoded once each by
 * cf_decode_pixel: a look-up instead of a pow per channel, bit-identical;
 * a value that is not one of them is decoded directly. */
typedef struct code_table {
  int used;
  uint32_t key[256]; /* each code's float's bits */
  double radiance[256];
  uint8_t clipped[256];
} code_table;

static void code_table_init(code_table *t, const cf_decode *decode, int eight_bit) {
  t->used = eight_bit;
  if (!eight_bit) return;
  uint8_t codes[256];
  float values[256];
  for (int c = 0; c < 256; ++c) codes[c] = (uint8_t)c;
  image_scale_u8(codes, 256, values);
  for (int c = 0; c < 256; ++c) {
    double rgb[3];
    t->clipped[c] = (uint8_t)(cf_decode_pixel(decode, &values[c], 1, rgb) & 1u);
    t->radiance[c] = rgb[0];
    memcpy(&t->key[c], &values[c], sizeof t->key[c]);
  }
}

/* cf_decode_pixel, through the table where it holds every channel. */
static unsigned decode_stored(const code_table *t, const cf_decode *decode, const float *stored,
                              int channels, double radiance[3]) {
  const int grey = channels < 3;
  if (t->used) {
    unsigned clipped = 0;
    int c = 0;
    for (; c < 3; ++c) {
      const float value = stored[grey ? 0 : c], scaled = value * 255.0f;
      if (!(scaled >= 0.0f && scaled <= 255.0f)) break;
      const int code = (int)(scaled + 0.5f);
      uint32_t bits;
      memcpy(&bits, &value, sizeof bits);
      if (bits != t->key[code]) break;
      radiance[c] = t->radiance[code];
      clipped |= (unsigned)t->clipped[code] << c;
    }
    if (c == 3) return clipped;
  }
  return cf_decode_pixel(decode, stored, channels, radiance);
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

void capture_add_observations(const cf_capture *capture, size_t k, const cf_image *image,
                              const cf_image *mask, const cf_decode *decode, int eight_bit,
                              cf_observations *o, image_observations *out) {
  const size_t slots = (size_t)o->lights;
  int bounds[4];
  capture_surface_bounds(capture, k, image->width, image->height, bounds);
  code_table table;
  code_table_init(&table, decode, eight_bit);
  size_t i = o->count;
  memset(out, 0, sizeof *out);
  for (int y = bounds[1]; y < bounds[3]; ++y) {
    for (int x = bounds[0]; x < bounds[2]; ++x) {
      surface_point point;
      surface_hit hit = capture_surface_at(capture, k, x, y, &point);
      if (hit == SURFACE_MISS) continue;
      ++out->sphere_pixels;
      if (hit == SURFACE_MARGIN || !in_mask(mask, x, y)) continue;

      const float *stored =
          image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
      unsigned clipped = decode_stored(&table, decode, stored, image->channels, o->rgb + 3 * i);
      int lit = lights_at(capture, k, &point, o->light_dir + 3 * slots * i,
                          o->irradiance + 3 * slots * i);
      memcpy(o->normal + 3 * i, point.normal, sizeof point.normal);
      memcpy(o->view + 3 * i, point.view, sizeof point.view);
      o->flags[i] = (uint8_t)(clipped | (lit ? 0u : CF_OBS_UNLIT));
      o->image[i] = (uint32_t)k;
      o->pixel[2 * i] = (float)(x + 0.5);
      o->pixel[2 * i + 1] = (float)(y + 0.5);
      ++i;
      out->clipped += clipped != 0;
    }
  }
  out->observations = i - o->count;
  o->count = i;
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

enum { SCREENERS = 2 }; /* threads for the images' bounds (2 cores) */

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

/* Leave out image k's observations [begin, end) that hold a value that is
 * not radiance, moving the rest down to *kept; add its counts to *all. */
static void screen_image(cf_capture *capture, size_t k, size_t begin, size_t end,
                         const radiance_bounds *bounds, size_t *kept, left_out_counts *all) {
  cf_observations *o = &capture->obs;
  cf_capture_image *info = &capture->images[k];
  const radiance_bounds b = *bounds;
  left_out_counts out = {0};
  size_t run = begin; /* the kept observations [run, i) go to *kept on */
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
      capture_move_observations(o, *kept, o, run, i - run);
      *kept += i - run;
      run = i + 1;
      continue;
    }
    double z = brightest / b.sigma;
    all->signal += b.sigma > 0.0 ? z * z : INFINITY;
  }
  capture_move_observations(o, *kept, o, run, end - run);
  *kept += end - run;
  all->sigma = fmax(all->sigma, b.sigma);
  info->not_radiance = out.low + out.high;
  info->observations -= info->not_radiance;
  if ((double)info->not_radiance > CF_NOT_RADIANCE_TRACE * (double)(end - begin))
    warn_left_out(capture, k, &b, &out);
  all->low += out.low;
  all->high += out.high;
  if (out.highest > all->highest) all->highest = out.highest, all->limit = out.limit;
}

/* Every image's bounds of radiance, images side by side (each a quantile
 * of its values: 0.1 s of s96's load alone). */
typedef struct image_bounds {
  const cf_capture *capture;
  const size_t *begin; /* image k's observations: [begin[k], begin[k + 1]) */
  radiance_bounds *bounds;
  cf_status *status;
  cf_error *errs;
} image_bounds;

static void bounds_of_image(void *user, int k) {
  image_bounds *b = user;
  b->status[k] = bounds_of(b->capture, b->begin[k], b->begin[k + 1], &b->bounds[k], &b->errs[k]);
}

/* begin[k]: image k's first observation (the images' counts), begin[n]
 * the count; then each image's bounds. */
static cf_status all_bounds(const cf_capture *capture, size_t *begin, radiance_bounds *bounds,
                            cf_error *err) {
  const size_t n = capture->spec.num_images;
  cf_status *status = calloc(n ? n : 1, sizeof *status);
  cf_error *errs = calloc(n ? n : 1, sizeof *errs);
  cf_status s = status && errs ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  begin[0] = 0;
  for (size_t k = 0; k < n; ++k) begin[k + 1] = begin[k] + capture->images[k].observations;
  image_bounds b = {capture, begin, bounds, status, errs};
  if (s == CF_OK && n > 0) cf_parallel_for((int)n, SCREENERS, bounds_of_image, &b);
  for (size_t k = 0; s == CF_OK && k < n; ++k)
    if ((s = status[k]) != CF_OK && err) *err = errs[k];
  free(status);
  free(errs);
  return s;
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
  size_t kept = 0;
  left_out_counts all = {0};
  cf_status s = check_reached(capture, err);
  size_t *begin = malloc((n + 1) * sizeof *begin);
  radiance_bounds *bounds = calloc(n ? n : 1, sizeof *bounds);
  if (s == CF_OK && (!begin || !bounds)) s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) s = all_bounds(capture, begin, bounds, err);
  for (size_t k = 0; s == CF_OK && k < n; ++k)
    if (begin[k + 1] > begin[k])
      screen_image(capture, k, begin[k], begin[k + 1], &bounds[k], &kept, &all);
  free(begin);
  free(bounds);
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
