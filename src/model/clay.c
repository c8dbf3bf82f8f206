/* M4 clay: a thin absorbing film (water, oil) over the clay body
 * (docs/model.md §3.5, steps 1-8: (22)-(30)):
 *
 *   f = S(F0_1, r1; l, v) + T(c_i) T(c_o) a f_base / η1²
 *   f_base = S(F0_2, r2; l', v') + K (1 − F(F0_2, c_i'))(1 − F(F0_2, c_o')) ON(ρ, σ; l', v')
 *
 * F is the exact dielectric Fresnel (8) at both interfaces (model version 2).
 * Every quantity of the film depends on F0_1 through η1; derivatives with
 * respect to F0_1 are written d_<name> (∂<name>/∂F0_1) and chained by hand.
 *
 * In the film, with l' = (l − c_i n)/η1 + c_i' n (step 3), the tangent
 * parts scale by 1/η1, so the invariants of the refracted pair are
 *   c_i', c_o',  t'² = t²/η1²,  g' = l'·v' − c_i' c_o' = g/η1²,
 * and the base needs no vectors. */
#include <string.h>

#include "models.h"

static void clay_prepare(const double *params, cf_prepared *prep) {
  cf_clay_prep *p = &prep->clay;
  double sigma = params[CF_CLAY_DIFFUSE_ROUGHNESS];
  double r1 = params[CF_CLAY_FILM_ROUGHNESS];
  double r2 = params[CF_CLAY_BASE_ROUGHNESS];
  p->on = oren_nayar_coeffs(sigma);
  p->a2_1 = (r1 * r1) * (r1 * r1);
  p->inv_a2_1 = 1.0 / p->a2_1;
  p->da2_1 = 4.0 * r1 * r1 * r1;
  p->a2_2 = (r2 * r2) * (r2 * r2);
  p->inv_a2_2 = 1.0 / p->a2_2;
  p->da2_2 = 4.0 * r2 * r2 * r2;
  p->eta_2 = fresnel_eta(params[CF_CLAY_BASE_F0]);

  /* step 1: η1 = (1 + √F0_1)/(1 − √F0_1), in s = √F0_1 (ds/dF0_1 = 1/(2s);
   * F0_1 >= 0.01 keeps s >= 0.1) */
  double f0_1 = params[CF_CLAY_FILM_F0];
  double s = sqrt(f0_1);
  double ds = 0.5 / s;
  double one_p = 1.0 + s, one_m = 1.0 - s;
  p->eta_1 = fresnel_eta(f0_1);
  p->inv_eta = one_m / one_p;
  p->d_inv_eta = -2.0 / (one_p * one_p) * ds;
  p->inv_eta2 = p->inv_eta * p->inv_eta;
  p->d_inv_eta2 = 2.0 * p->inv_eta * p->d_inv_eta;

  /* step 6: F̄_i = 1 − (1 − F̄_e)/η1², F̄_e the exact Fresnel's hemispherical
   * mean (closed form, terms.h); ∂η1/∂F0_1 = 2/(1 − s)² ds;
   * K = 1/(1 − ρ F̄_i e^{−4τ}) */
  cf_fresnel_mean fbar_e = fresnel_dielectric_mean(one_p / one_m);
  double d_fbar_e = fbar_e.d_eta * 2.0 / (one_m * one_m) * ds;
  double fbar_i = 1.0 - (1.0 - fbar_e.value) * p->inv_eta2;
  double d_fbar_i = d_fbar_e * p->inv_eta2 - (1.0 - fbar_e.value) * p->d_inv_eta2;
  for (int c = 0; c < 3; ++c) {
    double rho = params[CF_CLAY_ALBEDO + c];
    double tau = params[CF_CLAY_OPTICAL_DEPTH + c];
    double e4 = exp(-4.0 * tau);
    double x = rho * fbar_i * e4;
    double k = 1.0 / (1.0 - x);
    p->rho[c] = rho;
    p->tau[c] = tau;
    p->k[c] = k;
    p->dk_df0_1[c] = k * k * rho * e4 * d_fbar_i;
    p->dk_dtau[c] = -4.0 * x * k * k;
  }
}

