/* What is left in a fit's highlight cores
 * (docs/studies/2026-11-26-highlight-cores.md): the photos'
 * noise floor measured without any model, the radial profile of the
 * prediction and the photo through each core, and the point-spread-
 * function test (the prediction convolved with a narrow core plus a
 * power-law halo, fitted on the odd images, tested on the even ones).
 *
 *   clayfit_cores FIT.json
 *
 * A measurement program, not part of clayfit: it prints its numbers. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "clayfit/fit_file.h"
#include "clayfit/image.h"

enum { WIN = 5, HALF = 2, NP = 6 }; /* the noise window and its quadratic */
enum { CORE_R = 3, RING_R = 12, KERNEL_R = 15, PATCH_R = RING_R + KERNEL_R };

typedef struct image_data {
  int w, h;
  float *y[3], *p[3];  /* photo and prediction (NaN: not an observation) */
  unsigned char *clip; /* per pixel: clipped channels (bits) */
  int bx, by;          /* the brightest observation's pixel */
} image_data;

typedef struct all {
  const cf_capture *capture;
  const cf_observations *o;
  double *pred;
  size_t images;
  size_t *first, *last;
} all;

/* ---- per-image dense pictures ---- */

static void image_free(image_data *d) {
  for (int c = 0; c < 3; ++c) free(d->y[c]), free(d->p[c]);
  free(d->clip);
}

static int image_fill(const all *a, size_t k, image_data *d) {
  const cf_capture_image *im = cf_capture_image_at(a->capture, k);
  size_t n = (size_t)im->width * (size_t)im->height;
  d->w = im->width, d->h = im->height;
  for (int c = 0; c < 3; ++c) {
    d->y[c] = malloc(n * sizeof(float));
    d->p[c] = malloc(n * sizeof(float));
    if (!d->y[c] || !d->p[c]) return 0;
    for (size_t q = 0; q < n; ++q) d->y[c][q] = d->p[c][q] = NAN;
  }
  d->clip = calloc(n, 1);
  if (!d->clip) return 0;
  double best = -1.0;
  for (size_t i = a->first[k]; i < a->last[k]; ++i) {
    int x = (int)a->o->pixel[2 * i], yy = (int)a->o->pixel[2 * i + 1];
    size_t q = (size_t)yy * (size_t)d->w + (size_t)x;
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) {
      d->y[c][q] = (float)a->o->rgb[3 * i + c];
      d->p[c][q] = (float)a->pred[3 * i + c];
      sum += a->o->rgb[3 * i + c];
    }
    d->clip[q] = a->o->flags[i] & CF_OBS_CLIPPED;
    if (sum > best) best = sum, d->bx = x, d->by = yy;
  }
  return 1;
}

static int is_core(const image_data *d, int x, int y, double r) {
  double dx = x - d->bx, dy = y - d->by;
  return dx * dx + dy * dy <= r * r;
}

/* ---- 1. the noise floor: local quadratic fits ---- */

/* The 25 × 25 projection I − H onto the residuals of a quadratic in a
 * 5 × 5 window. */
static void residual_projector(double m[WIN * WIN][WIN * WIN]) {
  double a[WIN * WIN][NP], ata[NP][NP] = {{0}}, inv[NP][NP];
  for (int j = 0; j < WIN * WIN; ++j) {
    double u = j % WIN - HALF, v = j / WIN - HALF;
    double row[NP] = {1, u, v, u * u, u * v, v * v};
    memcpy(a[j], row, sizeof row);
  }
  for (int r = 0; r < NP; ++r)
    for (int s = 0; s < NP; ++s)
      for (int j = 0; j < WIN * WIN; ++j) ata[r][s] += a[j][r] * a[j][s];
  double g[NP][2 * NP]; /* Gauss-Jordan */
  for (int r = 0; r < NP; ++r)
    for (int s = 0; s < 2 * NP; ++s) g[r][s] = s < NP ? ata[r][s] : (s - NP == r);
  for (int r = 0; r < NP; ++r) {
    double piv = g[r][r];
    for (int s = 0; s < 2 * NP; ++s) g[r][s] /= piv;
    for (int t = 0; t < NP; ++t) {
      if (t == r) continue;
      double f = g[t][r];
      for (int s = 0; s < 2 * NP; ++s) g[t][s] -= f * g[r][s];
    }
  }
  for (int r = 0; r < NP; ++r)
    for (int s = 0; s < NP; ++s) inv[r][s] = g[r][s + NP];
  for (int i = 0; i < WIN * WIN; ++i)
    for (int j = 0; j < WIN * WIN; ++j) {
      double h = 0.0;
      for (int r = 0; r < NP; ++r)
        for (int s = 0; s < NP; ++s) h += a[i][r] * inv[r][s] * a[j][s];
      m[i][j] = (i == j) - h;
    }
}

enum { BINS = 40 };
typedef struct noise_bins {
  double lo, hi; /* log10 of the level */
  double var[3][BINS], level[3][BINS];
  double count[3][BINS];
} noise_bins;

