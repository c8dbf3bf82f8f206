/* The STD lobe with a free tail (src/model/tailed.h, docs/model.md §2.8),
 * property by property (docs/model.md §4.6):
 *   1. special functions against closed forms and quadrature;
 *   2. at γ = 2 the D, visibility and lobe are GGX's (the early return to
 *      the bit; the general formulas forced at γ = 2 to 1e-12);
 *   3. ∫ D cos θ_h dω = 1 by quadrature over α and γ, near the limits too;
 *   4. Smith's identity ∫ max(0, o·m) D(m) dm = c_o (1 + Λ(c_o));
 *   5. every analytic derivative against central differences;
 *   6. reciprocity of the lobe;
 *   7. the white furnace: directional albedo of D·V (F = 1) <= 1 + 1e-3;
 *   8. finite on the hard-case grid; the Beckmann limit is continuous.
 * Prints the cost of one evaluation (value + gradient) against GGX's. */
#include <math.h>
#include <string.h>
#include <time.h>

#include "model/tailed.h"
#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PI 3.14159265358979323846

/* ---- adaptive Gauss-Kronrod (7, 15) quadrature (QUADPACK's qk15) ---- */

typedef double (*integrand)(double x, void *user);

static const double xgk[8] = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.0};
static const double wgk[8] = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
static const double wg[4] = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

static double gk15(integrand f, void *user, double a, double b, double *err) {
  double c = 0.5 * (a + b), h = 0.5 * (b - a);
  double fc = f(c, user), rk = fc * wgk[7], rg = fc * wg[3];
  for (int j = 0; j < 7; ++j) {
    double s = f(c - h * xgk[j], user) + f(c + h * xgk[j], user);
    rk += wgk[j] * s;
    if (j & 1) rg += wg[j / 2] * s;
  }
  *err = fabs((rk - rg) * h);
  return rk * h;
}

static double adaptive(integrand f, void *user, double a, double b, double tol, int depth) {
  double err, r = gk15(f, user, a, b, &err);
  if (err <= tol || depth >= 40) return r;
  double m = 0.5 * (a + b);
  return adaptive(f, user, a, m, 0.5 * tol, depth + 1) +
         adaptive(f, user, m, b, 0.5 * tol, depth + 1);
}

/* ---- 1. special functions ---- */

static double rel(double a, double b) {
  double m = fmax(fabs(a), fabs(b));
  return m > 0.0 ? fabs(a - b) / m : 0.0;
}

/* B_x(p, q) = x^p/p ∫_0^1 (1 − x u^(1/p))^(q − 1) du (t = x u^(1/p): smooth) */
typedef struct beta_args {
  double x, p, q;
} beta_args;

static double beta_integrand(double u, void *user) {
  const beta_args *b = user;
  return pow(1.0 - b->x * pow(u, 1.0 / b->p), b->q - 1.0);
}

static double incomplete_beta_quadrature(double x, double p, double q) {
  beta_args b = {x, p, q};
  return exp(p * log(x)) / p * adaptive(beta_integrand, &b, 0.0, 1.0, 1e-16, 0);
}

/* B_x(p, q) from the fraction (the quantity masking_general forms). */
static double incomplete_beta(double x, double p, double q) {
  return exp(p * log(x) + q * log1p(-x)) / p * cf_beta_fraction(x, p, q, 0, 0, NULL, NULL);
}

static void check_special_functions(void) {
  /* Γ(a + 1/2)/Γ(a + 1): exact at a = 1/2, 1, n; ψ differences exact at 1/2 and 1 */
  double d;
  double r = cf_log_gamma_ratio_half(0.5, &d);
  CHECK(fabs(r - log(2.0 / sqrt(PI))) < 1e-15, "ln R(1/2) = %.17g", r);
  CHECK(fabs(d - (2.0 * log(2.0) - 2.0)) < 1e-15, "psi(1) - psi(3/2) = %.17g", d);
  r = cf_log_gamma_ratio_half(1.0, &d);
  CHECK(fabs(r - log(sqrt(PI) / 2.0)) < 1e-15, "ln R(1) = %.17g", r);
  CHECK(fabs(d - (1.0 - 2.0 * log(2.0))) < 1e-15, "psi(3/2) - psi(2) = %.17g", d);
  double worst = 0.0, worst_d = 0.0;
  for (double a = 0.55; a < 3e4; a *= 1.37) {
    double ref = lgamma(a + 0.5) - lgamma(a + 1.0); /* lgamma: ~1e-15 relative of ln Γ */
    double got = cf_log_gamma_ratio_half(a, &d);
    double tol = 4e-16 * (fabs(lgamma(a + 0.5)) + fabs(lgamma(a + 1.0))) + 1e-15;
    worst = fmax(worst, fabs(got - ref) / tol);
    double h = 1e-5 * a, dp, dm;
    double fd =
        (cf_log_gamma_ratio_half(a + h, &dp) - cf_log_gamma_ratio_half(a - h, &dm)) / (2 * h);
    worst_d = fmax(worst_d, fabs(fd - d) / (1e-8 * fabs(d) + 1e-10));
  }
  CHECK(worst <= 1.0, "ln R against lgamma: worst %.3g of the tolerance", worst);
  CHECK(worst_d <= 1.0, "d ln R against differences: worst %.3g of the tolerance", worst_d);

  /* B_x(1, 1/2) = 2 (1 − √(1 − x)); B_x(1/2, 1) = 2 √x; B_x(2, 1/2) closed */
  double worst_b = 0.0;
  for (double x = 1e-6; x < 0.7; x *= 1.9) {
    double s = sqrt(1.0 - x);
    worst_b = fmax(worst_b, fabs(incomplete_beta(x, 1.0, 0.5) / (2.0 * x / (1.0 + s)) - 1.0));
    if (x < 1.5 / 3.0)
      worst_b = fmax(worst_b, fabs(incomplete_beta(x, 0.5, 1.0) / (2 * sqrt(x)) - 1));
    double b2 = 4.0 / 3.0 - 2.0 * s + 2.0 * s * s * s / 3.0; /* ∫ t (1 − t)^(−1/2) */
    if (x > 1e-2 && x < 3.0 / 4.5)
      worst_b = fmax(worst_b, fabs(incomplete_beta(x, 2.0, 0.5) / b2 - 1.0));
  }
  CHECK(worst_b < 1e-12, "incomplete beta against closed forms: worst relative %.3g", worst_b);

  /* non-integer parameters against quadrature, and the fraction's
   * derivative along p and q against differences */
  static const double ps[] = {0.5, 0.5001, 0.8, 2.7, 40.0}, xs[] = {1e-3, 0.1, 0.3, 0.45};
  double worst_q = 0.0, worst_dq = 0.0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j) {
      double p = ps[i], q = 0.5, x = xs[j];
      if (!(x < (p + 1) / (p + q + 2))) continue;
      double ref = incomplete_beta_quadrature(x, p, q);
      worst_q = fmax(worst_q, fabs(incomplete_beta(x, p, q) / ref - 1.0));
      double dcf_unused, with_derivative = cf_beta_fraction(x, p, q, 1, 0, &dcf_unused, NULL);
      worst_q = fmax(worst_q, rel(with_derivative, cf_beta_fraction(x, p, q, 0, 0, NULL, NULL)));
      for (int along = 0; along < 2; ++along) {
        double dcf, h = 1e-6 * p;
        cf_beta_fraction(x, p, q, along == 0, along == 1, &dcf, NULL);
        double fp = along ? cf_beta_fraction(x, p, q + h, 0, 0, NULL, NULL)
                          : cf_beta_fraction(x, p + h, q, 0, 0, NULL, NULL);
        double fm = along ? cf_beta_fraction(x, p, q - h, 0, 0, NULL, NULL)
                          : cf_beta_fraction(x, p - h, q, 0, 0, NULL, NULL);
        worst_dq = fmax(worst_dq, fabs((fp - fm) / (2 * h) - dcf) / (1e-7 * fabs(dcf) + 1e-9));
      }
    }
  CHECK(worst_q < 1e-12, "incomplete beta against quadrature: worst relative %.3g", worst_q);
  CHECK(worst_dq <= 1.0, "fraction derivative: worst %.3g of the tolerance", worst_dq);
  printf(
      "special functions: ln R worst %.2g, d ln R %.2g of tolerance; B_x closed forms %.2g, "
      "quadrature %.2g; fraction derivative %.2g of tolerance\n",
      worst, worst_d, worst_b, worst_q, worst_dq);
}

/* ---- 2. GGX at γ = 2 ---- */

/* One random lit geometry and parameters. */
typedef struct lobe_case {
  double a2, f0;
  cf_geometry g;
} lobe_case;