/* Steps 2 and 5: refracted cosine c' = sqrt((η1² − 1) + c²)/η1, without
 * the cancellation of sqrt(1 − (1 − c²)/η1²), its reciprocal (the path
 * length in the film) and its ∂/∂F0_1. With ρ = sqrt(η1² − 1 + c²),
 * c' = ρ/η1, 1/ρ = (1/η1)/c'. ρ is also the g of the film's Fresnel at c
 * (terms.h), kept as `root`. */
typedef struct refracted_cos {
  double c, inv_c, d_c, root;
} refracted_cos;

static inline refracted_cos refract_cos(const cf_clay_prep *p, double c) {
  refracted_cos r;
  double root = fresnel_root(&p->eta_1, c);
  r.root = root;
  r.c = root * p->inv_eta;
  r.inv_c = 1.0 / r.c;
  double inv_root = p->inv_eta * r.inv_c;
  r.d_c = 0.5 * p->inv_eta * p->eta_1.du * inv_root + root * p->d_inv_eta;
  return r;
}

/* Steps 2-3: the refracted pair (the base lobe's cosines, and its half
 * vector from t'² = t²/η1²), as clay_eval takes them, for M4T's batches
 * (clay_eval computes them in place: M4's code as it was). */
typedef struct clay_refraction {
  refracted_cos ri, ro;
  cf_half_vector hb;
} clay_refraction;

static inline clay_refraction clay_refract(const cf_clay_prep *p, const cf_geometry *g) {
  clay_refraction r;
  r.ri = refract_cos(p, g->cos_i);
  r.ro = refract_cos(p, g->cos_o);
  r.hb = half_vector(g->t_sq * p->inv_eta2, r.ri.c + r.ro.c);
  return r;
}

/* grad: rows of length dim (M4's 11, M4T's 12 with the tail last); tailed:
 * a constant at each call (M4T), so that M4 keeps GGX's code. given: NULL,
 * or the refracted pair and both lobes' D V (the film's, the base's)
 * computed before (M4T's batches, clay_block_eval); a constant at each call. */
typedef struct clay_given {
  clay_refraction r;
  cf_std_dv lobe[2];
} clay_given;

/* The quantities of clay_eval's value (steps 2-8) that its derivatives
 * reuse, one named step after another: the film's top specular, the film
 * (the refracted pair, the transmissions into it, the absorption's path),
 * the base in the film, and the per-channel combination. */
typedef struct clay_forward {
  cf_fresnel fresnel_1, f1_i, f1_o, fresnel_2, f2_i, f2_o;
  cf_std_dv s1, s2;
  refracted_cos ri, ro, larger; /* larger: max(c_i', c_o') */
  cf_half_vector hb;
  double top, t1_i, t1_o, transmission, g_b, path;
  double base_specular, t2_i, t2_o, transmission_b, x, on;
  double phi_unit, diffuse_unit, absorption[3], phi[3], base[3];
} clay_forward;

/* step 8, first term: the film's top specular, in air */
CF_ALWAYS_INLINE void clay_top(const cf_clay_prep *p, const cf_geometry *g, int with_grad,
                               int tailed, const clay_given *given, clay_forward *w) {
  w->fresnel_1 = fresnel_dielectric(&p->eta_1, g->c_d, fresnel_root(&p->eta_1, g->c_d));
  w->s1 = given ? given->lobe[0]
                : cf_lobe_dv(tailed ? &p->tail[0] : NULL, &p->table, p->a2_1, p->inv_a2_1,
                             g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, with_grad);
  w->top = w->fresnel_1.value * w->s1.value;
}

/* steps 2-5: the refracted pair's invariants, T(c_i) T(c_o) (T(c) = 1 −
 * F(F0_1, c), g the refraction's root) and the path factor 1/c_i' + 1/c_o'
 * of the absorption */
