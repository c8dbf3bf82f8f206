/* A microfacet distribution with a free tail: STD, the Student-t
 * distribution of slopes (Ribardière, Bringier, Meneveaux, Simonot 2017,
 * "STD: Student's t-Distribution of Slopes for Microfacet Based BSDFs",
 * Eurographics; CGF 36(2)), docs/model.md §2.8. One small function per
 * term, each with its partial derivatives, shaped like the GGX terms of
 * terms.h so that a model can swap them in:
 *
 *   GGX (terms.h)          STD (here)
 *   ggx_d        →  std_d:              value, d_a2, d_gamma, d_sin2
 *   smith_ggx_v  →  cf_std_v:           value, d_a2, d_gamma, d_ci, d_co
 *   F · D · V    →  cf_std_lobe_eval:   value, d_a2, d_gamma, d_f0, d_weight,
 *                                       d_sin2, d_ci, d_co
 *
 * Parameters: α² (the GGX α² = r⁴ of docs/model.md (6)) and the tail γ > 1.5.
 * γ = 2 is GGX exactly; γ → ∞ is Beckmann with the same α; γ → 1.5 is the
 * heaviest tail with a finite masking. What depends on (α², γ) only is
 * computed once (cf_std_tail_prepare), like inv_a2 for GGX.
 * Private to src/model. Pure C11 + libm. */
#ifndef CLAYFIT_MODEL_TAILED_H
#define CLAYFIT_MODEL_TAILED_H

#include "terms.h"

/* The tail's guarded limits (docs/model.md §2.8, "Hard cases and guards"). */
#define CF_STD_GAMMA_GGX 2.0 /* exactly GGX: the GGX code's values, to the bit */
#define CF_STD_GAMMA_MIN 1.5 /* at and below: the masking is infinite, the lobe 0 */
/* At and above: the masking is Beckmann's (the limit), ∂Λ/∂γ = 0. At 1e6 the
 * STD masking differs from it by < 4e-7 relative in L (test_tailed_lobe), and
 * the continued fraction would need O(√γ) steps. */
#define CF_STD_GAMMA_BECKMANN 1e6
/* cos²θ_h is floored here (γ != 2): D ∝ cos^(2γ−4) θ_h diverges at the
 * horizon for γ < 2 and its derivative for γ < 3 (test_tailed_lobe's hard
 * grid overflows without it at c_i = c_o = 1e-100). Only pairs with both
 * cosines below 2e-30 reach the floor (cos θ_h >= (c_i + c_o)/2). */
#define CF_STD_COS2_MIN 1e-60

typedef enum cf_std_regime {
  CF_STD_MASKED,   /* γ <= 1.5: no finite masking; lobe and visibility 0 */
  CF_STD_GGX,      /* γ == 2 */
  CF_STD_GENERAL,  /* 1.5 < γ < 1e6, γ != 2 */
  CF_STD_BECKMANN, /* γ >= 1e6: Beckmann masking */
} cf_std_regime;

/* What depends on the parameters only (docs/model.md (T1), (T4)). */
typedef struct cf_std_tail {
  double a2, inv_a2, gamma;
  double a;         /* γ − 1 */
  double b2;        /* β² = (γ − 1) α², the slopes' Student scale squared */
  double k;         /* K = a Γ(a + 1/2) / (√π Γ(a + 1)); K · B(a, 1/2) = 1 */
  double dlnk_da;   /* d ln K / da = 1/a + ψ(a + 1/2) − ψ(a + 1) */
  double inv_2a_m1; /* 1 / (2a − 1) = 1 / (2γ − 3) */
  cf_std_regime regime;
} cf_std_tail;

cf_std_tail cf_std_tail_prepare(double a2, double gamma);

/* ---- The distribution of normals (docs/model.md (T1); derivatives (T2)):
 *   D = 1 / (π α² cos⁴θ_h (1 + tan²θ_h / ((γ − 1) α²))^γ)
 *     = r^(γ−2) (β² / q)² / (π α²),   q = sin²θ_h + β² cos²θ_h,  r = β² cos²θ_h / q,
 * (Ribardière et al. 2017, the STD with its α and γ; the form of bbm's
 * ndf/studentt.h; d_sin2 along sin² + cos² = 1, as ggx_d). ln r by log1p where r is near 1 (the
 * Beckmann limit). */
typedef struct cf_std_d {
  double value, d_a2, d_gamma, d_sin2;
} cf_std_d;

