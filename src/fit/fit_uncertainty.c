/* The uncertainty of a fit (fit_uncertainty.h). */
#include "fit_uncertainty.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fit_plan.h"
#include "lsq/linalg.h"

/* A model slot's standard deviation from its unknown's variance:
 * dρ = ρ d log ρ; dσ = dσ² / (2σ), and at σ = 0, where σ = √σ² is not
 * differentiable, the half-width √sd(σ²) (σ² <= sd(σ²) within one sd). */
double fit_slot_sd(const fit_problem *p, int slot, double variance) {
  double sd = sqrt(fmax(0.0, variance)), x = fit_problem_read_values(p)->params[slot];
  fit_slot_form form = fit_slot_form_of(fit_problem_model(p), slot);
  if (form == FIT_SLOT_LOG) return x * sd;
  if (form == FIT_SLOT_SQUARE) return x > 0.5 * sqrt(sd) ? sd / (2.0 * x) : sqrt(sd);
  return sd;
}

/* Unknown u: one of the model's slots, not at a bound? */
static int free_material(const fit_problem *p, int u) {
  return fit_problem_unknown(p, u).kind == &fit_kind_material && !fit_problem_read_at_bound(p)[u];
}

/* The model slots' block of JᵀJ, each column scaled to its range's width
 * (∂/∂ρ = ∂/∂log ρ / ρ). */
static int scaled_model_block(const fit_problem *p, const double *jtj, int *slots, double *h) {
  int n = fit_problem_unknown_count(p), m = 0;
  int map[CF_MAX_DIM];
  double width[CF_MAX_DIM];
  const double *params = fit_problem_read_values(p)->params;
  cf_model_id model = fit_problem_model(p);
  for (int u = 0; u < n && m < CF_MAX_DIM; ++u) {
    if (!free_material(p, u)) continue;
    int slot = fit_problem_unknown(p, u).slot;
    map[m] = u;
    slots[m] = slot;
    width[m] = fit_slot_form_of(model, slot) == FIT_SLOT_LOG
                   ? fit_slot_width(model, slot) / params[slot]
                   : fit_problem_upper(p, u) - fit_problem_lower(p, u);
    ++m;
  }
  for (int a = 0; a < m; ++a)
    for (int c = 0; c < m; ++c) h[a * m + c] = jtj[map[a] * n + map[c]] * width[a] * width[c];
  return m;
}

/* The covariance of the unknowns not at a bound (those at one are held
 * there: their rows and columns are 0), from their block of JᵀJ scaled to
 * a unit diagonal (Jacobi), so that the rank test (cf_lsq_covariance:
 * eigenvalues within 1e-12 of the largest) sees collinear columns, not
 * columns of different scales: the response's prior is in its own units
 * and the data in σ's, and a noise-free EXR capture's σ (5e-9) put 1e20
 * between the two (a slope that only the prior holds looked singular, and
 * the fit held the diffuse roughness as "not constrained"). */
cf_status fit_free_covariance(const fit_problem *p, const double *jtj, double *covariance,
                              int *rank_deficient, cf_error *err) {
  int n = fit_problem_unknown_count(p), m = 0;
  const int *at_bound = fit_problem_read_at_bound(p);
  int *map = malloc((size_t)n * sizeof *map);
  double *sub = malloc((size_t)n * (size_t)n * sizeof *sub);
  double *sub_covariance = malloc((size_t)n * (size_t)n * sizeof *sub_covariance);
  double *unit = malloc((size_t)n * sizeof *unit);
  cf_status s =
      map && sub && sub_covariance && unit ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
  for (int u = 0; s == CF_OK && u < n; ++u)
    if (!at_bound[u]) map[m++] = u;
  for (int a = 0; s == CF_OK && a < m; ++a) { /* (a column of 0 stays, and is singular) */
    double d = jtj[map[a] * n + map[a]];
    unit[a] = d > 0.0 && isfinite(d) ? 1.0 / sqrt(d) : 1.0;
  }
  for (int a = 0; s == CF_OK && a < m; ++a)
    for (int b = 0; b < m; ++b) sub[a * m + b] = jtj[map[a] * n + map[b]] * unit[a] * unit[b];
  *rank_deficient = 0;
  if (s == CF_OK && m > 0) s = cf_lsq_covariance(m, sub, sub_covariance, rank_deficient, err);
  if (s == CF_OK) {
    memset(covariance, 0, (size_t)n * (size_t)n * sizeof *covariance);
    for (int a = 0; !*rank_deficient && a < m; ++a)
      for (int b = 0; b < m; ++b)
        covariance[map[a] * n + map[b]] = sub_covariance[a * m + b] * unit[a] * unit[b];
  }
  free(map);
  free(sub);
  free(sub_covariance);
  free(unit);
  return s;
}

