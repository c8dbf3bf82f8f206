/* clayfit: the layered clay reflectance model (docs/model.md), evaluated in C.
 *
 * What the evaluator returns
 * --------------------------
 * The BRDF f(l, v) itself, per linear-RGB channel, in 1/sr: NOT f·cos.
 * The radiance reflected from a light of irradiance E (measured
 * perpendicular to the light direction) is L = f · E · c_i, c_i = n·l.
 * On request it also returns the exact analytic derivative of every channel
 * with respect to every entry of the parameter vector.
 *
 * Conventions (docs/model.md §1)
 * -------------------------------
 * - n, l, v are unit vectors pointing away from the surface: the outward
 *   normal, toward the light, toward the camera. The evaluator does not
 *   normalise them (the CLI does); give unit vectors.
 * - If c_i = n·l <= 0 or c_o = n·v <= 0, f = 0 (and its gradient is 0).
 *   Likewise when c_i·c_o is below DBL_MIN (both directions within about
 *   1e-154 of the horizon): there a narrow specular lobe exceeds the range
 *   of double (f ~ 1/(4π c α³)) and its derivative would overflow; the
 *   reflected radiance f·c_i of such a pair has measure zero in any image.
 * - Roughness is perceptual: the GGX width is α = r².
 * - F0 is the reflectance at normal incidence; η = (1 + √F0)/(1 − √F0).
 *   M2-M4 use the exact dielectric Fresnel of that η (model version 2,
 *   CF_MODEL_VERSION), which vanishes at F0 = 0.
 * - Parameters are used exactly as given, never clamped. Their ranges
 *   (cf_param_info.lower/upper, docs/model.md §1.6) are for the caller
 *   and the solver to enforce; cf_params_check() tests a vector against
 *   them. Outside the ranges the result may be meaningless or not finite.
 *
 * Parameter vectors
 * -----------------
 * A model's parameter vector is the concatenation of its parameters in the
 * order of its CF_PARAMS_<MODEL> list below; an RGB parameter takes three
 * consecutive entries (r, g, b). The constants CF_<MODEL>_<PARAM> give each
 * parameter's first slot and CF_<MODEL>_DIM the length, for example for
 * M4 (clay), dim 11:
 *   [0..2] albedo ρ (RGB)      [3] diffuse_roughness σ (rad)
 *   [4] film_roughness r1      [5] film_f0 F0_1
 *   [6..8] optical_depth τ (RGB)
 *   [9] base_roughness r2      [10] base_f0 F0_2
 *
 * Gradients
 * ---------
 * grad (when not NULL) receives 3 × dim doubles, channel-major:
 *   grad[c * dim + k] = ∂f_c / ∂params[k],  c = 0 (R), 1 (G), 2 (B).
 * Entries of an RGB parameter for another channel are 0.
 */
#ifndef CLAYFIT_MODEL_H
#define CLAYFIT_MODEL_H

#include <float.h>
#include <stddef.h>

#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The version of the model's formulas (docs/model.md, top), written into
 * fit.json and the presets. 1: Schlick's Fresnel in M2-M4 (until issue 18);
 * 2: the exact dielectric Fresnel from η (docs/model.md (8)), so that M2 at
 * F0 = 0 is M1 and the ladder is nested. The parameters did not change. */
#define CF_MODEL_VERSION 2

/* ---------------------------------------------------------------------
 * The parameter table: the one place that describes every parameter.
 * X(ID, name, symbol, components, unit, default, lower, upper, meaning)
 * name: as in docs/model.md §1.5 (files, CLI, reports, presets).
 * unit: "1" for dimensionless, "rad" for radians.
 * default: the value used when none is given (and, later, held when a
 *   capture does not constrain the parameter).
 * lower, upper: the ranges of docs/model.md §1.6 (the fit bounds), inclusive.
 * ------------------------------------------------------------------- */
