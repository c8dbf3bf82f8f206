/* The fit's uncertainty (fit_uncertainty.h, private to src/fit):
 *   - the tiles' sandwich covariance (fit_tile_covariance): its scores
 *     g_t = Σ_{i in tile t} ψ_i ∂μ_i/∂x come from the problem's analytic
 *     Jacobian (fit_problem_group_scores), checked against central
 *     differences of fit_problem_predict with ψ formed as the normal
 *     equations weigh a residual, on M2 with every slot, the scale, the
 *     exposures and a response curve free, sample weights, a Huber or
 *     Cauchy loss with residuals beyond it and clipped channels (censored
 *     and not): with A⁻¹ = I on entry the sandwich is B = Σ g gᵀ itself,
 *     and each entry must agree to 1e-6 of √(B_aa B_bb). A missing sign,
 *     ρ', weight or chain factor in the analytic scores shows here (it
 *     moves every JPEG sd);
 *   - the covariance of the free unknowns (fit_free_covariance) of a
 *     normal matrix whose columns differ in scale by 1e20 but are far from
 *     collinear: not rank deficient, and its inverse exact (judged on the
 *     unscaled matrix, it was "rank deficient", and a noise-free fit with
 *     a response curve held its diffuse roughness); two collinear columns
 *     are still rank deficient. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/model.h"
#include "problem/problem.h"
#include "fit_support.h"
#include "fit_uncertainty.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { TILE_PX = 4 };

/* Observation i's tile number (its image and TILE_PX square), as a key. */
static size_t tile_key(const fit_problem *p, size_t i) {
  size_t o = fit_rows_observation(&p->rows, i);
  size_t x = (size_t)(p->obs->pixel[2 * o] / TILE_PX),
         y = (size_t)(p->obs->pixel[2 * o + 1] / TILE_PX);
  return ((size_t)p->rows.image[i] * 4096 + y) * 4096 + x;
}

/* Each observation's tile numbered 0 .. tiles − 1 (by a quadratic search:
 * the capture is small). */
static size_t number_tiles(const fit_problem *p, size_t *tile) {
  size_t tiles = 0;
  size_t *keys = malloc(p->rows.count * sizeof *keys);
  for (size_t i = 0; keys && i < p->rows.count; ++i) {
    size_t key = tile_key(p, i), t = 0;
    while (t < tiles && keys[t] != key) ++t;
    if (t == tiles) keys[tiles++] = key;
    tile[i] = t;
  }
  free(keys);
  return tiles;
}

/* ψ of every residual at the current values (fit_problem.h): w ρ'(e²) e
 * slope / σ, e = (y − μ)/σ, a clipped channel's from the censored
 * likelihood. */
static void score_parts(const fit_problem *p, const double *mu, const double *y, double *psi) {
  for (size_t i = 0; i < 3 * p->rows.count; ++i) {
    const fit_rows *r = &p->rows;
    double e = (y[i] - mu[i]) * r->inv_sigma[i], slope = 1.0;
    double w = r->sample_root ? r->sample_root[i / 3] * r->sample_root[i / 3] : 1.0;
    if (r->flags[i / 3] >> (i % 3) & 1u) e = -fit_censored_residual(-e, &slope);
    psi[i] =
        slope == 0.0 ? 0.0 : w * fit_problem_loss_weight(p, e * e) * e * slope * r->inv_sigma[i];
  }
}

/* B = Σ_t g_t g_tᵀ with g_t from central differences of the prediction. */
static void reference_meat(fit_problem *p, const size_t *tile, size_t tiles, double *b) {
  size_t m = (size_t)p->unknowns.num, n = 3 * p->rows.count;
  double *x = malloc(m * sizeof *x), *moved = malloc(m * sizeof *moved);
  double *mu = malloc(n * sizeof *mu), *y = malloc(n * sizeof *y), *psi = malloc(n * sizeof *psi);
  double *up = malloc(n * sizeof *up), *down = malloc(n * sizeof *down);
  double *g = calloc(tiles * m, sizeof *g);
  cf_error err = {0};
  if (!x || !moved || !mu || !y || !psi || !up || !down || !g) {
    CHECK(0, "out of memory");
    goto done;
  }
  fit_problem_get_x(p, x);
  CHECK(fit_problem_predict(p, mu, y, &err) == CF_OK, "%s", err.message);
  score_parts(p, mu, y, psi);
  for (size_t u = 0; u < m; ++u) {
    double h = 1e-5 * fmax(1.0, fabs(x[u]));
    memcpy(moved, x, m * sizeof *x);
    moved[u] = x[u] + h;
    fit_problem_set_x(p, moved);
    fit_problem_predict(p, up, y, &err);
    moved[u] = x[u] - h;
    fit_problem_set_x(p, moved);
    fit_problem_predict(p, down, y, &err);
    for (size_t i = 0; i < n; ++i) g[tile[i / 3] * m + u] += psi[i] * (up[i] - down[i]) / (2.0 * h);
  }
  fit_problem_set_x(p, x);
  for (size_t t = 0; t < tiles; ++t)
    for (size_t a = 0; a < m; ++a)
      for (size_t c = 0; c < m; ++c) b[a * m + c] += g[t * m + a] * g[t * m + c];
done:
  free(x);
  free(moved);
  free(mu);
  free(y);
  free(psi);
  free(up);
  free(down);
  free(g);
}