static lobe_case random_case(cf_rng *rng, double p_grazing) {
  lobe_case k;
  do {
    double n[3], l[3], v[3];
    random_directions(rng, p_grazing, 0.02, n, l, v);
    k.g = cf_geometry_from_directions(n, l, v);
  } while (!cf_geometry_is_lit(&k.g));
  double r = cf_rng_range(rng, 0.03, 1.0);
  k.a2 = r * r * r * r;
  k.f0 = cf_rng_range(rng, 0.0, 0.25);
  return k;
}

static cf_std_lobe std_lobe_of(const cf_std_tail *t, const lobe_case *k, int with_grad) {
  return cf_std_lobe_eval(t, k->f0, k->g.weight_d, k->g.sin2_h, k->g.cos2_h, k->g.cos_i, k->g.cos_o,
                          with_grad);
}

static void check_ggx_special_case(cf_rng *rng) {
  double worst_general = 0.0, worst_near = 0.0;
  long unequal = 0;
  for (int i = 0; i < 20000; ++i) {
    lobe_case k = random_case(rng, 0.2);
    const cf_geometry *g = &k.g;
    cf_ggx_d gd = ggx_d(k.a2, 1.0 / k.a2, g->sin2_h, g->cos2_h);
    cf_smith_v gv = smith_ggx_v(k.a2, g->cos_i, g->cos_o);
    double fresnel = fresnel_schlick(k.f0, g->weight_d);
    double ggx_lobe = fresnel * (gd.value * gv.value); /* dielectric.c's order */

    /* the early return: to the bit */
    cf_std_tail t = cf_std_tail_prepare(k.a2, 2.0);
    cf_std_d d = std_d(&t, g->sin2_h, g->cos2_h);
    cf_std_v v = cf_std_v_eval(&t, g->cos_i, g->cos_o, 1);
    cf_std_lobe s = std_lobe_of(&t, &k, 1);
    unequal += d.value != gd.value || d.d_a2 != gd.d_a2 || d.d_sin2 != gd.d_sin2 ||
               v.value != gv.value || v.d_a2 != gv.d_a2 || v.d_ci != gv.d_ci || v.d_co != gv.d_co ||
               s.value != ggx_lobe;

    /* the general formulas forced at γ = 2, and the general path beside it */
    cf_std_tail forced = t;
    forced.regime = CF_STD_GENERAL;
    for (int which = 0; which < 3; ++which) {
      cf_std_tail u = forced;
      if (which)
        u = cf_std_tail_prepare(k.a2, which == 1 ? nextafter(2.0, 3.0) : nextafter(2.0, 1.0));
      cf_std_d du = std_d(&u, g->sin2_h, g->cos2_h);
      cf_std_v vu = cf_std_v_eval(&u, g->cos_i, g->cos_o, 1);
      cf_std_lobe su = std_lobe_of(&u, &k, 1);
      double e =
          fmax(fmax(rel(du.value, gd.value), rel(vu.value, gv.value)), rel(su.value, ggx_lobe));
      /* derivatives: relative to the term's own scale (value / variable) */
      e = fmax(e, fabs(du.d_a2 - gd.d_a2) / (fabs(gd.d_a2) + gd.value / k.a2) * 1e-3);
      e = fmax(e, fabs(vu.d_ci - gv.d_ci) / (fabs(gv.d_ci) + gv.value / g->cos_i) * 1e-3);
      e = fmax(e, fabs(vu.d_a2 - gv.d_a2) / (fabs(gv.d_a2) + gv.value / k.a2) * 1e-3);
      if (which == 0)
        worst_general = fmax(worst_general, e);
      else
        worst_near = fmax(worst_near, e);
    }
  }
  CHECK(unequal == 0, "gamma = 2: %ld cases differ from GGX's code", unequal);
  CHECK(worst_general <= 1e-12, "general formulas at gamma = 2: worst %.3g relative",
        worst_general);
  CHECK(worst_near <= 1e-12, "gamma = 2 +- 1 ulp: worst %.3g relative", worst_near);
  printf(
      "GGX at gamma = 2: early return bit-equal in 20000 cases; general formulas %.2g, "
      "one ulp away %.2g (values; derivatives scaled by 1e-3)\n",
      worst_general, worst_near);
}

/* ---- 3. and 4. normalisation and Smith's identity, by quadrature over
 * the slope x = tan θ_m / α, x = u/(1 − u), u in [0, 1) ---- */

typedef struct slope_args {
  const cf_std_tail *t;
  double alpha, c_o, s_o;
  double power; /* x = (u/(1 − u))^power: a bounded integrand for heavy tails */
} slope_args;

static void slope_angles(const slope_args *s, double u, double *x, double *dx, double *sin2,
                         double *cos2) {
  double y = u / (1.0 - u);
  *x = pow(y, s->power);
  *dx = s->power * pow(y, s->power - 1.0) / ((1.0 - u) * (1.0 - u));
  double tan2 = s->alpha * s->alpha * *x * *x;
  *cos2 = 1.0 / (1.0 + tan2);
  *sin2 = tan2 / (1.0 + tan2);
}

/* 2π D cos θ sin θ dθ/du with dθ = cos²θ α dx */
static double projected_area_integrand(double u, void *user) {
  const slope_args *s = user;
  if (u >= 1.0) return 0.0;
  double x, dx, sin2, cos2;
  slope_angles(s, u, &x, &dx, &sin2, &cos2);
  double d = std_d(s->t, sin2, cos2).value;
  return 2.0 * PI * d * cos2 * cos2 * s->alpha * s->alpha * x * dx;
}

/* D sin θ Φ(θ) dθ/du, Φ = ∫ max(0, c_o cos θ + s_o sin θ cos φ) dφ in closed form */
static double masking_integrand(double u, void *user) {
  const slope_args *s = user;
  if (u >= 1.0) return 0.0;
  double x, dx, sin2, cos2;
  slope_angles(s, u, &x, &dx, &sin2, &cos2);
  double cos_m = sqrt(cos2), sin_m = sqrt(sin2);
  double A = s->c_o * cos_m, B = s->s_o * sin_m, phi;
  if (B <= A) {
    phi = 2.0 * PI * A;
  } else {
    double phi0 = acos(-A / B);
    phi = 2.0 * (A * phi0 + B * sqrt((1.0 - A / B) * (1.0 + A / B)));
  }
  double d = std_d(s->t, sin2, cos2).value;
  return d * cos2 * cos_m * s->alpha * s->alpha * x * phi * dx;
}

/* Λ from the paper's closed form (Ribardière et al. 2017 eqs. 13-15, with
 * ₂F₁(1/2, γ − 1/2; 3/2; −cot²θ/((γ − 1) α²))) evaluated with 50 digits
 * (mpmath 1.3), α² = 0.09, c = 1e-8, 0.01, 0.3, 0.7, 0.99. Below γ = 1.6
 * the quadrature of Smith's identity cannot reach the masking's mass (at
 * slopes beyond 1e30); this checks those γ. */
static const struct {
  double gamma, lambda[5];
} masking_reference[] = {
    {1.5001,
     {3.376991849772667e+10, 3.3767737460611641e+4, 1.0735012865820151e+3, 3.4434724185221961e+2,
      4.8076249556410475e+1}},
    {1.501,
     {3.3842434409916226e+9, 3.3835817282192525e+3, 1.0729848556550233e+2, 3.4351496979142619e+1,
      4.7791069358132697}},
    {1.55,
     {7.5612007211848674e+7, 7.511586227706356e+1, 2.095061740400557, 6.0407840708502789e-1,
      6.9357124772283034e-2}},
    {1.6,
     {4.1877606292107262e+7, 4.1383265728314363e+1, 1.0262663306212486, 2.6641894470447985e-1,
      2.5151954979128833e-2}},
    {2.5,
     {1.169545151850515e+7, 1.1203528823816697e+1, 9.7230075577609209e-2, 5.1599503364130348e-3,
      1.5201628431573572e-5}},
    {3.7,
     {9.9188601197301844e+6, 9.4273431812147899, 5.176775327753948e-2, 6.3178875114230431e-4,
      2.184956618851015e-8}},
    {50,
     {8.5283057867236313e+6, 8.0372577783286181, 2.1783888498739381e-2, 3.1028096055160026e-7,
      0.0}},
    {1e5,
     {8.4628749893630818e+6, 7.9718542119672315, 2.0571273298311804e-2, 8.2723695507130304e-8,
      0.0}},
};

static void check_masking_reference(void) {
  static const double cs[5] = {1e-8, 0.01, 0.3, 0.7, 0.99};
  double worst = 0.0;
  for (size_t i = 0; i < sizeof masking_reference / sizeof masking_reference[0]; ++i) {
    cf_std_tail t = cf_std_tail_prepare(0.09, masking_reference[i].gamma);
    for (int j = 0; j < 5; ++j) {
      /* G1 = 1/(1 + Λ): compare 1 + Λ */
      double e = rel(1.0 + cf_std_lambda(&t, cs[j]), 1.0 + masking_reference[i].lambda[j]);
      CHECK(e <= 1e-12, "Lambda(gamma %g, c %g) = %.17g, the closed form %.17g",
            masking_reference[i].gamma, cs[j], cf_std_lambda(&t, cs[j]),
            masking_reference[i].lambda[j]);
      worst = fmax(worst, e);
    }
  }
  printf("masking against the paper's closed form (50 digits): worst relative 1 + Lambda %.2g\n",
         worst);
}