/* RSS/(25 − 6) of the window at (x, y) of picture f, or −1 where a pixel
 * is missing or clipped. */
static double window_variance(const image_data *d, const float *f, int x, int y,
                              double m[WIN * WIN][WIN * WIN]) {
  double v[WIN * WIN];
  for (int j = 0; j < WIN * WIN; ++j) {
    int xx = x + j % WIN - HALF, yy = y + j / WIN - HALF;
    if (xx < 0 || yy < 0 || xx >= d->w || yy >= d->h) return -1.0;
    size_t q = (size_t)yy * (size_t)d->w + (size_t)xx;
    if (isnan(f[q]) || d->clip[q]) return -1.0;
    v[j] = f[q];
  }
  double rss = 0.0;
  for (int i = 0; i < WIN * WIN; ++i) {
    double r = 0.0;
    for (int j = 0; j < WIN * WIN; ++j) r += m[i][j] * v[j];
    rss += r * r;
  }
  return rss / (WIN * WIN - NP);
}

static void noise_collect(const image_data *d, double m[WIN * WIN][WIN * WIN], noise_bins *b) {
  for (int y = 0; y < d->h; ++y)
    for (int x = 0; x < d->w; ++x) {
      size_t q = (size_t)y * (size_t)d->w + (size_t)x;
      if (isnan(d->y[0][q]) || is_core(d, x, y, 8.0)) continue; /* smooth shading only */
      for (int c = 0; c < 3; ++c) {
        double var = window_variance(d, d->y[c], x, y, m);
        double level = d->y[c][q];
        if (var < 0.0 || level <= 0.0) continue;
        int k = (int)floor((log10(level) - b->lo) / (b->hi - b->lo) * BINS);
        if (k < 0 || k >= BINS) continue;
        b->var[c][k] += var, b->level[c][k] += level, b->count[c][k] += 1.0;
      }
    }
}

/* σ²(y) = a + b y per channel, least squares over the bins (each bin's
 * mean variance, weighed by its count over its variance²). */
static void noise_model(const noise_bins *b, double a[3], double s[3]) {
  for (int c = 0; c < 3; ++c) {
    double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < BINS; ++k) {
      if (b->count[c][k] < 50) continue;
      double x = b->level[c][k] / b->count[c][k], v = b->var[c][k] / b->count[c][k];
      double w = b->count[c][k] / (v * v);
      sw += w, sx += w * x, sy += w * v, sxx += w * x * x, sxy += w * x * v;
    }
    double det = sw * sxx - sx * sx;
    s[c] = (sw * sxy - sx * sy) / det;
    a[c] = (sy - s[c] * sx) / sw;
  }
}

/* ---- 2. the cores: radial profiles and the PSF ---- */

typedef struct psf {
  double w, r0, beta; /* halo fraction, its scale (px) and power */
  int streak;         /* 1: the halo along the image's rows only */
} psf;

static void kernel_build(const psf *k, double *out /* (2R+1)² */) {
  int n = 2 * KERNEL_R + 1;
  double sum = 0.0;
  for (int j = 0; j < n * n; ++j) {
    double u = j % n - KERNEL_R, v = j / n - KERNEL_R, r2 = u * u + v * v;
    int off_row = k->streak && v != 0.0;
    out[j] = r2 <= (double)KERNEL_R * KERNEL_R && !off_row
                 ? pow(1.0 + r2 / (k->r0 * k->r0), -k->beta)
                 : 0.0;
    sum += out[j];
  }
  for (int j = 0; j < n * n; ++j) out[j] *= k->w / sum;
  out[KERNEL_R * n + KERNEL_R] += 1.0 - k->w;
}

/* The prediction (or, off the observations, the photo) at q. */
static double source(const image_data *d, int c, int x, int y) {
  if (x < 0 || y < 0 || x >= d->w || y >= d->h) return 0.0;
  size_t q = (size_t)y * (size_t)d->w + (size_t)x;
  if (!isnan(d->p[c][q])) return d->p[c][q];
  return isnan(d->y[c][q]) ? 0.0 : d->y[c][q];
}

typedef struct sums {
  double e2, y2;
} sums;

/* The prediction at pixel (x, y), channel c, by one of the tests below
 * (NAN: none). */
typedef double (*predict_fn)(const image_data *d, int c, int x, int y, const void *user);

/* Add image d's residuals within RING_R of its brightest pixel (core:
 * r ≤ CORE_R; ring: CORE_R < r ≤ RING_R) against `predict` (NAN: the
 * fit's prediction); a clipped channel predicted at or above its value is
 * censored. */
static void window_error(const image_data *d, predict_fn predict, const void *user, sums *core,
                         sums *ring) {
  for (int y = d->by - RING_R; y <= d->by + RING_R; ++y)
    for (int x = d->bx - RING_R; x <= d->bx + RING_R; ++x) {
      if (x < 0 || y < 0 || x >= d->w || y >= d->h || !is_core(d, x, y, RING_R)) continue;
      size_t q = (size_t)y * (size_t)d->w + (size_t)x;
      if (isnan(d->y[0][q])) continue;
      sums *s = is_core(d, x, y, CORE_R) ? core : ring;
      for (int c = 0; c < 3; ++c) {
        double mu = predict(d, c, x, y, user), yv = d->y[c][q];
        if (isnan(mu)) mu = d->p[c][q];
        if ((d->clip[q] >> c & 1u) && mu >= yv) continue; /* censored */
        s->e2 += (mu - yv) * (mu - yv), s->y2 += yv * yv;
      }
    }
}