/* clang-format off */
#define CF_PARAM_MAP(X)                                                        \
  X(ALBEDO, "albedo", "rho", 3, "1", 0.5, 0.0, 1.0,                            \
    "diffuse albedo of the clay body, per linear-RGB channel")                 \
  X(DIFFUSE_ROUGHNESS, "diffuse_roughness", "sigma", 1, "rad", 0.0, 0.0, 1.2, \
    "Oren-Nayar slope deviation of the diffuse body (0 = Lambert)")            \
  X(ROUGHNESS, "roughness", "r", 1, "1", 0.5, 0.03, 1.0,                       \
    "perceptual GGX roughness of the specular interface (alpha = r^2)")        \
  X(F0, "f0", "F0", 1, "1", 0.04, 0.0, 0.25,                                   \
    "normal-incidence Fresnel reflectance of the specular interface")          \
  X(COAT_WEIGHT, "coat_weight", "w_c", 1, "1", 0.0, 0.0, 1.0,                  \
    "weight of Burley's clear-coat lobe (0 = no coat; Burley 2012 default)")  \
  X(COAT_GLOSS, "coat_gloss", "gloss", 1, "1", 1.0, 0.0, 1.0,                  \
    "gloss of the clear-coat lobe: GTR1 width a = 0.1 - 0.099 gloss")          \
  X(FILM_ROUGHNESS, "film_roughness", "r1", 1, "1", 0.15, 0.03, 1.0,           \
    "perceptual GGX roughness of the film's top surface (alpha = r1^2)")       \
  X(FILM_F0, "film_f0", "F0_1", 1, "1", 0.02, 0.01, 0.25,                      \
    "normal-incidence reflectance of the air-to-film interface (water 0.02)") \
  X(OPTICAL_DEPTH, "optical_depth", "tau", 3, "1", 0.1, 0.0, 8.0,              \
    "optical depth of the film at normal incidence, per channel "              \
    "(density x absorption)")                                                  \
  X(BASE_ROUGHNESS, "base_roughness", "r2", 1, "1", 0.5, 0.03, 1.0,            \
    "perceptual GGX roughness of the clay surface under the film")            \
  X(BASE_F0, "base_f0", "F0_2", 1, "1", 0.004, 0.0, 0.25,                      \
    "normal-incidence reflectance of the film-to-clay interface "             \
    "(clay under water about 0.004)")                                          \
  X(TAIL, "tail", "gamma", 1, "1", 2.0, 1.6, 100.0,                            \
    "tail of the STD microfacet lobes (2 = GGX; lower = longer tail, "        \
    "large = Beckmann)")

/* clang-format on */

typedef enum cf_param_id {
#define CF__PARAM_ENUM(ID, ...) CF_PARAM_##ID,
  CF_PARAM_MAP(CF__PARAM_ENUM)
#undef CF__PARAM_ENUM
      CF_PARAM_COUNT
} cf_param_id;

/* CF_NCOMP_<ID>: number of vector entries of a parameter (1 or 3). */
enum {
#define CF__PARAM_NCOMP(ID, name, symbol, ncomp, ...) CF_NCOMP_##ID = ncomp,
  CF_PARAM_MAP(CF__PARAM_NCOMP)
#undef CF__PARAM_NCOMP
};

/* ---------------------------------------------------------------------
 * The model ladder (docs/model.md §3): each model's parameters
 * in vector order, then X(ID, code, name, params list, summary).
 * ------------------------------------------------------------------- */
/* clang-format off */
#define CF_PARAMS_LAMBERT(P, M) P(M, ALBEDO)
#define CF_PARAMS_OREN_NAYAR(P, M) P(M, ALBEDO) P(M, DIFFUSE_ROUGHNESS)
#define CF_PARAMS_DIELECTRIC(P, M) \
  P(M, ALBEDO) P(M, DIFFUSE_ROUGHNESS) P(M, ROUGHNESS) P(M, F0)
#define CF_PARAMS_CLEARCOAT(P, M)                                          \
  P(M, ALBEDO) P(M, DIFFUSE_ROUGHNESS) P(M, ROUGHNESS) P(M, F0)            \
  P(M, COAT_WEIGHT) P(M, COAT_GLOSS)
#define CF_PARAMS_CLAY(P, M)                                               \
  P(M, ALBEDO) P(M, DIFFUSE_ROUGHNESS) P(M, FILM_ROUGHNESS) P(M, FILM_F0)  \
  P(M, OPTICAL_DEPTH) P(M, BASE_ROUGHNESS) P(M, BASE_F0)

/* A tailed twin's vector is its GGX twin's followed by the tail, so every
 * slot constant of the twin holds in it (param_table.c checks). */
#define CF_PARAMS_DIELECTRIC_TAILED(P, M) \
  P(M, ALBEDO) P(M, DIFFUSE_ROUGHNESS) P(M, ROUGHNESS) P(M, F0) P(M, TAIL)