CF_ALWAYS_INLINE void clay_film(const cf_clay_prep *p, const cf_geometry *g,
                                const clay_given *given, clay_forward *w) {
  const double c_i = g->cos_i, c_o = g->cos_o;
  w->ri = given ? given->r.ri : refract_cos(p, c_i);
  w->ro = given ? given->r.ro : refract_cos(p, c_o);
  w->f1_i = fresnel_dielectric(&p->eta_1, c_i, w->ri.root);
  w->f1_o = fresnel_dielectric(&p->eta_1, c_o, w->ro.root);
  w->t1_i = w->f1_i.transmission, w->t1_o = w->f1_o.transmission;
  w->transmission = w->t1_i * w->t1_o;
  double t_sq_b = g->t_sq * p->inv_eta2;
  w->g_b = g->g * p->inv_eta2;
  w->hb = given ? given->r.hb : half_vector(t_sq_b, w->ri.c + w->ro.c);
  w->path = w->ri.inv_c + w->ro.inv_c;
}

/* step 7: the base's specular and diffuse lobes, in the film */
CF_ALWAYS_INLINE void clay_base(const cf_clay_prep *p, int with_grad, int tailed,
                                const clay_given *given, clay_forward *w) {
  const cf_fresnel_eta *e2 = &p->eta_2;
  const refracted_cos *ri = &w->ri, *ro = &w->ro;
  w->fresnel_2 = fresnel_dielectric(e2, w->hb.c_d, fresnel_root(e2, w->hb.c_d));
  w->s2 = given ? given->lobe[1]
                : cf_lobe_dv(tailed ? &p->tail[1] : NULL, &p->table, p->a2_2, p->inv_a2_2,
                             w->hb.sin2_h, w->hb.cos2_h, ri->c, ro->c, with_grad);
  w->base_specular = w->fresnel_2.value * w->s2.value;
  w->f2_i = fresnel_dielectric(e2, ri->c, fresnel_root(e2, ri->c));
  w->f2_o = fresnel_dielectric(e2, ro->c, fresnel_root(e2, ro->c));
  w->t2_i = w->f2_i.transmission, w->t2_o = w->f2_o.transmission;
  w->transmission_b = w->t2_i * w->t2_o;
  w->larger = ri->c > ro->c ? *ri : *ro;
  w->x = w->g_b > 0.0 ? w->g_b * w->larger.inv_c : 0.0; /* ON's angular factor */
  w->on = (p->on.a + p->on.b * w->x) * CF_INV_PI;       /* ON / ρ */
}

/* step 8: combine per channel; phi = T T a / η1² */
CF_ALWAYS_INLINE void clay_combine(const cf_clay_prep *p, clay_forward *w, double f[3]) {
  w->phi_unit = w->transmission * p->inv_eta2, w->diffuse_unit = w->transmission_b * w->on;
  for (int c = 0; c < 3; ++c) {
    w->absorption[c] = exp(-p->tau[c] * w->path);
    w->phi[c] = w->phi_unit * w->absorption[c];
    w->base[c] = w->base_specular + p->k[c] * p->rho[c] * w->diffuse_unit;
    f[c] = w->top + w->phi[c] * w->base[c];
  }
}

CF_ALWAYS_INLINE void clay_store_terms(const cf_clay_prep *p, const clay_forward *w,
                                       cf_clay_terms *terms) {
  terms->top = w->top;
  terms->transmission = w->transmission;
  terms->inv_eta2 = p->inv_eta2;
  for (int c = 0; c < 3; ++c) {
    terms->absorption[c] = w->absorption[c];
    terms->recycling[c] = p->k[c];
    terms->base[c] = w->base[c];
  }
}

/* The gradient's rows from the value's quantities: the top lobe, the
 * refracted invariants' ∂/∂F0_1, the base's specular and diffuse lobes,
 * chained per channel. */