/* The prediction convolved with a (2 KERNEL_R + 1)² kernel (NULL: as
 * predicted). */
static double convolved(const image_data *d, int c, int x, int y, const void *user) {
  const double *kernel = user;
  int n = 2 * KERNEL_R + 1;
  if (!kernel) return NAN;
  double mu = 0.0;
  for (int j = 0; j < n * n; ++j)
    if (kernel[j] != 0.0)
      mu += kernel[j] * source(d, c, x + j % n - KERNEL_R, y + j / n - KERNEL_R);
  return mu;
}

static void core_error(const image_data *d, const double *kernel, sums *core, sums *ring) {
  window_error(d, convolved, kernel, core, ring);
}

typedef struct set {
  image_data *img;
  size_t count;
} set;

static double psf_cost(const set *s, int parity, const psf *k, double *kernel, sums *core,
                       sums *ring) {
  sums cs = {0, 0}, rs = {0, 0};
  if (k) kernel_build(k, kernel);
  for (size_t i = 0; i < s->count; ++i)
    if (parity < 0 || (int)(i % 2) == parity) core_error(&s->img[i], k ? kernel : NULL, &cs, &rs);
  if (core) *core = cs;
  if (ring) *ring = rs;
  return cs.e2 + rs.e2; /* the core and its ring: where a halo would show */
}

/* The PSF that minimises the odd images' error: a coarse grid, then
 * coordinate refinement. */
static psf psf_fit(const set *s, double *kernel, int streak) {
  psf best = {0.0, 1.0, 1.5, streak};
  double cost = psf_cost(s, 1, NULL, kernel, NULL, NULL);
  const double ws[] = {0.005, 0.01, 0.02, 0.05, 0.1, 0.2};
  const double r0s[] = {0.3, 0.6, 1.0, 2.0, 4.0};
  const double betas[] = {1.1, 1.5, 2.0, 3.0, 6.0};
  for (size_t a = 0; a < sizeof ws / sizeof *ws; ++a)
    for (size_t b = 0; b < 5; ++b)
      for (size_t g = 0; g < 5; ++g) {
        psf k = {ws[a], r0s[b], betas[g], streak};
        double c = psf_cost(s, 1, &k, kernel, NULL, NULL);
        if (c < cost) cost = c, best = k;
      }
  for (int round = 0; round < 4 && best.w > 0.0; ++round)
    for (int p = 0; p < 3; ++p)
      for (int sgn = -1; sgn <= 1; sgn += 2) {
        psf k = best;
        double *v = p == 0 ? &k.w : p == 1 ? &k.r0 : &k.beta;
        *v *= sgn > 0 ? 1.25 : 0.8;
        if (k.w >= 1.0 || k.beta <= 1.01) continue;
        double c = psf_cost(s, 1, &k, kernel, NULL, NULL);
        if (c < cost) cost = c, best = k;
      }
  return best;
}

static void profile(const set *s) {
  enum { RB = 13 };
  double po[RB] = {0}, pp[RB] = {0}, n[RB] = {0}, rr[RB] = {0};
  for (size_t i = 0; i < s->count; ++i) {
    const image_data *d = &s->img[i];
    double peak = 0.0; /* the prediction's peak: profiles in its units */
    for (int y = d->by - 2; y <= d->by + 2; ++y)
      for (int x = d->bx - 2; x <= d->bx + 2; ++x) {
        size_t q = (size_t)y * (size_t)d->w + (size_t)x;
        double v = d->p[0][q] + d->p[1][q] + d->p[2][q];
        if (v > peak) peak = v;
      }
    for (int y = d->by - RB; y <= d->by + RB; ++y)
      for (int x = d->bx - RB; x <= d->bx + RB; ++x) {
        size_t q = (size_t)y * (size_t)d->w + (size_t)x;
        double r = hypot(x - d->bx, y - d->by);
        int b = (int)floor(r + 0.5);
        if (b >= RB || isnan(d->y[0][q]) || d->clip[q] || !(peak > 0)) continue;
        po[b] += (d->y[0][q] + d->y[1][q] + d->y[2][q]) / peak;
        pp[b] += (d->p[0][q] + d->p[1][q] + d->p[2][q]) / peak;
        rr[b] += r, n[b] += 1;
      }
  }
  printf(
      "radial profile around the brightest pixel, all images, unclipped pixels, in units of "
      "the predicted peak:\n  r(px)  observed  predicted  obs/pred\n");
  for (int b = 0; b < RB; ++b)
    if (n[b] > 0)
      printf("  %5.2f  %8.4f  %9.4f  %8.3f\n", rr[b] / n[b], po[b] / n[b], pp[b] / n[b],
             po[b] / pp[b]);
}

