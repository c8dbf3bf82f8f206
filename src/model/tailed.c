/* STD, the Student-t distribution of slopes, with its height-correlated
 * Smith masking in closed form (docs/model.md §2.8; Ribardière et al.
 * 2017). The special functions it needs are here too, from libm only. */
#include "tailed.h"

#define CF_INV_SQRT_PI 0.56418958354775628695

/* ---- Special functions ------------------------------------------------ */

/* Stirling's series, y >= 16 (DLMF 5.11.1 and 5.11.2; the first omitted
 * terms are below 1e-17 there):
 *   ln Γ(y) = (y − 1/2) ln y − y + ln(2π)/2 + Σ B_2k / (2k (2k − 1) y^(2k−1)),
 *   ψ(y)    = ln y − 1/(2y) − Σ B_2k / (2k y^(2k)),   k = 1..7. */
static const double lngamma_series[7] = {1.0 / 12,   -1.0 / 360,      1.0 / 1260, -1.0 / 1680,
                                         1.0 / 1188, -691.0 / 360360, 1.0 / 156};
static const double digamma_series[7] = {-1.0 / 12,  1.0 / 120,     -1.0 / 252, 1.0 / 240,
                                         -1.0 / 132, 691.0 / 32760, -1.0 / 12};

/* Σ c_k u^k, k = 0..6, by Horner */
static double series7(const double *c, double u) {
  double sum = c[6];
  for (int k = 5; k >= 0; --k) sum = sum * u + c[k];
  return sum;
}

static double stirling_lngamma_tail(double y) {
  return series7(lngamma_series, 1.0 / (y * y)) / y;
}

static double stirling_digamma_tail(double y) {
  double inv2 = 1.0 / (y * y);
  return inv2 * series7(digamma_series, inv2);
}

double cf_log_gamma_ratio_half(double a, double *d_ln) {
  /* R(x) = R(x + 1) (x + 1)/(x + 1/2) until x >= 16 */
  double x = a, product = 1.0, d_shift = 0.0;
  while (x < 16.0) {
    product *= (x + 1.0) / (x + 0.5);
    d_shift += 1.0 / (x + 1.0) - 1.0 / (x + 0.5);
    x += 1.0;
  }
  double y1 = x + 0.5, y2 = x + 1.0;
  double ln_ratio = log1p(-0.5 / y2); /* ln(y1 / y2) without cancellation */
  double ln_r =
      x * ln_ratio - 0.5 * log(y2) + 0.5 + stirling_lngamma_tail(y1) - stirling_lngamma_tail(y2);
  if (d_ln) {
    *d_ln = ln_ratio - 0.5 / y1 + 0.5 / y2 + stirling_digamma_tail(y1) - stirling_digamma_tail(y2) +
            d_shift;
  }
  return ln_r + log(product);
}

/* One coefficient d_j of DLMF 8.17.22 and its derivative along (dp, dq):
 *   d_(2m+1) = −(p + m)(p + q + m) x / ((p + 2m)(p + 2m + 1)),
 *   d_(2m)   = m (q − m) x / ((p + 2m − 1)(p + 2m)). */
static void beta_fraction_coefficient(int j, double x, double p, double q, double dp, double dq,
                                      double *d, double *dd) {
  int m = j / 2;
  double num, dnum, u, v;
  if (j & 1) {
    num = -(p + m) * (p + q + m) * x;
    dnum = -(dp * (p + q + m) + (p + m) * (dp + dq)) * x;
    u = p + 2 * m;
    v = u + 1.0;
  } else {
    num = m * (q - m) * x;
    dnum = m * dq * x;
    u = p + 2 * m - 1.0;
    v = u + 1.0;
  }
  double den = u * v, dden = dp * (u + v);
  *d = num / den;
  *dd = (dnum - *d * dden) / den;
}

enum { BETA_FRACTION_MAX_STEPS = 100000 };

/* The value alone: the same recurrence without the derivative (value-only
 * evaluations are about a quarter cheaper, test_tailed_lobe bench). */