static const double grid_r[] = {0.03, 0.1, 0.3, 0.6, 1.0};
static const double grid_gamma[] = {1.5 + 1e-3, 1.55,  1.8, 2.0, 2.5, 4.0,
                                    10.0,       100.0, 1e4, 1e6, 1e9};
enum { GRID_R = 5, GRID_GAMMA = 11 };

static void check_normalisation_and_masking(void) {
  static const double cos_o[] = {1.0, 0.9, 0.5, 0.1, 0.01, 1e-3};
  double worst_norm = 0.0, worst_smith = 0.0, worst_beckmann_smith = 0.0;
  for (int i = 0; i < GRID_R; ++i)
    for (int j = 0; j < GRID_GAMMA; ++j) {
      double a2 = pow(grid_r[i], 4), gamma = grid_gamma[j];
      cf_std_tail t = cf_std_tail_prepare(a2, gamma);
      /* the projected area of masking decays like x^(2 − 2γ): bounded in u
       * with x = y^p, p (2γ − 3) >= 1 */
      slope_args s = {&t, sqrt(a2), 1.0, 0.0, 1.0};
      double area = adaptive(projected_area_integrand, &s, 0.0, 1.0, 1e-10, 0);
      CHECK(fabs(area - 1.0) <= 1e-6, "r %g gamma %g: integral of D cos = %.12g", grid_r[i], gamma,
            area);
      worst_norm = fmax(worst_norm, fabs(area - 1.0));
      for (int k = 0; k < 6; ++k) {
        s.c_o = cos_o[k];
        s.s_o = sqrt((1.0 - s.c_o) * (1.0 + s.c_o));
        if (gamma < 1.6) continue; /* mass beyond slope 1e30: check_masking_reference */
        s.power = fmax(1.0, 1.0 / (2.0 * gamma - 3.0));
        double split = s.s_o > 0.0 ? s.c_o / (s.s_o * s.alpha) : INFINITY; /* the kink's x */
        split = pow(split, 1.0 / s.power);
        double u_split = isinf(split) ? 1.0 : split / (1.0 + split);
        double integral =
            adaptive(masking_integrand, &s, 0.0, u_split, 1e-11, 0) +
            (u_split < 1.0 ? adaptive(masking_integrand, &s, u_split, 1.0, 1e-11, 0) : 0.0);
        double expected = s.c_o * (1.0 + cf_std_lambda(&t, s.c_o)); /* (c_o + L)/2 */
        double e = fabs(integral / expected - 1.0);
        if (t.regime == CF_STD_BECKMANN) {
          worst_beckmann_smith = fmax(worst_beckmann_smith, e);
          continue;
        }
        CHECK(e <= 1e-6, "Smith: r %g gamma %g c_o %g: %.12g against c_o (1 + Lambda) %.12g",
              grid_r[i], gamma, s.c_o, integral, expected);
        worst_smith = fmax(worst_smith, e);
      }
    }
  /* at γ >= 1e6 Λ is Beckmann's and D is still STD's: they differ by O(1/γ) */
  CHECK(worst_beckmann_smith <= 1e-5, "Smith in the Beckmann regime: worst %.3g",
        worst_beckmann_smith);
  printf(
      "normalisation: worst |integral - 1| %.2g; Smith identity: worst relative %.2g "
      "(Beckmann regime %.2g)\n",
      worst_norm, worst_smith, worst_beckmann_smith);
}

/* ---- 5. derivatives against central differences ---- */

/* x = {α², γ, F0, weight_d, sin²θ_h, c_i, c_o}; cos²θ_h moves with sin²θ_h */
enum { NX = 7, NF = 3 };
static const char *const x_names[NX] = {"a2", "gamma", "f0", "weight", "sin2", "c_i", "c_o"};
static const char *const f_names[NF] = {"D", "V", "lobe"};

typedef struct grad_point {
  double x[NX], cos2; /* cos²θ_h at x[4] */
} grad_point;

static void eval_point(const grad_point *p, const double *x, double f[NF], double g[NF][NX]) {
  cf_std_tail t = cf_std_tail_prepare(x[0], x[1]);
  double cos2 = p->cos2 - (x[4] - p->x[4]);
  cf_std_d d = std_d(&t, x[4], cos2);
  cf_std_v v = cf_std_v_eval(&t, x[5], x[6], 1);
  cf_std_lobe s = cf_std_lobe_eval(&t, x[2], x[3], x[4], cos2, x[5], x[6], 1);
  f[0] = d.value, f[1] = v.value, f[2] = s.value;
  if (!g) return;
  double gd[NX] = {d.d_a2, d.d_gamma, 0, 0, d.d_sin2, 0, 0};
  double gv[NX] = {v.d_a2, v.d_gamma, 0, 0, 0, v.d_ci, v.d_co};
  double gs[NX] = {s.d_a2, s.d_gamma, s.d_f0, s.d_weight, s.d_sin2, s.d_ci, s.d_co};
  memcpy(g[0], gd, sizeof gd), memcpy(g[1], gv, sizeof gv), memcpy(g[2], gs, sizeof gs);
}

static double step_of(const grad_point *p, int k) {
  const double *x = p->x;
  switch (k) {
    case 0:
      return 1e-6 * x[0];
    case 1:
      return 1e-6 * fmin(x[1] - CF_STD_GAMMA_MIN, x[1]);
    case 2:
    case 3:
      return 1e-6;
    case 4:
      return 1e-6 * fmin(x[4], p->cos2);
    default:
      return 1e-6 * fmin(x[k], 1.0 - x[k]);
  }
}

/* Compares every derivative at p; returns the worst error / tolerance. */
static double compare_gradient(const grad_point *p, const char *where) {
  double f[NF], g[NF][NX], worst = 0.0;
  eval_point(p, p->x, f, g);
  for (int k = 0; k < NX; ++k) {
    double h = step_of(p, k);
    if (!(h > 0.0)) continue;
    double xp[NX], xm[NX], fp[NF], fm[NF];
    memcpy(xp, p->x, sizeof xp), memcpy(xm, p->x, sizeof xm);
    xp[k] += h, xm[k] -= h;
    h = 0.5 * (xp[k] - xm[k]);                          /* the steps as represented */
    if (xp[k] == p->x[k] || xm[k] == p->x[k]) continue; /* sin²θ_h = 1 − 1e-23: no step */
    eval_point(p, xp, fp, NULL);
    eval_point(p, xm, fm, NULL);
    for (int j = 0; j < NF; ++j) {
      double fd = (fp[j] - fm[j]) / (2.0 * h);
      double scale = fmax(fmax(fabs(f[j]), fabs(fp[j])), fabs(fm[j]));
      /* rounding: a few ε |f| / h; above γ = 1e3 the fraction B_z(a, 1/2)
       * near its switch point carries up to 1e-12 relative (docs/model.md §2.8) */
      double noise = p->x[1] > 1e3 ? 1e-11 : 1e-13;
      /* + 1e-280: subnormal values (D far in its tail) have no digits to compare */
      double tol = 1e-6 * fmax(fabs(g[j][k]), fabs(fd)) + noise * scale / h + 1e-280;
      double err = g[j][k] == fd ? 0.0 : fabs(g[j][k] - fd) / tol;
      CHECK(err <= 1.0,
            "%s: d%s/d%s = %.10g, differences %.10g (a2 %g gamma %.17g sin2 %g c_i %g c_o %g)",
            where, f_names[j], x_names[k], g[j][k], fd, p->x[0], p->x[1], p->x[4], p->x[5],
            p->x[6]);
      if (err > worst || err != err) worst = err != err ? INFINITY : err;
    }
  }
  return worst;
}

static double random_gamma(cf_rng *rng) {
  double u = cf_rng_uniform(rng);
  if (u < 0.1) return 2.0;
  if (u < 0.4) return cf_rng_range(rng, 1.5, 4.0);
  if (u < 0.7) return 1.5 + pow(10.0, cf_rng_range(rng, -4.0, 0.0));
  return pow(10.0, cf_rng_range(rng, log10(4.0), 5.0));
}

static grad_point point_of(const lobe_case *k, double gamma) {
  grad_point p = {{k->a2, gamma, k->f0, k->g.weight_d, k->g.sin2_h, k->g.cos_i, k->g.cos_o},
                  k->g.cos2_h};
  return p;
}

