/* The GGX that best reproduces a tailed (STD) lobe, for the GGX-only
 * formats (include/clayfit/tailed_ggx.h, src/model/tailed_ggx.c,
 * docs/presets.md "Tailed lobes in GGX-only formats"):
 *   1. at γ = 2 the mapping is the identity with a loss < 1e-6, from the
 *      tailed lobe's own (r, F0) and from a start away from it;
 *   2. over r in [0.05, 1] and γ from 1.55 to 1e6, with either Fresnel, the
 *      loss is finite and positive, below the naive mapping's (same r, F0),
 *      and decreases toward γ = 2 from both sides; near γ = 1.5, where the
 *      lobe is almost 0, it stays at most 100 %;
 *   3. the quadrature is converged: every size doubled moves the loss by
 *      < 5e-4 relative and the GGX by < 2e-4 (under M4's film: < 2e-3 and
 *      < 5e-4);
 *   4. the metric is the one documented: an independent quadrature over the
 *      incident directions (the model's own lobe, cf_std_lobe_eval) gives
 *      the same losses, and the fitted GGX is its minimum;
 *   5. bad input is refused with the reason (the note's wording:
 *      tests/export/test_tailed_note.c).
 * Prints the table of docs/presets.md and the cost of one call. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clayfit/tailed_ggx.h"
#include "model/tailed.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PI 3.14159265358979323846

static const cf_tailed_ggx_quadrature default_q = CF_TAILED_GGX_QUADRATURE;

static cf_tailed_ggx fit(double r, double gamma, double f0, cf_tailed_fresnel fresnel,
                         const cf_tailed_ggx_quadrature *q, const double *start) {
  cf_tailed_ggx f;
  cf_error err = {0};
  cf_status s = cf_tailed_ggx_fit(r, gamma, f0, NULL, fresnel, q, start, &f, &err);
  CHECK(s == CF_OK, "r %g gamma %g f0 %g: %s", r, gamma, f0, err.message);
  return f;
}

/* ---- 1. the identity at γ = 2 ---- */
static void test_identity(void) {
  const double rs[] = {0.03, 0.05, 0.2, 0.5, 1.0}, f0s[] = {0.0, 0.02, 0.04, 0.25};
  for (int fr = 0; fr < 2; ++fr)
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 4; ++j) {
        double r = rs[i], f0 = f0s[j];
        cf_error err = {0};
        cf_tailed_fresnel kind = fr ? CF_TAILED_FRESNEL_DIELECTRIC : CF_TAILED_FRESNEL_SCHLICK;
        cf_tailed_ggx f = fit(r, 2.0, f0, kind, &default_q, NULL);
        CHECK(f.r == r && f.f0 == f0 && f.rms_loss < 1e-6, "gamma 2, r %g f0 %g: GGX %g %g loss %g",
              r, f0, f.r, f.f0, f.rms_loss);
        /* from a start away from it (F0 = 0 with the dielectric Fresnel is
         * no lobe: nothing to fit) */
        double start[2] = {r > 0.5 ? 0.7 * r : 1.4 * r, 0.6 * f0 + 0.01};
        f = fit(r, 2.0, f0, kind, &default_q, start);
        if (!(fr && f0 == 0.0))
          CHECK(fabs(f.r - r) < 1e-6 * r && fabs(f.f0 - f0) < 1e-6 && f.rms_loss < 1e-6,
                "gamma 2, r %g f0 %g from (%g, %g): GGX %.9g %.9g loss %g", r, f0, start[0],
                start[1], f.r, f.f0, f.rms_loss);
        cf_tailed_ggx d;
        CHECK(cf_tailed_ggx_default(r, 2.0, f0, NULL, &d, &err) == CF_OK && d.r == r &&
                  d.f0 == f0 && d.rms_loss < 1e-6,
              "entry point at gamma 2, r %g f0 %g: %g %g %g %s", r, f0, d.r, d.f0, d.rms_loss,
              err.message);
      }
}

/* ---- 2. the losses over the range ---- */
static const double grid_r[] = {0.05, 0.1, 0.3, 0.6, 1.0};
/* toward 2 from below, then from above */
static const double below[] = {1.55, 1.7, 1.85, 1.95, 2.0};
static const double above[] = {1e6, 100.0, 10.0, 4.0, 2.5, 2.05, 2.0};

