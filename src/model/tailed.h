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
 *   D · V        →  std_dv (inline), cf_std_dv_eval: value, d_a2, d_gamma,
 *                   d_sin2, d_ci, d_co, the masking from a table built once per
 *                   γ (cf_std_table_build; the models' hot path, no Fresnel)
 *
 * Parameters: α² (the GGX α² = r⁴ of docs/model.md (6)) and the tail γ > 1.5.
 * γ = 2 is GGX exactly; γ → ∞ is Beckmann with the same α; γ → 1.5 is the
 * heaviest tail with a finite masking. What depends on (α², γ) only is
 * computed once (cf_std_tail_prepare), like inv_a2 for GGX.
 * Private to src/model. Pure C11 + libm. */
#ifndef CLAYFIT_MODEL_TAILED_H
#define CLAYFIT_MODEL_TAILED_H

#include <stdint.h>
#include <string.h>

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
/* From here up D's ln r is log1p's (std_d) */
#define CF_STD_GAMMA_LOG1P 64.0

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
  double inv_a;     /* 1/a */
  double k;         /* K = a Γ(a + 1/2) / (√π Γ(a + 1)); K · B(a, 1/2) = 1 */
  double dlnk_da;   /* d ln K / da = 1/a + ψ(a + 1/2) − ψ(a + 1) */
  double inv_2a_m1; /* 1 / (2a − 1) = 1 / (2γ − 3) */
  cf_std_regime regime;
} cf_std_tail;

cf_std_tail cf_std_tail_prepare(double a2, double gamma);

/* ---- The distribution of normals (docs/model.md (T1); derivatives (T2)):
 *   D = 1 / (π α² cos⁴θ_h (1 + tan²θ_h / ((γ − 1) α²))^γ)
 *     = r^(γ−2) (β² / q)² / (π α²) = r^γ / (π α² cos⁴θ_h),
 *   q = sin²θ_h + β² cos²θ_h,  r = β² cos²θ_h / q,
 * (Ribardière et al. 2017, the STD with its α and γ; the form of bbm's
 * ndf/studentt.h; d_sin2 along sin² + cos² = 1, as ggx_d). ln r by log1p (exact where r is near
 * 1, the Beckmann limit). */
typedef struct cf_std_d {
  double value, d_a2, d_gamma, d_sin2;
} cf_std_d;

