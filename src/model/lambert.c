/* M0 lambert: f = ρ/π (docs/model.md (18)). */
#include "models.h"

enum { DIM = CF_LAMBERT_DIM };

static void lambert_prepare(const double *params, cf_prepared *prep) {
  for (int c = 0; c < 3; ++c)
    prep->diffuse.rho_over_pi[c] = params[CF_LAMBERT_ALBEDO + c] * CF_INV_PI;
}

static void lambert_value(const cf_prepared *prep, const cf_geometry *g, double f[3]) {
  (void)g;
  for (int c = 0; c < 3; ++c) f[c] = prep->diffuse.rho_over_pi[c];
}

static void lambert_value_grad(const cf_prepared *prep, const cf_geometry *g, double f[3],
                               double *grad) {
  lambert_value(prep, g, f);
  cf_zero_other_channels(grad, DIM, CF_LAMBERT_ALBEDO);
  for (int c = 0; c < 3; ++c) grad[c * DIM + CF_LAMBERT_ALBEDO + c] = CF_INV_PI;
}

const cf_model_impl cf_lambert_impl = {lambert_prepare, lambert_value, lambert_value_grad, NULL};