static void check_gradients(cf_rng *rng) {
  double worst_random = 0.0, worst_hard = 0.0;
  for (int i = 0; i < 4000; ++i) {
    lobe_case k = random_case(rng, 0.2);
    if (k.g.cos_i >= 1.0 || k.g.cos_o >= 1.0) continue;
    grad_point p = point_of(&k, random_gamma(rng));
    worst_random = fmax(worst_random, compare_gradient(&p, "random"));
  }
  /* the hard cases: grazing and near-normal cosines, α at both ends, γ at
   * the masking's limit, at GGX, large, and in the Beckmann regime */
  static const double rs[] = {0.03, 1.0};
  static const double gammas[] = {1.5 + 1e-4, 1.5 + 1e-2, 2.0, 3.0, 1e5, 2e6};
  static const double cs[] = {1e-8, 1e-3, 0.5, 1.0 - 1e-6};
  static const double phis[] = {0.0, 0.5 * PI, PI};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 6; ++b)
      for (int i = 0; i < 4; ++i)
        for (int o = 0; o < 4; ++o)
          for (int q = 0; q < 3; ++q) {
            double n[3] = {0, 0, 1}, l[3], v[3];
            direction_from(cs[i], 0.0, l);
            direction_from(cs[o], phis[q], v);
            lobe_case k = {pow(rs[a], 4), 0.04, cf_geometry_from_directions(n, l, v)};
            if (!cf_geometry_is_lit(&k.g)) continue;
            grad_point p = point_of(&k, gammas[b]);
            worst_hard = fmax(worst_hard, compare_gradient(&p, "hard case"));
          }
  printf("derivatives: worst error / tolerance %.2g (random), %.2g (hard cases)\n", worst_random,
         worst_hard);
}

/* ---- 6. reciprocity ---- */

static void check_reciprocity(cf_rng *rng) {
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    lobe_case k = random_case(rng, 0.2);
    cf_std_tail t = cf_std_tail_prepare(k.a2, random_gamma(rng));
    const cf_geometry *g = &k.g;
    cf_std_lobe a =
        cf_std_lobe_eval(&t, k.f0, g->weight_d, g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, 1);
    cf_std_lobe b =
        cf_std_lobe_eval(&t, k.f0, g->weight_d, g->sin2_h, g->cos2_h, g->cos_o, g->cos_i, 1);
    double e = fmax(fmax(rel(a.value, b.value), rel(a.d_gamma, b.d_gamma)),
                    fmax(rel(a.d_ci, b.d_co), rel(a.d_a2, b.d_a2)));
    CHECK(e <= 1e-12, "reciprocity: f(l, v) %.17g, f(v, l) %.17g (gamma %g)", a.value, b.value,
          t.gamma);
    worst = fmax(worst, e);
  }
  printf("reciprocity: worst relative difference %.2g\n", worst);
}

/* ---- 7. the white furnace: R(v) = ∫ D V c_i dω_l with F = 1, over the
 * half vector h (dω_l = 4 (v·h) dω_h), h at slope x = tan θ_h / α and
 * azimuth φ from v's; c_i = 2 (v·h) cos θ_h − c_o > 0 below φ_max ---- */

typedef struct furnace_args {
  const cf_std_tail *t;
  double alpha, c_o, s_o;
  double sin2, cos2, cos_h, sin_h; /* of the current θ_h */
} furnace_args;

static double furnace_inner(double phi, void *user) {
  const furnace_args *f = user;
  double vh = f->s_o * f->sin_h * cos(phi) + f->c_o * f->cos_h;
  double c_i = 2.0 * vh * f->cos_h - f->c_o;
  if (!(c_i > 0.0)) return 0.0;
  if (c_i > 1.0) c_i = 1.0;
  double d = std_d(f->t, f->sin2, f->cos2).value;
  double v = cf_std_v_eval(f->t, c_i, f->c_o, 0).value;
  return 4.0 * d * v * c_i * vh;
}

static double furnace_outer(double u, void *user) {
  furnace_args *f = user;
  if (u >= 1.0) return 0.0;
  double x = u / (1.0 - u), dx = 1.0 / ((1.0 - u) * (1.0 - u));
  double tan2 = f->alpha * f->alpha * x * x;
  f->cos2 = 1.0 / (1.0 + tan2);
  f->sin2 = tan2 / (1.0 + tan2);
  f->cos_h = sqrt(f->cos2);
  f->sin_h = sqrt(f->sin2);
  /* c_i > 0 ⇔ cos φ > κ */
  double phi_max = PI;
  if (f->s_o > 0.0 && f->sin_h > 0.0) {
    double kappa = (0.5 * f->c_o / f->cos_h - f->c_o * f->cos_h) / (f->s_o * f->sin_h);
    if (kappa >= 1.0) return 0.0;
    if (kappa > -1.0) phi_max = acos(kappa);
  } else if (2.0 * f->cos2 <= 1.0) {
    return 0.0;
  }
  double inner = 2.0 * adaptive(furnace_inner, f, 0.0, phi_max, 1e-9, 0);
  /* sin θ dθ = sin θ cos²θ α dx */
  return inner * f->sin_h * f->cos2 * f->alpha * dx;
}

static void check_white_furnace(void) {
  static const double rs[] = {0.03, 0.3, 0.6, 1.0};
  static const double gammas[] = {1.51, 1.6, 2.0, 3.0, 10.0, 100.0};
  static const double cos_o[] = {1.0, 0.7, 0.3, 0.1, 0.02};
  double worst = 0.0, at_r = 0, at_gamma = 0, at_c = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 5; ++k) {
        cf_std_tail t = cf_std_tail_prepare(pow(rs[i], 4), gammas[j]);
        furnace_args f = {
            &t, rs[i] * rs[i], cos_o[k], sqrt((1 - cos_o[k]) * (1 + cos_o[k])), 0, 0, 0, 0};
        double albedo = adaptive(furnace_outer, &f, 0.0, 1.0, 1e-7, 0);
        CHECK(albedo <= 1.0 + 1e-3 && albedo > 0.0, "furnace: r %g gamma %g c_o %g: albedo %.9g",
              rs[i], gammas[j], cos_o[k], albedo);
        if (albedo > worst) worst = albedo, at_r = rs[i], at_gamma = gammas[j], at_c = cos_o[k];
      }
  printf("white furnace: largest directional albedo %.7f (r %g, gamma %g, c_o %g)\n", worst, at_r,
         at_gamma, at_c);
}

/* ---- 7b. the lobe over blocks (tailed_block.c): the vector path's exp
 * and log1p against libm, and its D V against std_dv's ---- */

/* |a − b| in units of b's last place (of the least subnormal below DBL_MIN) */
static double ulps_from(double a, double b) {
  if (a == b) return 0.0;
  double b_abs = fabs(b), ulp = nextafter(b_abs, INFINITY) - b_abs;
  return fabs(a - b) / (b_abs < DBL_MIN ? 0x1p-1074 : ulp);
}

/* exp over y in [−745, 0] (y = γ ln r) and log1p over x in [0, 1e70]
 * (x = tan²θ_h/β²; up to 1e66 at the floors), each within 1 ulp of libm
 * (libm's exp and log1p are themselves within 1 ulp). */
static void check_block_math(cf_rng *rng) {
  double worst_exp = 0.0, worst_log = 0.0, at_exp = 0.0, at_log = 0.0;
  for (int i = 0; i < 250000; ++i) {
    double y[CF_STD_BLOCK], x[CF_STD_BLOCK], e[CF_STD_BLOCK], l[CF_STD_BLOCK];
    for (int k = 0; k < CF_STD_BLOCK; ++k) {
      double u = cf_rng_uniform(rng);
      y[k] = (k & 1) ? -745.0 * u : -u * pow(10.0, cf_rng_range(rng, -20.0, 1.0));
      x[k] = (k & 1) ? pow(10.0, cf_rng_range(rng, -300.0, 70.0)) : 4.0 * u;
    }
    if (i == 0) y[0] = 0.0, y[1] = -745.0, x[0] = 0.0, x[1] = 1e-320; /* 0 and a subnormal */
    cf_std_block_exp(y, e);
    cf_std_block_log1p(x, l);
    for (int k = 0; k < CF_STD_BLOCK; ++k) {
      double de = ulps_from(e[k], exp(y[k])), dl = ulps_from(l[k], log1p(x[k]));
      if (de > worst_exp) worst_exp = de, at_exp = y[k];
      if (dl > worst_log) worst_log = dl, at_log = x[k];
    }
  }
  CHECK(worst_exp <= 1.0, "block exp: %.2f ulps from libm at %.17g", worst_exp, at_exp);
  CHECK(worst_log <= 1.0, "block log1p: %.2f ulps from libm at %.17g", worst_log, at_log);
  printf("block exp and log1p (%s): %.2f and %.2f ulps from libm at worst\n",
         cf_std_block_vector() ? "the vector path" : "libm's, no vector path here", worst_exp,
         worst_log);
}

/* One entry of the vector path against std_dv's: |Δ| <= tol (|x| + |D V| s),
 * s the entry's natural scale (below). */
