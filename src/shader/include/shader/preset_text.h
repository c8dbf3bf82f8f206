/* What every material file clayfit writes shares, export's formats and the
 * shaders alike (preset_text.c): a growing text buffer, the notes each file
 * carries (what maps exactly, approximately, what is dropped, what is
 * outside the target's range) and the lines of provenance. The interface of
 * clayfit_shader to the layer above it (src/export). */
#ifndef CLAYFIT_SHADER_PRESET_TEXT_H
#define CLAYFIT_SHADER_PRESET_TEXT_H

#include <stddef.h>

#include "clayfit/fit_file.h"
#include "clayfit/status.h"
#include "core/text_escape.h"

/* ---- text ---- */
typedef struct preset_text {
  char *data;
  size_t size, capacity;
  int failed; /* out of memory */
} preset_text;

void preset_printf(preset_text *t, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Untrusted text (a name, a path: from fit.json or the command line)
 * escaped for the file's syntax (core/text_escape.h). */
void preset_escaped(preset_text *t, text_escape_fn escape, const char *text);
/* Write the text to path and free it. */
cf_status preset_text_write(preset_text *t, const char *path, cf_error *err);
void preset_text_free(preset_text *t);

/* ---- notes ---- */
typedef enum preset_note_kind {
  PRESET_EXACT,   /* the target computes what the model does */
  PRESET_APPROX,  /* the target's term differs (how, in the note) */
  PRESET_DROPPED, /* the target has no such term */
  PRESET_RANGE    /* a value outside the target's range: also a warning */
} preset_note_kind;

enum { PRESET_MAX_NOTES = 40 };

typedef struct preset_notes {
  int count;
  preset_note_kind kind[PRESET_MAX_NOTES];
  char text[PRESET_MAX_NOTES][512];
  /* optional: told the text of every PRESET_RANGE note, as it is noted
   * (export: its warnings) */
  void (*range)(void *user, const char *text);
  void *range_user;
} preset_notes;

void preset_note(preset_notes *n, preset_note_kind kind, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The notes as comment lines, each starting with `prefix`, under a heading
 * per kind. */
void preset_notes_write(preset_text *t, const preset_notes *n, const char *prefix);

/* ---- provenance ---- */
/* Three lines: clayfit version, fit file, model, capture; every line starts
 * with `prefix`, and the text from fit.json and the fit file's path are
 * escaped with `escape` (the syntax of a comment, or text_escape_utf8 for a
 * JSON string). */
void preset_provenance(preset_text *t, const cf_fit_file *fit, const char *fit_path,
                       const char *prefix, text_escape_fn escape);

#endif /* CLAYFIT_SHADER_PRESET_TEXT_H */