static void check_side(double r, cf_tailed_fresnel kind, const double *gammas, int n) {
  double previous = INFINITY;
  for (int k = 0; k < n; ++k) {
    cf_tailed_ggx f = fit(r, gammas[k], 0.04, kind, &default_q, NULL);
    if (gammas[k] == 2.0) {
      CHECK(f.rms_loss < 1e-6, "r %g: loss %g at gamma 2", r, f.rms_loss);
    } else {
      CHECK(isfinite(f.rms_loss) && f.rms_loss > 1e-4, "r %g gamma %g: loss %g", r, gammas[k],
            f.rms_loss);
      CHECK(f.rms_loss < f.naive_loss * (1.0 - 1e-3),
            "r %g gamma %g fresnel %d: the fit (%g) does not beat the naive mapping (%g)", r,
            gammas[k], (int)kind, f.rms_loss, f.naive_loss);
    }
    CHECK(f.rms_loss < previous, "r %g fresnel %d: loss %g at gamma %g is not below %g at %g", r,
          (int)kind, f.rms_loss, gammas[k], previous, gammas[k > 0 ? k - 1 : 0]);
    previous = f.rms_loss;
  }
}

static void test_range(void) {
  for (int fr = 0; fr < 2; ++fr)
    for (int i = 0; i < 5; ++i) {
      cf_tailed_fresnel kind = fr ? CF_TAILED_FRESNEL_DIELECTRIC : CF_TAILED_FRESNEL_SCHLICK;
      check_side(grid_r[i], kind, below, 5);
      check_side(grid_r[i], kind, above, 7);
    }
}

/* Near γ = 1.5 the lobe is almost 0 (masked). With the dielectric Fresnel,
 * F0' = 0 is no lobe at all, so the fit never loses more than 100 %; and it
 * must not stall at F0' = 0 where a dim GGX does better (r 0.3, γ 1.51 stopped
 * there at 100 % before the step toward F0 = 0 was cut; 84 % now). */
static void test_near_limit(void) {
  const double gammas[] = {1.5000001, 1.501, 1.51}, rs[] = {0.03, 0.3, 1.0};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      cf_tailed_ggx f = fit(rs[i], gammas[j], 0.04, CF_TAILED_FRESNEL_DIELECTRIC, &default_q, NULL);
      CHECK(f.rms_loss <= 1.0 + 1e-9 && f.rms_loss > 0.1, "r %g gamma %.9g: loss %g (GGX %g, %g)",
            rs[i], gammas[j], f.rms_loss, f.r, f.f0);
    }
  cf_tailed_ggx f = fit(0.3, 1.51, 0.04, CF_TAILED_FRESNEL_DIELECTRIC, &default_q, NULL);
  CHECK(f.rms_loss < 0.9 && f.f0 > 1e-3, "r 0.3 gamma 1.51: loss %g at F0' %g", f.rms_loss, f.f0);
}

