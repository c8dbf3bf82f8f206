/* The GGX that best reproduces a tailed (STD) lobe (clayfit/tailed_ggx.h,
 * docs/presets.md "Tailed lobes in GGX-only formats"): the quadrature of the
 * metric, the least-squares problem over it, solved through src/lsq. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/tailed_ggx.h"
#include "lsq/lsq.h"
#include "tailed.h"

/* The metric: a camera sees a sphere lit by a distant point light from a
 * direction drawn uniformly over the sphere of directions. In the local frame
 * of a pixel, the view ω_o then has the density c_o dω_o (the sphere's
 * projected area) and the light ω_i the density dω_i over the upper
 * hemisphere; the pixel's radiance is f · c_i. So
 *   E(g) = ∫∫ (c_i (f_g − f_T))² dω_i c_o dω_o,   loss = √(E(g) / ∫∫ (c_i f_T)² dω_i c_o dω_o),
 * the relative RMS of those pixels over the lobe alone. The quadrature
 * (CF_TAILED_GGX_QUADRATURE: 32 × 32 × 12 Gauss-Legendre points) runs over
 * the view's elevation ψ (c_o = sin ψ, tan ψ = r tan(π u / 2)) and, for
 * each view, over the half vector h (dω_i = 4 (o·h) dω_h): θ_h by
 * tan θ_h = α tan(π u / 2) (the nodes follow D's width α), φ_h over
 * [0, φ_max], where φ_max closes the region c_i > 0 (the integrand vanishes
 * there as c_i², so the rule stays spectral). */

/* clayfit/tailed_ggx.h */
void cf_gauss_legendre01(int n, double *x, double *w) {
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = cos(CF_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p1 = 1.0, p2 = 0.0;
      for (int j = 1; j <= n; ++j) {
        double p3 = p2;
        p2 = p1;
        p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
      }
      dp = n * (z * p1 - p2) / (z * z - 1.0);
      double step = p1 / dp;
      z -= step;
      if (fabs(step) < 1e-15) break;
    }
    x[i] = 0.5 * (1.0 - z);
    x[n - 1 - i] = 0.5 * (1.0 + z);
    w[i] = w[n - 1 - i] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
}

/* The Fresnel of both lobes, the one switch: Schlick's or the exact
 * dielectric one of terms.h (docs/model.md (8)); F and ∂F/∂F0 at c_d. */
typedef struct tail_fresnel_prep {
  cf_tailed_fresnel kind;
  cf_fresnel_eta eta; /* eta.f0: F0 for either kind */
} tail_fresnel_prep;

static tail_fresnel_prep tail_fresnel_prepare(cf_tailed_fresnel kind, double f0) {
  tail_fresnel_prep p = {kind, fresnel_eta(f0)};
  return p;
}

static double tail_fresnel(const tail_fresnel_prep *p, double c_d, double *d_f0) {
  if (p->kind == CF_TAILED_FRESNEL_SCHLICK) {
    double w = schlick_weight(c_d);
    *d_f0 = 1.0 - w;
    return fresnel_schlick(p->eta.f0, w);
  }
  cf_fresnel f = fresnel_dielectric(&p->eta, c_d, fresnel_root(&p->eta, c_d));
  *d_f0 = f.d_f0;
  return f.value;
}

/* One quadrature node: its weight, the factor k of the residual (the
 * pixel's radiance is k·f: c_i in air), its geometry, the tailed lobe. */
typedef struct tail_node {
  double w, k, c_i, c_o, sin2_h, cos2_h, c_d, target;
} tail_node;

/* M4's base under the film (docs/model.md (23)-(26), (30)): the lobe's own
 * directions l', v' are the refracted ones, inside the cone c' >= c_min;
 * an outside pixel sees k·f with, changing variables (dω = η1² c'/c dω'),
 *   E = ∫∫ (k Δf)² dω_i' w_o dω_o',  k² = c_i c_i' T(c_i)² e^(−2τ/c_i'),
 *   w_o = c_o' T(c_o)² e^(−2τ/c_o'),
 * with c the outside cosine of c' and T = 1 − F(F0_1, c). The constants
 * a_tau's mean and 1/η1² drop out of the relative loss. */
