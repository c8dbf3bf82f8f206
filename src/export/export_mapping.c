/* The physics of the mapping from the models of docs/model.md §3 to the targets'
 * inputs, and what the writers share (export_internal.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "export_internal.h"

/* ---- text ---- */

void export_printf(export_text *t, const char *format, ...) {
  if (t->failed) return;
  for (;;) {
    va_list args;
    va_start(args, format);
    size_t room = t->capacity - t->size;
    int n = vsnprintf(t->data ? t->data + t->size : NULL, t->data ? room : 0, format, args);
    va_end(args);
    if (n < 0) {
      t->failed = 1;
      return;
    }
    if (t->data && (size_t)n < room) {
      t->size += (size_t)n;
      return;
    }
    size_t capacity = t->capacity ? t->capacity * 2 : 4096;
    while (capacity < t->size + (size_t)n + 1) capacity *= 2;
    char *grown = realloc(t->data, capacity);
    if (!grown) {
      t->failed = 1;
      return;
    }
    t->data = grown;
    t->capacity = capacity;
  }
}

void export_escaped(export_text *t, text_escape_fn escape, const char *text) {
  if (t->failed) return;
  char *escaped = text_escape_alloc(escape, text);
  if (!escaped) {
    t->failed = 1;
    return;
  }
  export_printf(t, "%s", escaped);
  free(escaped);
}

void export_text_free(export_text *t) {
  free(t->data);
  t->data = NULL;
  t->size = t->capacity = 0;
}

cf_status export_text_write(export_text *t, const char *path, cf_error *err) {
  cf_status s = t->failed ? cf_error_set(err, CF_ENOMEM, "%s: out of memory", path)
                          : cf_write_file(path, t->data ? t->data : "", t->size, err);
  export_text_free(t);
  return s;
}

/* ---- notes ---- */

void export_note(export_notes *n, export_note_kind kind, const char *format, ...) {
  char text[512];
  va_list args;
  va_start(args, format);
  vsnprintf(text, sizeof text, format, args);
  va_end(args);
  if (n->count < EXPORT_MAX_NOTES) {
    n->kind[n->count] = kind;
    memcpy(n->text[n->count], text, sizeof text);
    ++n->count;
  }
  if (kind == EXPORT_RANGE && n->warnings && n->warnings->count < CF_EXPORT_MAX_WARNINGS) {
    snprintf(n->warnings->text[n->warnings->count], sizeof n->warnings->text[0], "%s: %s",
             n->format_name ? n->format_name : "export", text);
    ++n->warnings->count;
  }
}

void export_notes_write(export_text *t, const export_notes *n, const char *prefix) {
  static const char *const heading[] = {"maps exactly", "maps approximately", "dropped",
                                        "outside the target's range"};
  for (int kind = 0; kind < 4; ++kind) {
    int any = 0;
    for (int i = 0; i < n->count; ++i) {
      if ((int)n->kind[i] != kind) continue;
      if (!any) export_printf(t, "%s%s:\n", prefix, heading[kind]);
      any = 1;
      /* wrap at about 90 columns */
      const char *s = n->text[i];
      int first = 1;
      while (*s) {
        size_t len = strlen(s), cut = len;
        if (len > 84) {
          cut = 84;
          while (cut > 20 && s[cut] != ' ') --cut;
        }
        export_printf(t, "%s%s%.*s\n", prefix, first ? "  - " : "    ", (int)cut, s);
        s += cut;
        while (*s == ' ') ++s;
        first = 0;
      }
    }
  }
}

/* ---- physics ---- */

double export_ior_from_f0(double f0) {
  double s = sqrt(f0);
  return (1.0 + s) / (1.0 - s);
}

double export_f0_from_ior(double ior) {
  double r = (ior - 1.0) / (ior + 1.0);
  return r * r;
}

double export_sigma_materialx_glsl(double sigma) {
  return sigma / EXPORT_PI;
}

double export_sigma_fujii(double sigma) {
  double s2 = sigma * sigma;
  double a = 1.0 - 0.5 * s2 / (s2 + 0.33), b = 0.45 * s2 / (s2 + 0.09);
  return b / a;
}

double export_gtr1_width(double gloss) {
  return 0.1 + (0.001 - 0.1) * gloss;
}