CF_ALWAYS_INLINE void clay_gradient(const cf_clay_prep *p, const cf_geometry *g,
                                    const clay_forward *w, double *grad, int dim, int tailed) {
  const refracted_cos ri = w->ri, ro = w->ro, larger = w->larger;
  const cf_half_vector hb = w->hb;
  const cf_std_dv s1 = w->s1, s2 = w->s2;
  /* top lobe */
  double dtop_dr1 = w->fresnel_1.value * s1.d_a2 * p->da2_1;
  double dtop_df0_1 = w->fresnel_1.d_f0 * s1.value;
  double dtransmission = -(w->f1_i.d_f0 * w->t1_o + w->t1_i * w->f1_o.d_f0);

  /* ∂/∂F0_1 of the refracted invariants */
  double d_path = -ri.d_c * ri.inv_c * ri.inv_c - ro.d_c * ro.inv_c * ro.inv_c;
  double d_t_sq_b = g->t_sq * p->d_inv_eta2;
  double d_g_b = g->g * p->d_inv_eta2;
  double d_sum_b = ri.d_c + ro.d_c;
  double d_s_sq_b = d_t_sq_b + 2.0 * (ri.c + ro.c) * d_sum_b;
  double d_sin2_b = (d_t_sq_b - hb.sin2_h * d_s_sq_b) * hb.inv_s_sq;
  /* c_d' = sqrt(s'²)/2, so ∂c_d' = ∂s'² / (8 c_d') = ∂s'² c_d' / (2 s'²) */
  double d_c_d_b = 0.5 * d_s_sq_b * hb.c_d * hb.inv_s_sq;

  /* base specular: through F(c_d'), D(sin²θ_h') and V(c_i', c_o') */
  const cf_fresnel fresnel_2 = w->fresnel_2;
  double dbase_spec_df0_1 = fresnel_2.d_c * d_c_d_b * s2.value +
                            fresnel_2.value * s2.d_sin2 * d_sin2_b +
                            fresnel_2.value * (s2.d_ci * ri.d_c + s2.d_co * ro.d_c);
  double dbase_spec_dr2 = fresnel_2.value * s2.d_a2 * p->da2_2;
  double dbase_spec_df0_2 = fresnel_2.d_f0 * s2.value;
  /* the one tail of both lobes (M4T) */
  double dtop_dtail = w->fresnel_1.value * s1.d_gamma;
  double dbase_spec_dtail = fresnel_2.value * s2.d_gamma;

  /* base diffuse: transmissions into the clay, and the angular factor */
  double dtransmission_b_df0_1 = -(w->f2_i.d_c * ri.d_c * w->t2_o + w->t2_i * w->f2_o.d_c * ro.d_c);
  double dtransmission_b_df0_2 = -(w->f2_i.d_f0 * w->t2_o + w->t2_i * w->f2_o.d_f0);
  double dx_df0_1 = 0.0;
  if (w->g_b > 0.0) dx_df0_1 = (d_g_b - w->g_b * larger.d_c * larger.inv_c) * larger.inv_c;
  double don_df0_1 = p->on.b * dx_df0_1 * CF_INV_PI;
  double don_dsigma = (p->on.d_a + p->on.d_b * w->x) * CF_INV_PI;

  /* channel-independent factors of the rows below (diffuse_unit = ∂base/∂(Kρ),
   * phi_unit = phi/a) */
  double ddiffuse_unit_df0_1 = dtransmission_b_df0_1 * w->on + w->transmission_b * don_df0_1;
  double dphi_unit_df0_1 = dtransmission * p->inv_eta2 + w->transmission * p->d_inv_eta2;
  for (int c = 0; c < 3; ++c) {
    double *row = grad + c * dim;
    double k = p->k[c], k_rho = k * p->rho[c], phi = w->phi[c], base = w->base[c];
    double diffuse_b = w->diffuse_unit * p->rho[c]; /* K-free base diffuse */
    double dphi_df0_1 = w->absorption[c] * (dphi_unit_df0_1 - w->phi_unit * p->tau[c] * d_path);
    double dbase_df0_1 =
        dbase_spec_df0_1 + p->dk_df0_1[c] * diffuse_b + k_rho * ddiffuse_unit_df0_1;

    /* ∂(K ρ)/∂ρ = K² (K = 1/(1 − ρ F̄_i e^{−4τ})) */
    row[CF_CLAY_ALBEDO + c] = phi * w->diffuse_unit * k * k;
    row[CF_CLAY_DIFFUSE_ROUGHNESS] = phi * k_rho * w->transmission_b * don_dsigma;
    row[CF_CLAY_FILM_ROUGHNESS] = dtop_dr1;
    row[CF_CLAY_FILM_F0] = dtop_df0_1 + dphi_df0_1 * base + phi * dbase_df0_1;
    row[CF_CLAY_OPTICAL_DEPTH + c] = phi * (-w->path * base + p->dk_dtau[c] * diffuse_b);
    row[CF_CLAY_BASE_ROUGHNESS] = phi * dbase_spec_dr2;
    row[CF_CLAY_BASE_F0] = phi * (dbase_spec_df0_2 + k_rho * w->on * dtransmission_b_df0_2);
    if (tailed) row[CF_CLAY_TAILED_TAIL] = dtop_dtail + phi * dbase_spec_dtail;
  }
}