static double block_error(double vec, double ref, double dv, double scale) {
  if (vec == ref) return 0.0;
  if (!isfinite(vec) || !isfinite(ref)) return INFINITY;
  return fabs(vec - ref) / (fabs(ref) + fabs(dv) * scale);
}

/* The vector path's D V and its partials against std_dv (the scalar path)
 * on random geometries (a third grazing) and the hard-case grid, over the
 * tail's range and r from 0.03 to 1. The tolerance is relative, scaled by
 * what an error of ε in ln r (the scalar path takes ln(1 + x), the vector
 * path log1p) does to D (γ ε, and |γ ln r| ε through exp): every entry
 * within tol (1 + γ + |γ ln r|)(|x| + |D V| s) of std_dv's, s its natural
 * scale: 0 for D V, 1/α² for ∂/∂α², 1 + |ln r| for ∂/∂γ, (γ + 2)/(q cos²θ_h)
 * for ∂/∂sin²θ_h, 1/c for ∂/∂c. */
#define BLOCK_TOLERANCE 1e-14
static void check_block_lobe(cf_rng *rng) {
  enum { MAX = 512 };
  static double n[MAX][3], l[MAX][3], v[MAX][3];
  size_t hard = hard_geometries(n, l, v, MAX);
  static const double gammas[] = {1.5 + 1e-6, 1.55, 1.7,  1.9,   2.5, 3.0,  5.0,
                                  20.0,       63.0, 64.0, 100.0, 1e4, 9.9e5};
  const int n_gamma = (int)(sizeof gammas / sizeof gammas[0]);
  double worst[6] = {0.0};
  static const char *const names[6] = {"D V", "d_a2", "d_gamma", "d_sin2", "d_ci", "d_co"};
  long count = 0;
  for (int j = 0; j < n_gamma; ++j) {
    cf_std_table tb;
    cf_std_table_build(&tb, gammas[j]);
    for (int block = 0; block < 400 + (int)hard / CF_STD_BLOCK + 1; ++block) {
      /* two lobes of one tail, as M4T's film and base; r at its bounds too */
      cf_std_tail t[2];
      cf_std_block_in in[2];
      for (int lobe = 0; lobe < 2; ++lobe) {
        int pick = (2 * block + lobe) % 5;
        double r = pick == 0 ? 0.03 : pick == 1 ? 1.0 : cf_rng_range(rng, 0.03, 1.0);
        t[lobe] = cf_std_tail_prepare(r * r * r * r, gammas[j]);
        for (int k = 0; k < CF_STD_BLOCK; ++k) {
          size_t h = block < 400 || lobe ? hard : (size_t)(block - 400) * CF_STD_BLOCK + (size_t)k;
          cf_geometry g =
              h < hard ? cf_geometry_from_directions(n[h], l[h], v[h]) : random_case(rng, 0.3).g;
          if (!cf_geometry_is_lit(&g)) g = random_case(rng, 0.3).g;
          in[lobe].sin2[k] = g.sin2_h, in[lobe].cos2[k] = g.cos2_h;
          in[lobe].c_i[k] = g.cos_i, in[lobe].c_o[k] = g.cos_o;
        }
      }
      cf_std_dv_block vec[2], ref[2];
      cf_std_dv_block_eval(t, &tb, 1, 2, in, 1, vec);
      cf_std_dv_block_eval(t, &tb, 0, 2, in, 1, ref);
      for (int lobe = 0; lobe < 2; ++lobe)
        for (int k = 0; k < CF_STD_BLOCK; ++k) {
          const cf_std_tail *tl = &t[lobe];
          const cf_std_block_in *x = &in[lobe];
          const cf_std_dv_block *a = &vec[lobe], *b = &ref[lobe];
          double c2 = x->cos2[k] > CF_STD_COS2_MIN ? x->cos2[k] : CF_STD_COS2_MIN;
          double q = x->sin2[k] + tl->b2 * c2, ln_r = -log1p(x->sin2[k] / (tl->b2 * c2));
          double dv = b->value[k], amp = 1.0 + tl->gamma + fabs(tl->gamma * ln_r);
          double e[6] = {
              block_error(a->value[k], b->value[k], 0.0, 0.0) / amp,
              block_error(a->d_a2[k], b->d_a2[k], dv, 1.0 / tl->a2) / amp,
              block_error(a->d_gamma[k], b->d_gamma[k], dv, 1.0 + fabs(ln_r)) / amp,
              block_error(a->d_sin2[k], b->d_sin2[k], dv, (tl->gamma + 2.0) / (q * c2)) / amp,
              block_error(a->d_ci[k], b->d_ci[k], dv, 1.0 / x->c_i[k]) / amp,
              block_error(a->d_co[k], b->d_co[k], dv, 1.0 / x->c_o[k]) / amp,
          };
          for (int m = 0; m < 6; ++m) {
            CHECK(e[m] <= BLOCK_TOLERANCE,
                  "block lobe %s: gamma %g a2 %g sin2 %g cos2 %g c_i %g c_o %g: %.17g, std_dv "
                  "%.17g",
                  names[m], tl->gamma, tl->a2, x->sin2[k], x->cos2[k], x->c_i[k], x->c_o[k],
                  (&a->value[0])[m * CF_STD_BLOCK + k], (&b->value[0])[m * CF_STD_BLOCK + k]);
            if (e[m] > worst[m]) worst[m] = e[m];
          }
          ++count;
        }
    }
  }
  printf("block lobe (%s) against std_dv, %ld evaluations: worst scaled errors",
         cf_std_block_vector() ? "vector path" : "no vector path here: std_dv itself", count);
  for (int m = 0; m < 6; ++m) printf(" %s %.2g", names[m], worst[m]);
  printf(" (tolerance %.0e)\n", BLOCK_TOLERANCE);
}

/* ---- 8. the hard-case grid and the Beckmann limit ---- */

#ifndef HARD_ANGLE_MIN
#define HARD_ANGLE_MIN 1e-200
#endif
static void check_hard_grid(void) {
  enum { MAX = 512 };
  static double n[MAX][3], l[MAX][3], v[MAX][3];
  size_t count = hard_geometries(n, l, v, MAX);
  /* and grazing pairs whose half vector reaches D's floor: l = v at 1e-45 and 1e-100 */
  static const double extra[] = {1e-20, 1e-45, 1e-100};
  for (int i = 0; i < 3; ++i)
    for (int a = 0; a < 3 && count < MAX; ++a, ++count) {
      n[count][0] = n[count][1] = 0.0, n[count][2] = 1.0;
      direction_from(extra[i], 0.0, l[count]);
      direction_from(extra[i], 0.5 * PI * a, v[count]);
    }
  static const double rs[] = {0.03, 1.0};
  static const double gammas[] = {1.5 + 1e-9, 1.5 + 1e-3, 1.7, 2.0, 3.0, 1e5, 1e6, 1e12};
  long lit = 0, bad = 0;
  for (size_t c = 0; c < count; ++c) {
    cf_geometry g = cf_geometry_from_directions(n[c], l[c], v[c]);
    if (!cf_geometry_is_lit(&g)) continue;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 8; ++j)
        for (int f = 0; f < 2; ++f) {
          cf_std_tail t = cf_std_tail_prepare(pow(rs[i], 4), gammas[j]);
          cf_std_lobe s = cf_std_lobe_eval(&t, f ? 0.25 : 0.0, g.weight_d, g.sin2_h, g.cos2_h,
                                           g.cos_i, g.cos_o, 1);
          int ok = isfinite(s.value) && s.value >= 0.0 && isfinite(s.d_a2) && isfinite(s.d_gamma) &&
                   isfinite(s.d_f0) && isfinite(s.d_weight);
          /* ∂V/∂c ∝ V² ∝ 1/(c_i + c_o)²: with D's growth at θ_h → 90° for γ < 2
           * finite where c_i c_o >= 1e-200 (docs/model.md §2.8) */
          if (g.cos_i * g.cos_o >= HARD_ANGLE_MIN)
            ok = ok && isfinite(s.d_sin2) && isfinite(s.d_ci) && isfinite(s.d_co);
          ++lit;
          if (!ok) {
            ++bad;
            CHECK(0,
                  "hard case: c_i %g c_o %g cos2_h %g r %g gamma %g: value %g d_a2 %g d_gamma %g "
                  "d_ci %g d_sin2 %g",
                  g.cos_i, g.cos_o, g.cos2_h, rs[i], gammas[j], s.value, s.d_a2, s.d_gamma, s.d_ci,
                  s.d_sin2);
          }
        }
  }
  CHECK(lit > 1000, "only %ld lit hard cases", lit);
  printf("hard-case grid: %ld lit evaluations, %ld not finite\n", lit, bad);
}

/* Beckmann's D with the same α, exp(−tan²/α²)/(π α² cos⁴) */
static double beckmann_d(double a2, double sin2, double cos2) {
  return exp(-sin2 / (cos2 * a2)) / (PI * a2 * cos2 * cos2);
}

