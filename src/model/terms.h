/* The building blocks of docs/model.md §2, one small function a
 * term, each with the partial derivatives the models chain together.
 * Private to src/model. Pure C11 + libm. */
#ifndef CLAYFIT_MODEL_TERMS_H
#define CLAYFIT_MODEL_TERMS_H

#include <float.h>
#include <math.h>

#include "clayfit/model.h"
#include "core/vec.h" /* CF_PI, CF_INV_PI */

/* The models' per-observation bodies are written once with an optional
 * gradient and must be inlined into their value-only and value+gradient
 * callers, so that the value-only path drops the derivative work. */
#if defined(__GNUC__)
#define CF_ALWAYS_INLINE static inline __attribute__((always_inline))
#define CF_FLATTEN __attribute__((flatten)) /* every call inside inlined */
#else
#define CF_ALWAYS_INLINE static inline
#define CF_FLATTEN
#endif

/* In a 3 × dim gradient, zero the entries of the RGB parameter at `slot`
 * that belong to the other channels (∂f_c/∂p_k = 0 for k != c). */
static inline void cf_zero_other_channels(double *grad, int dim, int slot) {
  for (int c = 0; c < 3; ++c)
    for (int k = 1; k < 3; ++k) grad[c * dim + slot + (c + k) % 3] = 0.0;
}

/* ---- Schlick's Fresnel: F(F0, c) = F0 + (1 − F0)(1 − c)^5, c in [0, 1]
 * (Schlick 1994 eq. 24; docs/model.md (8s)): model version 1's F, kept for
 * Burley's clear coat (F0 fixed at 0.04) and the STD lobe of tailed.h.
 * M2-M4 use the exact dielectric F below. schlick_weight is (1 − c)^5 with c clamped;
 * schlick_weight_dc its derivative in c (0 where the clamp is active). */
static inline double schlick_weight(double c) {
  double x = 1.0 - c;
  x = x > 0.0 ? x : 0.0; /* ternaries, not fmin/fmax: these compile to */
  x = x < 1.0 ? x : 1.0; /* one instruction each */
  double x2 = x * x;
  return x2 * x2 * x;
}

static inline double schlick_weight_dc(double c) {
  double x = 1.0 - c;
  double x2 = x * x;
  return (x > 0.0 && x < 1.0) ? -5.0 * x2 * x2 : 0.0;
}

static inline double fresnel_schlick(double f0, double weight) {
  return f0 + (1.0 - f0) * weight;
}

/* ---- The exact unpolarised dielectric Fresnel (docs/model.md (8); Walter
 * et al. 2007 eq. 22; pbrt-v4 FrDielectric), for light arriving from the
 * side of index 1 at an interface of relative index η >= 1, η from F0 by
 * (7). With u = η² − 1 and g = sqrt(u + c²) (the `root` of the refracted
 * cosine g/η, (23)):
 *   r_s = (c − g)/(c + g) = −t/A,  r_p = (η² c − g)/(η² c + g) = t B/C,
 *   A = c + g, t = u/A (= g − c without cancellation), B = c A − 1,
 *   C = η² c + g,   F = (r_s² + r_p²)/2,
 * and the transmission 1 − F from 1 − r² = (1 − r)(1 + r), without the
 * cancellation of 1 − F at grazing (where F rounds to 1 + ε):
 *   T = 2 c g (1/A² + η²/C²) >= 0.
 * F ≡ 0 at F0 = 0 (u = 0, r_s = r_p = 0), F(F0, 1) = F0, F(F0, 0) = 1. */
typedef struct cf_fresnel_eta {
  double f0;
  double u;  /* η² − 1 = 4√F0/(1 − √F0)², (22); exactly 0 at F0 = 0 */
  double du; /* ∂u/∂F0 = 2(1 + √F0)/(√F0 (1 − √F0)³); unused at F0 = 0 */
} cf_fresnel_eta;

static inline cf_fresnel_eta fresnel_eta(double f0) {
  cf_fresnel_eta e;
  double s = sqrt(f0), one_m = 1.0 - s;
  e.f0 = f0;
  e.u = 4.0 * s / (one_m * one_m);
  e.du = s > 0.0 ? 2.0 * (1.0 + s) / (s * one_m * one_m * one_m) : 0.0;
  return e;
}

/* g = sqrt(η² − 1 + c²): M4 reuses its film's refracted-cosine root. */
static inline double fresnel_root(const cf_fresnel_eta *e, double c) {
  return sqrt(e->u + c * c);
}

