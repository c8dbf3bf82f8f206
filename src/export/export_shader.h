/* The exact model as shader source: one body of maths (export_shader.c),
 * written once in a subset common to GLSL ES 3.0 and HLSL, emitted behind
 * a per-language prelude by the GLSL (three.js) and the Unity (HLSL)
 * writers, so that the two cannot drift (docs/shaders.md). Private to
 * src/export. */
#ifndef CLAYFIT_EXPORT_SHADER_H
#define CLAYFIT_EXPORT_SHADER_H

#include "export_internal.h"

typedef enum export_shader_lang { EXPORT_SHADER_GLSL, EXPORT_SHADER_HLSL } export_shader_lang;

/* The rung the shader evaluates: 0-4 for M0-M4 (a tailed fit is its GGX
 * twin, export_material_from_fit; CLAYFIT_TAILED selects the STD lobe). */
int export_shader_rung(const export_material *m);

/* `#define CLAYFIT_MODEL n`, the language's prelude and the shared body,
 * between the lines "// ---- clayfit shared body: begin" and "...: end"
 * (the tests compare that block across languages). */
void export_shader_library(export_text *t, export_shader_lang lang, const export_material *m);

/* A tailed model's lobes back to the fitted (r, F0) from the GGX that
 * export_material_from_fit wrote in their place: the shaders evaluate the
 * tail exactly. */
void export_shader_exact(export_material *m);

/* The notes of the shader formats: what is exact, and the target's lighting
 * (one sentence). */
void export_shader_notes(export_notes *n, const export_material *m, const char *lighting);

/* 32 lowercase hex digits from text (two 64-bit FNV-1a hashes): Unity's
 * GUIDs, deterministic in the exported content. */
void export_shader_guid(const char *text, size_t size, const char *salt, char guid[33]);

#endif /* CLAYFIT_EXPORT_SHADER_H */
