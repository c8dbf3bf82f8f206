/* M2 over four observations at once (cf_eval_batch's path for M2; the
 * model of dielectric.c, docs/model.md (20)): the four lanes of an AVX
 * vector where the processor has AVX (asked at run time: only these
 * functions are compiled for it, the build stays baseline x86-64), else
 * one observation at a time.
 *
 * Bit for bit the scalar path's results: the lanes do the same operations
 * in the same order as fresnel_dielectric, ggx_d, smith_ggx_v (terms.h),
 * ggx_dv (tailed.h) and dielectric_eval, with no fused multiply-add
 * (-ffp-contract=off, and AVX without FMA), and IEEE +, −, ×, / and √ round
 * the same in a lane as in a scalar register (test_batch compares the two
 * with memcmp). The partials M2 does not use (∂F/∂c, ∂D/∂sin²θ_h, ∂V/∂c)
 * are left out. A group of four with an unlit observation, and F0 = 0
 * (fresnel_dielectric_at_zero), go one at a time. On one thread, the best
 * of 60 passes over 16 384 observations (CPU time), value + gradient 34
 * against 11.6 ns an observation, the value 19 against 5.9 ns; a pass of
 * the peers' M2 problem (bench/peers, 146 112 pairs) 4.3-5.6 against
 * 1.9-2.0 ms. (M4's two GGX lobes in lanes, the rest of (30) one at a
 * time as M4T's batches do it, gained 1 %: not kept.) */
#include <string.h>

#include "models.h"

#if defined(__x86_64__) && defined(__GNUC__)
#define CF_M2_LANES 1
#include <immintrin.h>

/* One observation, lit or not, as eval.c's path does it. */
static void one(const cf_dielectric_prep *p, const cf_geometry *g, double f[3], double *grad) {
  if (cf_geometry_is_lit(g)) {
    cf_dielectric_eval(p, g, f, grad, CF_DIELECTRIC_DIM);
    return;
  }
  f[0] = f[1] = f[2] = 0.0;
  if (grad) memset(grad, 0, 3 * CF_DIELECTRIC_DIM * sizeof *grad);
}

#define CF_AVX __attribute__((target("avx")))
#define CF_AVX_INLINE static inline __attribute__((always_inline, target("avx")))

typedef double v4d __attribute__((vector_size(32)));

/* A geometry field of four observations. */
#define LANES(g, field) ((v4d){(g)[0].field, (g)[1].field, (g)[2].field, (g)[3].field})

/* fresnel_dielectric (terms.h) at root g = fresnel_root(e, c), u > 0:
 * F, T = 1 − F, ∂F/∂F0. */
typedef struct vfresnel {
  v4d value, transmission, d_f0;
} vfresnel;

CF_AVX_INLINE vfresnel vfresnel_dielectric(const cf_fresnel_eta *e, v4d c, int with_grad) {
  vfresnel f;
  const double u = e->u, eta2 = 1.0 + u;
  v4d g = _mm256_sqrt_pd(u + c * c);
  v4d a = c + g, cc = eta2 * c + g;
  v4d a_cc = a * cc, inv = 1.0 / (a_cc * g);
  v4d inv_a = cc * g * inv, inv_cc = a * g * inv, inv_g = a_cc * inv;
  v4d inv_a2 = inv_a * inv_a, inv_cc2 = inv_cc * inv_cc;
  v4d ua = u * inv_a;
  v4d r_s = -ua * inv_a, r_p = ua * (c * a - 1.0) * inv_cc;
  f.value = 0.5 * (r_s * r_s + r_p * r_p);
  f.transmission = 2.0 * c * g * (inv_a2 + eta2 * inv_cc2);
  if (!with_grad) return f;
  v4d u_a4 = u * inv_a2 * inv_a2;
  f.d_f0 = e->du * c * inv_g * (u_a4 + r_p * (2.0 * g * g - eta2) * inv_cc2);
  return f;
}

/* Four observations, all lit: dielectric_eval's f and 3 × dim gradient
 * (tailed = 0, dim = CF_DIELECTRIC_DIM). */
