/* clayfit: material presets from a fit (clayfit export).
 *
 * A fit.json read back (cf_fit_file_read in clayfit/fit_file.h) becomes a
 * material in one of these formats:
 *   json          clayfit's own preset (data_schema/preset.schema.json):
 *                 lossless, the model and its parameters with units,
 *                 uncertainties and provenance; `clayfit eval --preset`
 *                 evaluates it
 *   mtlx          MaterialX 1.38 standard_surface
 *   mtlx-openpbr  MaterialX 1.39 open_pbr_surface (OpenPBR 1.1)
 *   gltf          glTF 2.0 (.gltf, a UV sphere in a data URI, with
 *                 KHR_materials_clearcoat, _ior and _specular)
 *   blender       a Blender 4 Python script building a Principled BSDF
 *   mitsuba       a Mitsuba 3 scene fragment (diffuse, roughplastic or
 *                 principled)
 *   glsl, unity   the model exactly, as shaders (docs/shaders.md): a three.js
 *                 ShaderMaterial module; a folder with a Unity shader,
 *                 material and .meta files
 * No target has every term of the models of docs/model.md §3: each file says in a
 * comment which parameters map exactly, which approximately and what is
 * dropped, and every value a target cannot take is a warning (never
 * silently clamped). The mapping is in src/export/export_mapping.c; glsl and
 * unity are written by the shader layer (clayfit/shader.h). */
#ifndef CLAYFIT_EXPORT_H
#define CLAYFIT_EXPORT_H

#include "clayfit/fit_file.h"
#include "clayfit/model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_export_format {
  CF_EXPORT_JSON,
  CF_EXPORT_MTLX,
  CF_EXPORT_MTLX_OPENPBR,
  CF_EXPORT_GLTF,
  CF_EXPORT_BLENDER,
  CF_EXPORT_MITSUBA,
  CF_EXPORT_GLSL,  /* three.js ShaderMaterial (GLSL ES 3.0), the model exactly */
  CF_EXPORT_UNITY, /* a folder: Unity built-in pipeline shader, material, .meta */
  CF_EXPORT_FORMAT_COUNT
} cf_export_format;

/* "json", "mtlx", "mtlx-openpbr", "gltf", "blender", "mitsuba", "glsl", "unity". */
const char *cf_export_format_name(cf_export_format format);
/* CF_ENOTFOUND (listing the formats) for an unknown name. */
cf_status cf_export_format_find(const char *name, cf_export_format *format, cf_error *err);

enum { CF_EXPORT_MAX_WARNINGS = 16 };

/* What a target could not take, one sentence each. */
typedef struct cf_export_warnings {
  int count;
  char text[CF_EXPORT_MAX_WARNINGS][544];
} cf_export_warnings;

/* Write the fit's material to `path` in `format`. `fit_path` (may be NULL)
 * is recorded as provenance. warnings (may be NULL) receives what the
 * target could not express. */
cf_status cf_export_write(const cf_fit_file *fit, const char *fit_path, cf_export_format format,
                          const char *path, cf_export_warnings *warnings, cf_error *err);

/* Read a json preset back (untrusted: checked like every input; errors
 * name the file and the JSON path): its model and parameter vector. */
cf_status cf_export_preset_read(const char *path, cf_model_id *model, double params[CF_MAX_DIM],
                                cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_EXPORT_H */