typedef struct tail_film {
  cf_fresnel_eta eta1; /* the film's */
  double eta2, c_min, tau;
} tail_film;

static tail_film tail_film_prepare(double film_f0, double tau) {
  tail_film f = {fresnel_eta(film_f0), 0.0, 0.0, tau};
  f.eta2 = 1.0 + f.eta1.u;
  f.c_min = sqrt(f.eta1.u / f.eta2);
  return f;
}

/* c'·T(c)²·e^(−2τ/c') and, in *c_out, the outside cosine c; 0 outside the cone. */
static double tail_film_factor(const tail_film *f, double c_in, double *c_out) {
  double c2 = f->eta2 * c_in * c_in - f->eta1.u;
  *c_out = c2 > 0.0 ? sqrt(c2) : 0.0;
  if (!(*c_out > 0.0)) return 0.0;
  double t = 1.0 - fresnel_dielectric(&f->eta1, *c_out, fresnel_root(&f->eta1, *c_out)).value;
  return c_in * t * t * exp(-2.0 * f->tau / c_in);
}

typedef struct tail_problem {
  tail_node *nodes;
  size_t count;
  double energy; /* Σ w (c_i f_T)²: the loss's denominator */
  cf_tailed_fresnel fresnel;
} tail_problem;

/* The half vectors of one view (c_o, weight w_o): appends the nodes where c_i > 0. */
static void tail_view_nodes(tail_problem *p, const cf_std_tail *t, const tail_fresnel_prep *fresnel,
                            const tail_film *film, double c_o, double w_o,
                            const cf_tailed_ggx_quadrature *q, const double *xu, const double *wu,
                            const double *xp, const double *wp) {
  double s_o = sqrt((1.0 - c_o) * (1.0 + c_o)), alpha = sqrt(t->a2);
  double l_o = cf_std_masking_eval(t, c_o, 0).value;
  /* under a film both directions are in the cone c' >= c_min, and so is h:
   * θ_h's nodes end there (u <= u_max). r 1 under η1 3 (F0_1 0.25): doubling
   * the quadrature moved the loss by 1.9 % with nodes up to 90°, 4e-5 so */
  double u_max = 1.0;
  if (film)
    u_max = 2.0 / CF_PI * atan(sqrt(1.0 - film->c_min * film->c_min) / (film->c_min * alpha));
  for (int a = 0; a < q->thetas; ++a) {
    double tu = tan(0.5 * CF_PI * u_max * xu[a]), tan_h = alpha * tu, tan2 = tan_h * tan_h;
    double dtheta = u_max * alpha * 0.5 * CF_PI * (1.0 + tu * tu) / (1.0 + tan2);
    double cos2_h = 1.0 / (1.0 + tan2), sin2_h = tan2 * cos2_h;
    double c_h = sqrt(cos2_h), s_h = tan_h * c_h;
    /* c_i > 0  <=>  cos φ > −c_o cos 2θ_h / (s_o sin 2θ_h) = num / den */
    double num = -c_o * (cos2_h - sin2_h), den = 2.0 * s_o * s_h * c_h;
    if (num >= den) continue; /* no φ lights this h */
    double phi_max = num <= -den ? CF_PI : acos(num / den);
    for (int b = 0; b < q->phis; ++b) {
      double phi = phi_max * xp[b];
      double c_d = s_o * s_h * cos(phi) + c_o * c_h, c_i = 2.0 * c_d * c_h - c_o;
      if (!(c_i > 0.0) || !(c_d > 0.0)) continue;
      double k = c_i, c_out;
      if (film) {
        k = tail_film_factor(film, c_i, &c_out);
        if (!(k > 0.0)) continue; /* outside the cone: no outside light reaches it */
        k = sqrt(k * c_out);
      }
      tail_node *n = &p->nodes[p->count++];
      n->k = k;
      /* view · θ_h (dθ/du, sin θ_h) · φ (both signs) · dω_i/dω_h */
      n->w = w_o * wu[a] * dtheta * s_h * 2.0 * phi_max * wp[b] * 4.0 * c_d;
      n->c_i = c_i;
      n->c_o = c_o;
      n->sin2_h = sin2_h;
      n->cos2_h = cos2_h;
      n->c_d = c_d;
      /* V of (T6), 0.5 / (c_o L_i + c_i L_o), with L_o once per view: the
       * masking's continued fraction is half the cost of a call */
      double vis = 0.5 / (c_o * cf_std_masking_eval(t, c_i, 0).value + c_i * l_o), d_f0;
      double dv = std_d(t, sin2_h, cos2_h).value * vis;
      n->target = tail_fresnel(fresnel, c_d, &d_f0) * dv;
      double e = k * n->target;
      p->energy += n->w * e * e;
    }
  }
}