/* ---- the defocus: the lit silhouette's edge ---- */

/* The silhouette's edge where a light from the side (the image whose
 * light has the largest |x|, each side) lights the rim: the photo's
 * green channel within 25° of ±x from the ball's centre (the observations'
 * mean pixel), in 0.25-px rings; the width from 90 % to 10 % of the value
 * 2 px inside the half-way point (a blur of σ has 2.56 σ). */
static void silhouette_edge(const all *a) {
  double cx = 0, cy = 0;
  size_t n0 = a->last[0] - a->first[0];
  for (size_t i = a->first[0]; i < a->last[0]; ++i)
    cx += a->o->pixel[2 * i], cy += a->o->pixel[2 * i + 1];
  cx /= (double)n0, cy /= (double)n0;
  double radius = sqrt((double)n0 / 3.14159265358979); /* inside the mask's margin */
  for (int side = -1; side <= 1; side += 2) {
    size_t k = 0;
    double best = -2.0;
    for (size_t j = 0; j < a->images; ++j) {
      double lx = side * a->o->light_dir[3 * (size_t)a->o->lights * a->first[j]];
      if (lx > best) best = lx, k = j;
    }
    cf_image im = {0};
    cf_error err = {0};
    if (cf_capture_read_radiance(a->capture, k, &im, NULL, &err) != CF_OK) {
      fprintf(stderr, "%s\n", err.message);
      return;
    }
    enum { NB = 80 }; /* from radius − 2 to radius + 18 px */
    double sum[NB] = {0}, cnt[NB] = {0};
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) {
        double dx = x + 0.5 - cx, dy = y + 0.5 - cy, r = hypot(dx, dy);
        if (fabs(atan2(dy, side * dx)) > 25.0 * 3.14159265358979 / 180.0) continue;
        int b = (int)floor((r - radius + 2.0) * 4.0);
        if (b < 0 || b >= NB) continue;
        sum[b] += im.pixels[3 * ((size_t)y * (size_t)im.width + (size_t)x) + 1], cnt[b] += 1;
      }
    cf_image_free(&im);
    double v[NB];
    for (int b = 0; b < NB; ++b) v[b] = cnt[b] > 0 ? sum[b] / cnt[b] : NAN;
    int half = -1;
    double top = 0.0;
    for (int b = 0; b < NB; ++b) top = isnan(v[b]) ? top : fmax(top, v[b]);
    for (int b = 1; b < NB && half < 0; ++b)
      if (v[b] < 0.5 * top) half = b;
    if (half < 8) continue;
    double plateau = v[half - 8], at[2] = {NAN, NAN}, level[2] = {0.9, 0.1};
    for (int t = 0; t < 2; ++t)
      for (int b = half - 8; b + 1 < NB && isnan(at[t]); ++b)
        if (v[b] >= level[t] * plateau && v[b + 1] < level[t] * plateau)
          at[t] = (b + (v[b] - level[t] * plateau) / (v[b] - v[b + 1])) / 4.0;
    printf(
        "silhouette edge, image %zu (light from %s): 90 %% to 10 %% of the rim in %.2f px "
        "(a Gaussian blur of sigma %.2f px)\n",
        k + 1, side > 0 ? "+x" : "-x", at[1] - at[0], (at[1] - at[0]) / 2.563);
  }
}

/* ---- driver ---- */

static int load(const char *fit_path, cf_capture **capture, cf_fit_file *fit, all *a) {
  cf_error err = {0};
  if (cf_fit_file_read(fit_path, fit, &err) != CF_OK)
    return fprintf(stderr, "%s\n", err.message), 0;
  cf_capture_options co = {0};
  if (cf_capture_load(fit->capture_path, &co, capture, &err) != CF_OK)
    return fprintf(stderr, "%s\n", err.message), 0;
  a->capture = *capture;
  a->o = cf_capture_observations(*capture);
  a->images = cf_capture_image_count(*capture);
  a->pred = malloc(3 * a->o->count * sizeof *a->pred);
  a->first = malloc(a->images * sizeof *a->first);
  a->last = calloc(a->images, sizeof *a->last);
  if (!a->pred || !a->first || !a->last) return 0;
  cf_fit_options opt;
  cf_fit_default_options(&opt, fit->result.model);
  opt.footprint = fit->footprint;
  opt.footprint_tolerance = fit->footprint_tolerance;
  if (cf_fit_predict(*capture, &fit->result, &opt, a->pred, NULL, &err) != CF_OK)
    return fprintf(stderr, "%s\n", err.message), 0;
  for (size_t k = 0; k < a->images; ++k) a->first[k] = a->o->count;
  for (size_t i = 0; i < a->o->count; ++i) {
    uint32_t k = a->o->image[i];
    if (a->first[k] == a->o->count) a->first[k] = i;
    a->last[k] = i + 1;
  }
  return 1;
}