/* ---- 3. the quadrature is converged ---- */
static void test_converged(void) {
  const double cases[][2] = {{0.03, 1e6}, {0.05, 1.6}, {0.3, 1.7}, {1.0, 1.55}, {1.0, 10.0}};
  const cf_tailed_ggx_quadrature doubled = {2 * default_q.views, 2 * default_q.thetas,
                                            2 * default_q.phis};
  for (int k = 0; k < 5; ++k) {
    double r = cases[k][0], gamma = cases[k][1];
    cf_tailed_ggx a = fit(r, gamma, 0.04, CF_TAILED_FRESNEL_MODELS, &default_q, NULL);
    cf_tailed_ggx b = fit(r, gamma, 0.04, CF_TAILED_FRESNEL_MODELS, &doubled, NULL);
    double dl = fabs(a.rms_loss - b.rms_loss) / b.rms_loss;
    double dn = fabs(a.naive_loss - b.naive_loss) / b.naive_loss;
    double dp = fmax(fabs(a.r - b.r) / b.r, fabs(a.f0 - b.f0) / b.f0);
    CHECK(dl < 5e-4 && dn < 5e-4 && dp < 2e-4,
          "r %g gamma %g: doubling the quadrature moves the loss by %.2g, the naive loss by "
          "%.2g, the GGX by %.2g (relative)",
          r, gamma, dl, dn, dp);
  }
  /* under M4's film (water, oil; thin and thick) */
  const double film[][4] = {{0.03, 1.6, 0.02, 0.1},
                            {0.13, 1.7, 0.05, 0.1},
                            {0.55, 1.8, 0.06, 0.2},
                            {1.0, 10.0, 0.25, 2.0}};
  for (int k = 0; k < 4; ++k) {
    cf_tailed_ggx a, b;
    cf_error err = {0};
    const double under[2] = {film[k][2], film[k][3]};
    CHECK(cf_tailed_ggx_fit(film[k][0], film[k][1], 0.02, under, CF_TAILED_FRESNEL_MODELS,
                            &default_q, NULL, &a, &err) == CF_OK &&
              cf_tailed_ggx_fit(film[k][0], film[k][1], 0.02, under, CF_TAILED_FRESNEL_MODELS,
                                &doubled, NULL, &b, &err) == CF_OK,
          "under a film: %s", err.message);
    double dl = fabs(a.rms_loss - b.rms_loss) / b.rms_loss;
    double dp = fmax(fabs(a.r - b.r) / b.r, fabs(a.f0 - b.f0) / b.f0);
    CHECK(dl < 2e-3 && dp < 5e-4,
          "under a film, r %g gamma %g: doubling the quadrature moves the loss by %.2g, the GGX "
          "by %.2g (relative)",
          film[k][0], film[k][1], dl, dp);
    printf(
        "under a film (F0_1 %g, tau %g), r %g gamma %g: loss %.4g, GGX (%.5g, %.5g); doubled: "
        "%.2g, %.2g relative\n",
        film[k][2], film[k][3], film[k][0], film[k][1], a.rms_loss, a.r, a.f0, dl, dp);
  }
}

/* ---- 4. the metric, by an independent quadrature over ω_i ----
 * Views: Gauss-Legendre in c_o with the weight c_o; light: Gauss-Legendre in
 * c_i times the midpoint rule in φ (dω_i = dc_i dφ); the lobes by the model's
 * cf_std_lobe_eval (Schlick's Fresnel) at the model's half vector. */
enum { BF_VIEWS = 48, BF_LIGHTS = 64, BF_PHIS = 128 };

typedef struct brute {
  double *w, *c_i, *c_o, *sin2, *cos2, *weight_d, *target;
  size_t count;
} brute;

static brute brute_build(double r, double gamma, double f0) {
  brute b;
  size_t n = (size_t)BF_VIEWS * BF_LIGHTS * BF_PHIS;
  double *all = malloc(7 * n * sizeof *all);
  b.w = all, b.c_i = all + n, b.c_o = all + 2 * n, b.sin2 = all + 3 * n, b.cos2 = all + 4 * n;
  b.weight_d = all + 5 * n, b.target = all + 6 * n;
  b.count = 0;
  double xo[BF_VIEWS], wo[BF_VIEWS], xi[BF_LIGHTS], wi[BF_LIGHTS];
  cf_gauss_legendre01(BF_VIEWS, xo, wo);
  cf_gauss_legendre01(BF_LIGHTS, xi, wi);
  cf_std_tail t = cf_std_tail_prepare(r * r * r * r, gamma);
  for (int v = 0; v < BF_VIEWS; ++v)
    for (int l = 0; l < BF_LIGHTS; ++l)
      for (int p = 0; p < BF_PHIS; ++p) {
        double c_o = xo[v], c_i = xi[l], phi = PI * (p + 0.5) / BF_PHIS;
        double s_o = sqrt(1.0 - c_o * c_o), s_i = sqrt(1.0 - c_i * c_i);
        double t_sq = s_i * s_i + s_o * s_o + 2.0 * s_i * s_o * cos(phi);
        cf_half_vector h = half_vector(t_sq, c_i + c_o);
        size_t k = b.count++;
        b.w[k] = c_o * wo[v] * wi[l]; /* constant factors cancel in the ratio */
        b.c_i[k] = c_i, b.c_o[k] = c_o, b.sin2[k] = h.sin2_h, b.cos2[k] = h.cos2_h;
        b.weight_d[k] = schlick_weight(h.c_d);
        b.target[k] =
            cf_std_lobe_eval(&t, f0, b.weight_d[k], h.sin2_h, h.cos2_h, c_i, c_o, 0).value;
      }
  return b;
}