static cf_status tail_problem_build(tail_problem *p, double r, double gamma, double f0,
                                    cf_tailed_fresnel fresnel, const tail_film *film,
                                    const cf_tailed_ggx_quadrature *q, cf_error *err) {
  size_t max_nodes = (size_t)q->views * (size_t)q->thetas * (size_t)q->phis;
  int max_rule = q->views > q->thetas ? q->views : q->thetas;
  max_rule = max_rule > q->phis ? max_rule : q->phis;
  memset(p, 0, sizeof *p);
  p->fresnel = fresnel;
  p->nodes = malloc(max_nodes * sizeof *p->nodes);
  double *rules = malloc(6 * (size_t)max_rule * sizeof *rules);
  if (!p->nodes || !rules) {
    free(p->nodes);
    free(rules);
    p->nodes = NULL;
    return cf_error_set(err, CF_ENOMEM, "GGX fit of a tailed lobe: out of memory");
  }
  double *xo = rules, *wo = xo + max_rule, *xu = wo + max_rule, *wu = xu + max_rule;
  double *xp = wu + max_rule, *wp = xp + max_rule;
  cf_gauss_legendre01(q->views, xo, wo);
  cf_gauss_legendre01(q->thetas, xu, wu);
  cf_gauss_legendre01(q->phis, xp, wp);
  cf_std_tail t = cf_std_tail_prepare(r * r * r * r, gamma);
  tail_fresnel_prep fr = tail_fresnel_prepare(fresnel, f0);
  /* views by their elevation ψ (c_o = sin ψ): tan ψ = r tan(π u / 2). A
   * sharp lobe changes over c_o ~ α at grazing and is flat above; the scale
   * r = √α, between the two, needs 32 views where uniform c_o needs 100
   * and the scale α misses the normal views (the doubling test). Under a
   * film, c_o' in [c_min, 1], no grazing view: uniform in c_o'. */
  for (int v = 0; v < q->views && film; ++v) {
    double c_o = film->c_min + (1.0 - film->c_min) * xo[v], c_out;
    double w_o = 2.0 * CF_PI * (1.0 - film->c_min) * wo[v] * tail_film_factor(film, c_o, &c_out);
    if (w_o > 0.0) tail_view_nodes(p, &t, &fr, film, c_o, w_o, q, xu, wu, xp, wp);
  }
  for (int v = 0; v < q->views && !film; ++v) {
    double tu = tan(0.5 * CF_PI * xo[v]), tan_psi = r * tu;
    double dpsi = r * 0.5 * CF_PI * (1.0 + tu * tu) / (1.0 + tan_psi * tan_psi);
    double cos_psi = 1.0 / sqrt(1.0 + tan_psi * tan_psi), c_o = tan_psi * cos_psi;
    /* c_o dω_o = 2π c_o dc_o, dc_o = cos ψ dψ */
    double w_o = 2.0 * CF_PI * c_o * cos_psi * dpsi * wo[v];
    tail_view_nodes(p, &t, &fr, NULL, c_o, w_o, q, xu, wu, xp, wp);
  }
  free(rules);
  return CF_OK;
}