#define CF_PARAMS_CLAY_TAILED(P, M)                                        \
  P(M, ALBEDO) P(M, DIFFUSE_ROUGHNESS) P(M, FILM_ROUGHNESS) P(M, FILM_F0)  \
  P(M, OPTICAL_DEPTH) P(M, BASE_ROUGHNESS) P(M, BASE_F0) P(M, TAIL)

/* X(ID, code, name, params list, GGX twin, summary); the GGX twin is the
 * model itself for a model without a tail. */
#define CF_MODEL_MAP(X)                                                      \
  X(LAMBERT, "M0", "lambert", CF_PARAMS_LAMBERT, LAMBERT,                    \
    "Lambertian diffuse: f = rho/pi")                                        \
  X(OREN_NAYAR, "M1", "oren_nayar", CF_PARAMS_OREN_NAYAR, OREN_NAYAR,        \
    "Oren-Nayar qualitative diffuse (rough matte clay)")                     \
  X(DIELECTRIC, "M2", "dielectric", CF_PARAMS_DIELECTRIC, DIELECTRIC,        \
    "GGX specular interface over Oren-Nayar diffuse (dry or glazed clay)")   \
  X(CLEARCOAT, "M3", "clearcoat", CF_PARAMS_CLEARCOAT, CLEARCOAT,            \
    "M2 plus Burley's GTR1 clear-coat lobe (Burley 2012)")                   \
  X(CLAY, "M4", "clay", CF_PARAMS_CLAY, CLAY,                                \
    "absorbing GGX film (water/oil) over a GGX + Oren-Nayar clay body")      \
  X(DIELECTRIC_TAILED, "M2T", "dielectric_tailed",                           \
    CF_PARAMS_DIELECTRIC_TAILED, DIELECTRIC,                                 \
    "M2 with a free tail: an STD specular lobe (tail 2 = M2)")               \
  X(CLAY_TAILED, "M4T", "clay_tailed", CF_PARAMS_CLAY_TAILED, CLAY,          \
    "M4 with one free tail shared by its film and base lobes (tail 2 = M4)")

/* clang-format on */

typedef enum cf_model_id {
#define CF__MODEL_ENUM(ID, ...) CF_MODEL_##ID,
  CF_MODEL_MAP(CF__MODEL_ENUM)
#undef CF__MODEL_ENUM
      CF_MODEL_COUNT
} cf_model_id;

/* Slot constants: CF_<MODEL>_<PARAM> is the first vector entry of PARAM in
 * MODEL's vector, CF_<MODEL>_DIM the vector's length. */
#define CF__SLOT(MODEL, ID) \
  CF_##MODEL##_##ID, CF__##MODEL##_##ID##_LAST = CF_##MODEL##_##ID + CF_NCOMP_##ID - 1,
