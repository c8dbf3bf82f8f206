/* M3 clearcoat (docs/model.md (21); Burley 2012, B.2):
 *   f = M2 + w_c · 0.25 · F(0.04, c_d) · D1(a, c_h) · Vs(0.25; c_i, c_o),
 *   a = 0.1 + (0.001 − 0.1) gloss.
 * Burley's coat adds energy on top of M2 (docs/model.md §4.3). */
#include "models.h"

enum { DIM = CF_CLEARCOAT_DIM };

/* Burley's fixed constants: the coat's F0 (IOR 1.5) and the 0.25 weight of
 * the disney_brdf reference shader; its visibility (α_g = 0.25) depends on
 * the geometry only and is in cf_geometry. */
static const double coat_f0 = 0.04;
static const double coat_scale = 0.25;

static void clearcoat_prepare(const double *params, cf_prepared *prep) {
  cf_clearcoat_prep *p = &prep->clearcoat;
  cf_dielectric_prepare(params, &p->dielectric);
  double gloss = params[CF_CLEARCOAT_COAT_GLOSS];
  double a = 0.1 + (0.001 - 0.1) * gloss;
  p->weight = params[CF_CLEARCOAT_COAT_WEIGHT];
  p->a2 = a * a;
  p->log_a2 = log(p->a2);
  p->da2_dgloss = 2.0 * a * (0.001 - 0.1);
}

CF_ALWAYS_INLINE void clearcoat_eval(const cf_clearcoat_prep *p, const cf_geometry *g, double f[3],
                                     double *grad) {
  cf_dielectric_eval(&p->dielectric, g, f, grad, DIM);
  double fresnel = fresnel_schlick(coat_f0, g->weight_d);
  cf_gtr1 d1 = gtr1_d(p->a2, p->log_a2, g->sin2_h, g->cos2_h);
  double vis = g->coat_visibility;
  double unit_coat = coat_scale * fresnel * d1.value * vis; /* w_c = 1 */
  double coat = p->weight * unit_coat;
  for (int c = 0; c < 3; ++c) f[c] += coat;
  if (!grad) return;
  double dcoat_dgloss = p->weight * coat_scale * fresnel * vis * d1.d_a2 * p->da2_dgloss;
  for (int c = 0; c < 3; ++c) {
    grad[c * DIM + CF_CLEARCOAT_COAT_WEIGHT] = unit_coat;
    grad[c * DIM + CF_CLEARCOAT_COAT_GLOSS] = dcoat_dgloss;
  }
}

static void clearcoat_value(const cf_prepared *prep, const cf_geometry *g, double f[3]) {
  clearcoat_eval(&prep->clearcoat, g, f, NULL);
}

static void clearcoat_value_grad(const cf_prepared *prep, const cf_geometry *g, double f[3],
                                 double *grad) {
  clearcoat_eval(&prep->clearcoat, g, f, grad);
}

const cf_model_impl cf_clearcoat_impl = {clearcoat_prepare, clearcoat_value, clearcoat_value_grad,
                                         NULL};