/* E(g)/E(0) of docs/presets.md at GGX (r, f0), squared */
static double brute_cost(const brute *b, double r, double f0) {
  cf_std_tail g = cf_std_tail_prepare(r * r * r * r, 2.0);
  double e = 0.0, e0 = 0.0;
  for (size_t k = 0; k < b->count; ++k) {
    double f =
        cf_std_lobe_eval(&g, f0, b->weight_d[k], b->sin2[k], b->cos2[k], b->c_i[k], b->c_o[k], 0)
            .value;
    double res = b->c_i[k] * (f - b->target[k]), ref = b->c_i[k] * b->target[k];
    e += b->w[k] * res * res;
    e0 += b->w[k] * ref * ref;
  }
  return e / e0;
}

static void test_metric(void) {
  const double cases[][2] = {{0.5, 1.7}, {0.6, 6.0}};
  for (int k = 0; k < 2; ++k) {
    double r = cases[k][0], gamma = cases[k][1];
    cf_tailed_ggx f = fit(r, gamma, 0.04, CF_TAILED_FRESNEL_SCHLICK, &default_q, NULL);
    brute b = brute_build(r, gamma, 0.04);
    double naive = sqrt(brute_cost(&b, r, 0.04)), fitted = brute_cost(&b, f.r, f.f0);
    CHECK(fabs(naive - f.naive_loss) < 2e-3 * naive &&
              fabs(sqrt(fitted) - f.rms_loss) < 2e-3 * f.rms_loss,
          "r %g gamma %g: the losses %g (naive) and %g (fitted) are %g and %g by quadrature over "
          "the incident directions",
          r, gamma, f.naive_loss, f.rms_loss, naive, sqrt(fitted));
    const double moves[4][2] = {{1.02, 1.0}, {0.98, 1.0}, {1.0, 1.05}, {1.0, 0.95}};
    for (int m = 0; m < 4; ++m) {
      double c = brute_cost(&b, f.r * moves[m][0], f.f0 * moves[m][1]);
      CHECK(c > fitted, "r %g gamma %g: GGX (%g, %g) x (%g, %g) is closer than the fit (%g > %g)",
            r, gamma, f.r, f.f0, moves[m][0], moves[m][1], fitted, c);
    }
    free(b.w);
  }
}

/* ---- 5. bad input ---- */
static void refused(double r, double gamma, double f0, const char *reason) {
  cf_tailed_ggx f;
  cf_error err = {0};
  cf_status s = cf_tailed_ggx_default(r, gamma, f0, NULL, &f, &err);
  CHECK(s == CF_ERANGE && strstr(err.message, reason),
        "r %g gamma %g f0 %g: status %d, message '%s', expected '%s'", r, gamma, f0, (int)s,
        err.message, reason);
}