cf_status fit_sample_covariance(fit_problem *p, int threads, double *covariance, cf_error *err) {
  if (!fit_problem_sample_roots(p)) return CF_OK;
  size_t n = (size_t)fit_problem_unknown_count(p);
  double *b = malloc((n ? n * n : 1) * sizeof *b);
  cf_status s = b ? fit_sample_information(p, threads, b, err) /* B = Σ w² JᵀJ */
                  : cf_error_set(err, CF_ENOMEM, "out of memory");
  /* A⁻¹ B A⁻¹ (A⁻¹ is 0 on the rows and columns at a bound) */
  if (s == CF_OK && !cf_sandwich((int)n, covariance, b))
    s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) memcpy(covariance, b, n * n * sizeof *b);
  free(b);
  return s;
}

/* Mark the model slots that no observation moves: a column of the
 * Jacobian that is exactly 0 (the ones merely small are the eigenvalues'
 * and the hidden base's to judge). A slot at a bound too: the solver's
 * active set can hold one there that the data never touched (an albedo
 * started at its floor in a channel no light has), and it is not
 * "fitted". */
static int mark_unmoved(const fit_problem *p, const double *jtj, fit_plan *plan) {
  int found = 0, n = fit_problem_unknown_count(p);
  for (int u = 0; u < n; ++u) {
    fit_unknown unk = fit_problem_unknown(p, u);
    if (unk.kind == &fit_kind_material && !(jtj[(size_t)u * (size_t)n + (size_t)u] > 0.0)) {
      plan->status[unk.slot] = CF_PARAM_UNCONSTRAINED;
      found = 1;
    }
  }
  return found;
}

/* Mark the model slots the capture does not constrain: those no
 * observation moves, those that carry the eigenvectors of the
 * (width-scaled) normal matrix whose eigenvalues are negligible, or whose
 * standard deviation exceeds half their range. */
cf_status fit_find_unconstrained(fit_problem *p, const double *jtj, const double *covariance,
                                 int rank_deficient, fit_plan *plan, int *found, cf_error *err) {
  *found = mark_unmoved(p, jtj, plan);
  if (*found) return CF_OK;
  int n = fit_problem_unknown_count(p);
  if (covariance && !rank_deficient) {
    for (int u = 0; u < n; ++u) {
      if (!free_material(p, u)) continue;
      int slot = fit_problem_unknown(p, u).slot;
      double sd = fit_slot_sd(p, slot, covariance[u * n + u]);
      /* half the range: the data do not place it inside its bounds (a derivation) */
      if (sd > 0.5 * fit_slot_width(fit_problem_model(p), slot)) {
        plan->status[slot] = CF_PARAM_UNCONSTRAINED;
        *found = 1;
      }
    }
    return CF_OK;
  }
  int slots[CF_MAX_DIM];
  double h[CF_MAX_DIM * CF_MAX_DIM], values[CF_MAX_DIM], vectors[CF_MAX_DIM * CF_MAX_DIM];
  int m = scaled_model_block(p, jtj, slots, h);
  if (m == 0) return CF_OK;
  if (!cf_symmetric_eigen(m, h, values, vectors))
    return cf_error_set(err, CF_ENUMERIC, "the normal matrix of the model's slots is not finite");
  double largest = 0.0;
  for (int i = 0; i < m; ++i) largest = fmax(largest, values[i]);
  int weakest = 0;
  for (int i = 0; i < m; ++i) {
    if (values[i] < values[weakest]) weakest = i;
    if (values[i] > 1e-10 * largest) continue; /* fd063f4; 1e-12, 1e-8: no fit moves (study) */
    for (int k = 0; k < m; ++k) /* 0.3 < 1/√11: a weak direction of M4's 11 slots marks one */
      if (fabs(vectors[k * m + i]) > 0.3) {
        plan->status[slots[k]] = CF_PARAM_UNCONSTRAINED;
        *found = 1;
      }
  }
  int gains = fit_problem_has_kind(p, &fit_kind_exposure) ||
              fit_problem_has_kind(p, &fit_kind_balance) || fit_problem_has_kind(p, &fit_kind_light);
  if (!*found && gains && values[weakest] > 1e-10 * largest)
    /* the material is constrained: the deficiency is the gains' (holding
     * a model slot would not mend it; cf_fit_check_gains names the images
     * at the start) */
    return cf_error_set(err, CF_ENUMERIC,
                        "the gains (--fit-exposures, --fit-gains) or the scale are not "
                        "constrained at the solution though the material is: some image's "
                        "observations fix only its gain times the material");
  if (!*found) { /* the solver saw a deficiency: name the weakest direction's largest part */
    int best = 0;
    for (int k = 1; k < m; ++k)
      if (fabs(vectors[k * m + weakest]) > fabs(vectors[best * m + weakest])) best = k;
    plan->status[slots[best]] = CF_PARAM_UNCONSTRAINED;
    *found = 1;
  }
  return CF_OK;
}