/* Σσ²(y)/Σy² over every uncensored residual, in the cores and out. */
static void noise_floor(const all *a, const set *s, const double na[3], const double ns[3]) {
  sums all_s = {0, 0}, core = {0, 0}, rest = {0, 0}, fit_all = {0, 0}, fit_core = {0, 0},
       fit_rest = {0, 0};
  for (size_t k = 0; k < s->count; ++k) {
    const image_data *d = &s->img[k];
    for (size_t i = a->first[k]; i < a->last[k]; ++i) {
      int x = (int)a->o->pixel[2 * i], y = (int)a->o->pixel[2 * i + 1];
      int in = is_core(d, x, y, CORE_R);
      for (int c = 0; c < 3; ++c) {
        double yv = a->o->rgb[3 * i + c], mu = a->pred[3 * i + c];
        if ((a->o->flags[i] >> c & 1u) && mu >= yv) continue;
        double var = na[c] + ns[c] * yv;
        all_s.e2 += var, all_s.y2 += yv * yv;
        fit_all.e2 += (mu - yv) * (mu - yv), fit_all.y2 += yv * yv;
        sums *t = in ? &core : &rest, *u = in ? &fit_core : &fit_rest;
        t->e2 += var, t->y2 += yv * yv;
        u->e2 += (mu - yv) * (mu - yv), u->y2 += yv * yv;
      }
    }
  }
  printf(
      "noise floor (sigma^2 = a + b y from the photos, summed over the fit's residuals):\n"
      "  all %.3f %%   without cores %.3f %%   cores %.3f %%\n"
      "the fit, every observation: all %.3f %%   without cores %.3f %%   cores %.3f %%\n",
      100 * sqrt(all_s.e2 / all_s.y2), 100 * sqrt(rest.e2 / rest.y2), 100 * sqrt(core.e2 / core.y2),
      100 * sqrt(fit_all.e2 / fit_all.y2), 100 * sqrt(fit_rest.e2 / fit_rest.y2),
      100 * sqrt(fit_core.e2 / fit_core.y2));
}

/* Two lights close in direction: D = y1 − y2 p1/p2 (the shading change
 * from the prediction), its local quadratic residual variance against
 * σ²(y1) + (p1/p2)² σ²(y2). */
static void close_pairs(const all *a, const set *s, const double na[3], const double ns[3],
                        double m[WIN * WIN][WIN * WIN]) {
  const cf_observations *o = a->o;
  printf(
      "pairs of lights closer than 5.5 deg: measured / predicted variance of their difference\n");
  for (size_t i = 0; i < s->count; ++i)
    for (size_t j = i + 1; j < s->count; ++j) {
      const double *li = o->light_dir + 3 * (size_t)o->lights * a->first[i];
      const double *lj = o->light_dir + 3 * (size_t)o->lights * a->first[j];
      double cosang = li[0] * lj[0] + li[1] * lj[1] + li[2] * lj[2];
      if (cosang < cos(5.5 * 3.14159265358979 / 180.0)) continue;
      const image_data *d1 = &s->img[i], *d2 = &s->img[j];
      image_data diff = *d1;
      size_t n = (size_t)d1->w * (size_t)d1->h;
      float *f = malloc(n * sizeof *f);
      double meas = 0, pred = 0, y2 = 0;
      size_t cnt = 0;
      for (int c = 0; c < 3 && f; ++c) {
        for (size_t q = 0; q < n; ++q) {
          double ratio = d1->p[c][q] / d2->p[c][q];
          f[q] = isnan(d1->y[c][q]) || isnan(d2->y[c][q]) || d2->clip[q] ||
                         !(d1->p[c][q] > 0.01 && d2->p[c][q] > 0.01) /* lit in both */
                     ? NAN
                     : (float)(d1->y[c][q] - d2->y[c][q] * ratio);
        }
        for (int y = 0; y < d1->h; ++y)
          for (int x = 0; x < d1->w; ++x) {
            size_t q = (size_t)y * (size_t)d1->w + (size_t)x;
            if (isnan(f[q]) || is_core(d1, x, y, 8.0) || is_core(d2, x, y, 8.0)) continue;
            double v = window_variance(&diff, f, x, y, m);
            if (v < 0) continue;
            double r = d1->p[c][q] / d2->p[c][q];
            meas += v;
            pred += na[c] + ns[c] * d1->y[c][q] + r * r * (na[c] + ns[c] * d2->y[c][q]);
            y2 += d1->y[c][q] * d1->y[c][q];
            ++cnt;
          }
      }
      free(f);
      if (cnt)
        printf(
            "  images %zu & %zu (%.2f deg): %zu windows, measured/predicted %.3f, relative "
            "noise of one image %.3f %%\n",
            i + 1, j + 1, acos(fmin(1, cosang)) * 180 / 3.14159265358979, cnt, meas / pred,
            100 * sqrt(meas / 2 / y2));
    }
}

