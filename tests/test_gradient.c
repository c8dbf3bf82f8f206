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
 * stencil's resolution where the first derivative vanishes (σ = 0).
 *
 * An interface's F0 below 0.01 (f0, base_f0) is checked apart
 * (f0_small_difference): the exact Fresnel is analytic in s = √F0, not in
 * F0 (F = a F0 + b F0^{3/2} + ... at 0), and varies on the scale of
 * F0 itself, so the fixed step 1e-6 of (34) errs by 1e-5 there.
 *
 * usage: test_gradient [MODEL...] (codes or names; default every model) */
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
  long cases, comparisons, f0_zero, f0_zero_skipped;
  worst_case worst;
  const char *set;
} gradient_state;

static void eval_slot(cf_model_id model, const double *params, int k, double x, const double n[3],
                      const double l[3], const double v[3], double f[3]) {
  double p[CF_MAX_DIM];
  memcpy(p, params, sizeof p);
  p[k] = x;
  cf_eval(model, p, n, l, v, f, NULL);
}

/* Is slot k an interface's F0 (range starting at 0) below 0.01? */
static int f0_small(cf_model_id model, const double *params, int k) {
  const cf_param_info *p = cf_model_slot_param(model, k, NULL);
  return (p->id == CF_PARAM_F0 || p->id == CF_PARAM_BASE_F0) && params[k] < 0.01;
}

/* ∂f/∂F0 below F0 = 0.01, by differences in s = √F0 (f is analytic in s,
 * with a radius of at least s about s):
 * - F0 > 0: central, step 1e-4 s: ∂f/∂F0 = (∂f/∂s)/(2s);
 * - F0 = 0: f = f(0) + a s² + b s³ + c s⁴ + ..., ∂f/∂F0 = a; with
 *   Q(s) = (f(s²) − f(0))/s² = a + b s + c s² + ..., extrapolated twice
 *   (R1(s) = 2 Q(s/2) − Q(s) = a + O(s²), (4 R1(s/2) − R1(s))/3 = a + O(s³)),
 *   s = 8e-4 (rounding: 1e-16 |f| / s² times the extrapolation's ~5, below
 *   the 1e-7 |f| of the tolerance). The series is in (η² − 1)/c² ≈ 4s/c²: its
 *   O(s³) remainder is below 1e-5 where the cosines the F0 sees (c_i, c_o,
 *   c_d of the interface; M4's base sees refracted ones, >= 0.57) are >= 0.5.
 *   Below that it returns 0
 *   (not compared): ∂F/∂F0 at 0 grows like 1/c⁴ and varies on the scale
 *   F0 ~ c⁴; tests/test_fresnel.c checks that limit term by term.
 * *one_sided: 1 at F0 = 0, else 0. */
static int f0_small_difference(cf_model_id model, const double *params, int k, const double n[3],
                               const double l[3], const double v[3], double g_fd[3],
                               double quotient[3], int *one_sided) {
  const double x = params[k];
  double s = sqrt(x);
  *one_sided = x == 0.0;
  if (x > 0.0) {
    double h = 1e-4 * s, fp[3], fm[3];
    eval_slot(model, params, k, (s + h) * (s + h), n, l, v, fp);
    eval_slot(model, params, k, (s - h) * (s - h), n, l, v, fm);
    for (int c = 0; c < 3; ++c) {
      g_fd[c] = (fp[c] - fm[c]) / (2.0 * h) / (2.0 * s);
      quotient[c] = fabs(g_fd[c]);
    }
    return 1;
  }
  const cf_param_info *p = cf_model_slot_param(model, k, NULL);
  if (p->id == CF_PARAM_F0) {
    cf_geometry g = cf_geometry_from_directions(n, l, v);
    if (fmin(fmin(g.cos_i, g.cos_o), g.c_d) < 0.5) return 0;
  }
  double f0[3], q[3][3]; /* q[j][c] = Q(s_j), s_j = 8e-4 / 2^j */
  eval_slot(model, params, k, 0.0, n, l, v, f0);
  for (int j = 0; j < 3; ++j) {
    double sj = 8e-4 / (double)(1 << j), f[3];
    eval_slot(model, params, k, sj * sj, n, l, v, f);
    for (int c = 0; c < 3; ++c) q[j][c] = (f[c] - f0[c]) / (sj * sj);
  }
  for (int c = 0; c < 3; ++c) {
    double r1_s = 2.0 * q[1][c] - q[0][c], r1_half = 2.0 * q[2][c] - q[1][c];
    g_fd[c] = (4.0 * r1_half - r1_s) / 3.0;
    quotient[c] = fmax(fabs(q[0][c]), fmax(fabs(q[1][c]), fabs(q[2][c])));
  }
  return 1;
}

