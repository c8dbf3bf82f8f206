/* clayfit export: the formats and the dispatch (clayfit/export.h). */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "clayfit/shader.h"
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

/* Where a format's notes of values outside the target's range go. */
typedef struct export_warning_sink {
  cf_export_warnings *warnings;
  const char *format_name;
} export_warning_sink;

/* A range note as a warning: "gltf: ...". */
static void export_warning(void *user, const char *text) {
  export_warning_sink *sink = user;
  cf_export_warnings *w = sink->warnings;
  if (w->count >= CF_EXPORT_MAX_WARNINGS) return;
  snprintf(w->text[w->count], sizeof w->text[0], "%s: %s", sink->format_name, text);
  ++w->count;
}

cf_status cf_export_write(const cf_fit_file *fit, const char *fit_path, cf_export_format format,
                          const char *path, cf_export_warnings *warnings, cf_error *err) {
  if (warnings) warnings->count = 0;
  cf_status s = cf_params_check(fit->result.model, fit->result.params, err);
  if (s != CF_OK) return s;
  export_warning_sink sink = {warnings, cf_export_format_name(format)};
  preset_notes notes = {0};
  notes.range = warnings ? export_warning : NULL;
  notes.range_user = &sink;
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
    case CF_EXPORT_GLSL: /* the shaders write no value a target cannot take */
      return cf_shader_write(fit, fit_path, CF_SHADER_GLSL, path, err);
    case CF_EXPORT_UNITY:
      return cf_shader_write(fit, fit_path, CF_SHADER_UNITY, path, err);
    case CF_EXPORT_FORMAT_COUNT:
      break;
  }
  return cf_error_set(err, CF_EINVAL, "unknown export format %d", (int)format);
}