static double beta_fraction_value(double x, double p, double q, int *steps) {
  const double tiny = 1e-300, eps = 2.3e-16;
  double g = 1.0, cc = 1.0, dd_ = 0.0;
  int j = 1;
  for (; j <= BETA_FRACTION_MAX_STEPS; ++j) {
    double d, dd;
    beta_fraction_coefficient(j, x, p, q, 0.0, 0.0, &d, &dd);
    double den = 1.0 + d * dd_;
    if (fabs(den) < tiny) den = tiny;
    dd_ = 1.0 / den;
    double cn = 1.0 + d / cc;
    if (fabs(cn) < tiny) cn = tiny;
    cc = cn;
    double delta = cc * dd_;
    g *= delta;
    if (fabs(delta - 1.0) <= eps) break;
  }
  if (steps) *steps = j;
  return 1.0 / g;
}

double cf_beta_fraction(double x, double p, double q, double dp, double dq, double *d_cf,
                        int *steps) {
  if (!d_cf) return beta_fraction_value(x, p, q, steps);
  /* g = 1 + d1/(1 + d2/(1 + ...)) by the modified Lentz method, each
   * quantity carried with its derivative; the fraction is 1/g. */
  const double tiny = 1e-300, eps = 2.3e-16;
  double g = 1.0, dg = 0.0, cc = 1.0, dcc = 0.0, dd_ = 0.0, ddd = 0.0;
  int j = 1;
  for (; j <= BETA_FRACTION_MAX_STEPS; ++j) {
    double d, dd;
    beta_fraction_coefficient(j, x, p, q, dp, dq, &d, &dd);
    double den = 1.0 + d * dd_, dden = dd * dd_ + d * ddd;
    if (fabs(den) < tiny) den = tiny;
    dd_ = 1.0 / den;
    ddd = -dden * dd_ * dd_;
    double inv_cc = 1.0 / cc; /* one division for C and its derivative */
    double cn = 1.0 + d * inv_cc, dcn = (dd - d * dcc * inv_cc) * inv_cc;
    if (fabs(cn) < tiny) cn = tiny;
    cc = cn;
    dcc = dcn;
    double delta = cc * dd_, d_delta = dcc * dd_ + cc * ddd;
    dg = dg * delta + g * d_delta;
    g *= delta;
    /* converged when the step changes neither g nor dg beyond rounding */
    if (fabs(delta - 1.0) <= eps &&
        fabs(d_delta) * fabs(g) <= eps * ((fabs(dcc * dd_) + fabs(cc * ddd)) * fabs(g) + fabs(dg)))
      break;
  }
  if (steps) *steps = j;
  if (d_cf) *d_cf = -dg / (g * g);
  return 1.0 / g;
}

/* ---- The tail's parameters ------------------------------------------- */

cf_std_tail cf_std_tail_prepare(double a2, double gamma) {
  cf_std_tail t = {0};
  t.a2 = a2;
  t.inv_a2 = 1.0 / a2;
  t.gamma = gamma;
  t.a = gamma - 1.0;
  t.b2 = t.a * a2;
  t.inv_a = 1.0 / t.a;
  if (!(gamma > CF_STD_GAMMA_MIN)) {
    t.regime = CF_STD_MASKED;
    return t;
  }
  double d_ln_r;
  double ln_r = cf_log_gamma_ratio_half(t.a, &d_ln_r);
  t.k = t.a * exp(ln_r) * CF_INV_SQRT_PI;
  t.dlnk_da = 1.0 / t.a + d_ln_r;
  t.inv_2a_m1 = 1.0 / (2.0 * t.a - 1.0);
  if (gamma == CF_STD_GAMMA_GGX) {
    t.regime = CF_STD_GGX;
  } else if (gamma >= CF_STD_GAMMA_BECKMANN) {
    t.regime = CF_STD_BECKMANN;
  } else {
    t.regime = CF_STD_GENERAL;
  }
  return t;
}

/* ---- The masking -------------------------------------------------------- */