CF_ALWAYS_INLINE cf_std_d std_d(const cf_std_tail *t, double sin2_h, double cos2_h) {
  cf_std_d d = {0.0, 0.0, 0.0, 0.0};
  if (t->gamma <= 1.0 || !(cos2_h > 0.0)) return d; /* not normalisable / not lit */
  double gamma = t->gamma;
  if (t->regime == CF_STD_GGX) {
    cf_ggx_d g = ggx_d(t->a2, t->inv_a2, sin2_h, cos2_h);
    /* ∂/∂γ of the floored form below, as its neighbours γ = 2 ± h see it
     * (test_gradient's hard cases at c ~ 1e-100) */
    if (cos2_h < CF_STD_COS2_MIN) {
      cos2_h = CF_STD_COS2_MIN;
      sin2_h = 1.0 - CF_STD_COS2_MIN;
    }
    double q = sin2_h + t->b2 * cos2_h;
    d.value = g.value;
    d.d_a2 = g.d_a2;
    d.d_sin2 = g.d_sin2;
    d.d_gamma = g.value * (2.0 * sin2_h / q - log1p(sin2_h / (t->b2 * cos2_h)));
    return d;
  }
  int floored = cos2_h < CF_STD_COS2_MIN;
  if (floored) {
    cos2_h = CF_STD_COS2_MIN;
    sin2_h = 1.0 - CF_STD_COS2_MIN;
  }
  /* with x = tan²θ_h/β², r = 1/(1 + x) and β²/q = r/cos²θ_h, (T1) is
   *   D = r^γ / (π α² cos⁴θ_h),  ln r = −ln(1 + x);
   * x from a division of its own, since log and exp follow it on the lobe's
   * longest chain (M4T's value + gradient 127 against 130 ns with x from
   * 1/cos²θ_h, cf_eval_batch timed alternately); 1/q and 1/cos²θ_h from one
   * division. log(1 + x) carries 1.1e-16 absolute, γ · 1.1e-16 relative in
   * D: log1p (exact near the peak) from γ = 64 up (log1p costs 3× log here,
   * test_tailed_lobe bench) */
  double x = sin2_h / (t->b2 * cos2_h);
  double q = sin2_h + t->b2 * cos2_h, inv_qc = 1.0 / (q * cos2_h);
  double inv_cos2 = q * inv_qc, sin2_over_q = sin2_h * cos2_h * inv_qc; /* 1 − r */
  double ln_r = gamma < CF_STD_GAMMA_LOG1P ? -log(1.0 + x) : -log1p(x);
  d.value = exp(gamma * ln_r) * (inv_cos2 * inv_cos2) * (t->inv_a2 * CF_INV_PI);
  d.d_a2 = d.value * (gamma * sin2_over_q - 1.0) * t->inv_a2;
  d.d_gamma = d.value * (ln_r + gamma * sin2_over_q * t->inv_a);
  d.d_sin2 = floored ? 0.0 : -d.value * (gamma - 2.0 * q) * inv_qc;
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

/* ---- The masking tabulated once per γ, for the models' hot path
 * (docs/model.md §2.8, "The table"). With GGX's Q = α² + c² (1 − α²) (the
 * square of (10)'s shorthand) and the stretched cosine u = c/√Q, STD's
 * masking is GGX's times a function of u and γ alone, because Λ depends on
 * cot θ/α and γ only:
 *   L(c) = √Q g(u; γ),   g(u; γ) = L(c = u; α = 1, γ),   g ≡ 1 at γ = 2.
 * g is tabulated at fixed nodes in w = 1 − u² = s² α²/Q by octaves
 * [2^(−j−1), 2^(−j)], j = 0..45, of 16 (j = 0), 8, 4, 2 or 1 equal steps (to
 * j = 9, 15, 25, 45): g is even in u, so smooth in w at u = 0 (w = 1), and
 * g − u ∝ w^(γ−1) near u = 1 (singular for γ < 2), which octaves resolve;
 * below w = 2^−46, linear to g = 1 at w = 0. w needs no square root before
 * the lookup (√Q is taken beside it): M4T's value + gradient at tail 2.5
 * 134 against 141 ns with the table in 1 − u (cf_eval_batch, the two builds
 * timed alternately). Each step is the cubic Hermite from the values and
 * slopes at its ends; ∂g/∂γ is the same Hermite of the nodes' ∂g/∂γ and
 * ∂²g/∂w∂γ, so every derivative of the tabulated L is the derivative of its
 * value, exactly. The table holds each step's cubics in t (in [0, 1] along the
 * step) as power series, evaluated by Horner: 15 % off a tailed M4's
 * evaluation against the Hermite weights (a prototype, 147 against 171 ns).
 * One lookup: the octave from w's exponent bits, the step from its mantissa,
 * 64 bytes. */
enum {
  CF_STD_TABLE_OCTAVES = 46, /* j = 0..45 */
  CF_STD_TABLE_NODES = 153,  /* 16 + 8·9 + 4·6 + 2·10 + 1·20 steps, + 1 */
  CF_STD_TABLE_STEPS = CF_STD_TABLE_NODES - 1,
  CF_STD_GRID_GAMMAS = 33 /* the grid's γ nodes (tailed_grid.c) */
};

/* One node: g, ∂g/∂w, ∂g/∂γ, ∂²g/∂w∂γ. */
typedef struct cf_std_node {
  double g, g_w, g_gamma, g_w_gamma;
} cf_std_node;

/* One step from node k + 1 (t = 0) to node k (t = 1, w larger): g and
 * ∂g/∂γ as Σ c_n t^n, Σ d_n t^n. */
typedef struct cf_std_step {
  double c[4];
  double d[4];
} cf_std_step;

/* The table of one γ; built (cf_std_table_build) for the GGX and the
 * general regimes, where `built` is 1. */
typedef struct cf_std_table {
  cf_std_step step[CF_STD_TABLE_STEPS];
  double gamma;
  int built;
} cf_std_table;

/* The table from its nodes (in the order of cf_std_table_position). */
void cf_std_table_from_nodes(cf_std_table *tb, const cf_std_node node[CF_STD_TABLE_NODES]);

/* Octave j (0..45) has 2^log2_steps[j] steps and nodes first[j] ..
 * first[j + 1] from w = 2^−j downward; first[46] is the last node, at
 * w = 2^−46. */
extern const unsigned char cf_std_octave_first[CF_STD_TABLE_OCTAVES + 1];
extern const unsigned char cf_std_octave_log2_steps[CF_STD_TABLE_OCTAVES];

/* The position w of node k. */
double cf_std_table_position(int k);

/* The table at γ, from the precomputed grid over γ (tailed_grid.c, written
 * from the exact nodes by tools/tailed_grid_gen.c; cubic Hermite in
 * p = 1/(γ − 1) between its nodes, whose ∂/∂γ are again exact derivatives
 * of the result): about 0.7 µs. Builds nothing (built = 0) where the lobe
 * needs no table (γ <= 1.5, γ >= 1e6). */
void cf_std_table_build(cf_std_table *tb, double gamma);

/* The same table from the exact masking at every node (tests): 15-50 µs. */
void cf_std_table_build_exact(cf_std_table *tb, double gamma);

/* The exact nodes at any γ > 1.5 (the grid's generator, at γ up to 1e6). */
void cf_std_table_nodes_exact(cf_std_node node[CF_STD_TABLE_NODES], double gamma);

/* The grid over γ: nodes at p_j = 1/(γ_j − 1) = 1 + (j − 16) Δ, j = 0..32,
 * Δ = (1 − p_0)/16, p_0 = 1/(1e6 − 1): from the Beckmann switch (j = 0)
 * through GGX (j = 16, exactly) to γ = 1.5 + 2.5e-7 (j = 32). Each entry holds
 * h = g f, ∂h/∂w, ∂h/∂p, ∂²h/∂w∂p with f = 1 − p/2, which takes out the
 * pole 1/(2γ − 3) of g at γ → 1.5. Written from the exact nodes by
 * tools/tailed_grid_gen.c at every build (src/model/CMakeLists.txt). */
#define CF_STD_GRID_STEP ((1.0 - 1.0 / (CF_STD_GAMMA_BECKMANN - 1.0)) / 16.0)
static inline double std_grid_p(int j) {
  return 1.0 + (j - 16) * CF_STD_GRID_STEP;
}
static inline double std_grid_f(double gamma) {
  return (2.0 * gamma - 3.0) / (2.0 * gamma - 2.0); /* 1 − p/2 */
}
extern const double cf_std_grid[CF_STD_GRID_GAMMAS][CF_STD_TABLE_NODES][4];

/* One node from the exact masking: g, ∂g/∂u, ∂g/∂γ, ∂²g/∂u∂γ (in the
 * fields of ∂/∂w) at u = c with s² = 1 − c² given, α = 1 (t prepared at
 * α² = 1), from (T4)-(T5) and their mixed derivative. */
cf_std_node cf_std_node_exact(const cf_std_tail *t, double c, double s2);

/* g, ∂g/∂w and ∂g/∂γ at w from the table. */
typedef struct cf_std_g {
  double g, g_w, g_gamma;
} cf_std_g;

/* 2^k for −1022 <= k <= 1023, from its bits */
CF_ALWAYS_INLINE double std_pow2(int k) {
  uint64_t bits = (uint64_t)(k + 1023) << 52;
  double x;
  memcpy(&x, &bits, sizeof x);
  return x;
}

/* One step at t: Horner; with_grad: ∂/∂w = (∂/∂t)/h (inv_h = 1/h) and ∂/∂γ. */
CF_ALWAYS_INLINE cf_std_g std_table_step(const cf_std_step *st, double t, double inv_h,
                                         int with_grad) {
  const double *c = st->c, *d = st->d;
  cf_std_g r;
  r.g = c[0] + t * (c[1] + t * (c[2] + t * c[3]));
  if (!with_grad) return r;
  r.g_gamma = d[0] + t * (d[1] + t * (d[2] + t * d[3]));
  r.g_w = (c[1] + t * (2.0 * c[2] + 3.0 * t * c[3])) * inv_h;
  return r;
}

/* At w = 1 − u²: the octave from w's exponent bits, the step from its
 * mantissa (binary64, as everywhere in clayfit); every octave has 2^k
 * steps, so the step's width is an exact power of 2. */
CF_ALWAYS_INLINE cf_std_g std_table_lookup(const cf_std_table *tb, double w, int with_grad) {
  if (!(w < 1.0)) /* u = 0 (c = 0): the first node, t = 1 on the first step */
    return std_table_step(&tb->step[0], 1.0, (1 << cf_std_octave_log2_steps[0]) * 2.0, with_grad);
  if (!(w >= 0x1p-46)) { /* linear to g(w = 0) = 1, ∂g/∂γ = 0; w < 0 (c = 1 + ulp): 0 */
    const cf_std_step *last = &tb->step[CF_STD_TABLE_STEPS - 1];        /* t = 0: the last node */
    double slope = (last->c[0] - 1.0) * 0x1p46, w0 = w > 0.0 ? w : 0.0; /* ∂g/∂w */
    return (cf_std_g){1.0 + slope * w0, slope, last->d[0] * (w0 * 0x1p46)};
  }
  uint64_t bits;
  memcpy(&bits, &w, sizeof bits);
  int e = (int)(bits >> 52) - 1023; /* w in [2^e, 2^(e+1)), e from −46 to −1 */
  int j = -e - 1;
  /* w = (1 + f) 2^e: the step i is f's first k bits, t the rest */
  const uint64_t fraction_mask = 0xFFFFFFFFFFFFFull, one = 0x3FF0000000000000ull;
  int k = cf_std_octave_log2_steps[j];
  uint64_t f = bits & fraction_mask, t_bits = ((f << k) & fraction_mask) | one;
  int i = (int)(f >> (52 - k));
  double t;
  memcpy(&t, &t_bits, sizeof t);
  /* steps run from w = 2^−j down */
  const cf_std_step *st = &tb->step[cf_std_octave_first[j] + (1 << k) - i - 1];
  return std_table_step(st, t - 1.0, std_pow2(k - e), with_grad);
}

/* The masking (T4) from the table (the general regime's L; requires
 * 0 <= c <= 1): L = √Q g(w), w = s² α²/Q, and by the chain rule through w
 * (∂w/∂c = −2c α²/Q², ∂w/∂α² = s² c²/Q²) and Q,
 *   ∂L/∂c = c ((1 − α²) g − 2 α² ∂g/∂w / Q) / √Q,
 *   ∂L/∂α² = s² (g + 2 (c²/Q) ∂g/∂w) / (2 √Q),   ∂L/∂γ = √Q ∂g/∂γ. */
CF_ALWAYS_INLINE cf_std_masking std_masking_tabulated(const cf_std_table *tb, double a2, double c,
                                                      int with_grad) {
  cf_std_masking m;
  double s2 = (1.0 - c) * (1.0 + c);
  double q = a2 + c * c * (1.0 - a2), inv_q = 1.0 / q, sqrt_q = sqrt(q);
  cf_std_g g = std_table_lookup(tb, s2 * a2 * inv_q, with_grad); /* no cancellation at u = 1 */
  m.value = sqrt_q * g.g;
  if (!with_grad) return m;
  double inv_sqrt_q = sqrt_q * inv_q, g_w_q = g.g_w * inv_q;
  m.d_c = c * inv_sqrt_q * ((1.0 - a2) * g.g - 2.0 * a2 * g_w_q);
  m.d_a2 = 0.5 * s2 * inv_sqrt_q * (g.g + 2.0 * c * c * g_w_q);
  m.d_gamma = sqrt_q * g.g_gamma;
  return m;
}

/* ---- The lobe for the models: D V with its partials, the Fresnel left to
 * the caller (S = F · value; ∂S/∂x = F · d_x, ∂S/∂F = value). t carries α²
 * and γ; tb is the table built for the same γ (one table serves every lobe
 * that shares the tail). γ = 2: ggx_d and smith_ggx_v, to the bit, with
 * d_gamma from the table; γ >= 1e6: Beckmann's masking (T8). */
typedef struct cf_std_dv {
  double value, d_a2, d_gamma, d_sin2, d_ci, d_co;
} cf_std_dv;

/* GGX's D·V with the same partials (d_gamma = 0): the GGX rungs' lobe and
 * the benchmark's reference. */
CF_ALWAYS_INLINE cf_std_dv ggx_dv(double a2, double inv_a2, double sin2_h, double cos2_h,
                                  double c_i, double c_o, int with_grad) {
  cf_ggx_d d = ggx_d(a2, inv_a2, sin2_h, cos2_h);
  cf_smith_v v = smith_ggx_v(a2, c_i, c_o);
  cf_std_dv s = {d.value * v.value, 0.0, 0.0, 0.0, 0.0, 0.0};
  if (!with_grad) return s;
  s.d_a2 = d.d_a2 * v.value + d.value * v.d_a2;
  s.d_sin2 = d.d_sin2 * v.value;
  s.d_ci = d.value * v.d_ci;
  s.d_co = d.value * v.d_co;
  return s;
}

/* What an M2-like model prepares once per parameter vector. */
typedef struct cf_std_lobe_prep {
  cf_std_tail tail;
  cf_std_table table;
} cf_std_lobe_prep;

void cf_std_lobe_prepare(cf_std_lobe_prep *p, double a2, double gamma);

/* V = 1/(2 (c_o L_i + c_i L_o)) from two maskings, (T6). */
CF_ALWAYS_INLINE cf_std_v std_v_of(const cf_std_masking *mi, const cf_std_masking *mo, double c_i,
                                   double c_o, int with_grad) {
  cf_std_v v = {0.0, 0.0, 0.0, 0.0, 0.0};
  v.value = 0.5 / (c_o * mi->value + c_i * mo->value);
  if (!with_grad) return v;
  double v2 = 2.0 * v.value * v.value; /* −∂V/∂(c_o L_i + c_i L_o) */
  v.d_a2 = -v2 * (c_o * mi->d_a2 + c_i * mo->d_a2);
  v.d_gamma = -v2 * (c_o * mi->d_gamma + c_i * mo->d_gamma);
  v.d_ci = -v2 * (mo->value + c_o * mi->d_c);
  v.d_co = -v2 * (mi->value + c_i * mo->d_c);
  return v;
}

cf_std_masking cf_std_masking_beckmann(const cf_std_tail *t, double c);

CF_ALWAYS_INLINE cf_std_dv std_dv(const cf_std_tail *t, const cf_std_table *tb, double sin2_h,
                                  double cos2_h, double c_i, double c_o, int with_grad) {
  cf_std_dv s = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  if (t->regime == CF_STD_MASKED) return s;
  cf_std_d d = std_d(t, sin2_h, cos2_h);
  cf_std_v vis;
  if (t->regime == CF_STD_GGX) {
    cf_smith_v g = smith_ggx_v(t->a2, c_i, c_o);
    vis = (cf_std_v){g.value, g.d_a2, 0.0, g.d_ci, g.d_co};
    if (with_grad) { /* ∂V/∂γ = −2V² (c_o ∂L_i/∂γ + c_i ∂L_o/∂γ), ∂L/∂γ = √Q ∂g/∂γ */
      cf_std_masking mi = std_masking_tabulated(tb, t->a2, c_i, 1);
      cf_std_masking mo = std_masking_tabulated(tb, t->a2, c_o, 1);
      vis.d_gamma = -2.0 * g.value * g.value * (c_o * mi.d_gamma + c_i * mo.d_gamma);
    }
  } else {
    cf_std_masking mi, mo;
    if (t->regime == CF_STD_BECKMANN) {
      mi = cf_std_masking_beckmann(t, c_i);
      mo = cf_std_masking_beckmann(t, c_o);
    } else {
      mi = std_masking_tabulated(tb, t->a2, c_i, with_grad);
      mo = std_masking_tabulated(tb, t->a2, c_o, with_grad);
    }
    vis = std_v_of(&mi, &mo, c_i, c_o, with_grad);
  }
  s.value = d.value * vis.value;
  if (!with_grad) return s;
  s.d_a2 = d.d_a2 * vis.value + d.value * vis.d_a2;
  s.d_gamma = d.d_gamma * vis.value + d.value * vis.d_gamma;
  s.d_sin2 = d.d_sin2 * vis.value;
  s.d_ci = d.value * vis.d_ci;
  s.d_co = d.value * vis.d_co;
  return s;
}

/* std_dv out of line (tests, benchmarks, exports). */
cf_std_dv cf_std_dv_eval(const cf_std_tail *t, const cf_std_table *tb, double sin2_h, double cos2_h,
                         double c_i, double c_o, int with_grad);

/* GGX's D V with the same partials (d_gamma = 0), out of line: the
 * benchmark's reference. */
cf_std_dv cf_ggx_dv_eval(double a2, double sin2_h, double cos2_h, double c_i, double c_o,
                         int with_grad);

/* ---- The lobe over a block (tailed_block.c; docs/model.md §2.8, "Cost"):
 * std_dv of CF_STD_BLOCK observations at once, for M4T's batches
 * (cf_eval_batch). In the general regime, on a processor with AVX2 and
 * FMA, the four lanes of a vector, with the exp and log1p of
 * tailed_block.c (within 1 ulp of libm's); each entry within 1e-14 of
 * std_dv's relative to its scale times 1 + γ + |γ ln r| (test_tailed_lobe
 * block); elsewhere std_dv lane by lane. A lane's result does not depend
 * on the other lanes. */
enum { CF_STD_BLOCK = 4 };

typedef struct cf_std_dv_block {
  double value[CF_STD_BLOCK], d_a2[CF_STD_BLOCK], d_gamma[CF_STD_BLOCK];
  double d_sin2[CF_STD_BLOCK], d_ci[CF_STD_BLOCK], d_co[CF_STD_BLOCK];
} cf_std_dv_block;

/* 1 where the vector path runs (x86-64 with AVX2 and FMA). */
int cf_std_block_vector(void);

/* A lobe's inputs over a block. */
typedef struct cf_std_block_in {
  double sin2[CF_STD_BLOCK], cos2[CF_STD_BLOCK], c_i[CF_STD_BLOCK], c_o[CF_STD_BLOCK];
} cf_std_block_in;

/* `lobes` (1 or 2) lobes over a block: t, in and out hold one entry a
 * lobe, tb the table of their one tail (two lobes in one call overlap:
 * M4T's film and base). vector: cf_std_block_vector()'s answer, asked
 * once per prepare (0 forces std_dv lane by lane: the tests' reference). */
void cf_std_dv_block_eval(const cf_std_tail *t, const cf_std_table *tb, int vector, int lobes,
                          const cf_std_block_in *in, int with_grad, cf_std_dv_block *out);

/* The vector path's exp (of y <= 0) and log1p (of x >= 0), for their test;
 * libm's where cf_std_block_vector() is 0. */
void cf_std_block_exp(const double y[CF_STD_BLOCK], double out[CF_STD_BLOCK]);
void cf_std_block_log1p(const double x[CF_STD_BLOCK], double out[CF_STD_BLOCK]);

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
