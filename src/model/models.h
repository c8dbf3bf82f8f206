/* The models of the ladder behind one interface: what each precomputes
 * from its parameters once per call (prepare), and its value and
 * value-plus-gradient for one observation. Private to src/model. */
#ifndef CLAYFIT_MODEL_MODELS_H
#define CLAYFIT_MODEL_MODELS_H

#include "clayfit/model.h"
#include "tailed.h"
#include "terms.h"

/* M0 and the diffuse part of M1-M3: ρ/π and the Oren-Nayar coefficients. */
typedef struct cf_diffuse_prep {
  double rho_over_pi[3];
  cf_oren_nayar_coeffs on;
} cf_diffuse_prep;

/* M2 (and M2T): the diffuse prep plus the specular interface. */
typedef struct cf_dielectric_prep {
  cf_diffuse_prep diffuse;
  cf_fresnel_eta eta;        /* the interface's η² − 1 from F0 (7) */
  double a2, inv_a2, da2_dr; /* α² = r⁴, 1/α², ∂α²/∂r = 4 r³ */
  cf_std_tail tail;          /* M2T's lobe: STD's with tail.gamma and its table */
  cf_std_table table;
} cf_dielectric_prep;

/* M3: M2 plus the coat (a = 0.1 − 0.099 gloss). */
typedef struct cf_clearcoat_prep {
  cf_dielectric_prep dielectric;
  double weight, a2, log_a2, da2_dgloss;
} cf_clearcoat_prep;

/* M4: everything that depends on the parameters only. Derivatives with
 * respect to the film's F0_1 are prefixed d_ (∂/∂F0_1). */
typedef struct cf_clay_prep {
  cf_std_tail tail[2]; /* M4T: film and base STD's, one tail, one table */
  cf_std_table table;
  int vector; /* M4T's lobes as vectors over blocks (clay.c) */
  double rho[3];
  cf_oren_nayar_coeffs on;
  cf_fresnel_eta eta_1; /* top interface: η1² − 1 from F0_1 */
  double a2_1, inv_a2_1, da2_1;
  double inv_eta, d_inv_eta;   /* 1/η1 */
  double inv_eta2, d_inv_eta2; /* 1/η1² */
  double tau[3];
  double k[3], dk_df0_1[3], dk_dtau[3]; /* recycling K per channel */
  cf_fresnel_eta eta_2;                 /* base interface: η2² − 1 from F0_2 */
  double a2_2, inv_a2_2, da2_2;
} cf_clay_prep;

typedef union cf_prepared {
  cf_diffuse_prep diffuse;
  cf_dielectric_prep dielectric;
  cf_clearcoat_prep clearcoat;
  cf_clay_prep clay;
} cf_prepared;

/* One microfacet lobe's D·V with its partials: GGX's (terms.h), or STD's
 * with its tabulated masking when `tail` is not NULL (M2T, M4T; tailed.h),
 * which at tail 2 is GGX's to the bit. d_gamma is 0 for GGX. */
CF_ALWAYS_INLINE cf_std_dv cf_lobe_dv(const cf_std_tail *tail, const cf_std_table *table,
                                      double a2, double inv_a2, double sin2_h, double cos2_h,
                                      double c_i, double c_o, int with_grad) {
  if (tail) return std_dv(tail, table, sin2_h, cos2_h, c_i, c_o, with_grad);
  return ggx_dv(a2, inv_a2, sin2_h, cos2_h, c_i, c_o, with_grad);
}

/* value and value_grad are called for lit observations only (eval.c
 * answers the others); value_grad writes every entry of its 3 × dim
 * channel-major gradient (model.h). */
typedef struct cf_model_impl {
  void (*prepare)(const double *params, cf_prepared *prep);
  void (*value)(const cf_prepared *prep, const cf_geometry *g, double f[3]);
  void (*value_grad)(const cf_prepared *prep, const cf_geometry *g, double f[3], double *grad);
  /* NULL, or the whole of cf_eval_batch after prepare (unlit observations
   * included; M4T's lobes over blocks of observations, clay.c); returns 0
   * where it declines (eval.c then goes per observation) */
  int (*batch)(const cf_prepared *prep, size_t count, const cf_geometry *geometry, double *f,
               double *grad);
} cf_model_impl;

extern const cf_model_impl cf_lambert_impl;
extern const cf_model_impl cf_oren_nayar_impl;
extern const cf_model_impl cf_dielectric_impl;
extern const cf_model_impl cf_clearcoat_impl;
extern const cf_model_impl cf_clay_impl;
extern const cf_model_impl cf_dielectric_tailed_impl;
extern const cf_model_impl cf_clay_tailed_impl;

/* Shared preparation of the diffuse body and the M2 interface (M1-M3). */
void cf_diffuse_prepare(const double *rho, double sigma, cf_diffuse_prep *p);
void cf_dielectric_prepare(const double *params, cf_dielectric_prep *p);

/* M2 with its gradient written into rows of length `dim` (M3 reuses it
 * with dim 8, and writes its own two entries; M2T with 7, the tail last);
 * grad may be NULL. */
void cf_dielectric_eval(const cf_dielectric_prep *p, const cf_geometry *g, double f[3],
                        double *grad, int dim);

/* M2's batch (cf_model_impl.batch): four observations at once in the
 * lanes of a vector where the processor can (dielectric_block.c); 0 where
 * it declines. */
int cf_dielectric_batch(const cf_prepared *prep, size_t count, const cf_geometry *geometry,
                        double *f, double *grad);

/* M4 taken apart (docs/model.md (30)), for tests and reports:
 *   f_c = top + transmission · absorption_c · inv_eta2 · base_c. */
typedef struct cf_clay_terms {
  double top;           /* S(F0_1, r1; l, v) */
  double transmission;  /* T(c_i) T(c_o) */
  double inv_eta2;      /* 1/η1² */
  double absorption[3]; /* a = exp(−τ (1/c_i' + 1/c_o')) */
  double recycling[3];  /* K */
  double base[3];       /* f_base */
} cf_clay_terms;

/* All zero where the observation is not lit. */
void cf_clay_terms_eval(const double *params, const cf_geometry *g, cf_clay_terms *terms);

#endif /* CLAYFIT_MODEL_MODELS_H */
