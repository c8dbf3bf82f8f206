/* M2 dielectric (docs/model.md (20), (11)):
 *   f = S(F0, r; l, v) + (1 − F(F0, c_i))(1 − F(F0, c_o)) ON(ρ, σ; l, v),
 *   S = F(F0, c_d) D(r², c_h) V(r²; c_i, c_o),
 * F the exact dielectric Fresnel (8) (model version 2). */
#include "models.h"

void cf_dielectric_prepare(const double *params, cf_dielectric_prep *p) {
  cf_diffuse_prepare(params + CF_DIELECTRIC_ALBEDO, params[CF_DIELECTRIC_DIFFUSE_ROUGHNESS],
                     &p->diffuse);
  double r = params[CF_DIELECTRIC_ROUGHNESS];
  p->eta = fresnel_eta(params[CF_DIELECTRIC_F0]);
  p->a2 = (r * r) * (r * r);
  p->inv_a2 = 1.0 / p->a2;
  p->da2_dr = 4.0 * r * r * r;
}

/* M2 and M3 share the slots of albedo, diffuse_roughness, roughness, f0. */
_Static_assert((int)CF_DIELECTRIC_F0 == (int)CF_CLEARCOAT_F0 &&
                   (int)CF_DIELECTRIC_ROUGHNESS == (int)CF_CLEARCOAT_ROUGHNESS &&
                   (int)CF_DIELECTRIC_DIFFUSE_ROUGHNESS == (int)CF_CLEARCOAT_DIFFUSE_ROUGHNESS &&
                   (int)CF_DIELECTRIC_ALBEDO == (int)CF_CLEARCOAT_ALBEDO,
               "M3 extends M2's parameter vector");

/* tailed: a constant at each call, so that M2 and M3 keep GGX's code. */
CF_ALWAYS_INLINE void dielectric_eval(const cf_dielectric_prep *p, const cf_geometry *g,
                                      double f[3], double *grad, int dim, int tailed) {
  /* specular lobe, F at c_d; D·V GGX's (M2, M3) or STD's (M2T, docs/model.md
   * §2.8 and §3.8) */
  const cf_fresnel_eta *e = &p->eta;
  cf_fresnel fresnel = fresnel_dielectric(e, g->c_d, fresnel_root(e, g->c_d));
  cf_std_dv lobe = cf_lobe_dv(tailed ? &p->tail : NULL, &p->table, p->a2, p->inv_a2, g->sin2_h,
                              g->cos2_h, g->cos_i, g->cos_o, grad != NULL);
  double dv = lobe.value;
  double specular = fresnel.value * dv;

  /* diffuse lobe under the interface: (1 − F(F0, c_i))(1 − F(F0, c_o)),
   * exactly 1 at F0 = 0 (M2 is then M1 to the bit) */
  cf_fresnel f_i = fresnel_dielectric(e, g->cos_i, fresnel_root(e, g->cos_i));
  cf_fresnel f_o = fresnel_dielectric(e, g->cos_o, fresnel_root(e, g->cos_o));
  double t_i = f_i.transmission, t_o = f_o.transmission;
  double transmission = t_i * t_o;
  double x = g->on_angular;
  double q = p->diffuse.on.a + p->diffuse.on.b * x;
  for (int c = 0; c < 3; ++c) f[c] = specular + transmission * (p->diffuse.rho_over_pi[c] * q);
  if (!grad) return;

  cf_zero_other_channels(grad, dim, CF_DIELECTRIC_ALBEDO);
  double ds_dr = fresnel.value * lobe.d_a2 * p->da2_dr;
  double ds_df0 = fresnel.d_f0 * dv;
  double dt_df0 = -(f_i.d_f0 * t_o + t_i * f_o.d_f0);
  double dq_dsigma = p->diffuse.on.d_a + p->diffuse.on.d_b * x;
  for (int c = 0; c < 3; ++c) {
    double *row = grad + c * dim;
    double rho_over_pi = p->diffuse.rho_over_pi[c];
    row[CF_DIELECTRIC_ALBEDO + c] = transmission * CF_INV_PI * q;
    row[CF_DIELECTRIC_DIFFUSE_ROUGHNESS] = transmission * rho_over_pi * dq_dsigma;
    row[CF_DIELECTRIC_ROUGHNESS] = ds_dr;
    row[CF_DIELECTRIC_F0] = ds_df0 + dt_df0 * rho_over_pi * q;
    if (tailed) row[CF_DIELECTRIC_TAILED_TAIL] = fresnel.value * lobe.d_gamma;
  }
}

void cf_dielectric_eval(const cf_dielectric_prep *p, const cf_geometry *g, double f[3],
                        double *grad, int dim) {
  dielectric_eval(p, g, f, grad, dim, 0);
}

static void dielectric_prepare(const double *params, cf_prepared *prep) {
  cf_dielectric_prepare(params, &prep->dielectric);
}

static void dielectric_value(const cf_prepared *prep, const cf_geometry *g, double f[3]) {
  cf_dielectric_eval(&prep->dielectric, g, f, NULL, CF_DIELECTRIC_DIM);
}

static void dielectric_value_grad(const cf_prepared *prep, const cf_geometry *g, double f[3],
                                  double *grad) {
  cf_dielectric_eval(&prep->dielectric, g, f, grad, CF_DIELECTRIC_DIM);
}

const cf_model_impl cf_dielectric_impl = {dielectric_prepare, dielectric_value,
                                          dielectric_value_grad, cf_dielectric_batch};

/* M2T: M2's vector plus the tail (model.h). */
static void dielectric_tailed_prepare(const double *params, cf_prepared *prep) {
  cf_dielectric_prep *p = &prep->dielectric;
  cf_dielectric_prepare(params, p);
  p->tail = cf_std_tail_prepare(p->a2, params[CF_DIELECTRIC_TAILED_TAIL]);
  cf_std_table_build(&p->table, params[CF_DIELECTRIC_TAILED_TAIL]);
}

static void dielectric_tailed_value(const cf_prepared *prep, const cf_geometry *g, double f[3]) {
  dielectric_eval(&prep->dielectric, g, f, NULL, CF_DIELECTRIC_TAILED_DIM, 1);
}

static void dielectric_tailed_value_grad(const cf_prepared *prep, const cf_geometry *g, double f[3],
                                         double *grad) {
  dielectric_eval(&prep->dielectric, g, f, grad, CF_DIELECTRIC_TAILED_DIM, 1);
}

const cf_model_impl cf_dielectric_tailed_impl = {dielectric_tailed_prepare, dielectric_tailed_value,
                                                 dielectric_tailed_value_grad, NULL};
