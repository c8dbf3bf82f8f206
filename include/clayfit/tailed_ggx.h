/* clayfit: the GGX that best reproduces a tailed (STD) lobe, for renderers
 * that have GGX only (docs/presets.md, "Tailed lobes in GGX-only formats").
 *
 * A camera sees a sphere lit by a distant light from a direction drawn
 * uniformly over the sphere of directions; the GGX (r', F0') is the one of
 * least squares over those pixels, against the tailed lobe (r, γ, F0)
 * alone: in air (M2T's lobe, M4T's film) or, for M4T's base, under the film
 * (F0_1, τ), at the refracted directions where the model sees it. The
 * quadrature is fixed (Gauss-Legendre) and the fit is solved through the
 * project's least-squares layer (src/lsq): the same input gives the same
 * bits.
 *
 * Library clayfit_model_fit (src/model/tailed_ggx.c): the model's domain,
 * with the model's own terms, above clayfit_model and clayfit_lsq. */
#ifndef CLAYFIT_TAILED_GGX_H
#define CLAYFIT_TAILED_GGX_H

#include <stddef.h>

#include "clayfit/model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The Fresnel of both lobes: Schlick's (docs/model.md (8) of model version
 * 1) or the exact dielectric one from η = (1 + √F0)/(1 − √F0) (model
 * version 2). CF_TAILED_FRESNEL_MODELS is the models' own. */
typedef enum cf_tailed_fresnel {
  CF_TAILED_FRESNEL_SCHLICK,
  CF_TAILED_FRESNEL_DIELECTRIC
} cf_tailed_fresnel;
#if CF_MODEL_VERSION >= 2
#define CF_TAILED_FRESNEL_MODELS CF_TAILED_FRESNEL_DIELECTRIC
#else
#define CF_TAILED_FRESNEL_MODELS CF_TAILED_FRESNEL_SCHLICK
#endif

/* Gauss-Legendre points: views (their elevation), θ_h, φ_h, each in
 * [1, 256]. The default agrees with 128 × 192 × 64 points to 1.4e-4
 * relative in the loss and 3.5e-5 in (r', F0'), over r in [0.03, 1] and γ
 * in [1.55, 1e6] (docs/presets.md; tests/test_tailed_ggx.c doubles it). */
typedef struct cf_tailed_ggx_quadrature {
  int views, thetas, phis;
} cf_tailed_ggx_quadrature;
#define CF_TAILED_GGX_QUADRATURE \
  { 32, 32, 12 }

/* The fit. */
typedef struct cf_tailed_ggx {
  double r, f0;      /* the GGX fitted */
  double rms_loss;   /* relative RMS of the fitted GGX over the lobe */
  double naive_loss; /* the same for GGX with the tailed lobe's own (r, F0) */
  int iterations;    /* the solver's */
  size_t nodes;      /* quadrature points where c_i > 0 */
} cf_tailed_ggx;

/* The GGX of the tailed lobe (r, γ, F0): in air (film NULL) or under M4's
 * film (film = {F0_1, τ}, τ the channels' mean), with a chosen Fresnel,
 * quadrature and start (NULL: the tailed lobe's own (r, F0)). r, F0, F0_1
 * and τ in the parameter table's ranges, γ > 1.5 and finite, the start in
 * the table's ranges, else CF_ERANGE with the reason ("GGX fit of a tailed
 * lobe: tail gamma 1.2 must be above 1.5 ..."); a quadrature outside
 * [1, 256] is CF_EINVAL. At γ = 2 the lobe is GGX: the answer is the start
 * with a loss of 0 (to rounding). */
cf_status cf_tailed_ggx_fit(double r, double gamma, double f0, const double *film,
                            cf_tailed_fresnel fresnel, const cf_tailed_ggx_quadrature *q,
                            const double start[2], cf_tailed_ggx *out, cf_error *err);

/* What the exporters call: the models' Fresnel, the default quadrature,
 * the tailed lobe's own start. */
cf_status cf_tailed_ggx_default(double r, double gamma, double f0, const double *film,
                                cf_tailed_ggx *out, cf_error *err);

/* Gauss-Legendre nodes and weights on [0, 1], n of them (Newton on P_n from
 * the Chebyshev-like guess; Numerical Recipes' gauleg): the quadratures of
 * this fit and of the exporter's other least-squares mappings. */
void cf_gauss_legendre01(int n, double *x, double *w);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_TAILED_GGX_H */