CF_ALWAYS_INLINE void clay_eval(const cf_clay_prep *p, const cf_geometry *g, double f[3],
                                double *grad, int dim, int tailed, cf_clay_terms *terms,
                                const clay_given *given) {
  clay_forward w;
  clay_top(p, g, grad != NULL, tailed, given, &w);
  clay_film(p, g, given, &w);
  clay_base(p, grad != NULL, tailed, given, &w);
  clay_combine(p, &w, f);
  if (terms) clay_store_terms(p, &w, terms);
  if (grad) clay_gradient(p, g, &w, grad, dim, tailed);
}

static void clay_value(const cf_prepared *prep, const cf_geometry *g, double f[3]) {
  clay_eval(&prep->clay, g, f, NULL, CF_CLAY_DIM, 0, NULL, NULL);
}

static void clay_value_grad(const cf_prepared *prep, const cf_geometry *g, double f[3],
                            double *grad) {
  /* clay_eval writes every entry but the other channels' RGB ones */
  cf_zero_other_channels(grad, CF_CLAY_DIM, CF_CLAY_ALBEDO);
  cf_zero_other_channels(grad, CF_CLAY_DIM, CF_CLAY_OPTICAL_DEPTH);
  clay_eval(&prep->clay, g, f, grad, CF_CLAY_DIM, 0, NULL, NULL);
}

void cf_clay_terms_eval(const double *params, const cf_geometry *g, cf_clay_terms *terms) {
  *terms = (cf_clay_terms){0};
  if (!cf_geometry_is_lit(g)) return;
  cf_prepared prep;
  clay_prepare(params, &prep);
  double f[3];
  clay_eval(&prep.clay, g, f, NULL, CF_CLAY_DIM, 0, terms, NULL);
}

const cf_model_impl cf_clay_impl = {clay_prepare, clay_value, clay_value_grad, NULL};

/* M4T: M4's vector plus one tail for both lobes (model.h). */
static void clay_tailed_prepare(const double *params, cf_prepared *prep) {
  clay_prepare(params, prep);
  cf_clay_prep *p = &prep->clay;
  double gamma = params[CF_CLAY_TAILED_TAIL];
  p->tail[0] = cf_std_tail_prepare(p->a2_1, gamma);
  p->tail[1] = cf_std_tail_prepare(p->a2_2, gamma);
  cf_std_table_build(&p->table, gamma); /* the masking of both lobes (one tail) */
  /* the lobes over blocks of observations where they run as vectors:
   * M4T's value + gradient 108 against 131 ns (clayfit bench eval, best
   * passes of 7 runs alternating with the build before); at tail 2 (GGX's
   * code), above 1e6 and without AVX2, per observation */
  p->vector = p->tail[0].regime == CF_STD_GENERAL && cf_std_block_vector();
}

static void clay_tailed_value(const cf_prepared *prep, const cf_geometry *g, double f[3]) {
  clay_eval(&prep->clay, g, f, NULL, CF_CLAY_TAILED_DIM, 1, NULL, NULL);
}

static void clay_tailed_value_grad(const cf_prepared *prep, const cf_geometry *g, double f[3],
                                   double *grad) {
  cf_zero_other_channels(grad, CF_CLAY_TAILED_DIM, CF_CLAY_ALBEDO);
  cf_zero_other_channels(grad, CF_CLAY_TAILED_DIM, CF_CLAY_OPTICAL_DEPTH);
  clay_eval(&prep->clay, g, f, grad, CF_CLAY_TAILED_DIM, 1, NULL, NULL);
}

/* M4T over a batch where the lobes run as vectors (prep->vector): both
 * lobes of CF_STD_BLOCK lit observations at once (cf_std_dv_block_eval),
 * then the rest of clay_eval per observation. Unlit observations are
 * answered as eval.c does; a last, partial block repeats its last
 * observation, so that an observation's result never depends on its
 * neighbours. */
