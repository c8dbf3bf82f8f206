/* M1 oren_nayar: f = ON(ρ, σ; l, v) (docs/model.md (19), (12)). */
#include "models.h"

void cf_diffuse_prepare(const double *rho, double sigma, cf_diffuse_prep *p) {
  for (int c = 0; c < 3; ++c) p->rho_over_pi[c] = rho[c] * CF_INV_PI;
  p->on = oren_nayar_coeffs(sigma);
}

static void oren_nayar_prepare(const double *params, cf_prepared *prep) {
  cf_diffuse_prepare(params + CF_OREN_NAYAR_ALBEDO, params[CF_OREN_NAYAR_DIFFUSE_ROUGHNESS],
                     &prep->diffuse);
}

CF_ALWAYS_INLINE void oren_nayar_eval(const cf_diffuse_prep *p, const cf_geometry *g, double f[3],
                                      double *grad) {
  enum { DIM = CF_OREN_NAYAR_DIM };
  double x = g->on_angular;
  double q = p->on.a + p->on.b * x;
  for (int c = 0; c < 3; ++c) f[c] = p->rho_over_pi[c] * q;
  if (!grad) return;
  cf_zero_other_channels(grad, DIM, CF_OREN_NAYAR_ALBEDO);
  double dq_dsigma = p->on.d_a + p->on.d_b * x;
  for (int c = 0; c < 3; ++c) {
    double *row = grad + c * DIM;
    row[CF_OREN_NAYAR_ALBEDO + c] = CF_INV_PI * q;
    row[CF_OREN_NAYAR_DIFFUSE_ROUGHNESS] = p->rho_over_pi[c] * dq_dsigma;
  }
}

static void oren_nayar_value(const cf_prepared *prep, const cf_geometry *g, double f[3]) {
  oren_nayar_eval(&prep->diffuse, g, f, NULL);
}

static void oren_nayar_value_grad(const cf_prepared *prep, const cf_geometry *g, double f[3],
                                  double *grad) {
  oren_nayar_eval(&prep->diffuse, g, f, grad);
}

const cf_model_impl cf_oren_nayar_impl = {oren_nayar_prepare, oren_nayar_value,
                                          oren_nayar_value_grad, NULL};
