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
#include "cores.h"

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

int is_core(const image_data *d, int x, int y, double r) {
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
