/* Every analytic derivative against the finite difference of docs/model.md (34) (step
 * 1e-6 max(|x|, 1), central inside the range, one-sided at a bound), on
 * 10^4 random cases per model plus the hard-case grid, with the mixed
 * tolerance |g − g_fd| <= ε_a + ε_r max(|g|, |g_fd|).
 *
 * ε_a is scaled by the value: a difference quotient carries a rounding
 * error of about ε_mach |f| / h ≈ 1e-10 |f| (f spans 0 to 1e150 between
 * normal incidence and the grazing cases), so ε_a = 1e-7 (|f| + 1e-6) is
 * a thousand times that error, and 1e-6 (1/sr) is where a value is too
 * small to matter next to any pixel. The relative part covers the
 * difference quotient's truncation error O(h²); it is taken of
 * max(|g|, |g_fd|, q), q the largest one-step difference quotient of the
 * stencil (support/cases.h), which is |g| where f is smooth and the
 * stencil's resolution where the first derivative vanishes (σ = 0). */
#include <math.h>
#include <string.h>

#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { RANDOM_CASES = 10000, MAX_GEOMETRIES = 512 };
static const double eps_abs = 1e-7, eps_abs_floor = 1e-6;
static const double eps_rel_central = 1e-6, eps_rel_one_sided = 1e-5;
/* The tailed rungs' masking is a table of cubic Hermite pieces (docs/model.md
 * §2.8): C1, its second derivative jumps at the knots, and a one-sided
 * second-order quotient over [x, x + 2h] that spans a knot errs by about
 * h |Δf''|, measured up to 1.9e-4 relative (M4T, film_f0 at its bound).
 * Central quotients inside the range keep 1e-6. */
static const double eps_rel_one_sided_table = 1e-3;

typedef struct worst_case {
  double ratio; /* |g − g_fd| / tolerance */
  double g, g_fd, f;
  int slot, channel;
  long index;
} worst_case;

typedef struct gradient_state {
  cf_model_id model;
  long cases, comparisons;
  worst_case worst;
  const char *set;
} gradient_state;

static void compare(gradient_state *s, const double *params, const double n[3], const double l[3],
                    const double v[3]) {
  const int dim = cf_model_info_get(s->model)->dim;
  double f[3], grad[3 * CF_MAX_DIM];
  cf_eval(s->model, params, n, l, v, f, grad);
  for (int k = 0; k < dim; ++k) {
    double g_fd[3], quotient[3];
    int one_sided = 0;
    finite_difference(s->model, params, k, n, l, v, g_fd, quotient, &one_sided);
    for (int c = 0; c < 3; ++c) {
      double g = grad[c * dim + k];
      int table = cf_model_info_get(s->model)->tail_slot >= 0;
      double eps_rel = !one_sided ? eps_rel_central
                       : table    ? eps_rel_one_sided_table
                                  : eps_rel_one_sided;
      double tol = eps_abs * (fabs(f[c]) + eps_abs_floor) +
                   eps_rel * fmax(fmax(fabs(g), fabs(g_fd[c])), quotient[c]);
      double err = fabs(g - g_fd[c]);
      ++s->comparisons;
      if (err / tol > s->worst.ratio || !(err <= tol)) {
        s->worst = (worst_case){err / tol, g, g_fd[c], f[c], k, c, s->cases};
      }
      char name[48];
      CHECK(err <= tol,
            "%s %s case %ld: d f[%d] / d %s: analytic %.10g, finite "
            "difference %.10g (f = %.6g, %s)",
            cf_model_info_get(s->model)->code, s->set, s->cases, c,
            cf_model_slot_name(s->model, k, name, sizeof name), g, g_fd[c], f[c],
            one_sided ? "one-sided" : "central");
    }
  }
  ++s->cases;
}

static double hard_n[MAX_GEOMETRIES][3], hard_l[MAX_GEOMETRIES][3], hard_v[MAX_GEOMETRIES][3];
static size_t hard_count;

static void visit_extreme(const double *params, void *user) {
  for (size_t i = 0; i < hard_count; ++i) compare(user, params, hard_n[i], hard_l[i], hard_v[i]);
}

static void report(const gradient_state *s) {
  char name[48];
  printf(
      "%s %-7s: %ld cases, %ld comparisons; worst |g - g_fd| / tol = %.3g "
      "(d f[%d] / d %s: analytic %.10g, fd %.10g, f %.4g)\n",
      cf_model_info_get(s->model)->code, s->set, s->cases, s->comparisons, s->worst.ratio,
      s->worst.channel, cf_model_slot_name(s->model, s->worst.slot, name, sizeof name), s->worst.g,
      s->worst.g_fd, s->worst.f);
}

int main(void) {
  printf(
      "tolerance: |g - g_fd| <= %.0e (|f| + %.0e) + eps_r max(|g|, |g_fd|, q), "
      "eps_r = %.0e central, %.0e one-sided\n",
      eps_abs, eps_abs_floor, eps_rel_central, eps_rel_one_sided);
  hard_count = hard_geometries(hard_n, hard_l, hard_v, MAX_GEOMETRIES);
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    cf_model_id model = (cf_model_id)m;
    gradient_state random_state = {.model = model, .set = "random"};
    cf_rng rng = cf_rng_seed(4242 + (uint64_t)m);
    for (int i = 0; i < RANDOM_CASES; ++i) {
      double params[CF_MAX_DIM], n[3], l[3], v[3];
      random_params(&rng, model, 0.1, params);
      random_directions(&rng, 0.1, 0.02, n, l, v);
      compare(&random_state, params, n, l, v);
    }
    report(&random_state);
    gradient_state hard_state = {.model = model, .set = "hard"};
    for_each_extreme_params(model, visit_extreme, &hard_state);
    report(&hard_state);
  }
  return check_finish("test_gradient");
}