/* Every other observation weighed 0.5 .. 2, a quarter of the rows' red
 * marked clipped, M2 with everything free a little off its values. */
static void setup(fit_problem *p) {
  double *weight = malloc(p->rows.count * sizeof *weight);
  cf_error err = {0};
  for (size_t i = 0; weight && i < p->rows.count; ++i) weight[i] = 0.5 + 1.5 * (double)(i % 7) / 6.0;
  CHECK(weight && fit_problem_set_sample_weights(p, weight, &err) == CF_OK, "weights: %s",
        err.message);
  free(weight);
  fit_problem_set_sigma(p, 1.0);
  for (size_t i = 0; i < p->rows.count; i += 4) p->rows.flags[i] |= 1u;
  const double slopes[CF_RESPONSE_MODEL_KNOTS] = {0.8, 0.7, 0.9, 1.1, 1.3, 1.2};
  memcpy(p->values.response, slopes, sizeof slopes);
  fit_problem_clear_unknowns(p);
  for (int k = 0; k < p->dim; ++k) fit_problem_free_slot(p, k);
  fit_problem_free_scale(p);
  fit_problem_free_exposures(p);
  fit_problem_free_response(p);
  CHECK(fit_problem_finish(p, &err) == CF_OK, "finish: %s", err.message);
  double x[64];
  fit_problem_get_x(p, x);
  for (int u = 0; u < p->unknowns.num; ++u) x[u] += 0.01 * (u % 5 - 2); /* inside the bounds */
  fit_problem_set_x(p, x);
}

static void test_scores(const cf_capture *capture, cf_loss loss, const char *what) {
  fit_problem *p;
  cf_error err = {0};
  if (fit_problem_new(&p, capture, CF_MODEL_DIELECTRIC, NULL, 0, 1, &err) != CF_OK) {
    CHECK(0, "init: %s", err.message);
    return;
  }
  fit_problem_set_loss(p, loss, 1.0);
  setup(p);
  size_t m = (size_t)p->unknowns.num, *tile = malloc(p->rows.count * sizeof *tile);
  double *b = calloc(m * m, sizeof *b), *ref = calloc(m * m, sizeof *ref);
  if (!tile || !b || !ref || m > 64) {
    CHECK(0, "out of memory (or %zu unknowns)", m);
    goto done;
  }
  size_t tiles = number_tiles(p, tile);
  for (size_t a = 0; a < m; ++a) b[a * m + a] = 1.0; /* A⁻¹ = I: the sandwich is B */
  int applied = 0;
  CHECK(fit_tile_covariance(p, TILE_PX, b, &applied, &err) == CF_OK, "%s: %s", what, err.message);
  CHECK(applied, "%s: the sandwich not applied (%zu tiles, %zu unknowns)", what, tiles, m);
  reference_meat(p, tile, tiles, ref);
  size_t beyond = 0, clipped = 0;
  double *mu = malloc(3 * p->rows.count * sizeof *mu), *y = malloc(3 * p->rows.count * sizeof *y);
  if (mu && y && fit_problem_predict(p, mu, y, &err) == CF_OK)
    for (size_t i = 0; i < 3 * p->rows.count; ++i) {
      beyond += fabs(mu[i] - y[i]) * p->rows.inv_sigma[i] > p->loss_scale;
      clipped += (p->rows.flags[i / 3] & 1u) && i % 3 == 0 && mu[i] < y[i];
    }
  free(mu);
  free(y);
  CHECK(loss == CF_LOSS_NONE || beyond > 100, "%s: %zu residuals beyond the loss", what, beyond);
  CHECK(clipped > 10, "%s: %zu clipped channels below their clip level", what, clipped);
  double worst = 0.0;
  size_t wa = 0, wc = 0;
  for (size_t a = 0; a < m; ++a)
    for (size_t c = 0; c < m; ++c) {
      /* (a response knot no observation reaches has a score of 0) */
      double size = fmax(sqrt(ref[a * m + a] * ref[c * m + c]), 1e-300);
      double off = fabs(b[a * m + c] - ref[a * m + c]) / size;
      if (!(off <= worst)) worst = off, wa = a, wc = c;
    }
  CHECK(worst < 1e-6, "%s: B[%zu][%zu] %.9g, by differences %.9g (unknowns of kinds %s, %s)", what,
        wa, wc, b[wa * m + wc], ref[wa * m + wc], p->unknowns.unknown[wa].kind->name,
        p->unknowns.unknown[wc].kind->name);
  printf(
      "%s: %zu unknowns, %zu tiles, %zu residuals beyond the loss: B's worst relative "
      "difference %.2g\n",
      what, m, tiles, beyond, worst);
done:
  free(tile);
  free(b);
  free(ref);
  fit_problem_free(p);
}