static void check_beckmann_limit(void) {
  double worst_d = 0.0, worst_l = 0.0;
  for (double r = 0.03; r <= 1.0; r *= 1.6) {
    double a2 = pow(r, 4);
    cf_std_tail big = cf_std_tail_prepare(a2, 1e12);
    for (double t2 = 0.0; t2 <= 10.0 * a2; t2 += a2) { /* tan²θ_h up to 10 α² */
      double cos2 = 1.0 / (1.0 + t2), sin2 = t2 / (1.0 + t2);
      worst_d = fmax(worst_d, rel(std_d(&big, sin2, cos2).value, beckmann_d(a2, sin2, cos2)));
    }
    /* the masking on both sides of the switch to Beckmann's */
    cf_std_tail below = cf_std_tail_prepare(a2, nextafter(CF_STD_GAMMA_BECKMANN, 0.0));
    cf_std_tail at = cf_std_tail_prepare(a2, CF_STD_GAMMA_BECKMANN);
    CHECK(below.regime == CF_STD_GENERAL && at.regime == CF_STD_BECKMANN, "regimes at the switch");
    for (double c = 1e-6; c < 1.0; c *= 1.7) {
      double lb = cf_std_masking_eval(&below, c, 0).value,
             la = cf_std_masking_eval(&at, c, 0).value;
      worst_l = fmax(worst_l, rel(lb, la));
    }
  }
  CHECK(worst_d <= 1e-10, "D at gamma 1e12 against Beckmann: worst relative %.3g", worst_d);
  CHECK(worst_l <= 1e-5, "masking across the Beckmann switch: worst relative jump %.3g", worst_l);
  printf(
      "Beckmann limit: D(gamma = 1e12) within %.2g of Beckmann's; masking jumps by at most "
      "%.2g (relative L) at gamma = %g\n",
      worst_d, worst_l, CF_STD_GAMMA_BECKMANN);
}

/* ---- 9. the masking tabulated once per γ (tailed.h, docs/model.md §2.8
 * "The table"): against the exact masking, its derivatives against
 * differences of its own value, GGX at γ = 2, the hard cases, reciprocity ---- */

/* c from 0 to 1: uniform, log-spaced toward 0 and toward 1 */
enum { TABLE_CS = 1201 };
static double table_c(int i) {
  if (i <= 400) return i / 400.0;
  if (i <= 800) return pow(10.0, -10.0 + 10.0 * (i - 400) / 400.0);
  return 1.0 - pow(10.0, -15.0 * (i - 800) / 400.0);
}

static const double table_gammas[] = {1.5 + 1e-6, 1.501, 1.51, 1.52, 1.54, 1.55, 1.56, 1.6, 1.7,
                                      1.8,        1.9,   1.99, 2.0,  2.01, 2.2,  2.5,  3.0, 3.7,
                                      5.0,        10.0,  30.0, 100,  1e3,  1e4,  1e5,  5e5, 9.99e5};
#define TABLE_GAMMA_ASSERTED 1.55 /* below: printed, not asserted */

/* the worst relative error of the table's L against the exact masking */
static double table_error(const cf_std_table *tb, double gamma) {
  static const double rs[] = {0.03, 0.05, 0.08, 0.13, 0.2, 0.3, 0.45, 0.6, 0.8, 1.0};
  double worst = 0.0;
  for (int i = 0; i < 10; ++i) {
    cf_std_tail t = cf_std_tail_prepare(pow(rs[i], 4), gamma);
    t.regime = CF_STD_GENERAL; /* γ = 2: the general formulas (1e-15 from GGX's) */
    for (int k = 0; k < TABLE_CS; ++k) {
      double c = table_c(k);
      double exact = cf_std_masking_eval(&t, c, 0).value;
      double tab = std_masking_tabulated(tb, t.a2, c, 0).value;
      worst = fmax(worst, rel(tab, exact));
    }
  }
  return worst;
}

static void check_table_accuracy(void) {
  double worst = 0.0, worst_exact_nodes = 0.0, worst_low = 0.0, worst_slice = 0.0;
  static cf_std_table tb, exact;
  for (size_t i = 0; i < sizeof table_gammas / sizeof table_gammas[0]; ++i) {
    double gamma = table_gammas[i];
    cf_std_table_build(&tb, gamma);
    cf_std_table_build_exact(&exact, gamma);
    CHECK(tb.built && exact.built, "gamma %g: table not built", gamma);
    double e = table_error(&tb, gamma), e_exact = table_error(&exact, gamma);
    if (gamma >= TABLE_GAMMA_ASSERTED) {
      CHECK(e <= 1e-6, "gamma %g: table against the exact masking, worst relative %.3g", gamma, e);
      worst = fmax(worst, e);
      worst_exact_nodes = fmax(worst_exact_nodes, e_exact);
    } else {
      printf("table below gamma %g: gamma %.7g worst relative %.2g (exact nodes %.2g)\n",
             TABLE_GAMMA_ASSERTED, gamma, e, e_exact);
      worst_low = fmax(worst_low, e);
    }
    /* the grid's slice against the exact nodes (the γ interpolation alone):
     * c[0] is g at a step's lower node */
    for (int k = 0; k < CF_STD_TABLE_STEPS; ++k)
      worst_slice = fmax(worst_slice, rel(tb.step[k].c[0], exact.step[k].c[0]));
  }
  /* at the grid's own γ the slice is the exact nodes */
  double worst_at_nodes = 0.0;
  for (int j = 0; j < CF_STD_GRID_GAMMAS; j += 4) {
    double gamma = 1.0 + 1.0 / std_grid_p(j);
    if (!(gamma < CF_STD_GAMMA_BECKMANN)) continue;
    cf_std_table_build(&tb, gamma);
    cf_std_table_build_exact(&exact, gamma);
    double scale = 0.0; /* ∂g/∂γ underflows at some nodes: against its largest */
    for (int k = 0; k < CF_STD_TABLE_STEPS; ++k) scale = fmax(scale, fabs(exact.step[k].d[0]));
    for (int k = 0; k < CF_STD_TABLE_STEPS; ++k)
      worst_at_nodes =
          fmax(worst_at_nodes, fmax(rel(tb.step[k].c[0], exact.step[k].c[0]),
                                    fabs(tb.step[k].d[0] - exact.step[k].d[0]) / scale));
  }
  CHECK(worst_at_nodes <= 1e-9, "the slice at the grid's gammas: %.3g from the exact nodes",
        worst_at_nodes);
  CHECK(std_grid_p(16) == 1.0, "the grid has a node at GGX");
  /* no table where the lobe needs none */
  cf_std_table_build(&tb, 1.5);
  CHECK(!tb.built, "a table at gamma 1.5");
  cf_std_table_build(&tb, CF_STD_GAMMA_BECKMANN);
  CHECK(!tb.built, "a table in the Beckmann regime");
  printf(
      "table: worst relative error of L %.2g for gamma in [%g, 1e6) (exact nodes %.2g; the "
      "grid's gamma interpolation %.2g at the nodes, %.2g at its own gammas); below gamma %g: "
      "%.2g\n",
      worst, TABLE_GAMMA_ASSERTED, worst_exact_nodes, worst_slice, worst_at_nodes,
      TABLE_GAMMA_ASSERTED, worst_low);
}

/* The table's first node, u = 0 (w = 1): ∂g/∂w and ∂²g/∂w∂γ there are limits
 * (tailed.c, first_node_slopes); against −(∂g/∂u)/(2u) from the exact masking
 * at u = 1e-4, where the difference is O(u²), and its central difference in γ. */
static void check_table_first_node(void) {
  static const double gammas[] = {1.51, 1.6, 2.0, 2.5, 5.0, 30.0, 1e3};
  static cf_std_node node[CF_STD_TABLE_NODES];
  const double u = 1e-4, s2 = (1.0 - u) * (1.0 + u);
  double worst = 0.0, worst_gamma = 0.0;
  for (size_t i = 0; i < sizeof gammas / sizeof gammas[0]; ++i) {
    double gamma = gammas[i], h = 1e-4 * fmin(gamma - 1.5, 0.1); /* the pole at 1.5 */
    cf_std_table_nodes_exact(node, gamma);
    CHECK(cf_std_table_position(0) == 1.0, "the first node is at w = 1");
    double slope[3];
    for (int k = 0; k < 3; ++k) { /* at γ, γ + h, γ − h */
      cf_std_tail t = cf_std_tail_prepare(1.0, gamma + (k == 0 ? 0.0 : k == 1 ? h : -h));
      t.regime = CF_STD_GENERAL;
      slope[k] = -0.5 * cf_std_node_exact(&t, u, s2).g_w / u;
    }
    double e = fabs(node[0].g_w - slope[0]) / fmax(1.0, fabs(slope[0]));
    double fd = (slope[1] - slope[2]) / (2.0 * h);
    double e_gamma = fabs(node[0].g_w_gamma - fd) / fmax(1.0, fabs(fd));
    CHECK(e <= 1e-6 && e_gamma <= 1e-6,
          "gamma %g: first node dg/dw %.12g against %.12g, d2g/dwdgamma %.12g against %.12g", gamma,
          node[0].g_w, slope[0], node[0].g_w_gamma, fd);
    worst = fmax(worst, e);
    worst_gamma = fmax(worst_gamma, e_gamma);
  }
  printf("table's first node (u = 0): dg/dw within %.2g, d2g/dw dgamma within %.2g of the limit\n",
         worst, worst_gamma);
}