/* E(g) / energy at GGX (r, f0), with its gradient and Gauss-Newton Hessian
 * (JᵀJ) in (r, f0) when grad is not NULL. */
static double tail_cost(const tail_problem *p, double r, double f0, double *grad, double *hess) {
  double a2 = r * r * r * r, inv_a2 = 1.0 / a2, da2_dr = 4.0 * r * r * r;
  double sum = 0.0, g0 = 0.0, g1 = 0.0, h00 = 0.0, h01 = 0.0, h11 = 0.0;
  tail_fresnel_prep fresnel = tail_fresnel_prepare(p->fresnel, f0);
  for (size_t k = 0; k < p->count; ++k) {
    const tail_node *n = &p->nodes[k];
    cf_ggx_d d = ggx_d(a2, inv_a2, n->sin2_h, n->cos2_h);
    cf_smith_v v = smith_ggx_v(a2, n->c_i, n->c_o);
    double df, fr = tail_fresnel(&fresnel, n->c_d, &df);
    double res = n->k * (fr * (d.value * v.value) - n->target); /* target's order */
    sum += n->w * res * res;
    if (!grad) continue;
    double j0 = n->k * fr * (d.d_a2 * v.value + d.value * v.d_a2) * da2_dr;
    double j1 = n->k * df * d.value * v.value;
    g0 += n->w * j0 * res;
    g1 += n->w * j1 * res;
    h00 += n->w * j0 * j0;
    h01 += n->w * j0 * j1;
    h11 += n->w * j1 * j1;
  }
  double inv_e = 1.0 / p->energy;
  if (grad) {
    grad[0] = g0 * inv_e;
    grad[1] = g1 * inv_e;
    hess[0] = h00 * inv_e;
    hess[1] = h01 * inv_e;
    hess[2] = h11 * inv_e;
  }
  return sum * inv_e;
}

/* The problem for src/lsq: one residual block, all the nodes, whose cost
 * is ½ E(g)/energy, with the normal equations of tail_cost. */
static int tail_evaluate(void *user, const double *x, size_t block, double *cost, double *jtj,
                         double *jtu) {
  (void)block;
  double grad[2], hess[3];
  double c = tail_cost(user, x[0], x[1], jtj ? grad : NULL, hess);
  if (!isfinite(c)) return CF_LSQ_NOT_FINITE;
  *cost = 0.5 * c;
  if (!jtj) return CF_LSQ_EVALUATED;
  jtj[0] = hess[0], jtj[1] = jtj[2] = hess[1], jtj[3] = hess[2];
  jtu[0] = grad[0], jtu[1] = grad[1];
  return isfinite(hess[0] + hess[1] + hess[2] + grad[0] + grad[1]) ? CF_LSQ_EVALUATED
                                                                   : CF_LSQ_NOT_FINITE;
}

static int tail_block_columns(void *user, size_t block, const int **columns) {
  static const int both[2] = {0, 1};
  (void)user, (void)block;
  *columns = both;
  return 2;
}

/* One solve over (r, F0) in the box [lo, hi] from x, to its minimum in x:
 * *cost is E(g)/energy there, *at_lower_f0 whether F0 ends at lo[1] with
 * the data wanting it lower. */
static cf_status tail_solve_box(tail_problem *p, const double lo[2], const double hi[2],
                                double x[2], double *cost, int *iterations, int *at_lower_f0,
                                cf_error *err) {
  int at_bound[2] = {0, 0};
  cf_lsq_problem problem = {2, x, lo, hi, 1, tail_evaluate, tail_block_columns, p, at_bound};
  cf_lsq_options options;
  cf_lsq_default_options(&options);
  options.threads = 1; /* one block */
  /* far above the most a solve took: 26 iterations over the tail's range
   * [1.6, 100], 93 near γ = 1.5 (r 0.05, γ 1.501, Schlick's F0 0.004) */
  options.max_iterations = 200;
  /* the minimum to 6e-7 relative in (r', F0') (an F0' below 1e-4 to 3e-9)
   * against the hand-written LM this replaced run to steps of 1e-13, over
   * 1 450 lobes with γ in [1.6, 100] (r 0.03-1, F0 0-0.25, both Fresnels,
   * in air and under films); the solver's defaults leave 1.8e-3 (r 0.3,
   * γ 1.6, Schlick's F0 0.004: F0' 2.7e-5), 1e-12 and 1e-8 (function,
   * parameter) 2.4e-5 (r 1, γ 1.6, F0 0.004), where the loss is flat in F0' */
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-10;
  cf_lsq_summary summary;
  cf_status s = cf_lsq_solve(&problem, &options, &summary, err);
  if (s != CF_OK) {
    cf_error_prefix(err, "GGX fit of a tailed lobe");
    return s;
  }
  *cost = 2.0 * summary.final_cost;
  *iterations += summary.iterations;
  *at_lower_f0 = at_bound[1] < 0;
  return CF_OK;
}