typedef struct clay_block {
  const cf_geometry *g[CF_STD_BLOCK];
  size_t index[CF_STD_BLOCK];
  clay_given given[CF_STD_BLOCK]; /* the refracted pairs, then the lobes */
  int n;
} clay_block;

CF_ALWAYS_INLINE void clay_block_eval(const cf_clay_prep *p, clay_block *b, double *f, double *grad,
                                      int with_grad) {
  cf_std_block_in in[2];
  for (int k = 0; k < CF_STD_BLOCK; ++k) {
    int m = k < b->n ? k : b->n - 1;
    const cf_geometry *g = b->g[m];
    const clay_refraction *r = &b->given[m].r;
    in[0].sin2[k] = g->sin2_h, in[0].cos2[k] = g->cos2_h;
    in[0].c_i[k] = g->cos_i, in[0].c_o[k] = g->cos_o;
    in[1].sin2[k] = r->hb.sin2_h, in[1].cos2[k] = r->hb.cos2_h;
    in[1].c_i[k] = r->ri.c, in[1].c_o[k] = r->ro.c;
  }
  cf_std_dv_block lobe[2];
  cf_std_dv_block_eval(p->tail, &p->table, p->vector, 2, in, with_grad, lobe);
  const size_t row = 3 * (size_t)CF_CLAY_TAILED_DIM;
  for (int k = 0; k < b->n; ++k) {
    clay_given *gv = &b->given[k];
    for (int l = 0; l < 2; ++l)
      gv->lobe[l] = (cf_std_dv){lobe[l].value[k],  lobe[l].d_a2[k], lobe[l].d_gamma[k],
                                lobe[l].d_sin2[k], lobe[l].d_ci[k], lobe[l].d_co[k]};
    double *gk = with_grad ? grad + row * b->index[k] : NULL;
    if (with_grad) {
      cf_zero_other_channels(gk, CF_CLAY_TAILED_DIM, CF_CLAY_ALBEDO);
      cf_zero_other_channels(gk, CF_CLAY_TAILED_DIM, CF_CLAY_OPTICAL_DEPTH);
    }
    clay_eval(p, b->g[k], f + 3 * b->index[k], gk, CF_CLAY_TAILED_DIM, 1, NULL, gv);
  }
  b->n = 0;
}

CF_ALWAYS_INLINE void clay_tailed_batch_body(const cf_clay_prep *p, size_t count,
                                             const cf_geometry *geometry, double *f, double *grad,
                                             int with_grad) {
  const size_t row = 3 * (size_t)CF_CLAY_TAILED_DIM;
  clay_block b;
  b.n = 0;
  for (size_t i = 0; i < count; ++i) {
    const cf_geometry *g = &geometry[i];
    if (!cf_geometry_is_lit(g)) {
      f[3 * i] = f[3 * i + 1] = f[3 * i + 2] = 0.0;
      if (with_grad) memset(grad + row * i, 0, row * sizeof *grad);
      continue;
    }
    b.g[b.n] = g;
    b.index[b.n] = i;
    b.given[b.n].r = clay_refract(p, g);
    if (++b.n == CF_STD_BLOCK) clay_block_eval(p, &b, f, grad, with_grad);
  }
  if (b.n) clay_block_eval(p, &b, f, grad, with_grad);
}

/* CF_FLATTEN: GCC left the Fresnels out of line in the value path (M4T's
 * value 78 against 63 ns inlined); forcing them inline everywhere instead
 * took M2's evaluation out of line, 2 % slower */
CF_FLATTEN static int clay_tailed_batch(const cf_prepared *prep, size_t count,
                                        const cf_geometry *geometry, double *f, double *grad) {
  if (!prep->clay.vector) return 0;
  if (grad)
    clay_tailed_batch_body(&prep->clay, count, geometry, f, grad, 1);
  else
    clay_tailed_batch_body(&prep->clay, count, geometry, f, NULL, 0);
  return 1;
}

const cf_model_impl cf_clay_tailed_impl = {clay_tailed_prepare, clay_tailed_value,
                                           clay_tailed_value_grad, clay_tailed_batch};