/* The tabulated lobe D V at x = {α², γ, −, −, sin²θ_h, c_i, c_o}, its table
 * built for x's γ (exact nodes or the grid's slice). */
static void eval_tabulated(const grad_point *p, const double *x, int exact_nodes, double *f,
                           double g[NX]) {
  static cf_std_table tb;
  if (exact_nodes)
    cf_std_table_build_exact(&tb, x[1]);
  else
    cf_std_table_build(&tb, x[1]);
  cf_std_tail t = cf_std_tail_prepare(x[0], x[1]);
  double cos2 = p->cos2 - (x[4] - p->x[4]);
  cf_std_dv s = cf_std_dv_eval(&t, &tb, x[4], cos2, x[5], x[6], g != NULL);
  *f = s.value;
  if (!g) return;
  double gs[NX] = {s.d_a2, s.d_gamma, 0, 0, s.d_sin2, s.d_ci, s.d_co};
  memcpy(g, gs, sizeof gs);
}

static double compare_tabulated_gradient(const grad_point *p, int exact_nodes, const char *where) {
  double f, g[NX], worst = 0.0;
  eval_tabulated(p, p->x, exact_nodes, &f, g);
  for (int k = 0; k < NX; ++k) {
    if (k == 2 || k == 3) continue; /* F0, weight: the caller's Fresnel */
    /* γ: a larger step, for the slice's rounding near γ = 1.5 (5e-13 relative:
     * its variable p = 1/(γ − 1) carries 1e-16 absolute, and h ∝ 2γ − 3) */
    double h = k == 1 ? fmin(1e-6 * p->x[1], 1e-4 * (p->x[1] - CF_STD_GAMMA_MIN)) : step_of(p, k);
    if (!(h > 0.0)) continue;
    double xp[NX], xm[NX], fp, fm;
    memcpy(xp, p->x, sizeof xp), memcpy(xm, p->x, sizeof xm);
    xp[k] += h, xm[k] -= h;
    h = 0.5 * (xp[k] - xm[k]);
    if (xp[k] == p->x[k] || xm[k] == p->x[k]) continue;
    eval_tabulated(p, xp, exact_nodes, &fp, NULL);
    eval_tabulated(p, xm, exact_nodes, &fm, NULL);
    double fd = (fp - fm) / (2.0 * h);
    double scale = fmax(fmax(fabs(f), fabs(fp)), fabs(fm));
    double tol = 1e-6 * fmax(fabs(g[k]), fabs(fd)) + 1e-13 * scale / h + 1e-280;
    double err = g[k] == fd ? 0.0 : fabs(g[k] - fd) / tol;
    CHECK(err <= 1.0,
          "%s: d(DV)/d%s = %.10g, differences %.10g (a2 %g gamma %.17g sin2 %g c_i %g c_o %g)",
          where, x_names[k], g[k], fd, p->x[0], p->x[1], p->x[4], p->x[5], p->x[6]);
    if (err > worst || err != err) worst = err != err ? INFINITY : err;
  }
  return worst;
}

static void check_table_gradients(cf_rng *rng) {
  double worst = 0.0, worst_exact = 0.0, worst_hard = 0.0;
  for (int i = 0; i < 3000; ++i) {
    lobe_case k = random_case(rng, 0.2);
    if (k.g.cos_i >= 1.0 || k.g.cos_o >= 1.0) continue;
    double gamma = random_gamma(rng);
    if (gamma >= CF_STD_GAMMA_BECKMANN) gamma = 2.5;
    grad_point p = point_of(&k, gamma);
    worst = fmax(worst, compare_tabulated_gradient(&p, 0, "tabulated"));
    if (i % 20 == 0)
      worst_exact = fmax(worst_exact, compare_tabulated_gradient(&p, 1, "tabulated, exact nodes"));
  }
  /* near-normal and grazing cosines, both ends of α, γ near 1.5, at 2, large */
  static const double rs[] = {0.03, 1.0};
  static const double gammas[] = {1.5 + 1e-4, 1.5 + 1e-2, 2.0, 3.0, 1e5};
  static const double cs[] = {1e-8, 1e-3, 0.5, 1.0 - 1e-6};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 5; ++b)
      for (int i = 0; i < 4; ++i)
        for (int o = 0; o < 4; ++o) {
          double n[3] = {0, 0, 1}, l[3], v[3];
          direction_from(cs[i], 0.0, l);
          direction_from(cs[o], 0.5 * PI, v);
          lobe_case k = {pow(rs[a], 4), 0.04, cf_geometry_from_directions(n, l, v)};
          if (!cf_geometry_is_lit(&k.g)) continue;
          grad_point p = point_of(&k, gammas[b]);
          worst_hard = fmax(worst_hard, compare_tabulated_gradient(&p, 0, "tabulated hard case"));
        }
  printf(
      "tabulated lobe derivatives against differences of its value: worst error / tolerance %.2g "
      "(random), %.2g (exact nodes), %.2g (hard cases)\n",
      worst, worst_exact, worst_hard);
}

static void check_table_ggx_reciprocity_hard(cf_rng *rng) {
  /* γ = 2: GGX's code to the bit, in dielectric.c's order F (D V) */
  long unequal = 0;
  static cf_std_lobe_prep prep;
  for (int i = 0; i < 20000; ++i) {
    lobe_case k = random_case(rng, 0.2);
    const cf_geometry *g = &k.g;
    cf_ggx_d gd = ggx_d(k.a2, 1.0 / k.a2, g->sin2_h, g->cos2_h);
    cf_smith_v gv = smith_ggx_v(k.a2, g->cos_i, g->cos_o);
    double fresnel = fresnel_schlick(k.f0, g->weight_d);
    if (i % 1000 == 0) cf_std_lobe_prepare(&prep, k.a2, 2.0);
    prep.tail = cf_std_tail_prepare(k.a2, 2.0);
    cf_std_dv s =
        cf_std_dv_eval(&prep.tail, &prep.table, g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, 1);
    cf_std_dv r = cf_ggx_dv_eval(k.a2, g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, 1);
    unequal += fresnel * s.value != fresnel * (gd.value * gv.value) ||
               fresnel * s.d_a2 != fresnel * (gd.d_a2 * gv.value + gd.value * gv.d_a2) ||
               s.d_sin2 != gd.d_sin2 * gv.value || s.d_ci != gd.value * gv.d_ci ||
               s.d_co != gd.value * gv.d_co || s.value != r.value || s.d_a2 != r.d_a2 ||
               !(isfinite(s.d_gamma));
  }
  CHECK(unequal == 0, "tabulated lobe at gamma = 2: %ld cases differ from GGX's code", unequal);

  /* reciprocity: one table for both directions */
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    lobe_case k = random_case(rng, 0.2);
    if (i % 500 == 0) {
      double gamma = random_gamma(rng);
      cf_std_lobe_prepare(&prep, k.a2, gamma);
    }
    prep.tail = cf_std_tail_prepare(k.a2, prep.table.gamma);
    const cf_geometry *g = &k.g;
    cf_std_dv a =
        cf_std_dv_eval(&prep.tail, &prep.table, g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, 1);
    cf_std_dv b =
        cf_std_dv_eval(&prep.tail, &prep.table, g->sin2_h, g->cos2_h, g->cos_o, g->cos_i, 1);
    double e = fmax(fmax(rel(a.value, b.value), rel(a.d_gamma, b.d_gamma)),
                    fmax(rel(a.d_ci, b.d_co), rel(a.d_a2, b.d_a2)));
    CHECK(e <= 1e-12, "tabulated reciprocity: %.17g against %.17g (gamma %g)", a.value, b.value,
          prep.table.gamma);
    worst = fmax(worst, e);
  }

  /* the hard-case grid */
  enum { MAX = 512 };
  static double n[MAX][3], l[MAX][3], v[MAX][3];
  size_t count = hard_geometries(n, l, v, MAX);
  static const double rs[] = {0.03, 1.0};
  static const double gammas[] = {1.5 + 1e-9, 1.5 + 1e-3, 1.7, 2.0, 3.0, 1e5, 1e6, 1e12};
  long lit = 0, bad = 0;
  for (int j = 0; j < 8; ++j) {
    cf_std_table_build(&prep.table, gammas[j]);
    for (int i = 0; i < 2; ++i) {
      prep.tail = cf_std_tail_prepare(pow(rs[i], 4), gammas[j]);
      for (size_t c = 0; c < count; ++c) {
        cf_geometry g = cf_geometry_from_directions(n[c], l[c], v[c]);
        if (!cf_geometry_is_lit(&g)) continue;
        cf_std_dv s =
            cf_std_dv_eval(&prep.tail, &prep.table, g.sin2_h, g.cos2_h, g.cos_i, g.cos_o, 1);
        int ok = isfinite(s.value) && s.value >= 0.0 && isfinite(s.d_a2) && isfinite(s.d_gamma);
        if (g.cos_i * g.cos_o >= HARD_ANGLE_MIN)
          ok = ok && isfinite(s.d_sin2) && isfinite(s.d_ci) && isfinite(s.d_co);
        ++lit;
        if (!ok) {
          ++bad;
          CHECK(0, "tabulated hard case: c_i %g c_o %g r %g gamma %g: value %g d_gamma %g d_ci %g",
                g.cos_i, g.cos_o, rs[i], gammas[j], s.value, s.d_gamma, s.d_ci);
        }
      }
    }
  }
  /* the masking's own edges: c = 0, 1, one ulp above 1 (a refracted cosine's
   * rounding), subnormal; L = 1 at c = 1 */
  static const double edge_c[] = {0.0, 1.0, 1.0 + 0x1p-52, 1e-310, 0x1p-50};
  for (int j = 0; j < 8; ++j) {
    cf_std_table_build(&prep.table, gammas[j]);
    if (!prep.table.built) continue;
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 5; ++k) {
        cf_std_masking m = std_masking_tabulated(&prep.table, pow(rs[i], 4), edge_c[k], 1);
        int ok = isfinite(m.value) && m.value > 0.0 && isfinite(m.d_c) && isfinite(m.d_a2) &&
                 isfinite(m.d_gamma);
        if (edge_c[k] >= 1.0) ok = ok && fabs(m.value - 1.0) <= 1e-15;
        CHECK(ok, "tabulated masking at c = %.17g (r %g gamma %g): L %.17g d_c %g d_gamma %g",
              edge_c[k], rs[i], gammas[j], m.value, m.d_c, m.d_gamma);
      }
  }
  printf(
      "tabulated lobe: GGX's code to the bit at gamma = 2 (20000 cases); reciprocity worst %.2g; "
      "hard-case grid %ld lit evaluations, %ld not finite\n",
      worst, lit, bad);
}