void export_material_from_fit(const cf_fit_file *fit, export_material *m) {
  memset(m, 0, sizeof *m);
  const double *p = fit->result.params;
  m->model = fit->result.model;
  m->info = cf_model_info_get(m->model);
  for (int c = 0; c < 3; ++c) m->albedo[c] = p[c]; /* albedo is slot 0 of every model */
  m->sigma = m->model == CF_MODEL_LAMBERT ? 0.0 : p[CF_OREN_NAYAR_DIFFUSE_ROUGHNESS];
  if (m->model == CF_MODEL_DIELECTRIC || m->model == CF_MODEL_CLEARCOAT) {
    m->roughness = p[CF_DIELECTRIC_ROUGHNESS];
    m->f0 = p[CF_DIELECTRIC_F0];
    m->ior = export_ior_from_f0(m->f0);
  }
  if (m->model == CF_MODEL_CLEARCOAT) {
    m->coat_weight = p[CF_CLEARCOAT_COAT_WEIGHT];
    m->coat_gloss = p[CF_CLEARCOAT_COAT_GLOSS];
    m->gtr1_a = export_gtr1_width(m->coat_gloss);
    m->ggx_coat_weight = 0.25 * m->coat_weight;
    m->ggx_coat_roughness = sqrt(m->gtr1_a);
  }
  if (m->model == CF_MODEL_CLAY) {
    m->film_roughness = p[CF_CLAY_FILM_ROUGHNESS];
    m->film_f0 = p[CF_CLAY_FILM_F0];
    m->film_ior = export_ior_from_f0(m->film_f0);
    for (int c = 0; c < 3; ++c) {
      m->tau[c] = p[CF_CLAY_OPTICAL_DEPTH + c];
      m->transmittance[c] = exp(-2.0 * m->tau[c]);
    }
    m->base_roughness = p[CF_CLAY_BASE_ROUGHNESS];
    m->base_f0 = p[CF_CLAY_BASE_F0];
    m->base_ior_rel = export_ior_from_f0(m->base_f0);
    m->base_ior_abs = m->film_ior * m->base_ior_rel;
  }
}

void export_provenance(export_text *t, const cf_fit_file *fit, const char *fit_path,
                       const char *prefix, text_escape_fn escape) {
  const cf_model_info *m = cf_model_info_get(fit->result.model);
  export_printf(t, "%sclayfit %s material preset: model %s (%s), fitted by clayfit ", prefix,
                CLAYFIT_EXPORT_VERSION, m->code, m->name);
  export_escaped(t, escape, fit->clayfit_version);
  export_printf(t, " on ");
  export_escaped(t, escape, fit->created);
  export_printf(t, "\n%sfit: ", prefix);
  export_escaped(t, escape, fit_path ? fit_path : "(not given)");
  export_printf(t, "; capture: ");
  export_escaped(t, escape, fit->capture_name);
  export_printf(t, " (");
  export_escaped(t, escape, fit->radiometry);
  export_printf(t, " radiometry, ");
  export_escaped(t, escape, fit->capture_path);
  export_printf(t, "); relative RMSE %.4g\n", fit->result.relative_rmse);
  export_printf(t, "%smodel: docs/model.md of clayfit %s; mapping: docs/presets.md\n", prefix,
                CLAYFIT_EXPORT_VERSION);
}

void export_common_notes(export_notes *n, const export_material *m) {
  export_note(n, EXPORT_EXACT,
              "albedo %.6g, %.6g, %.6g (linear RGB) -> the diffuse colour; clayfit's "
              "roughness is perceptual (GGX alpha = r^2): each target's convention is given "
              "with its input below",
              m->albedo[0], m->albedo[1], m->albedo[2]);
  if (m->model == CF_MODEL_CLAY)
    export_note(n, EXPORT_APPROX,
                "film optical depth tau %.6g, %.6g, %.6g -> coat colour exp(-2 tau) = %.6g, "
                "%.6g, %.6g, the film's round-trip transmittance at normal incidence; no target "
                "models absorption along the refracted paths exp(-tau (1/c_i' + 1/c_o')) nor "
                "the recycling K of light reflected back down by the film",
                m->tau[0], m->tau[1], m->tau[2], m->transmittance[0], m->transmittance[1],
                m->transmittance[2]);
  if (m->model == CF_MODEL_CLAY)
    export_note(n, EXPORT_APPROX,
                "base_f0 %.6g is the film-to-clay reflectance: relative IOR %.6g; the clay's "
                "IOR in air is film IOR x relative IOR = %.6g x %.6g = %.6g",
                m->base_f0, m->base_ior_rel, m->film_ior, m->base_ior_rel, m->base_ior_abs);
}
