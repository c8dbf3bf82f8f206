/* The highlight cores (bench/cores.c says what the program measures): the
 * radial profiles of the prediction and the photo through each core, the
 * shift test, and the point-spread-function test (the prediction
 * convolved with a narrow core plus a power-law halo, fitted on the odd
 * images, tested on the even ones). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cores.h"

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

void profile(const set *s) {
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
void shift_test(const set *s) {
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
void core_grid(const set *s, size_t k) {
  if (k >= s->count) return; /* a capture of fewer images (the demo has 16) */
  const image_data *d = &s->img[k];
  if (d->bx < 4 || d->by < 4 || d->bx + 4 >= d->w || d->by + 4 >= d->h) return;
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
void core_radii(const set *s) {
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
void radial_and_star(const set *s) {
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

void psf_test(set *s, int streak) {
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