/* F, T = 1 − F and the partials ∂F/∂c, ∂F/∂F0 (through u); ∂T = −∂F. */
typedef struct cf_fresnel {
  double value, transmission, d_c, d_f0;
} cf_fresnel;

/* At F0 = 0, F ≡ 0 and ∂F/∂c = 0; ∂F/∂F0 is the limit of F/F0 as u → 0
 * (r_s → −u/(4c²), r_p → u(2c² − 1)/(4c²), u → 4√F0):
 *   ∂F/∂F0 = (1 + (1 − 2c²)²) / (2 c⁴),
 * finite for c > 0 (F is smooth in F0 there although √F0 is not). It grows
 * like 1/c⁴: below c = 1e-25 it is held at its value there (1e100), so that
 * times a lobe's D·V (up to 1e166 at cosines of 1e-154, docs/model.md §4.1)
 * it stays finite; such a pair's radiance f·c_i has no measure. */
static inline cf_fresnel fresnel_dielectric_at_zero(double c) {
  cf_fresnel f = {0.0, 1.0, 0.0, 0.0};
  double cl = c > 1e-25 ? c : 1e-25;
  double c2 = cl * cl, m = 1.0 - 2.0 * c2;
  f.d_f0 = (1.0 + m * m) / (2.0 * c2 * c2);
  return f;
}

/* F(F0, c) with g = fresnel_root(e, c); c in (0, 1]. With ∂g/∂u = 1/(2g),
 * ∂g/∂c = c/g and r_s = −u/A², r_p = (η² c − g)/C:
 *   ∂r_s/∂u = −c/(g A²),            ∂r_s/∂c = 2u/(g A²),
 *   ∂r_p/∂u = c (2g² − η²)/(g C²),  ∂r_p/∂c = 2η² u/(g C²),
 * so ∂F/∂u = (c/g)(u/A⁴ + r_p (2g² − η²)/C²), ∂F/∂c = (2u/g)(η² r_p/C² − u/A⁴)
 * and ∂F/∂F0 = ∂u/∂F0 · ∂F/∂u (finite as F0 → 0: ∂u/∂F0 ~ 1/√F0, ∂F/∂u ~ u). */
static inline cf_fresnel fresnel_dielectric(const cf_fresnel_eta *e, double c, double g) {
  if (e->u == 0.0) return fresnel_dielectric_at_zero(c);
  cf_fresnel f;
  const double u = e->u, eta2 = 1.0 + u;
  double a = c + g, cc = eta2 * c + g;
  /* one division for 1/A, 1/C and 1/g (A C g >= u^{3/2}: no underflow for
   * any F0 > 0); the division and the root are the cost of the value */
  double a_cc = a * cc, inv = 1.0 / (a_cc * g);
  double inv_a = cc * g * inv, inv_cc = a * g * inv, inv_g = a_cc * inv;
  double inv_a2 = inv_a * inv_a, inv_cc2 = inv_cc * inv_cc;
  double ua = u * inv_a;
  double r_s = -ua * inv_a, r_p = ua * (c * a - 1.0) * inv_cc; /* η²c − g = u (cA − 1)/A */
  f.value = 0.5 * (r_s * r_s + r_p * r_p);
  f.transmission = 2.0 * c * g * (inv_a2 + eta2 * inv_cc2);
  double u_a4 = u * inv_a2 * inv_a2;
  f.d_c = 2.0 * u * inv_g * (eta2 * r_p * inv_cc2 - u_a4);
  f.d_f0 = e->du * c * inv_g * (u_a4 + r_p * (2.0 * g * g - eta2) * inv_cc2);
  return f;
}

/* The cosine-weighted hemispherical mean F̄ = ∫₀¹ F(F0, c) 2c dc of the
 * exact Fresnel for light from outside, in closed form (docs/model.md (27);
 * Stern 1964; d'Eon 2016), and ∂F̄/∂η. Requires η > 1 (M4's film,
 * F0_1 >= 0.01, η1 >= 1.22, where the form agrees with quadrature to 6e-16
 * and its derivative to 4e-14; it cancels near η = 1). */
typedef struct cf_fresnel_mean {
  double value, d_eta;
} cf_fresnel_mean;

