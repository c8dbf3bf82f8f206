/* clayfit: the material library's gallery page (docs/report.md, "The
 * gallery and thumbnails"): one index.html that works offline (inline style
 * and script, nothing fetched), a card per entry with its thumbnail, name,
 * tags, chosen model, parameters with standard deviations, relative RMSE
 * and a link to its report; a failed entry shows as failed, with its
 * reason. The cards are static HTML, readable without JavaScript; the
 * inline script only reorders them (sort by name, model, relative RMSE or
 * any parameter) and hides them (filter by text, by a tag's value, by
 * state, by a parameter's range).
 *
 * Every string an entry holds is untrusted (names and tags come from a
 * manifest): text is HTML-escaped, paths are percent-encoded (so that a
 * name such as `javascript:x` stays a relative file name), and the data the
 * script sorts on is JSON in an escaped attribute, never script text. */
#ifndef CLAYFIT_GALLERY_H
#define CLAYFIT_GALLERY_H

#include <stddef.h>

#include "clayfit/fit.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cf_gallery_tag {
  const char *key, *value; /* "clay_body", "stoneware" */
} cf_gallery_tag;

/* One parameter as the card shows it: value ± sd per component. */
typedef struct cf_gallery_param {
  const char *name; /* "albedo" */
  int components;   /* 1, or 3 (linear RGB) */
  double value[3];  /* finite */
  double sd[3];     /* NaN: none (held, at a bound, or not estimated) */
  const char *unit; /* "1" (dimensionless: not shown), "rad", ...; NULL: none */
} cf_gallery_param;

typedef enum cf_gallery_state {
  CF_GALLERY_FITTED,
  CF_GALLERY_FAILED, /* shown with its reason */
  CF_GALLERY_MISSING /* not fitted (yet) */
} cf_gallery_state;

enum { CF_GALLERY_MAX_PARAMS = 64, CF_GALLERY_MAX_TAGS = 256 };

typedef struct cf_gallery_entry {
  const char *name;
  const cf_gallery_tag *tags;
  size_t tag_count; /* at most CF_GALLERY_MAX_TAGS */
  cf_gallery_state state;
  const char *model; /* the chosen model's code ("M4"); NULL: none */
  const cf_gallery_param *params;
  size_t param_count;    /* at most CF_GALLERY_MAX_PARAMS */
  double relative_rmse;  /* a fraction (0.012 shows as 1.2 %); NaN: unknown */
  const char *thumbnail; /* relative to the page's folder; NULL: none */
  const char *report;    /* the entry's report page (a failed entry: its
                            failed.json or log), relative; NULL: none */
  const char *reason;    /* why it failed (CF_GALLERY_FAILED) */
} cf_gallery_entry;

/* Fill params (room for CF_MAX_DIM records; param_count receives how many)
 * with a fit's parameters: one record per parameter of its model, its
 * value(s), sd (NaN where the fit has none: not finite or 0, that is not
 * fitted), unit; names and units point into the model's table. */
void cf_gallery_params_from_result(const cf_fit_result *result, cf_gallery_param *params,
                                   size_t *param_count);

/* Write the gallery of entries[0..count) to path (index.html) with the
 * page's title, whole or not at all (cf_write_file). CF_EINVAL naming the
 * entry for a NULL name, a path that is absolute or a URL's
 * scheme-relative `//`, too many tags or parameters, a parameter of
 * components other than 1 or 3 or a value not finite; CF_EIO (path
 * and reason) when the file cannot be written; CF_ENOMEM. */
cf_status cf_report_write_gallery(const cf_gallery_entry *entries, size_t count, const char *title,
                                  const char *path, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_GALLERY_H */