/* docs/model.md (T4)-(T5): with s² = 1 − c², Q = s² β² + c², z = s² β²/Q,
 *   L = c + K (2E − c T),  E = z^a √Q / (2a − 1),  T = B_z(a, 1/2),
 * T by its continued fraction below the fraction's switch point, else as
 * B(a, 1/2) − B_(1−z)(1/2, a) = 1/K − B_(1−z)(1/2, a), where L = 2KE + cK B_(1−z)(1/2, a)
 * has no cancellation at all. The pieces the derivatives (and the table's
 * mixed derivative) need: K T and K ∂T/∂a at fixed β². */
typedef struct masking_parts {
  double value, q, ln_z, e, kt, k_dt_da;
} masking_parts;

static masking_parts masking_parts_of(const cf_std_tail *t, double c, double s2, int with_grad) {
  masking_parts m = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  double a = t->a, k = t->k;
  double q = s2 * t->b2 + c * c, sqrt_q = sqrt(q);
  double z = s2 * t->b2 / q, w = c * c / q; /* w = 1 − z */
  /* ln z by log1p near z = 1: a ln z must stay exact for a up to 1e6 */
  double ln_z = z > 0.5 ? log1p(-w) : log(z);
  double za = exp(a * ln_z);
  double e = za * sqrt_q * t->inv_2a_m1;
  double c_over = c / sqrt_q; /* √(1 − z) */
  double d_cf = 0.0, dt_da = 0.0;
  m.q = q;
  m.ln_z = ln_z;
  m.e = e;
  if (z < (a + 1.0) / (a + 2.5)) {
    double cf = cf_beta_fraction(z, a, 0.5, 1.0, 0.0, with_grad ? &d_cf : NULL, NULL);
    double tt = za * c_over * cf / a; /* B_z(a, 1/2) = z^a (1 − z)^(1/2) cf / a */
    m.value = c + k * (2.0 * e - c * tt);
    m.kt = k * tt;
    if (with_grad) dt_da = tt * (ln_z - 1.0 / a) + za * c_over * d_cf / a;
  } else {
    double cf = cf_beta_fraction(w, 0.5, a, 0.0, 1.0, with_grad ? &d_cf : NULL, NULL);
    double tail = 2.0 * c_over * za * cf; /* B_w(1/2, a) = w^(1/2) (1 − w)^a cf / (1/2) */
    m.value = 2.0 * k * e + c * k * tail;
    m.kt = 1.0 - k * tail;
    if (with_grad) dt_da = -t->dlnk_da / k - 2.0 * c_over * za * (ln_z * cf + d_cf);
  }
  m.k_dt_da = k * dt_da;
  return m;
}

/* ∂L/∂c = 1 − K T − 2cKE/s²; ∂L/∂β² = K E/β²; ∂L/∂a at fixed β² (T5) */
static cf_std_masking masking_from_parts(const cf_std_tail *t, const masking_parts *p, double c,
                                         double s2) {
  cf_std_masking m = {p->value, 0.0, 0.0, 0.0};
  double k = t->k, e = p->e;
  m.d_c = 1.0 - p->kt - 2.0 * c * k * e / s2;
  double d_b2 = k * e / t->b2;
  double d_a =
      t->dlnk_da * (m.value - c) + 2.0 * k * e * (p->ln_z - 2.0 * t->inv_2a_m1) - c * p->k_dt_da;
  m.d_a2 = t->a * d_b2;           /* β² = a α² */
  m.d_gamma = d_a + t->a2 * d_b2; /* a = γ − 1 */
  return m;
}

static cf_std_masking masking_general(const cf_std_tail *t, double c, double s2, int with_grad) {
  masking_parts p = masking_parts_of(t, c, s2, with_grad);
  if (!with_grad) return (cf_std_masking){p.value, 0.0, 0.0, 0.0};
  return masking_from_parts(t, &p, c, s2);
}

/* docs/model.md (T8): Beckmann's masking with ν = c/(s α),
 *   L = c erf(ν) + s α e^(−ν²)/√π. */