/* Below this floor F0's next is 0 itself: floors of 1e-9, 1e-12 and 1e-16
 * give the same GGX over the tail's range [1.6, 100], and 1e-9 the fewest
 * solves near γ = 1.5 (2 134 lobes: r 0.03-1, γ 1.5000001-1e6, F0 0-0.25,
 * both Fresnels, in air and under films). */
#define TAIL_F0_FLOOR_MIN 1e-9

/* Least squares over (r, F0) in the parameter table's box from x, to the
 * minimum in x; *cost is E(g)/energy there, *iterations the solver's. F0 goes at most 90 % of the
 * way to its floor in a solve, the floor lowered tenfold while the data
 * want F0 below it: the dielectric Fresnel's ∂F/∂F0 grows like 1/c⁴ at
 * F0 = 0, and a solve free to land there stalls (r 0.3, γ 1.51: F0' 0 and
 * a loss of 100 %, where a dim GGX gives 84 %; r 1, γ 1.6, F0 0.004: 100 %
 * against 48 %). */
static cf_status tail_solve(tail_problem *p, double x[2], double *cost, int *iterations,
                            cf_error *err) {
  double lo[2] = {cf_param_info_get(CF_PARAM_ROUGHNESS)->lower,
                  cf_param_info_get(CF_PARAM_F0)->lower};
  const double hi[2] = {cf_param_info_get(CF_PARAM_ROUGHNESS)->upper,
                        cf_param_info_get(CF_PARAM_F0)->upper};
  const double table_lower = lo[1];
  *iterations = 0;
  for (double f0_floor = 0.1 * x[1];; f0_floor *= 0.1) {
    int at_floor;
    lo[1] = f0_floor > TAIL_F0_FLOOR_MIN ? f0_floor : table_lower;
    cf_status s = tail_solve_box(p, lo, hi, x, cost, iterations, &at_floor, err);
    if (s != CF_OK || !at_floor || lo[1] == table_lower) return s;
  }
}

static cf_status tail_check(double r, double gamma, double f0, cf_error *err) {
  const cf_param_info *rr = cf_param_info_get(CF_PARAM_ROUGHNESS);
  const cf_param_info *ff = cf_param_info_get(CF_PARAM_F0);
  if (!(r >= rr->lower && r <= rr->upper))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe: roughness %g is outside [%g, %g] (the "
                        "parameter table's range of r)",
                        r, rr->lower, rr->upper);
  if (!(f0 >= ff->lower && f0 <= ff->upper))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe: F0 %g is outside [%g, %g] (the parameter "
                        "table's range of F0)",
                        f0, ff->lower, ff->upper);
  if (!isfinite(gamma))
    return cf_error_set(err, CF_ERANGE, "GGX fit of a tailed lobe: tail gamma %g is not finite",
                        gamma);
  if (!(gamma > CF_STD_GAMMA_MIN))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe: tail gamma %g must be above %g (at and below "
                        "it the STD lobe has no finite masking)",
                        gamma, CF_STD_GAMMA_MIN);
  return CF_OK;
}