static void compare(gradient_state *s, const double *params, const double n[3], const double l[3],
                    const double v[3]) {
  const int dim = cf_model_info_get(s->model)->dim;
  const int table = cf_model_info_get(s->model)->tail_slot >= 0; /* a tailed twin */
  double f[3], grad[3 * CF_MAX_DIM];
  cf_eval(s->model, params, n, l, v, f, grad);
  for (int k = 0; k < dim; ++k) {
    double g_fd[3], quotient[3];
    int one_sided = 0;
    if (f0_small(s->model, params, k)) {
      s->f0_zero += params[k] == 0.0;
      if (!f0_small_difference(s->model, params, k, n, l, v, g_fd, quotient, &one_sided)) {
        ++s->f0_zero_skipped;
        continue;
      }
    } else {
      finite_difference(s->model, params, k, n, l, v, g_fd, quotient, &one_sided);
    }
    for (int c = 0; c < 3; ++c) {
      double g = grad[c * dim + k];
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
            "difference %.10g (f = %.6g, at %.6g, %s)",
            cf_model_info_get(s->model)->code, s->set, s->cases, c,
            cf_model_slot_name(s->model, k, name, sizeof name), g, g_fd[c], f[c], params[k],
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
      "(d f[%d] / d %s: analytic %.10g, fd %.10g, f %.4g); F0 at 0: %ld (%ld with a cosine "
      "below 0.5, not compared)\n",
      cf_model_info_get(s->model)->code, s->set, s->cases, s->comparisons, s->worst.ratio,
      s->worst.channel, cf_model_slot_name(s->model, s->worst.slot, name, sizeof name), s->worst.g,
      s->worst.g_fd, s->worst.f, s->f0_zero, s->f0_zero_skipped);
}

/* The models named on the command line (codes or names), else all. */
static int models_from_args(int argc, char **argv, cf_model_id *models) {
  if (argc < 2) {
    for (int m = 0; m < CF_MODEL_COUNT; ++m) models[m] = (cf_model_id)m;
    return CF_MODEL_COUNT;
  }
  int count = 0;
  for (int i = 1; i < argc && count < CF_MODEL_COUNT; ++i) {
    cf_error err = {0};
    if (cf_model_find(argv[i], &models[count], &err) == CF_OK)
      ++count;
    else
      CHECK(0, "%s", err.message);
  }
  return count;
}

int main(int argc, char **argv) {
  cf_model_id models[CF_MODEL_COUNT];
  int model_count = models_from_args(argc, argv, models);
  printf(
      "tolerance: |g - g_fd| <= %.0e (|f| + %.0e) + eps_r max(|g|, |g_fd|, q), "
      "eps_r = %.0e central, %.0e one-sided\n",
      eps_abs, eps_abs_floor, eps_rel_central, eps_rel_one_sided);
  hard_count = hard_geometries(hard_n, hard_l, hard_v, MAX_GEOMETRIES);
  for (int j = 0; j < model_count; ++j) {
    cf_model_id model = models[j];
    gradient_state random_state = {.model = model, .set = "random"};
    cf_rng rng = cf_rng_seed(4242 + (uint64_t)model);
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