static cf_std_masking masking_beckmann(const cf_std_tail *t, double c, double s2) {
  cf_std_masking m;
  double s = sqrt(s2), alpha = sqrt(t->a2);
  double nu = c / (s * alpha), e = exp(-nu * nu), erf_nu = erf(nu);
  m.value = c * erf_nu + s * alpha * e * CF_INV_SQRT_PI;
  m.d_c = erf_nu - c * alpha * e * CF_INV_SQRT_PI / s;
  m.d_a2 = 0.5 * s * e * CF_INV_SQRT_PI / alpha;
  m.d_gamma = 0.0;
  return m;
}

cf_std_masking cf_std_masking_beckmann(const cf_std_tail *t, double c) {
  double s2 = (1.0 - c) * (1.0 + c);
  if (!(s2 > 0.0)) return (cf_std_masking){c, 1.0, 0.0, 0.0};
  return masking_beckmann(t, c, s2);
}

cf_std_masking cf_std_masking_eval(const cf_std_tail *t, double c, int with_grad) {
  cf_std_masking m = {c, 1.0, 0.0, 0.0};
  if (t->regime == CF_STD_MASKED) {
    m.value = INFINITY; /* Λ = ∞: the mean slope is infinite for γ <= 1.5 */
    m.d_c = 0.0;
    return m;
  }
  double s2 = (1.0 - c) * (1.0 + c);
  if (!(s2 > 0.0)) return m; /* normal incidence: Λ = 0 (for γ < 2, ∂L/∂c → −∞ here) */
  if (t->regime == CF_STD_BECKMANN) return masking_beckmann(t, c, s2);
  if (t->regime == CF_STD_GGX) {
    /* the GGX code's L of docs/model.md (10); only ∂/∂γ needs the general form */
    double lambda = sqrt(t->a2 + c * c * (1.0 - t->a2));
    if (with_grad) m = masking_general(t, c, s2, 1);
    m.value = lambda;
    m.d_c = c * (1.0 - t->a2) / lambda;
    m.d_a2 = 0.5 * s2 / lambda;
    return m;
  }
  return masking_general(t, c, s2, with_grad);
}

/* ---- The table's nodes (tailed.h, docs/model.md §2.8 "The table") ------- */

