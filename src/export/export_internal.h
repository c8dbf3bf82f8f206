/* What the export formats share: the physics of the mapping
 * (export_mapping.c), and, from the layer below (src/shader/include/shader/preset_text.h),
 * the text, the notes and the provenance of every material file. Private to
 * src/export. */
#ifndef CLAYFIT_EXPORT_INTERNAL_H
#define CLAYFIT_EXPORT_INTERNAL_H

#include <stddef.h>

#include "clayfit/export.h"
#include "clayfit/tailed_ggx.h"
#include "core/text_escape.h"
#include "core/vec.h"
#include "shader/preset_text.h"

/* ---- the physics ---- */
/* η = (1 + √F0)/(1 − √F0) (docs/model.md (7)) and back. */
double export_ior_from_f0(double f0);
double export_f0_from_ior(double ior);
/* Oren-Nayar σ (radians, the qualitative model of docs/model.md (12)) as
 *  - MaterialX's GLSL oren_nayar_diffuse_bsdf roughness: σ/π
 *    (mx_oren_nayar_diffuse: sigma2 = (roughness π)², the same A and B);
 *  - Fujii's σ_F of the "improved" / energy-preserving Oren-Nayar of
 *    OpenPBR (EON, base_diffuse_roughness) and Blender 4.3+ (Diffuse
 *    Roughness), f ∝ 1 + σ_F s/t: σ_F = B/A, the ratio of docs/model.md (12)'s
 *    angular term to its constant term. */
double export_sigma_materialx_glsl(double sigma);
double export_sigma_fujii(double sigma);
/* Burley's GTR1 width a = 0.1 − 0.099 gloss (docs/model.md (16)). */
double export_gtr1_width(double gloss);

/* ---- a tailed lobe (STD, docs/model.md §2.8) in the GGX-only formats
 * (docs/presets.md, "Tailed lobes in GGX-only formats"): the GGX of least
 * squares (clayfit/tailed_ggx.h, clayfit_model_fit) and its note. */

/* "GGX approximation: 6.1 % RMS over the lobe" (below 0.05 %: "< 0.1 %"),
 * the one wording of every preset. */
void export_ggx_loss_text(double rms_loss, char *text, size_t size);
/* The note of a tailed lobe (`lobe` names it: "the specular lobe"): its
 * (r, γ, F0), the GGX written and the loss. At γ = 2 (GGX itself, the
 * mapping the identity) an exact note with a loss of 0. */
void export_note_tailed(preset_notes *n, const char *lobe, double r, double gamma, double f0,
                        double r_ggx, double f0_ggx, double rms_loss);

/* ---- the diffuse colour a target's diffuse needs (docs/presets.md) ----
 * A target's diffuse per unit colour, for one of `variants` settings (e.g.
 * Blender 3's Roughness steps), at light l and view v about n = (0, 0, 1):
 * beta / colour of its BRDF, the same for every channel. */
typedef double (*export_diffuse_basis)(const void *ctx, int variant, const double l[3],
                                       const double v[3]);
typedef struct export_diffuse_colour {
  double colour[3]; /* in [0, 1] */
  int variant;      /* the best of the variants */
  double loss;      /* relative RMS of the model's diffuse left */
} export_diffuse_colour;
/* The colour (per channel) and variant by least squares against the model's
 * diffuse alone (its f minus its f at albedo 0), over a sphere seen from a
 * view of density c_o lit from a direction uniform over the hemisphere,
 * pixels f c_i: Gauss-Legendre 16^3 in (c_o, c_i, phi). `what` prefixes an
 * error of the model's evaluation. */
cf_status export_fit_diffuse_colour(const cf_fit_file *fit, export_diffuse_basis basis,
                                    const void *ctx, int variants, const char *what,
                                    export_diffuse_colour *out, cf_error *err);
/* M3's clear coat (Burley's GTR1, its Schlick F of F0 0.04) as the GGX coat
 * of glTF (F0 0.04, height-correlated Smith): the weight and roughness of
 * least squares over the sphere metric, and the relative RMS of the coat
 * left. */
cf_status export_coat_ggx_fit(const cf_fit_file *fit, double *weight, double *roughness,
                              double *loss, cf_error *err);
/* A tailed lobe of the fit and the GGX written for it (cf_tailed_ggx_default). */
typedef struct export_tailed_lobe {
  char name[192]; /* for the note: "the specular lobe" */
  double r, f0;   /* the fit's */
  double r_ggx, f0_ggx, rms_loss;
} export_tailed_lobe;

/* The fitted material, read off a fit by model. A tailed model (M2T, M4T)
 * is read as its GGX twin: `model` is the twin, every roughness and F0
 * below the GGX of its lobe (cf_tailed_ggx_default; M4T's base under the
 * film); `info` stays the fitted model's,
 * `lobes` the tailed lobes with their losses (export_common_notes notes
 * each). */
typedef struct export_material {
  cf_model_id model;         /* the GGX twin of the fitted model */
  const cf_model_info *info; /* the fitted model */
  double tail;               /* γ of the tailed lobes, 2 (GGX) for a GGX model */
  int lobe_count;            /* tailed lobes: 0, 1 (M2T) or 2 (M4T: film, base) */
  export_tailed_lobe lobes[2];
  double albedo[3], sigma;
  /* M2, M3: the interface */
  double roughness, f0, ior;
  /* M3: Burley's clear coat, and the GGX coat of the renderers that have
   * one: weight 0.25 coat_weight (Burley's 0.25), roughness sqrt(a), IOR 1.5
   * (F0 0.04) */
  double coat_weight, coat_gloss, gtr1_a;
  double ggx_coat_weight, ggx_coat_roughness;
  /* M4: the film and the base under it */
  double film_roughness, film_f0, film_ior, tau[3], transmittance[3];
  double base_roughness, base_f0, base_ior_rel, base_ior_abs;
} export_material;

/* CF_ENOMEM / CF_ENUMERIC from the GGX fit of a tailed lobe. */
cf_status export_material_from_fit(const cf_fit_file *fit, export_material *m, cf_error *err);

/* The common notes: roughness convention, σ and the film's colour. */
void export_common_notes(preset_notes *n, const export_material *m);

/* The writers, one file each. */
cf_status export_json(const cf_fit_file *fit, const char *fit_path, const char *path,
                      preset_notes *notes, cf_error *err);
cf_status export_mtlx(const cf_fit_file *fit, const char *fit_path, const char *path, int openpbr,
                      preset_notes *notes, cf_error *err);
cf_status export_gltf(const cf_fit_file *fit, const char *fit_path, const char *path,
                      preset_notes *notes, cf_error *err);
cf_status export_blender(const cf_fit_file *fit, const char *fit_path, const char *path,
                         preset_notes *notes, cf_error *err);
cf_status export_mitsuba(const cf_fit_file *fit, const char *fit_path, const char *path,
                         preset_notes *notes, cf_error *err);

#endif /* CLAYFIT_EXPORT_INTERNAL_H */
