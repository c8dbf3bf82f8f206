/* The exact model as shader source: one body of maths (shader.c), written
 * once in a subset common to GLSL ES 3.0 and HLSL, emitted behind a
 * per-language prelude by the GLSL (three.js, shader_glsl.c) and the Unity
 * (HLSL, shader_unity.c) writers, so that the two cannot drift
 * (docs/shaders.md). Private to src/shader. */
#ifndef CLAYFIT_SHADER_INTERNAL_H
#define CLAYFIT_SHADER_INTERNAL_H

#include "clayfit/shader.h"
#include "shader/preset_text.h"

typedef enum shader_lang { SHADER_GLSL, SHADER_HLSL } shader_lang;

/* The fitted material as the shaders take it: the fit's own values, a
 * tailed lobe's exactly (the shaders evaluate the STD lobe, no GGX in its
 * place); a parameter the model does not have holds the parameter table's
 * default (unused by the rung's code). */
typedef struct shader_material {
  const cf_model_info *info; /* the fitted model */
  int rung;                  /* 0-4 for M0-M4: the GGX twin's */
  int tailed;                /* M2T, M4T: CLAYFIT_TAILED selects the STD lobe */
  double tail;               /* γ; 2 (GGX) for a GGX model */
  double albedo[3], sigma;
  double roughness, f0;                                            /* M2, M3: the interface */
  double coat_weight, coat_gloss;                                  /* M3: Burley's clear coat */
  double film_roughness, film_f0, tau[3], base_roughness, base_f0; /* M4 */
} shader_material;

void shader_material_read(const cf_fit_file *fit, shader_material *m);

/* `#define CLAYFIT_MODEL n`, the language's prelude and the shared body,
 * between the lines "// ---- clayfit shared body: begin" and "...: end"
 * (the tests compare that block across languages). */
void shader_library(preset_text *t, shader_lang lang, const shader_material *m);

/* The notes of the shader formats: what is exact, and the target's lighting
 * (one sentence). */
void shader_notes(preset_notes *n, const shader_material *m, const char *lighting);

/* 32 lowercase hex digits from text (two 64-bit FNV-1a hashes): Unity's
 * GUIDs, deterministic in the exported content. */
void shader_hash_guid(const char *text, size_t size, const char *salt, char guid[33]);

/* The writers, one file each: a three.js ES module; a Unity folder (path:
 * the folder, created). */
cf_status shader_glsl(const cf_fit_file *fit, const char *fit_path, const char *path,
                      cf_error *err);
cf_status shader_unity(const cf_fit_file *fit, const char *fit_path, const char *path,
                       cf_error *err);

#endif /* CLAYFIT_SHADER_INTERNAL_H */
