/* clayfit: the fitted model exactly, as shader source (docs/shaders.md).
 *
 * A fit.json read back (cf_fit_file_read in clayfit/fit_file.h) becomes
 *   glsl    a three.js ShaderMaterial (an ES module, GLSL ES 3.0)
 *   unity   a folder for a Unity project's Assets: a built-in pipeline
 *           shader (HLSL), a material and their .meta files
 * each evaluating the model's own formulas (docs/model.md §2, §3), a tailed
 * lobe's included, in 32-bit floats. The maths is written once for both
 * languages (src/shader/shader.c). `clayfit export --format glsl|unity`
 * (clayfit/export.h) and the report's interactive view write them. */
#ifndef CLAYFIT_SHADER_H
#define CLAYFIT_SHADER_H

#include "clayfit/fit_file.h"
#include "clayfit/model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_shader_format {
  CF_SHADER_GLSL, /* three.js ShaderMaterial (GLSL ES 3.0) */
  CF_SHADER_UNITY /* a folder: Unity built-in pipeline shader, material, .meta */
} cf_shader_format;

/* Write the fit's material to `path` (for unity: the folder, created) in
 * `format`. `fit_path` (may be NULL) is recorded as provenance. The fit's
 * parameters are checked first (cf_params_check). */
cf_status cf_shader_write(const cf_fit_file *fit, const char *fit_path, cf_shader_format format,
                          const char *path, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_SHADER_H */
