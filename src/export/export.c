/* clayfit export: the formats and the dispatch (clayfit/export.h). */
#include <string.h>
#include <strings.h>

#include "export_internal.h"

static const char *const format_names[CF_EXPORT_FORMAT_COUNT] = {
    "json", "mtlx", "mtlx-openpbr", "gltf", "blender", "mitsuba", "glsl", "unity"};

const char *cf_export_format_name(cf_export_format format) {
  return (unsigned)format < CF_EXPORT_FORMAT_COUNT ? format_names[format] : "unknown";
}

cf_status cf_export_format_find(const char *name, cf_export_format *format, cf_error *err) {
  for (int i = 0; i < CF_EXPORT_FORMAT_COUNT; ++i)
    if (strcasecmp(name, format_names[i]) == 0) {
      *format = (cf_export_format)i;
      return CF_OK;
    }
  return cf_error_set(err, CF_ENOTFOUND,
                      "unknown format '%s' (the formats are json, mtlx, mtlx-openpbr, gltf, "
                      "blender, mitsuba, glsl, unity)",
                      name);
}

cf_status cf_export_write(const cf_fit_file *fit, const char *fit_path, cf_export_format format,
                          const char *path, cf_export_warnings *warnings, cf_error *err) {
  if (warnings) warnings->count = 0;
  cf_status s = cf_params_check(fit->result.model, fit->result.params, err);
  if (s != CF_OK) return s;
  export_notes notes = {0};
  notes.warnings = warnings;
  notes.format_name = cf_export_format_name(format);
  switch (format) {
    case CF_EXPORT_JSON:
      return export_json(fit, fit_path, path, &notes, err);
    case CF_EXPORT_MTLX:
      return export_mtlx(fit, fit_path, path, 0, &notes, err);
    case CF_EXPORT_MTLX_OPENPBR:
      return export_mtlx(fit, fit_path, path, 1, &notes, err);
    case CF_EXPORT_GLTF:
      return export_gltf(fit, fit_path, path, &notes, err);
    case CF_EXPORT_BLENDER:
      return export_blender(fit, fit_path, path, &notes, err);
    case CF_EXPORT_MITSUBA:
      return export_mitsuba(fit, fit_path, path, &notes, err);
    case CF_EXPORT_GLSL:
      return export_glsl(fit, fit_path, path, &notes, err);
    case CF_EXPORT_UNITY:
      return export_unity(fit, fit_path, path, &notes, err);
    case CF_EXPORT_FORMAT_COUNT:
      break;
  }
  return cf_error_set(err, CF_EINVAL, "unknown export format %d", (int)format);
}
