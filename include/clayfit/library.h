/* clayfit: reading a material library that `clayfit batch` wrote
 * (docs/batch.md), and comparing two of its entries (`clayfit library
 * compare`, docs/batch.md "Comparing entries"): their parameters side by
 * side with the difference in standard deviations, and the difference of
 * their renders under the standard light (clayfit/thumbnail.h). */
#ifndef CLAYFIT_LIBRARY_H
#define CLAYFIT_LIBRARY_H

#include <stddef.h>

#include "clayfit/fit.h"
#include "clayfit/image.h"
#include "clayfit/model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One fitted entry of a library: its fit as LIBRARY/<name>/fit.json has it. */
typedef struct cf_library_entry {
  char name[65];
  cf_model_id model;
  double params[CF_MAX_DIM]; /* the model's vector */
  double sd[CF_MAX_DIM];     /* NaN where fit.json has null (held, at a bound) */
  double relative_rmse;
} cf_library_entry;

/* Find `name` in LIBRARY/library.json and read its fit.json. CF_EINVAL
 * naming what is wrong: not a library (no or an unreadable library.json,
 * or not one clayfit wrote), an entry the library does not list, an entry
 * that failed (with its reason) or has no fit; CF_EIO and others from
 * reading fit.json. */
cf_status cf_library_entry_read(const char *library, const char *name, cf_library_entry *entry,
                                cf_error *err);

/* One parameter component of the comparison. */
typedef struct cf_library_param_diff {
  const char *name;    /* the parameter's name (the model table's) */
  int component;       /* 0; 0..2 (r, g, b) of an RGB parameter */
  int components;      /* 1 or 3 */
  int in_a, in_b;      /* 0: the parameter is not in that entry's model */
  double a, sd_a, b, sd_b; /* sd NaN: none (held, at a bound) */
  /* (a - b) / sqrt(sd_a² + sd_b²), a missing sd counting as 0; when both
   * are 0 or missing: 0 if a == b, else NaN (no uncertainty to measure the
   * difference in). NaN when the parameter is in one entry only. */
  double z;
} cf_library_param_diff;

enum { CF_LIBRARY_MAX_DIFFS = 2 * CF_MAX_DIM };

typedef struct cf_library_comparison {
  cf_library_entry a, b;
  size_t count; /* diffs: A's parameters in its order, then those only in B */
  cf_library_param_diff diffs[CF_LIBRARY_MAX_DIFFS];
  cf_image render_a, render_b; /* linear, under the standard light (cf_sphere_view_default) */
  cf_image difference;         /* render_a - render_b, per channel, linear */
  double max_abs_difference;   /* over every pixel and channel */
  double rms_difference;       /* over every pixel and channel */
} cf_library_comparison;

/* Compare entries a and b of a library: parameters and renders. The
 * renders are those of the entries' thumbnails. Free with
 * cf_library_comparison_free. Errors as cf_library_entry_read. */
cf_status cf_library_compare(const char *library, const char *a, const char *b,
                             cf_library_comparison *out, cf_error *err);
void cf_library_comparison_free(cf_library_comparison *comparison);

/* The difference image's display scale: the largest |difference| of a
 * pixel's channels maps to the diverging colour scale's ends at ± this
 * value (max_abs_difference; 0 for identical renders, all neutral). */
double cf_library_difference_scale(const cf_library_comparison *comparison);

/* Write into dir (created): a.png and b.png (the renders through the
 * thumbnail's display curve), a.exr, b.exr and difference.exr (linear,
 * 32-bit float; difference = A - B per channel), difference.png (each
 * pixel's channel difference of largest magnitude, signed, on a diverging
 * blue-white-red scale, white 0, red A brighter, full colour at ±scale),
 * compare.json (the parameters, the differences, the scale) and
 * compare.html (all of it on one offline page). */
cf_status cf_library_comparison_write(const cf_library_comparison *comparison, const char *dir,
                                      cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_LIBRARY_H */