#define CF__SLOT_ENUM(ID, code, name, PARAMS, twin, summary) \
  enum { PARAMS(CF__SLOT, ID) CF_##ID##_DIM };
CF_MODEL_MAP(CF__SLOT_ENUM)
#undef CF__SLOT_ENUM

/* The largest parameter vector of any model. */
#define CF_MAX_DIM CF_CLAY_TAILED_DIM

typedef struct cf_param_info {
  cf_param_id id;
  const char *name;   /* "albedo" */
  const char *symbol; /* ASCII spelling of the symbol in docs/model.md: "rho" */
  int components;     /* 1 (scalar) or 3 (linear RGB) */
  const char *unit;   /* "1" (dimensionless) or "rad" */
  double default_value;
  double lower, upper; /* inclusive range, the fit bounds (docs/model.md §1.6) */
  const char *meaning;
} cf_param_info;

typedef struct cf_model_info {
  cf_model_id id;
  const char *code; /* "M4" */
  const char *name; /* "clay" */
  const char *summary;
  int param_count;           /* number of parameters (an RGB one counts once) */
  const cf_param_id *params; /* in vector order */
  const int *offsets;        /* first vector slot of each parameter */
  int dim;                   /* length of the parameter vector */
  cf_model_id ggx_twin;      /* the model without the tail (itself if it has none) */
  int tail_slot;             /* the tail's slot, −1 for a GGX model */
} cf_model_info;

/* Table look-ups. Return NULL for an id outside the table. */
const cf_param_info *cf_param_info_get(cf_param_id id);
const cf_model_info *cf_model_info_get(cf_model_id id);

/* Every model's code ("M0", ...) and name ("lambert", ...), in id order,
 * NULL-terminated: index k is model id k. */
const char *const *cf_model_codes(void);
const char *const *cf_model_names(void);

/* Find a model by code or name, case-insensitive ("M4", "m4", "clay").
 * Returns CF_ENOTFOUND (with a message listing the models) if unknown. */
cf_status cf_model_find(const char *code_or_name, cf_model_id *id, cf_error *err);

/* Find a parameter of a model by name. CF_ENOTFOUND (with a message listing
 * the model's parameters) if the model has no such parameter. On success
 * *slot is its first vector entry and *info its description. */
cf_status cf_model_param_find(cf_model_id model, const char *name, int *slot,
                              const cf_param_info **info, cf_error *err);

/* The parameter that owns vector entry (slot) k of a model, and the
 * entry's component within it in *component (0 for a scalar parameter;
 * 0, 1, 2 for the r, g, b of an RGB one; optional, NULL). NULL for an
 * invalid model or an entry it does not have (k outside [0, dim)). The one
 * slot-to-parameter lookup: every caller asking which parameter a slot
 * belongs to (its range, unit, channel) goes through it. */
const cf_param_info *cf_model_slot_param(cf_model_id model, int k, int *component);

/* Name of vector entry k of a model: "albedo[1]" style for RGB entries is
 * written into buf (at least 32 bytes); returns buf. */
const char *cf_model_slot_name(cf_model_id model, int k, char *buf, size_t size);

/* The error of a fitted value of vector entry k against the truth in
 * units of max(|truth|, the width of the parameter's range): the scale on
 * which clayfit's benchmark and tests judge a recovered parameter. NaN
 * for an entry the model does not have. */
double cf_model_slot_error(cf_model_id model, int k, double fitted, double truth);

/* Fill params (model dim entries) with every parameter's default. */
void cf_model_default_params(cf_model_id model, double *params);

/* CF_OK if every entry is finite and within its range; otherwise
 * CF_ERANGE (or CF_EINVAL for NaN/Inf) with a message naming the entry. */
cf_status cf_params_check(cf_model_id model, const double *params, cf_error *err);

/* ---------------------------------------------------------------------
 * Geometry: everything the BRDF needs of (n, l, v), computed once per
 * observation by cf_geometry_from_directions (do not fill it by hand).
 *
 * The four invariants: with l_t = l − c_i n and v_t = v − c_o n (the parts
 * of l and v tangent to the surface),
 *   cos_i = n·l, cos_o = n·v,
 *   t_sq  = |l_t + v_t|²  (so |l + v|² = t_sq + (cos_i + cos_o)²),
 *   g     = l_t·v_t = l·v − c_i c_o.
 * Every formula of docs/model.md is written in these ((3), (4)); computing them from the
 * tangent parts keeps the half vector's sin²θ_h accurate at a mirror
 * configuration, and every expression is symmetric in l and v, so f is
 * reciprocal to the last bit.
 *
 * The rest are functions of the invariants that do not depend on any
 * parameter, so that a fit (which evaluates the same observations at
 * every iteration) computes them once. They are 0 where the pair is not
 * lit (cf_geometry_is_lit).
 * ------------------------------------------------------------------- */
typedef struct cf_geometry {
  double cos_i, cos_o, t_sq, g;
  double sin2_h, cos2_h;  /* of the half vector h = (l + v)/|l + v| */
  double c_d;             /* |l + v|/2 = v·h = l·h */
  double weight_d;        /* Schlick's (1 − c_d)^5 (M3's coat, the tailed lobe) */
  double on_angular;      /* Oren-Nayar's max(0, g)/max(c_i, c_o) */
  double coat_visibility; /* Burley's separable Smith GGX, α_g = 0.25 (M3) */
} cf_geometry;

/* Is the pair lit and seen (f can be non-zero)? c_i > 0, c_o > 0 and
 * c_i·c_o >= DBL_MIN (see "Conventions" above). False for NaN. */
static inline int cf_geometry_is_lit(const cf_geometry *g) {
  return g->cos_i > 0.0 && g->cos_o > 0.0 && g->cos_i * g->cos_o >= DBL_MIN;
}

cf_geometry cf_geometry_from_directions(const double n[3], const double l[3], const double v[3]);

/* Evaluate one observation. f receives 3 values (1/sr); grad, if not NULL,
 * 3 × dim derivatives as described above. CF_EINVAL for an unknown model
 * (outputs untouched); the parameters are not checked (cf_params_check). */
cf_status cf_eval(cf_model_id model, const double *params, const double n[3], const double l[3],
                  const double v[3], double f[3], double *grad);

/* The fitter's hot path: `count` observations with one parameter vector.
 * Work that depends only on the parameters is done once per call.
 *   geometry: count records (see cf_geometry_from_directions);
 *   f:        3 × count values, f[3 i + c];
 *   grad:     NULL, or 3 × dim × count derivatives,
 *             grad[(3 i + c) × dim + k] = ∂f_c(obs i) / ∂params[k]
 *             (row-major Jacobian rows, one per observation and channel). */
cf_status cf_eval_batch(cf_model_id model, const double *params, size_t count,
                        const cf_geometry *geometry, double *f, double *grad);

/* The same from directions: n, l, v are 3 × count doubles (x, y, z of
 * observation i at [3 i .. 3 i + 2]). */
cf_status cf_eval_batch_directions(cf_model_id model, const double *params, size_t count,
                                   const double *n, const double *l, const double *v, double *f,
                                   double *grad);

/* ---------------------------------------------------------------------
 * Pixel footprints (docs/model.md §5.6): a pixel measures the
 * mean of f over its footprint on the sphere, and where a lobe is narrower
 * than the footprint its value at the pixel centre is not that mean.
 * ------------------------------------------------------------------- */

/* The angular width (radians of half-vector tilt) of the model's narrowest
 * lobe at params: α = r² for a GGX lobe (M2, M3, M4's film and base), a
 * for M3's GTR1 clear coat while its weight is above 0; INFINITY for M0
 * and M1, which have none. */
double cf_model_lobe_width(cf_model_id model, const double *params);

/* Samples per side n (n × n) that integrate a lobe of angular width
 * `width` over a pixel across which the normal turns by `delta` radians,
 * whose centre's half vector is `theta_h` radians from the normal, to a
 * relative error of about `tolerance`: 1 (the pixel centre) where that is
 * enough, else an even n = 2P, P panels per side with two Gauss-Legendre
 * points each (cf_footprint_offset), at most max_samples (rounded down to
 * even).
 *
 * GGX near its peak is D ∝ (α² + θ²)^-2 in the tilt θ. The centre (the
 * midpoint rule on one panel of width δ) errs by δ²/24 (D_xx + D_yy), and
 * |D_xx/D| = |20θ² − 4α²|/(α² + θ²)² is at most 20/(α² + θ²): a relative
 * error of at most δ² · 5/(3 (α² + θ²)). Two Gauss-Legendre points on a
 * panel of width h err by h⁴/4320 D_xxxx (the rule's remainder), and
 * |D_xxxx/D| = 24 |80 t² − 48 t + 3| / (α² + θ²)² with t = θ²/(α² + θ²)
 * in [0, 1) is at most 840/(α² + θ²)²: over both axes a relative error of
 * at most (δ/P)⁴ · 7/(18 (α² + θ²)²). θ is the smallest tilt inside the
 * pixel (θ_h − δ/√2, at least 0). Where the lobe is as wide as the turn
 * (δ = α at its peak) and the tolerance is 2e-3, the centre's rule would
 * need 29 samples per side, the pairs 8. 1 for a non-positive delta or
 * tolerance, or an infinite width. */
int cf_footprint_samples(double width, double delta, double theta_h, double tolerance,
                         int max_samples);

/* The relative error bound above for n samples per side: the centre's for
 * n = 1, the Gauss-Legendre pairs' for an even n; NAN for another n. 0 for
 * a non-positive delta or an infinite width; INFINITY for α = θ = 0. */
double cf_footprint_error(double width, double delta, double theta_h, int samples);

/* Where sample j of n (n = 1 or even, 0 <= j < n) sits across the pixel,
 * in pixels from its centre (in [−½, ½]): 0 for n = 1; for n = 2P, in
 * panel ⌊j/2⌋ of width 1/P, at the panel's centre ∓ 1/(2√3 P). The
 * samples weigh the same. NAN for another n or j. */
double cf_footprint_offset(int samples, int j);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_MODEL_H */