/* The prediction at (x − dx, y − dy), bilinear; NaN off the observations. */
static double shifted(const image_data *d, int c, int x, int y, double dx, double dy) {
  double u = x - dx, v = y - dy;
  int x0 = (int)floor(u), y0 = (int)floor(v);
  double fx = u - x0, fy = v - y0, sum = 0.0;
  for (int j = 0; j < 4; ++j) {
    int xx = x0 + (j & 1), yy = y0 + (j >> 1);
    if (xx < 0 || yy < 0 || xx >= d->w || yy >= d->h) return NAN;
    double f = d->p[c][(size_t)yy * (size_t)d->w + (size_t)xx];
    sum += ((j & 1) ? fx : 1 - fx) * ((j >> 1) ? fy : 1 - fy) * f;
  }
  return sum;
}

/* The prediction shifted by (dx, dy) and scaled by g, where the shift
 * stays inside the image (else the prediction, scaled). */
typedef struct shift {
  double dx, dy, g;
} shift;

static double shifted_scaled(const image_data *d, int c, int x, int y, const void *user) {
  const shift *t = user;
  double mu = shifted(d, c, x, y, t->dx, t->dy);
  if (isnan(mu)) mu = d->p[c][(size_t)y * (size_t)d->w + (size_t)x];
  return mu * t->g;
}

/* Core (r ≤ CORE_R) and ring sums of image d's prediction shifted by
 * (dx, dy) and scaled by g. */
static void shift_error(const image_data *d, double dx, double dy, double g, sums *core,
                        sums *ring) {
  shift t = {dx, dy, g};
  window_error(d, shifted_scaled, &t, core, ring);
}

/* Per image, the sub-pixel shift of the prediction that minimises its
 * core's error (a light direction off by a fraction of a degree moves
 * the highlight by a fraction of a pixel). */
static void shift_test(const set *s) {
  sums c0 = {0, 0}, r0 = {0, 0}, c1 = {0, 0}, r1 = {0, 0}, cg = {0, 0}, cgs = {0, 0};
  double shifts[1024];
  size_t n = 0;
  for (size_t i = 0; i < s->count; ++i) {
    const image_data *d = &s->img[i];
    double best = HUGE_VAL, bx = 0, by = 0;
    for (double dy = -1.5; dy <= 1.501; dy += 0.1)
      for (double dx = -1.5; dx <= 1.501; dx += 0.1) {
        sums c = {0, 0}, r = {0, 0};
        shift_error(d, dx, dy, 1.0, &c, &r);
        if (c.e2 < best) best = c.e2, bx = dx, by = dy;
      }
    shift_error(d, 0, 0, 1.0, &c0, &r0);
    shift_error(d, bx, by, 1.0, &c1, &r1);
    for (int with_shift = 0; with_shift < 2; ++with_shift) { /* a gain on the core */
      double bestg = HUGE_VAL, gg = 1.0;
      for (double g = 0.5; g <= 2.0; g *= 1.01) {
        sums c = {0, 0}, r = {0, 0};
        shift_error(d, with_shift ? bx : 0, with_shift ? by : 0, g, &c, &r);
        if (c.e2 < bestg) bestg = c.e2, gg = g;
      }
      sums r = {0, 0};
      shift_error(d, with_shift ? bx : 0, with_shift ? by : 0, gg, with_shift ? &cgs : &cg, &r);
    }
    if (n < 1024) shifts[n++] = hypot(bx, by);
  }
  double mean = 0;
  for (size_t i = 0; i < n; ++i) mean += shifts[i];
  printf(
      "shift test (each image's prediction moved by the sub-pixel shift that best fits its "
      "core):\n  core %.2f %% -> %.2f %%;  ring %.2f %% -> %.2f %%;  mean |shift| %.2f px\n",
      100 * sqrt(c0.e2 / c0.y2), 100 * sqrt(c1.e2 / c1.y2), 100 * sqrt(r0.e2 / r0.y2),
      100 * sqrt(r1.e2 / r1.y2), mean / (double)n);
  printf("  a gain on each core: %.2f %%; a shift and a gain: %.2f %%\n", 100 * sqrt(cg.e2 / cg.y2),
         100 * sqrt(cgs.e2 / cgs.y2));
}

/* Image k's core as a grid: photo / prediction (channel sum, in units of
 * the prediction's peak). */
static void core_grid(const set *s, size_t k) {
  const image_data *d = &s->img[k];
  double peak = 0.0;
  for (int y = d->by - 4; y <= d->by + 4; ++y)
    for (int x = d->bx - 4; x <= d->bx + 4; ++x) {
      size_t q = (size_t)y * (size_t)d->w + (size_t)x;
      double v = d->p[0][q] + d->p[1][q] + d->p[2][q];
      if (v > peak) peak = v;
    }
  printf(
      "image %zu around (%d, %d): photo | prediction, in units of the predicted peak (* clipped)\n",
      k + 1, d->bx, d->by);
  for (int y = d->by - 4; y <= d->by + 4; ++y) {
    printf("  ");
    for (int x = d->bx - 4; x <= d->bx + 4; ++x) {
      size_t q = (size_t)y * (size_t)d->w + (size_t)x;
      printf("%5.2f%c", (d->y[0][q] + d->y[1][q] + d->y[2][q]) / peak, d->clip[q] ? '*' : ' ');
    }
    printf(" | ");
    for (int x = d->bx - 4; x <= d->bx + 4; ++x) {
      size_t q = (size_t)y * (size_t)d->w + (size_t)x;
      printf("%5.2f ", (d->p[0][q] + d->p[1][q] + d->p[2][q]) / peak);
    }
    printf("\n");
  }
}