static inline cf_fresnel_mean fresnel_dielectric_mean(double eta) {
  cf_fresnel_mean m;
  double e2 = eta * eta, e4 = e2 * e2, e8 = e4 * e4;
  double em = eta - 1.0, ep = eta + 1.0, e2m = e2 - 1.0, e2p = e2 + 1.0;
  double e4m = e4 - 1.0;
  double log_ratio = log(em / ep), log_eta = log(eta);
  double e2p2 = e2p * e2p, e2p3 = e2p2 * e2p, e2p4 = e2p2 * e2p2;
  double c_ratio = e2 * e2m * e2m / e2p3;                   /* × ln((η−1)/(η+1)) */
  double c_eta = 8.0 * e4 * (e4 + 1.0) / (e2p * e4m * e4m); /* × ln η */
  m.value = 0.5 + em * (3.0 * eta + 1.0) / (6.0 * ep * ep) + c_ratio * log_ratio -
            2.0 * e2 * eta * (e2 + 2.0 * eta - 1.0) / (e2p * e4m) + c_eta * log_eta;
  double poly = 4.0 * e8 + 13.0 * e4 * e2 * eta + 4.0 * e4 * e2 - 24.0 * e4 * eta + 15.0 * e4 +
                27.0 * e2 * eta + 16.0 * e2 - 8.0 * eta + 1.0;
  double d_rest = 4.0 * eta * poly / (3.0 * em * em * ep * ep * ep * e2p3);
  double d_c_ratio = 2.0 * eta * e2m * (5.0 * e2 - 1.0) / e2p4;
  double d_c_eta =
      -16.0 * e2 * eta * (e8 - e4 * e2 + 7.0 * e4 - e2 + 2.0) / (e2m * e2m * e2m * e2p4);
  m.d_eta = d_rest + d_c_ratio * log_ratio + d_c_eta * log_eta;
  return m;
}

/* ---- The half vector of a pair of directions, from the tangent-space
 * invariants: |l + v|² = t² + (c_i + c_o)², sin²θ_h = t²/|l + v|²,
 * cos²θ_h = (c_i + c_o)²/|l + v|², c_d = |l + v|/2 = v·h = l·h. */
typedef struct cf_half_vector {
  double s_sq;     /* |l + v|² */
  double inv_s_sq; /* 1 / |l + v|² */
  double sin2_h;   /* sin²θ_h */
  double cos2_h;   /* cos²θ_h */
  double c_d;      /* |l + v| / 2 */
} cf_half_vector;

static inline cf_half_vector half_vector(double t_sq, double c_sum) {
  cf_half_vector h;
  double c_sum_sq = c_sum * c_sum;
  h.s_sq = t_sq + c_sum_sq;
  h.inv_s_sq = 1.0 / h.s_sq;
  h.sin2_h = t_sq * h.inv_s_sq;
  h.cos2_h = c_sum_sq * h.inv_s_sq;
  h.c_d = 0.5 * sqrt(h.s_sq);
  return h;
}

/* ---- GGX / Trowbridge-Reitz distribution (Walter et al. 2007 eq. 33):
 *   D(α, c_h) = α² / (π ((α² − 1) c_h² + 1)²) = α² / (π (sin²θ_h + α² cos²θ_h)²)
 * The second form has no cancellation at the peak (sin²θ_h → 0).
 * inv_a2 = 1/α² (a property of the parameters, computed once).
 * d_a2:   ∂D/∂(α²);
 * d_sin2: ∂D/∂sin²θ_h along sin²θ_h + cos²θ_h = 1. */
typedef struct cf_ggx_d {
  double value, d_a2, d_sin2;
} cf_ggx_d;

static inline cf_ggx_d ggx_d(double a2, double inv_a2, double sin2_h, double cos2_h) {
  cf_ggx_d d;
  double q = sin2_h + a2 * cos2_h; /* >= α² cos²θ_h > 0 when lit */
  double inv_q = 1.0 / q;
  d.value = a2 * CF_INV_PI * inv_q * inv_q;
  d.d_a2 = d.value * (sin2_h - a2 * cos2_h) * inv_q * inv_a2;
  d.d_sin2 = -2.0 * d.value * (1.0 - a2) * inv_q;
  return d;
}

/* ---- Height-correlated Smith GGX visibility V = G2 / (4 c_i c_o)
 * (Heitz 2014 eq. 99; the form of Filament, glTF, MaterialX):
 *   V = 0.5 / (c_o Λ_i + c_i Λ_o),  Λ = sqrt(α² + c² (1 − α²)).
 * Written directly, never as G/(4 c_i c_o) (0/0 at the smallest cosines). */
typedef struct cf_smith_v {
  double value, d_a2, d_ci, d_co;
} cf_smith_v;