/* octave j: 16 steps for j = 0, 8 to j = 9, 4 to 15, 2 to 25, 1 to 45 */
const unsigned char cf_std_octave_log2_steps[CF_STD_TABLE_OCTAVES] = {
    4, 3, 3, 3, 3, 3, 3, 3, 3, 3, 2, 2, 2, 2, 2, 2, 1, 1, 1, 1, 1, 1, 1,
    1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
const unsigned char cf_std_octave_first[CF_STD_TABLE_OCTAVES + 1] = {
    0,   16,  24,  32,  40,  48,  56,  64,  72,  80,  88,  92,  96,  100, 104, 108,
    112, 114, 116, 118, 120, 122, 124, 126, 128, 130, 132, 133, 134, 135, 136, 137,
    138, 139, 140, 141, 142, 143, 144, 145, 146, 147, 148, 149, 150, 151, 152};
_Static_assert(CF_STD_TABLE_NODES == 153, "the octaves' steps add up");

double cf_std_table_position(int k) {
  int j = 0;
  while (j < CF_STD_TABLE_OCTAVES - 1 && cf_std_octave_first[j + 1] <= k) ++j;
  int steps = cf_std_octave_first[j + 1] - cf_std_octave_first[j], q = k - cf_std_octave_first[j];
  return ldexp(1.0 - 0.5 * q / steps, -j); /* q = steps: 2^(−j−1) */
}

cf_std_node cf_std_node_exact(const cf_std_tail *t, double c, double s2) {
  masking_parts p = masking_parts_of(t, c, s2, 1);
  cf_std_masking m = masking_from_parts(t, &p, c, s2);
  /* ∂(∂L/∂c)/∂γ = ∂/∂a|β² + α² ∂/∂β², from ∂L/∂c = 1 − KT − 2cKE/s² with
   *   ∂(KT)/∂a = K T dlnK/da + K ∂T/∂a,  ∂(KE)/∂a = K E (dlnK/da + ln z − 2/(2a − 1)),
   *   ∂(∂L/∂c)/∂β² = ∂(∂L/∂β²)/∂c = −(K E/β²) c (2a/s² + (2a − 1)(1 − β²)/Q). */
  double k = t->k, a = t->a, ke = k * p.e;
  double dc_da = -(t->dlnk_da * p.kt + p.k_dt_da) -
                 2.0 * c / s2 * ke * (t->dlnk_da + p.ln_z - 2.0 * t->inv_2a_m1);
  double dc_db2 = -ke / t->b2 * c * (2.0 * a / s2 + (2.0 * a - 1.0) * (1.0 - t->b2) / p.q);
  cf_std_node n = {m.value, m.d_c, m.d_gamma, dc_da + t->a2 * dc_db2};
  return n;
}

/* The first node, u = 0 (w = 1), at α = 1 (β² = a): g is even in u (L(−c) = L(c)
 * from Λ(−μ) = −1 − Λ(μ)), and ∂g/∂w = −(∂g/∂u)/(2u) tends to
 *   −K (a − 1)/(√a (2a − 1))
 * (1 − KT = 2Kc/√Q + O(c³) and E → √a/(2a − 1) in (T5)); its ∂/∂γ = d/da of
 * that, with d/da[(a − 1)/(√a (2a − 1))] = (5a − 2a² − 1)/(2 a^(3/2) (2a − 1)²). */
static void first_node_slopes(const cf_std_tail *t, cf_std_node *n) {
  double a = t->a, sqrt_a = sqrt(a), m = 2.0 * a - 1.0;
  double f = (a - 1.0) / (sqrt_a * m),
         df = (5.0 * a - 2.0 * a * a - 1.0) / (2.0 * a * sqrt_a * m * m);
  n->g_w = -t->k * f;
  n->g_w_gamma = -t->k * (t->dlnk_da * f + df);
}

void cf_std_table_nodes_exact(cf_std_node node[CF_STD_TABLE_NODES], double gamma) {
  cf_std_tail t = cf_std_tail_prepare(1.0, gamma);
  t.regime = CF_STD_GENERAL; /* at γ = 2 too: the nodes' ∂/∂γ */
  for (int k = 0; k < CF_STD_TABLE_NODES; ++k) {
    /* at α = 1, w = s² exactly and u = c = √(1 − w) (1 − w is exact) */
    double w = cf_std_table_position(k), u = sqrt(1.0 - w);
    cf_std_node n = cf_std_node_exact(&t, u, w);
    if (k == 0) {
      first_node_slopes(&t, &n);
    } else { /* ∂/∂w = −(∂/∂u)/(2u) */
      n.g_w = -0.5 * n.g_w / u;
      n.g_w_gamma = -0.5 * n.g_w_gamma / u;
    }
    node[k] = n;
  }
}

/* Hermite to power series on each step: with m = h ∂g/∂w at the ends,
 * g = p0 + m0 t + (3(p1 − p0) − 2 m0 − m1) t² + (2(p0 − p1) + m0 + m1) t³. */
static void power_series(double p0, double m0, double p1, double m1, double *c) {
  c[0] = p0;
  c[1] = m0;
  c[2] = 3.0 * (p1 - p0) - 2.0 * m0 - m1;
  c[3] = 2.0 * (p0 - p1) + m0 + m1;
}

void cf_std_table_from_nodes(cf_std_table *tb, const cf_std_node node[CF_STD_TABLE_NODES]) {
  for (int j = 0; j < CF_STD_TABLE_OCTAVES; ++j) {
    double h = ldexp(1.0, -j - 1 - cf_std_octave_log2_steps[j]);
    for (int s = cf_std_octave_first[j]; s < cf_std_octave_first[j + 1]; ++s) {
      const cf_std_node *a = &node[s + 1], *b = &node[s]; /* t = 0 at node s + 1 */
      power_series(a->g, h * a->g_w, b->g, h * b->g_w, tb->step[s].c);
      power_series(a->g_gamma, h * a->g_w_gamma, b->g_gamma, h * b->g_w_gamma, tb->step[s].d);
    }
  }
}

void cf_std_table_build_exact(cf_std_table *tb, double gamma) {
  cf_std_tail t = cf_std_tail_prepare(1.0, gamma);
  tb->gamma = gamma;
  tb->built = t.regime == CF_STD_GENERAL || t.regime == CF_STD_GGX;
  if (!tb->built) return;
  cf_std_node node[CF_STD_TABLE_NODES];
  cf_std_table_nodes_exact(node, gamma);
  cf_std_table_from_nodes(tb, node);
}

double cf_std_lambda(const cf_std_tail *t, double c) {
  cf_std_masking m = cf_std_masking_eval(t, c, 0);
  return (m.value - c) / (2.0 * c);
}

/* ---- The visibility and the lobe ---------------------------------------- */

cf_std_v cf_std_v_eval(const cf_std_tail *t, double c_i, double c_o, int with_grad) {
  cf_std_v v = {0.0, 0.0, 0.0, 0.0, 0.0};
  if (t->regime == CF_STD_MASKED) return v;
  if (t->regime == CF_STD_GGX) {
    cf_smith_v s = smith_ggx_v(t->a2, c_i, c_o);
    v.value = s.value;
    v.d_a2 = s.d_a2;
    v.d_ci = s.d_ci;
    v.d_co = s.d_co;
    if (with_grad) {
      double gi = cf_std_masking_eval(t, c_i, 1).d_gamma;
      double go = cf_std_masking_eval(t, c_o, 1).d_gamma;
      v.d_gamma = -2.0 * s.value * s.value * (c_o * gi + c_i * go);
    }
    return v;
  }
  cf_std_masking mi = cf_std_masking_eval(t, c_i, with_grad);
  cf_std_masking mo = cf_std_masking_eval(t, c_o, with_grad);
  v.value = 0.5 / (c_o * mi.value + c_i * mo.value);
  if (!with_grad) return v;
  double v2 = 2.0 * v.value * v.value; /* −∂V/∂(c_o L_i + c_i L_o) */
  v.d_a2 = -v2 * (c_o * mi.d_a2 + c_i * mo.d_a2);
  v.d_gamma = -v2 * (c_o * mi.d_gamma + c_i * mo.d_gamma);
  v.d_ci = -v2 * (mo.value + c_o * mi.d_c);
  v.d_co = -v2 * (mi.value + c_i * mo.d_c);
  return v;
}

cf_std_lobe cf_std_lobe_eval(const cf_std_tail *t, double f0, double weight_d, double sin2_h,
                             double cos2_h, double c_i, double c_o, int with_grad) {
  cf_std_lobe s = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  if (t->regime == CF_STD_MASKED) return s;
  double fresnel = fresnel_schlick(f0, weight_d);
  cf_std_d d = std_d(t, sin2_h, cos2_h);
  cf_std_v vis = cf_std_v_eval(t, c_i, c_o, with_grad);
  double dv = d.value * vis.value;
  s.value = fresnel * dv; /* the order of dielectric.c: bit-equal to it at γ = 2 */
  if (!with_grad) return s;
  s.d_a2 = fresnel * (d.d_a2 * vis.value + d.value * vis.d_a2);
  s.d_gamma = fresnel * (d.d_gamma * vis.value + d.value * vis.d_gamma);
  s.d_f0 = (1.0 - weight_d) * dv;
  s.d_weight = (1.0 - f0) * dv;
  s.d_sin2 = fresnel * d.d_sin2 * vis.value;
  s.d_ci = fresnel * d.value * vis.d_ci;
  s.d_co = fresnel * d.value * vis.d_co;
  return s;
}

/* ---- The lobe for the models, out of line -------------------------------- */

cf_std_dv cf_std_dv_eval(const cf_std_tail *t, const cf_std_table *tb, double sin2_h, double cos2_h,
                         double c_i, double c_o, int with_grad) {
  return with_grad ? std_dv(t, tb, sin2_h, cos2_h, c_i, c_o, 1)
                   : std_dv(t, tb, sin2_h, cos2_h, c_i, c_o, 0);
}

cf_std_dv cf_ggx_dv_eval(double a2, double sin2_h, double cos2_h, double c_i, double c_o,
                         int with_grad) {
  return ggx_dv(a2, 1.0 / a2, sin2_h, cos2_h, c_i, c_o, with_grad);
}