/* The inputs checked: the lobe, the film (when given) and the quadrature. */
static cf_status tail_inputs_check(double r, double gamma, double f0, const double *film,
                                   const cf_tailed_ggx_quadrature *q, cf_error *err) {
  cf_status s = tail_check(r, gamma, f0, err);
  if (s != CF_OK) return s;
  const cf_param_info *ff = cf_param_info_get(CF_PARAM_FILM_F0);
  const cf_param_info *tt = cf_param_info_get(CF_PARAM_OPTICAL_DEPTH);
  if (film && (!(film[0] >= ff->lower && film[0] <= ff->upper) ||
               !(film[1] >= tt->lower && film[1] <= tt->upper)))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe under a film: film F0 %g or optical depth %g "
                        "outside [%g, %g], [%g, %g] (the parameter table's ranges)",
                        film[0], film[1], ff->lower, ff->upper, tt->lower, tt->upper);
  if (q->views < 1 || q->thetas < 1 || q->phis < 1 || q->views > 256 || q->thetas > 256 ||
      q->phis > 256) /* 256³ points: 0.9 GB */
    return cf_error_set(err, CF_EINVAL,
                        "GGX fit of a tailed lobe: quadrature %d x %d x %d outside [1, 256]",
                        q->views, q->thetas, q->phis);
  return CF_OK;
}

cf_status cf_tailed_ggx_fit(double r, double gamma, double f0, const double *film,
                            cf_tailed_fresnel fresnel, const cf_tailed_ggx_quadrature *q,
                            const double start[2], cf_tailed_ggx *out, cf_error *err) {
  memset(out, 0, sizeof *out);
  cf_status s = tail_inputs_check(r, gamma, f0, film, q, err);
  if (s != CF_OK) return s;
  double x[2] = {start ? start[0] : r, start ? start[1] : f0};
  if (tail_check(x[0], 2.0, x[1], err) != CF_OK) {
    cf_error_prefix(err, "the start");
    return CF_ERANGE;
  }
  tail_film film_prep = film ? tail_film_prepare(film[0], film[1]) : (tail_film){0};
  tail_problem p;
  s = tail_problem_build(&p, r, gamma, f0, fresnel, film ? &film_prep : NULL, q, err);
  if (s != CF_OK) return s;
  out->nodes = p.count;
  if (!(p.energy > 0.0)) { /* F ≡ 0 (the dielectric Fresnel at F0 = 0): nothing to fit */
    out->r = r;
    out->f0 = f0;
    free(p.nodes);
    return CF_OK;
  }
  double cost;
  s = tail_solve(&p, x, &cost, &out->iterations, err);
  if (s == CF_OK) {
    /* F0 = 0 itself, which the steps only approach: near γ = 1.5 the lobe
     * is almost 0 and so is the best GGX, and with the dielectric Fresnel
     * F0 = 0 is no lobe, a loss of 1 (r 1, γ 1.501, F0 0.1: the solve ends
     * at F0' 1.4e-10 with a loss of 1.0000013; nothing changes within the
     * tail's range [1.6, 100]) */
    double lower = cf_param_info_get(CF_PARAM_F0)->lower;
    double at_zero = tail_cost(&p, x[0], lower, NULL, NULL);
    if (at_zero < cost) {
      x[1] = lower;
      cost = at_zero;
    }
    out->rms_loss = sqrt(cost);
    out->naive_loss = sqrt(tail_cost(&p, r, f0, NULL, NULL));
    out->r = x[0];
    out->f0 = x[1];
  }
  free(p.nodes);
  if (s == CF_OK && !isfinite(out->rms_loss))
    return cf_error_set(err, CF_ENUMERIC,
                        "GGX fit of a tailed lobe (r %g, gamma %g, F0 %g): the loss is not finite",
                        r, gamma, f0);
  return s;
}

cf_status cf_tailed_ggx_default(double r, double gamma, double f0, const double *film,
                                cf_tailed_ggx *out, cf_error *err) {
  const cf_tailed_ggx_quadrature q = CF_TAILED_GGX_QUADRATURE;
  return cf_tailed_ggx_fit(r, gamma, f0, film, CF_TAILED_FRESNEL_MODELS, &q, NULL, out, err);
}