static inline cf_smith_v smith_ggx_v(double a2, double c_i, double c_o) {
  cf_smith_v s;
  double lambda_i = sqrt(a2 + c_i * c_i * (1.0 - a2));
  double lambda_o = sqrt(a2 + c_o * c_o * (1.0 - a2));
  double inv_den = 1.0 / (c_o * lambda_i + c_i * lambda_o);
  s.value = 0.5 * inv_den;
  double v2 = 2.0 * s.value * s.value; /* −∂V/∂den = 0.5/den² */
  double inv_lambda_i = 1.0 / lambda_i, inv_lambda_o = 1.0 / lambda_o;
  s.d_a2 =
      -0.5 * v2 * (c_o * (1.0 - c_i * c_i) * inv_lambda_i + c_i * (1.0 - c_o * c_o) * inv_lambda_o);
  s.d_ci = -v2 * (lambda_o + c_o * c_i * (1.0 - a2) * inv_lambda_i);
  s.d_co = -v2 * (lambda_i + c_i * c_o * (1.0 - a2) * inv_lambda_o);
  return s;
}

/* Burley's clear coat uses this visibility with a fixed α_g = 0.25. */
#define CF_COAT_VISIBILITY_A2 (0.25 * 0.25)

/* ---- Burley's separable Smith GGX (smithG_GGX product, Burley 2012):
 *   Vs = 1 / ((c_i + sqrt(α_g² + c_i² − α_g² c_i²)) (c_o + sqrt(...c_o...))) */
static inline double smith_ggx_separable(double ag2, double c_i, double c_o) {
  double gi = c_i + sqrt(ag2 + c_i * c_i - ag2 * c_i * c_i);
  double go = c_o + sqrt(ag2 + c_o * c_o - ag2 * c_o * c_o);
  return 1.0 / (gi * go);
}

/* ---- Burley's GTR1 (Berry) lobe of the clear coat (Burley 2012, B.2):
 *   D1(a, c_h) = (a² − 1) / (π ln(a²) (1 + (a² − 1) c_h²))
 *             = (a² − 1) / (π ln(a²) (sin²θ_h + a² cos²θ_h)).
 * log_a2 = ln(a²) (a property of the parameters, computed once).
 * d_a2: ∂D1/∂(a²). Requires 0 < a² < 1 (the coat's a is in [0.001, 0.1]). */
typedef struct cf_gtr1 {
  double value, d_a2;
} cf_gtr1;

static inline cf_gtr1 gtr1_d(double a2, double log_a2, double sin2_h, double cos2_h) {
  cf_gtr1 d;
  double q = sin2_h + a2 * cos2_h;
  d.value = (a2 - 1.0) / (CF_PI * log_a2 * q);
  d.d_a2 = d.value * (1.0 / (a2 - 1.0) - 1.0 / (a2 * log_a2) - cos2_h / q);
  return d;
}

/* ---- Oren-Nayar qualitative model (Oren & Nayar 1994 eq. 30; the seed's
 * eq. 17), without trigonometry (docs/model.md (12)-(14)):
 *   ON = ρ/π (A + B · max(0, l·v − c_i c_o) / max(c_i, c_o)),
 *   A = 1 − 0.5 σ²/(σ² + 0.33),  B = 0.45 σ²/(σ² + 0.09).
 * The coefficients depend on σ only; the angular factor on geometry only. */
typedef struct cf_oren_nayar_coeffs {
  double a, b, d_a, d_b; /* A, B and their derivatives in σ */
} cf_oren_nayar_coeffs;

static inline cf_oren_nayar_coeffs oren_nayar_coeffs(double sigma) {
  cf_oren_nayar_coeffs k;
  double s2 = sigma * sigma;
  double da = s2 + 0.33, db = s2 + 0.09;
  k.a = 1.0 - 0.5 * s2 / da;
  k.b = 0.45 * s2 / db;
  k.d_a = -0.5 * 0.33 * 2.0 * sigma / (da * da);
  k.d_b = 0.45 * 0.09 * 2.0 * sigma / (db * db);
  return k;
}

/* max(0, g) / max(c_i, c_o), with g = l·v − c_i c_o (= sin α tan β
 * max(0, cos(φ_i − φ_o)) for unit vectors). */
static inline double oren_nayar_angular(double g, double c_i, double c_o) {
  if (g <= 0.0) return 0.0;
  return g / (c_i > c_o ? c_i : c_o);
}

#endif /* CLAYFIT_MODEL_TERMS_H */