/* A = D C D with C = (1 − r) I + r 11ᵀ (unit diagonal, C⁻¹ = (I − r/(1 +
 * (m − 1) r) 11ᵀ)/(1 − r)) and D from 1e-10 to 1e10: the covariance is
 * D⁻¹ C⁻¹ D⁻¹. Then columns 0 and 1 made equal: rank deficient. */
static void test_free_covariance(const cf_capture *capture) {
  fit_problem *p;
  cf_error err = {0};
  if (fit_problem_new(&p, capture, CF_MODEL_DIELECTRIC, NULL, 0, 1, &err) != CF_OK) {
    CHECK(0, "init: %s", err.message);
    return;
  }
  setup(p);
  size_t m = (size_t)p->unknowns.num;
  double *a = malloc(m * m * sizeof *a), *cov = malloc(m * m * sizeof *cov);
  double *d = malloc(m * sizeof *d), r = 0.3, worst = 0.0;
  if (!a || !cov || !d || m < 3) {
    CHECK(0, "out of memory (or %zu unknowns)", m);
    goto done;
  }
  for (size_t i = 0; i < m; ++i) d[i] = pow(10.0, -10.0 + 20.0 * (double)i / (double)(m - 1));
  for (size_t i = 0; i < m; ++i)
    for (size_t j = 0; j < m; ++j) a[i * m + j] = d[i] * d[j] * (i == j ? 1.0 : r);
  int deficient = -1;
  CHECK(fit_free_covariance(p, a, cov, &deficient, &err) == CF_OK, "%s", err.message);
  CHECK(deficient == 0, "columns of scales 1e-10 to 1e10, correlation %.1f: rank deficient", r);
  for (size_t i = 0; deficient == 0 && i < m; ++i)
    for (size_t j = 0; j < m; ++j) {
      double inverse = ((i == j ? 1.0 : 0.0) - r / (1.0 + (double)(m - 1) * r)) / (1.0 - r);
      worst = fmax(worst, fabs(cov[i * m + j] * d[i] * d[j] - inverse));
    }
  CHECK(worst < 1e-9, "the covariance off by %g (at a unit diagonal)", worst);
  for (size_t j = 0; j < m; ++j) a[0 * m + j] = a[1 * m + j] * d[0] / d[1]; /* column 0 ∝ 1 */
  for (size_t i = 0; i < m; ++i) a[i * m + 0] = a[i * m + 1] * d[0] / d[1];
  CHECK(fit_free_covariance(p, a, cov, &deficient, &err) == CF_OK, "%s", err.message);
  CHECK(deficient == 1, "two collinear columns: not flagged rank deficient");
done:
  free(a);
  free(cov);
  free(d);
  fit_problem_free(p);
}

int main(void) {
  char dir[64];
  if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  double params[CF_MAX_DIM] = {0.6, 0.4, 0.3, 0.3, 0.3, 0.05};
  cf_synth_options o;
  fit_test_synth_options(&o, CF_MODEL_DIELECTRIC, params);
  o.images = 4;
  o.width = 80;
  o.height = 60;
  o.focal_px = 100.0;
  cf_capture *capture = fit_test_capture(dir, "m2", &o);
  if (capture) {
    test_scores(capture, CF_LOSS_NONE, "no loss");
    test_scores(capture, CF_LOSS_HUBER, "Huber");
    test_scores(capture, CF_LOSS_CAUCHY, "Cauchy");
    test_free_covariance(capture);
    cf_capture_free(capture);
  }
  fit_test_remove_dir(dir);
  return check_finish("test_fit_uncertainty");
}