/* ---- the cost of one evaluation (printed, never asserted) ---- */

static double seconds_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

enum { BENCH_CASES = 4096 };

/* GGX's lobe and its gradient as dielectric.c forms them */
static double ggx_lobe_grad(double a2, double f0, const cf_geometry *g) {
  double fresnel = fresnel_schlick(f0, g->weight_d);
  cf_ggx_d d = ggx_d(a2, 1.0 / a2, g->sin2_h, g->cos2_h);
  cf_smith_v v = smith_ggx_v(a2, g->cos_i, g->cos_o);
  double value = fresnel * (d.value * v.value);
  double d_a2 = fresnel * (d.d_a2 * v.value + d.value * v.d_a2);
  double d_f0 = (1.0 - g->weight_d) * d.value * v.value;
  return value + 1e-30 * (d_a2 + d_f0 + d.d_sin2 + v.d_ci + v.d_co);
}

static double bench(const cf_geometry *g, double a2, double gamma, int with_grad) {
  volatile double sink = 0.0;
  long calls = 0;
  double start = seconds_now(), elapsed;
  cf_std_tail t = cf_std_tail_prepare(a2, gamma);
  do {
    double sum = 0.0;
    for (int i = 0; i < BENCH_CASES; ++i) {
      if (gamma == 0.0) {
        sum += ggx_lobe_grad(a2, 0.04, &g[i]);
      } else {
        cf_std_lobe s = cf_std_lobe_eval(&t, 0.04, g[i].weight_d, g[i].sin2_h, g[i].cos2_h,
                                         g[i].cos_i, g[i].cos_o, with_grad);
        sum += s.value + 1e-30 * (s.d_a2 + s.d_gamma + s.d_ci + s.d_co + s.d_sin2);
      }
    }
    sink += sum;
    calls += BENCH_CASES;
    elapsed = seconds_now() - start;
  } while (elapsed < 0.2);
  (void)sink;
  return 1e9 * elapsed / (double)calls;
}

/* the tabulated D V (cf_std_dv_eval), or GGX's (gamma 0) */
static double bench_dv(const cf_geometry *g, double a2, double gamma, int with_grad) {
  volatile double sink = 0.0;
  long calls = 0;
  double start = seconds_now(), elapsed;
  static cf_std_lobe_prep prep;
  if (gamma > 0.0) cf_std_lobe_prepare(&prep, a2, gamma);
  do {
    double sum = 0.0;
    for (int i = 0; i < BENCH_CASES; ++i) {
      cf_std_dv s = gamma > 0.0 ? cf_std_dv_eval(&prep.tail, &prep.table, g[i].sin2_h, g[i].cos2_h,
                                                 g[i].cos_i, g[i].cos_o, with_grad)
                                : cf_ggx_dv_eval(a2, g[i].sin2_h, g[i].cos2_h, g[i].cos_i,
                                                 g[i].cos_o, with_grad);
      sum += s.value + 1e-30 * (s.d_a2 + s.d_gamma + s.d_ci + s.d_co + s.d_sin2);
    }
    sink += sum;
    calls += BENCH_CASES;
    elapsed = seconds_now() - start;
  } while (elapsed < 0.2);
  (void)sink;
  return 1e9 * elapsed / (double)calls;
}

static void print_cost(cf_rng *rng) {
  static cf_geometry g[BENCH_CASES];
  for (int i = 0; i < BENCH_CASES; ++i) g[i] = random_case(rng, 0.05).g;
  double a2 = pow(0.3, 4);
  double ggx = bench(g, a2, 0.0, 1);
  printf("cost per lobe evaluation, value + gradient (r 0.3, %d random lit pairs): GGX %.1f ns",
         BENCH_CASES, ggx);
  static const double gammas[] = {2.0, 1.6, 2.5, 10.0, 1e3};
  for (int j = 0; j < 5; ++j) {
    double ns = bench(g, a2, gammas[j], 1);
    printf("; STD gamma %g %.1f ns (%.1fx)", gammas[j], ns, ns / ggx);
  }
  printf("; STD gamma 2.5 value only %.1f ns\n", bench(g, a2, 2.5, 0));
  printf("tabulated D V (no Fresnel), value + gradient: GGX %.1f ns", bench_dv(g, a2, 0.0, 1));
  for (int j = 0; j < 5; ++j)
    printf("; gamma %g %.1f ns", gammas[j], bench_dv(g, a2, gammas[j], 1));
  printf("; gamma 2.5 value only %.1f ns (GGX %.1f)\n", bench_dv(g, a2, 2.5, 0),
         bench_dv(g, a2, 0.0, 0));
  static cf_std_table tb;
  double start = seconds_now(), elapsed;
  long builds = 0;
  do {
    cf_std_table_build(&tb, 2.5 + 1e-9 * (double)(builds++ % 1000));
  } while ((elapsed = seconds_now() - start) < 0.1);
  printf("table build: %.2f us from the grid", 1e6 * elapsed / (double)builds);
  start = seconds_now(), builds = 0;
  do {
    cf_std_table_build_exact(&tb, 2.5 + 1e-9 * (double)(builds++ % 1000));
  } while ((elapsed = seconds_now() - start) < 0.1);
  printf(", %.1f us from the exact masking (gamma 2.5)\n", 1e6 * elapsed / (double)builds);
}

/* Usage: test_tailed_lobe [SECTION]: all sections, or the one named
 * (special, ggx, normalisation, gradients, reciprocity, furnace, hard,
 * beckmann, table, block, bench). */
int main(int argc, char **argv) {
  const char *only = argc > 1 ? argv[1] : NULL;
#define SECTION(name, call) \
  if (!only || strcmp(only, name) == 0) call
  cf_rng rng = cf_rng_seed(18);
  SECTION("special", check_special_functions());
  SECTION("ggx", check_ggx_special_case(&rng));
  SECTION("normalisation", check_normalisation_and_masking());
  SECTION("normalisation", check_masking_reference());
  SECTION("gradients", check_gradients(&rng));
  SECTION("reciprocity", check_reciprocity(&rng));
  SECTION("furnace", check_white_furnace());
  SECTION("hard", check_hard_grid());
  SECTION("beckmann", check_beckmann_limit());
  SECTION("table", check_table_accuracy());
  SECTION("table", check_table_first_node());
  SECTION("table", check_table_gradients(&rng));
  SECTION("table", check_table_ggx_reciprocity_hard(&rng));
  SECTION("block", check_block_math(&rng));
  SECTION("block", check_block_lobe(&rng));
  SECTION("bench", print_cost(&rng));
#undef SECTION
  return check_finish("test_tailed_lobe");
}