/* Where in the core the error is: per radius, the share of the core's
 * squared error and the relative error there. */
static void core_radii(const set *s) {
  double e2[5] = {0}, y2[5] = {0}, tot = 0, cnt[5] = {0}, sgn[5] = {0}, grey = 0, colour = 0;
  for (size_t i = 0; i < s->count; ++i) {
    const image_data *d = &s->img[i];
    for (int y = d->by - CORE_R; y <= d->by + CORE_R; ++y)
      for (int x = d->bx - CORE_R; x <= d->bx + CORE_R; ++x) {
        size_t q = (size_t)y * (size_t)d->w + (size_t)x;
        if (!is_core(d, x, y, CORE_R) || isnan(d->y[0][q])) continue;
        int b = (int)floor(hypot(x - d->bx, y - d->by) + 0.5);
        for (int c = 0; c < 3; ++c) {
          double mu = d->p[c][q], yv = d->y[c][q];
          if ((d->clip[q] >> c & 1u) && mu >= yv) continue;
          e2[b] += (mu - yv) * (mu - yv), y2[b] += yv * yv, tot += (mu - yv) * (mu - yv);
          sgn[b] += mu - yv, cnt[b] += 1;
        }
        if (d->clip[q]) continue; /* the colour split needs all three channels */
        double mean = 0.0;
        for (int c = 0; c < 3; ++c) mean += (d->p[c][q] - d->y[c][q]) / 3.0;
        for (int c = 0; c < 3; ++c) {
          double e = d->p[c][q] - d->y[c][q];
          grey += mean * mean, colour += (e - mean) * (e - mean);
        }
      }
  }
  printf(
      "the core's error by distance from the brightest pixel:\n  r(px)  share of the core's "
      "squared error  relative RMSE  mean (pred - obs)/rms(obs)\n");
  for (int b = 0; b <= CORE_R; ++b)
    printf("  %d      %5.1f %%   %6.2f %%   %+.3f\n", b, 100 * e2[b] / tot,
           100 * sqrt(e2[b] / y2[b]), sgn[b] / cnt[b] / sqrt(y2[b] / cnt[b]));
  printf(
      "  of the unclipped core pixels' squared error: %.1f %% grey (the channels' mean), %.1f %% "
      "colour (each channel's departure from it)\n",
      100 * grey / (grey + colour), 100 * colour / (grey + colour));
}

/* The best radial reshaping of the prediction: per 0.5-px ring around
 * the brightest pixel, the least-squares factor Σ y p / Σ p² from the odd
 * images, applied to the even ones (what any lobe shape could do if it
 * changed every image's core alike); and the light in the ring by
 * direction in the image (a star-shaped flare would show the same spikes
 * in every image). */
static void radial_and_star(const set *s) {
  enum { RB = 2 * RING_R + 2, AB = 16 };
  double yp[RB] = {0}, pp[RB] = {0}, ang_y[AB] = {0}, ang_p[AB] = {0};
  for (int pass = 0; pass < 2; ++pass) {
    sums before = {0, 0}, after = {0, 0};
    for (size_t i = (size_t)(1 - pass); i < s->count; i += 2) {
      const image_data *d = &s->img[i];
      for (int y = d->by - CORE_R; y <= d->by + CORE_R; ++y)
        for (int x = d->bx - CORE_R; x <= d->bx + CORE_R; ++x) {
          size_t q = (size_t)y * (size_t)d->w + (size_t)x;
          if (!is_core(d, x, y, CORE_R) || isnan(d->y[0][q])) continue;
          int b = (int)floor(2.0 * hypot(x - d->bx, y - d->by));
          for (int c = 0; c < 3; ++c) {
            double mu = d->p[c][q], yv = d->y[c][q];
            if (pass == 0) {
              if (d->clip[q] >> c & 1u) continue;
              yp[b] += yv * mu, pp[b] += mu * mu;
              continue;
            }
            double mu2 = pp[b] > 0 ? mu * yp[b] / pp[b] : mu;
            if (!((d->clip[q] >> c & 1u) && mu >= yv))
              before.e2 += (mu - yv) * (mu - yv), before.y2 += yv * yv;
            if (!((d->clip[q] >> c & 1u) && mu2 >= yv))
              after.e2 += (mu2 - yv) * (mu2 - yv), after.y2 += yv * yv;
          }
        }
    }
    if (pass == 1)
      printf(
          "best radial reshaping of the core (fitted on the odd images, on the even): %.2f %% -> "
          "%.2f %%\n",
          100 * sqrt(before.e2 / before.y2), 100 * sqrt(after.e2 / after.y2));
  }
  for (size_t i = 0; i < s->count; ++i) {
    const image_data *d = &s->img[i];
    for (int y = d->by - RING_R; y <= d->by + RING_R; ++y)
      for (int x = d->bx - RING_R; x <= d->bx + RING_R; ++x) {
        double r = hypot(x - d->bx, y - d->by);
        size_t q = (size_t)y * (size_t)d->w + (size_t)x;
        if (r <= 4.0 || r > RING_R || isnan(d->y[0][q])) continue;
        int a = (int)floor((atan2(y - d->by, x - d->bx) / (2 * 3.14159265358979) + 0.5) * AB) % AB;
        for (int c = 0; c < 3; ++c) ang_y[a] += d->y[c][q], ang_p[a] += d->p[c][q];
      }
  }
  printf(
      "the ring 4-12 px by direction in the image, 16 sectors from -x (180 deg) through -y "
      "(up), +x, +y (down), photo / prediction:\n ");
  for (int a = 0; a < AB; ++a) printf(" %.3f", ang_y[a] / ang_p[a]);
  printf("\n");
}

