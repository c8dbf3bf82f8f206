/* What every material file clayfit writes shares (preset_text.h): the text,
 * the notes, the provenance. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "shader/preset_text.h"

/* ---- text ---- */

void preset_printf(preset_text *t, const char *format, ...) {
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

void preset_escaped(preset_text *t, text_escape_fn escape, const char *text) {
  if (t->failed) return;
  char *escaped = text_escape_alloc(escape, text);
  if (!escaped) {
    t->failed = 1;
    return;
  }
  preset_printf(t, "%s", escaped);
  free(escaped);
}

void preset_text_free(preset_text *t) {
  free(t->data);
  t->data = NULL;
  t->size = t->capacity = 0;
}

cf_status preset_text_write(preset_text *t, const char *path, cf_error *err) {
  cf_status s = t->failed ? cf_error_set(err, CF_ENOMEM, "%s: out of memory", path)
                          : cf_write_file(path, t->data ? t->data : "", t->size, err);
  preset_text_free(t);
  return s;
}

/* ---- notes ---- */

void preset_note(preset_notes *n, preset_note_kind kind, const char *format, ...) {
  char text[512];
  va_list args;
  va_start(args, format);
  vsnprintf(text, sizeof text, format, args);
  va_end(args);
  if (n->count < PRESET_MAX_NOTES) {
    n->kind[n->count] = kind;
    memcpy(n->text[n->count], text, sizeof text);
    ++n->count;
  }
  if (kind == PRESET_RANGE && n->range) n->range(n->range_user, text);
}

void preset_notes_write(preset_text *t, const preset_notes *n, const char *prefix) {
  static const char *const heading[] = {"maps exactly", "maps approximately", "dropped",
                                        "outside the target's range"};
  for (int kind = 0; kind < 4; ++kind) {
    int any = 0;
    for (int i = 0; i < n->count; ++i) {
      if ((int)n->kind[i] != kind) continue;
      if (!any) preset_printf(t, "%s%s:\n", prefix, heading[kind]);
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
        preset_printf(t, "%s%s%.*s\n", prefix, first ? "  - " : "    ", (int)cut, s);
        s += cut;
        while (*s == ' ') ++s;
        first = 0;
      }
    }
  }
}

/* ---- provenance ---- */

void preset_provenance(preset_text *t, const cf_fit_file *fit, const char *fit_path,
                       const char *prefix, text_escape_fn escape) {
  const cf_model_info *m = cf_model_info_get(fit->result.model);
  preset_printf(t, "%sclayfit %s material preset: model %s (%s), fitted by clayfit ", prefix,
                CLAYFIT_VERSION, m->code, m->name);
  preset_escaped(t, escape, fit->clayfit_version);
  preset_printf(t, " on ");
  preset_escaped(t, escape, fit->created);
  preset_printf(t, "\n%sfit: ", prefix);
  preset_escaped(t, escape, fit_path ? fit_path : "(not given)");
  preset_printf(t, "; capture: ");
  preset_escaped(t, escape, fit->capture_name);
  preset_printf(t, " (");
  preset_escaped(t, escape, fit->radiometry);
  preset_printf(t, " radiometry, ");
  preset_escaped(t, escape, fit->capture_path);
  preset_printf(t, "); relative RMSE %.4g\n", fit->result.relative_rmse);
  preset_printf(t,
                "%smodel: docs/model.md of clayfit %s, model version %d%s; mapping: "
                "docs/presets.md\n",
                prefix, CLAYFIT_VERSION, fit->model_version,
                fit->model_version < CF_MODEL_VERSION ? " (fitted with Schlick's Fresnel)" : "");
}