static void test_bad_input(void) {
  refused(0.01, 1.8, 0.04, "roughness 0.01 is outside [0.03, 1]");
  refused(1.2, 1.8, 0.04, "roughness 1.2 is outside [0.03, 1]");
  refused(NAN, 1.8, 0.04, "roughness nan is outside");
  refused(0.3, 1.5, 0.04, "tail gamma 1.5 must be above 1.5");
  refused(0.3, 1.2, 0.04,
          "tail gamma 1.2 must be above 1.5 (at and below it the STD lobe has "
          "no finite masking)");
  refused(0.3, INFINITY, 0.04, "tail gamma inf is not finite");
  refused(0.3, NAN, 0.04, "tail gamma nan is not finite");
  refused(0.3, 1.8, -0.01, "F0 -0.01 is outside [0, 0.25]");
  refused(0.3, 1.8, 0.3, "F0 0.3 is outside [0, 0.25]");
  cf_tailed_ggx f;
  cf_error err = {0};
  const cf_tailed_ggx_quadrature none = {0, 32, 12}, huge = {32, 32, 257};
  CHECK(cf_tailed_ggx_fit(0.3, 1.8, 0.04, NULL, CF_TAILED_FRESNEL_MODELS, &none, NULL, &f, &err) ==
            CF_EINVAL,
        "an empty quadrature: %s", err.message);
  CHECK(cf_tailed_ggx_fit(0.3, 1.8, 0.04, NULL, CF_TAILED_FRESNEL_MODELS, &huge, NULL, &f, &err) ==
                CF_EINVAL &&
            strstr(err.message, "quadrature 32 x 32 x 257 outside [1, 256]"),
        "a quadrature too large: %s", err.message);
  const double start[2] = {0.3, 0.5};
  CHECK(cf_tailed_ggx_fit(0.3, 1.8, 0.04, NULL, CF_TAILED_FRESNEL_MODELS, &default_q, start, &f,
                          &err) == CF_ERANGE &&
            strstr(err.message, "the start: ") && strstr(err.message, "F0 0.5"),
        "a start out of range: %s", err.message);
  /* under M4's film: the film's ranges, and at γ = 2 the identity as in air */
  const double thin[2] = {0.005, 0.1}, nan_depth[2] = {0.02, NAN}, water[2] = {0.05, 0.3};
  CHECK(cf_tailed_ggx_fit(0.3, 1.8, 0.04, thin, CF_TAILED_FRESNEL_MODELS, &default_q, NULL, &f,
                          &err) == CF_ERANGE &&
            strstr(err.message, "film F0 0.005 or optical depth 0.1 outside"),
        "a film F0 below its range: %s", err.message);
  CHECK(cf_tailed_ggx_fit(0.3, 1.8, 0.04, nan_depth, CF_TAILED_FRESNEL_MODELS, &default_q, NULL, &f,
                          &err) == CF_ERANGE,
        "an optical depth NaN: %s", err.message);
  for (int i = 0; i < 3; ++i) {
    const double rs[] = {0.05, 0.3, 1.0};
    CHECK(cf_tailed_ggx_fit(rs[i], 2.0, 0.02, water, CF_TAILED_FRESNEL_MODELS, &default_q, NULL, &f,
                            &err) == CF_OK &&
              f.r == rs[i] && f.f0 == 0.02 && f.rms_loss < 1e-6,
          "under a film at gamma 2, r %g: %g %g %g", rs[i], f.r, f.f0, f.rms_loss);
  }
  /* the dielectric Fresnel at F0 = 0 is no lobe: the GGX of F0 = 0, exactly */
  f = fit(0.3, 1.7, 0.0, CF_TAILED_FRESNEL_DIELECTRIC, &default_q, NULL);
  CHECK(f.r == 0.3 && f.f0 == 0.0 && f.rms_loss == 0.0, "F0 0: %g %g %g", f.r, f.f0, f.rms_loss);
}

/* ---- the table of docs/presets.md, and the cost of a call ---- */
static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t); /* CPU time: the machine may be shared */
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void print_table(void) {
  const double rs[] = {0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0};
  const double gs[] = {1.55, 1.7, 1.85, 2.0, 2.5, 4.0, 10.0, 1e6};
  printf(
      "GGX approximation of the STD lobe (F0 0.04, the models' Fresnel): loss %% "
      "(fitted r, F0)\n| r \\ gamma |");
  for (int j = 0; j < 8; ++j) printf(" %g |", gs[j]);
  printf("\n");
  double seconds = 0.0;
  int calls = 0;
  for (int i = 0; i < 7; ++i) {
    printf("| %g |", rs[i]);
    for (int j = 0; j < 8; ++j) {
      cf_tailed_ggx f;
      cf_error err = {0};
      double t0 = now();
      cf_status s = cf_tailed_ggx_default(rs[i], gs[j], 0.04, NULL, &f, &err);
      seconds += now() - t0;
      ++calls;
      CHECK(s == CF_OK, "%s", err.message);
      printf(" %.1f (%.3g, %.3g) |", 100.0 * f.rms_loss, f.r, f.f0);
    }
    printf("\n");
  }
  printf("cf_tailed_ggx_default: %.0f us of CPU a call (mean of %d calls)\n", 1e6 * seconds / calls,
         calls);
}

int main(void) {
  test_identity();
  test_range();
  test_near_limit();
  test_converged();
  test_metric();
  test_bad_input();
  print_table();
  return check_finish("test_tailed_ggx");
}