static void psf_test(set *s, int streak) {
  double *kernel = malloc((2 * KERNEL_R + 1) * (2 * KERNEL_R + 1) * sizeof *kernel);
  if (!kernel) return;
  sums c0, r0, c1, r1;
  psf_cost(s, 0, NULL, kernel, &c0, &r0);
  psf best = psf_fit(s, kernel, streak);
  if (streak) printf("(the halo along the rows only: a horizontal streak)\n");
  psf_cost(s, 0, &best, kernel, &c1, &r1);
  printf(
      "PSF test (a fraction w of the light spread as (1 + r^2/r0^2)^-beta within %d px), "
      "fitted on the odd images, on the even:\n  w %.4f  r0 %.3f px  beta %.3f\n"
      "  core (r <= %d px): %.2f %% -> %.2f %%;  ring (%d < r <= %d px): %.2f %% -> %.2f %%\n",
      KERNEL_R, best.w, best.r0, best.beta, CORE_R, 100 * sqrt(c0.e2 / c0.y2),
      100 * sqrt(c1.e2 / c1.y2), CORE_R, RING_R, 100 * sqrt(r0.e2 / r0.y2),
      100 * sqrt(r1.e2 / r1.y2));
  psf_cost(s, 1, NULL, kernel, &c0, &r0);
  psf_cost(s, 1, &best, kernel, &c1, &r1);
  printf(
      "  (on the odd images it was fitted on: core %.2f %% -> %.2f %%; ring %.2f %% -> %.2f %%)\n",
      100 * sqrt(c0.e2 / c0.y2), 100 * sqrt(c1.e2 / c1.y2), 100 * sqrt(r0.e2 / r0.y2),
      100 * sqrt(r1.e2 / r1.y2));
  free(kernel);
}

int main(int argc, char **argv) {
  if (argc != 2) return fprintf(stderr, "usage: clayfit_cores FIT.json\n"), 2;
  cf_capture *capture = NULL;
  cf_fit_file fit;
  memset(&fit, 0, sizeof fit);
  all a = {0};
  if (!load(argv[1], &capture, &fit, &a)) return 1;
  set s = {calloc(a.images, sizeof(image_data)), a.images};
  static double m[WIN * WIN][WIN * WIN];
  residual_projector(m);
  noise_bins b;
  memset(&b, 0, sizeof b);
  b.lo = -4.0, b.hi = 0.0;
  for (size_t k = 0; k < a.images; ++k) {
    if (!image_fill(&a, k, &s.img[k])) return fprintf(stderr, "out of memory\n"), 1;
    noise_collect(&s.img[k], m, &b);
  }
  double na[3], ns[3];
  noise_model(&b, na, ns);
  printf(
      "noise model from 5x5 local quadratic fits (smooth regions, > 8 px from the highlight):\n");
  for (int c = 0; c < 3; ++c)
    printf("  channel %d: sigma^2 = %.4g + %.4g y  (sigma at y = 0.01: %.3g, at 0.1: %.3g)\n", c,
           na[c], ns[c], sqrt(na[c] + ns[c] * 0.01), sqrt(na[c] + ns[c] * 0.1));
  printf("  bins (channel 1): level  sigma  windows\n");
  for (int k = 0; k < BINS; ++k)
    if (b.count[1][k] >= 50)
      printf("    %.4g  %.4g  %.0f\n", b.level[1][k] / b.count[1][k],
             sqrt(b.var[1][k] / b.count[1][k]), b.count[1][k]);
  noise_floor(&a, &s, na, ns);
  silhouette_edge(&a);
  close_pairs(&a, &s, na, ns, m);
  profile(&s);
  core_radii(&s);
  core_grid(&s, 0);
  core_grid(&s, 40);
  shift_test(&s);
  radial_and_star(&s);
  psf_test(&s, 0);
  psf_test(&s, 1);
  for (size_t k = 0; k < a.images; ++k) image_free(&s.img[k]);
  free(s.img);
  free(a.pred), free(a.first), free(a.last);
  cf_fit_file_free(&fit);
  cf_capture_free(capture);
  return 0;
}