CF_AVX_INLINE void lanes_body(const cf_dielectric_prep *p, const cf_geometry *g, double *f,
                              double *grad, int with_grad) {
  const int dim = CF_DIELECTRIC_DIM;
  const double a2 = p->a2;
  v4d c_i = LANES(g, cos_i), c_o = LANES(g, cos_o), x = LANES(g, on_angular);
  v4d sin2 = LANES(g, sin2_h), cos2 = LANES(g, cos2_h);
  vfresnel fresnel = vfresnel_dielectric(&p->eta, LANES(g, c_d), with_grad);
  /* ggx_dv: ggx_d's D and smith_ggx_v's V */
  v4d q = sin2 + a2 * cos2, inv_q = 1.0 / q;
  v4d d = a2 * CF_INV_PI * inv_q * inv_q;
  v4d lambda_i = _mm256_sqrt_pd(a2 + c_i * c_i * (1.0 - a2));
  v4d lambda_o = _mm256_sqrt_pd(a2 + c_o * c_o * (1.0 - a2));
  v4d vis = 0.5 * (1.0 / (c_o * lambda_i + c_i * lambda_o));
  v4d dv = d * vis, specular = fresnel.value * dv;
  vfresnel f_i = vfresnel_dielectric(&p->eta, c_i, with_grad);
  vfresnel f_o = vfresnel_dielectric(&p->eta, c_o, with_grad);
  v4d transmission = f_i.transmission * f_o.transmission;
  v4d qd = p->diffuse.on.a + p->diffuse.on.b * x;
  v4d value[3];
  for (int c = 0; c < 3; ++c) value[c] = specular + transmission * (p->diffuse.rho_over_pi[c] * qd);
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) f[3 * k + c] = value[c][k];
  if (!with_grad) return;

  v4d d_a2 = d * (sin2 - a2 * cos2) * inv_q * p->inv_a2;
  v4d v2 = 2.0 * vis * vis;
  v4d inv_lambda_i = 1.0 / lambda_i, inv_lambda_o = 1.0 / lambda_o;
  v4d v_a2 =
      -0.5 * v2 * (c_o * (1.0 - c_i * c_i) * inv_lambda_i + c_i * (1.0 - c_o * c_o) * inv_lambda_o);
  v4d lobe_d_a2 = d_a2 * vis + d * v_a2;
  v4d ds_dr = fresnel.value * lobe_d_a2 * p->da2_dr;
  v4d ds_df0 = fresnel.d_f0 * dv;
  v4d dt_df0 = -(f_i.d_f0 * f_o.transmission + f_i.transmission * f_o.d_f0);
  v4d dq_dsigma = p->diffuse.on.d_a + p->diffuse.on.d_b * x;
  v4d albedo = transmission * CF_INV_PI * qd, sigma[3], f0[3];
  for (int c = 0; c < 3; ++c) {
    double rho_over_pi = p->diffuse.rho_over_pi[c];
    sigma[c] = transmission * rho_over_pi * dq_dsigma;
    f0[c] = ds_df0 + dt_df0 * rho_over_pi * qd;
  }
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) {
      double *row = grad + (3 * k + c) * dim;
      for (int a = 0; a < 3; ++a) row[CF_DIELECTRIC_ALBEDO + a] = a == c ? albedo[k] : 0.0;
      row[CF_DIELECTRIC_DIFFUSE_ROUGHNESS] = sigma[c][k];
      row[CF_DIELECTRIC_ROUGHNESS] = ds_dr[k];
      row[CF_DIELECTRIC_F0] = f0[c][k];
    }
}

/* The batch, groups of four lit observations in lanes (with_grad a
 * constant at each call). */
CF_AVX_INLINE void lanes_batch(const cf_dielectric_prep *p, size_t count,
                               const cf_geometry *geometry, double *f, double *grad,
                               int with_grad) {
  const size_t row = 3 * CF_DIELECTRIC_DIM;
  size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    const cf_geometry *g = geometry + i;
    if (cf_geometry_is_lit(&g[0]) && cf_geometry_is_lit(&g[1]) && cf_geometry_is_lit(&g[2]) &&
        cf_geometry_is_lit(&g[3])) {
      lanes_body(p, g, f + 3 * i, with_grad ? grad + row * i : NULL, with_grad);
      continue;
    }
    for (size_t k = i; k < i + 4; ++k)
      one(p, &geometry[k], f + 3 * k, with_grad ? grad + row * k : NULL);
  }
  for (; i < count; ++i) one(p, &geometry[i], f + 3 * i, with_grad ? grad + row * i : NULL);
}

CF_AVX static void lanes_grad(const cf_dielectric_prep *p, size_t count,
                              const cf_geometry *geometry, double *f, double *grad) {
  lanes_batch(p, count, geometry, f, grad, 1);
}

CF_AVX static void lanes_value(const cf_dielectric_prep *p, size_t count,
                               const cf_geometry *geometry, double *f) {
  lanes_batch(p, count, geometry, f, NULL, 0);
}
#endif

int cf_dielectric_batch(const cf_prepared *prep, size_t count, const cf_geometry *geometry,
                        double *f, double *grad) {
  const cf_dielectric_prep *p = &prep->dielectric;
#ifdef CF_M2_LANES
  if (p->eta.u > 0.0 && __builtin_cpu_supports("avx")) {
    if (grad)
      lanes_grad(p, count, geometry, f, grad);
    else
      lanes_value(p, count, geometry, f);
    return 1;
  }
#endif
  (void)p, (void)count, (void)geometry, (void)f, (void)grad;
  return 0;
}
