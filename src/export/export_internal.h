/* What the export formats share: a growing text buffer, the notes each
 * file carries (what maps exactly, approximately, what is dropped), and
 * the physics of the mapping (export_mapping.c). Private to src/export. */
#ifndef CLAYFIT_EXPORT_INTERNAL_H
#define CLAYFIT_EXPORT_INTERNAL_H

#include <stddef.h>

#include "clayfit/export.h"
#include "core/text_escape.h"

#define EXPORT_PI 3.14159265358979323846

/* ---- text ---- */
typedef struct export_text {
  char *data;
  size_t size, capacity;
  int failed; /* out of memory */
} export_text;

void export_printf(export_text *t, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Untrusted text (a name, a path: from fit.json or the command line)
 * escaped for the file's syntax (core/text_escape.h). */
void export_escaped(export_text *t, text_escape_fn escape, const char *text);
/* Write the text to path and free it. */
cf_status export_text_write(export_text *t, const char *path, cf_error *err);
void export_text_free(export_text *t);

/* ---- notes ---- */
typedef enum export_note_kind {
  EXPORT_EXACT,   /* the target computes what the model does */
  EXPORT_APPROX,  /* the target's term differs (how, in the note) */
  EXPORT_DROPPED, /* the target has no such term */
  EXPORT_RANGE    /* a value outside the target's range: also a warning */
} export_note_kind;

enum { EXPORT_MAX_NOTES = 40 };

typedef struct export_notes {
  int count;
  export_note_kind kind[EXPORT_MAX_NOTES];
  char text[EXPORT_MAX_NOTES][512];
  cf_export_warnings *warnings; /* may be NULL */
  const char *format_name;
} export_notes;

void export_note(export_notes *n, export_note_kind kind, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The notes as comment lines, each starting with `prefix` (and `suffix`
 * at the end of the line, for block comments that need it). */
void export_notes_write(export_text *t, const export_notes *n, const char *prefix);

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

/* The fitted material, read off a fit by model. */
typedef struct export_material {
  cf_model_id model;
  const cf_model_info *info;
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

void export_material_from_fit(const cf_fit_file *fit, export_material *m);

/* Three lines of provenance: clayfit version, fit file, model, capture;
 * every line starts with `prefix`, and the text from fit.json and the fit
 * file's path are escaped with `escape` (the syntax of a comment, or
 * text_escape_utf8 for a JSON string). */
void export_provenance(export_text *t, const cf_fit_file *fit, const char *fit_path,
                       const char *prefix, text_escape_fn escape);

/* The common notes: roughness convention, σ and the film's colour. */
void export_common_notes(export_notes *n, const export_material *m);

/* The writers, one file each. */
cf_status export_json(const cf_fit_file *fit, const char *fit_path, const char *path,
                      export_notes *notes, cf_error *err);
cf_status export_mtlx(const cf_fit_file *fit, const char *fit_path, const char *path, int openpbr,
                      export_notes *notes, cf_error *err);
cf_status export_gltf(const cf_fit_file *fit, const char *fit_path, const char *path,
                      export_notes *notes, cf_error *err);
cf_status export_blender(const cf_fit_file *fit, const char *fit_path, const char *path,
                         export_notes *notes, cf_error *err);
cf_status export_mitsuba(const cf_fit_file *fit, const char *fit_path, const char *path,
                         export_notes *notes, cf_error *err);

#endif /* CLAYFIT_EXPORT_INTERNAL_H */