static inline cf_std_d std_d(const cf_std_tail *t, double sin2_h, double cos2_h) {
  cf_std_d d = {0.0, 0.0, 0.0, 0.0};
  if (t->gamma <= 1.0 || !(cos2_h > 0.0)) return d; /* not normalisable / not lit */
  double gamma = t->gamma, b2 = t->b2;
  if (t->regime == CF_STD_GGX) {
    cf_ggx_d g = ggx_d(t->a2, t->inv_a2, sin2_h, cos2_h);
    /* ∂/∂γ of the floored form below, as its neighbours γ = 2 ± h see it */
    if (cos2_h < CF_STD_COS2_MIN) {
      cos2_h = CF_STD_COS2_MIN;
      sin2_h = 1.0 - CF_STD_COS2_MIN;
    }
    double q = sin2_h + b2 * cos2_h, bc = b2 * cos2_h, r = bc / q;
    double ln_r = r < 0.5 ? log(r) : -log1p(sin2_h / bc);
    d.value = g.value;
    d.d_a2 = g.d_a2;
    d.d_sin2 = g.d_sin2;
    d.d_gamma = g.value * (ln_r + 2.0 * sin2_h / q);
    return d;
  }
  int floored = cos2_h < CF_STD_COS2_MIN;
  if (floored) {
    cos2_h = CF_STD_COS2_MIN;
    sin2_h = 1.0 - CF_STD_COS2_MIN;
  }
  double q = sin2_h + b2 * cos2_h, inv_q = 1.0 / q;
  double bc = b2 * cos2_h, r = bc * inv_q;
  double ln_r = r < 0.5 ? log(r) : -log1p(sin2_h / bc);
  double ratio = b2 * inv_q;
  d.value = exp((gamma - 2.0) * ln_r) * ratio * ratio * t->inv_a2 * CF_INV_PI;
  d.d_a2 = d.value * t->a * (sin2_h - t->a2 * cos2_h) * inv_q * t->inv_a2;
  d.d_gamma = d.value * (ln_r + gamma * sin2_h * inv_q / t->a);
  d.d_sin2 = floored ? 0.0 : -d.value * ((gamma - 2.0) / cos2_h + gamma * (1.0 - b2) * inv_q);
  return d;
}

/* ---- The masking of one direction (docs/model.md (T3)-(T5)), as the
 * GGX visibility's shorthand Λ_x of docs/model.md (10):
 *   L(c) = c (1 + 2 Λ(c)),  Λ Smith's function (Ribardière et al. 2017 eq. 13),
 * finite at c = 0. GGX: L = sqrt(α² + c² (1 − α²)). d_c = ∂L/∂c. */
typedef struct cf_std_masking {
  double value, d_c, d_a2, d_gamma;
} cf_std_masking;

/* with_grad = 0 skips the derivatives (and the derivative of the continued
 * fraction). Requires 0 <= c <= 1. */
cf_std_masking cf_std_masking_eval(const cf_std_tail *t, double c, int with_grad);

/* Smith's Λ(c) = (L − c) / (2c) (for tests and G1 = 1/(1 + Λ)). */
double cf_std_lambda(const cf_std_tail *t, double c);

/* ---- Height-correlated Smith visibility V = G2 / (4 c_i c_o),
 * G2 = 1 / (1 + Λ_i + Λ_o) (Heitz 2014 eq. 99; Ribardière et al. 2017 §4):
 *   V = 1 / (2 (c_o L_i + c_i L_o)),   docs/model.md (T6). */
typedef struct cf_std_v {
  double value, d_a2, d_gamma, d_ci, d_co;
} cf_std_v;

cf_std_v cf_std_v_eval(const cf_std_tail *t, double c_i, double c_o, int with_grad);

/* ---- The specular lobe S = F(F0, c_d) D V (docs/model.md (T7)), F Schlick's
 * (8) with weight_d = (1 − c_d)^5 (cf_geometry.weight_d). d_weight = ∂S/∂weight_d
 * (chain with schlick_weight_dc for c_d); d_sin2, d_ci, d_co as D's and V's. */
typedef struct cf_std_lobe {
  double value, d_a2, d_gamma, d_f0, d_weight, d_sin2, d_ci, d_co;
} cf_std_lobe;

cf_std_lobe cf_std_lobe_eval(const cf_std_tail *t, double f0, double weight_d, double sin2_h,
                             double cos2_h, double c_i, double c_o, int with_grad);

/* ---- Special functions (libm only), exposed for their tests. */

/* ln(Γ(a + 1/2) / Γ(a + 1)) for a > −1/2, and its derivative
 * ψ(a + 1/2) − ψ(a + 1) in *d_ln: upward recurrence to a >= 16, then the
 * Stirling series of ln Γ and ψ (DLMF 5.11.1, 5.11.2). */
double cf_log_gamma_ratio_half(double a, double *d_ln);

/* The continued fraction of the incomplete beta function (DLMF 8.17.22),
 *   B_x(p, q) = x^p (1 − x)^q / p · cf,
 * for 0 <= x < (p + 1)/(p + q + 2) (where it converges fast), with the
 * derivative of cf along (dp, dq) in *d_cf (forward mode through the
 * modified Lentz recurrence; d_cf NULL: the value alone). *steps, if not
 * NULL, receives the count. */
double cf_beta_fraction(double x, double p, double q, double dp, double dq, double *d_cf,
                        int *steps);

#endif /* CLAYFIT_MODEL_TAILED_H */