/* ---- residuals correlated within a lossy codec's blocks ---- */

typedef struct tile_row {
  uint64_t tile;
  size_t row;
} tile_row;

static int by_tile(const void *a, const void *b) {
  const tile_row *x = a, *y = b;
  return x->tile < y->tile ? -1 : x->tile > y->tile;
}

/* Observation i's tile: its image and the tile_px × tile_px square of
 * pixels (from the image's corner, as a codec's blocks) it lies in. */
static uint64_t tile_key(const fit_problem *p, const cf_observations *obs, size_t i,
                         int tile_px) {
  size_t o = fit_problem_observation(p, i);
  uint64_t x = (uint64_t)fmax(0.0, obs->pixel[2 * o] / tile_px);
  uint64_t y = (uint64_t)fmax(0.0, obs->pixel[2 * o + 1] / tile_px);
  return (uint64_t)fit_problem_image(p, i) << 40 | (y & 0xfffffu) << 20 | (x & 0xfffffu);
}

/* Each used observation's tile as a number 0 .. *tiles − 1. */
static cf_status number_tiles(const fit_problem *p, int tile_px, size_t *tile, size_t *tiles,
                              cf_error *err) {
  size_t n = fit_problem_count(p);
  const cf_observations *obs = cf_capture_observations(fit_problem_capture(p));
  tile_row *rows = malloc((n ? n : 1) * sizeof *rows);
  if (!rows) return cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; i < n; ++i) rows[i] = (tile_row){tile_key(p, obs, i, tile_px), i};
  qsort(rows, n, sizeof *rows, by_tile);
  *tiles = 0;
  for (size_t a = 0; a < n; ++a) {
    if (a > 0 && rows[a].tile != rows[a - 1].tile) ++*tiles;
    tile[rows[a].row] = *tiles;
  }
  if (n > 0) ++*tiles;
  free(rows);
  return CF_OK;
}

/* Each tile's score: g[t × m + u] = Σ_{i in tile t} ψ_i ∂μ_i/∂x_u
 * (fit_problem_group_scores, from the analytic Jacobian), 0 for the
 * unknowns at a bound (held there). */
static cf_status tile_scores(const fit_problem *p, const size_t *tile, double *g, size_t tiles,
                             cf_error *err) {
  const size_t m = (size_t)fit_problem_unknown_count(p);
  const int *at_bound = fit_problem_read_at_bound(p);
  cf_status s = fit_problem_group_scores(p, tile, g, err);
  for (size_t t = 0; s == CF_OK && t < tiles; ++t)
    for (size_t u = 0; u < m; ++u)
      if (at_bound[u]) g[t * m + u] = 0.0;
  return s;
}

/* covariance ← A⁻¹ B A⁻¹ with B = Σ_t g_t g_tᵀ. */
static cf_status tile_sandwich(int m, const double *g, size_t tiles, double *covariance,
                               cf_error *err) {
  size_t mm = (size_t)m * (size_t)m;
  double *b = calloc(mm, sizeof *b);
  if (!b) return cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t t = 0; t < tiles; ++t)
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j)
        b[i * m + j] += g[t * (size_t)m + (size_t)i] * g[t * (size_t)m + (size_t)j];
  int done = cf_sandwich(m, covariance, b);
  if (done) memcpy(covariance, b, mm * sizeof *b);
  free(b);
  return done ? CF_OK : cf_error_set(err, CF_ENOMEM, "out of memory");
}

cf_status fit_tile_covariance(const fit_problem *p, int tile_px, double *covariance, int *applied,
                              cf_error *err) {
  const size_t n = fit_problem_count(p), m = (size_t)fit_problem_unknown_count(p);
  *applied = 0;
  if (n == 0 || m == 0) return CF_OK;
  size_t *tile = malloc(n * sizeof *tile), tiles = 0;
  double *g = NULL;
  cf_status s = tile ? number_tiles(p, tile_px, tile, &tiles, err)
                     : cf_error_set(err, CF_ENOMEM, "out of memory");
  /* B from fewer tiles than a few per unknown is singular or nearly */
  const int enough = tiles >= FIT_TILES_PER_UNKNOWN * m;
  if (s == CF_OK && enough && !(g = calloc(tiles * m, sizeof *g)))
    s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK && enough) s = tile_scores(p, tile, g, tiles, err);
  if (s == CF_OK && enough) s = tile_sandwich((int)m, g, tiles, covariance, err);
  *applied = s == CF_OK && enough;
  free(tile);
  free(g);
  return s;
}
