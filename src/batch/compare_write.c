/* clayfit library compare -o DIR: the renders, their difference (linear
 * EXR, and a PNG on a diverging colour scale), compare.json and
 * compare.html (include/clayfit/library.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "batch_internal.h"
#include "clayfit/library.h"
#include "clayfit/thumbnail.h"
#include "core/file.h"
#include "core/json_reader.h"

/* ColorBrewer's RdBu, 5 classes (sRGB): -1 blue .. 0 near-white .. +1 red. */
static const double diverging[5][3] = {{33, 102, 172}, {103, 169, 207}, {247, 247, 247},
                                        {239, 138, 98}, {178, 24, 43}};

/* sRGB (0..1) of t in [-1, 1] on the diverging scale, linearly between stops. */
static void diverging_colour(double t, float rgb[3]) {
  t = t < -1.0 ? -1.0 : t > 1.0 ? 1.0 : t;
  double x = (t + 1.0) * 2.0; /* 0..4 */
  int i = x >= 4.0 ? 3 : (int)x;
  double f = x - i;
  for (int c = 0; c < 3; ++c)
    rgb[c] = (float)(((1.0 - f) * diverging[i][c] + f * diverging[i + 1][c]) / 255.0);
}

/* Each pixel's channel difference of largest magnitude, signed, over scale. */
static cf_status difference_png(const cf_library_comparison *c, const char *path,
                                cf_error *err) {
  const cf_image *d = &c->difference;
  double scale = cf_library_difference_scale(c);
  cf_image out = {0};
  cf_status s = cf_image_alloc(&out, d->width, d->height, 3, err);
  for (size_t p = 0; s == CF_OK && p < (size_t)d->width * (size_t)d->height; ++p) {
    const float *v = &d->pixels[p * (size_t)d->channels];
    double m = 0.0;
    for (int k = 0; k < d->channels; ++k) m = fabs(v[k]) > fabs(m) ? v[k] : m;
    diverging_colour(scale > 0.0 ? m / scale : 0.0, &out.pixels[p * 3]);
  }
  if (s == CF_OK) s = cf_image_write(path, &out, 8, err);
  cf_image_free(&out);
  return s;
}

static json_t *number_or_null(double x) { return isfinite(x) ? json_real(x) : json_null(); }

static json_t *entry_json(const cf_library_entry *e) {
  return json_pack("{s:s, s:s, s:o}", "name", e->name, "model", cf_model_info_get(e->model)->code,
                   "relative_rmse", number_or_null(e->relative_rmse));
}

static json_t *diff_json(const cf_library_param_diff *d) {
  static const char *const channel[3] = {"r", "g", "b"};
  return json_pack("{s:s, s:o, s:b, s:b, s:o, s:o, s:o, s:o, s:o}", "name", d->name, "channel",
                   d->components == 3 ? json_string(channel[d->component]) : json_null(),
                   "in_a", d->in_a, "in_b", d->in_b, "a", number_or_null(d->a), "sd_a",
                   number_or_null(d->sd_a), "b", number_or_null(d->b), "sd_b",
                   number_or_null(d->sd_b), "difference_sd", number_or_null(d->z));
}

static cf_status write_json(const cf_library_comparison *c, const char *path, cf_error *err) {
  json_t *params = json_array();
  for (size_t i = 0; params && i < c->count; ++i)
    json_array_append_new(params, diff_json(&c->diffs[i]));
  json_t *doc = json_pack(
      "{s:i, s:o, s:o, s:o, s:{s:f, s:f, s:f, s:s, s:s}, s:{s:s, s:s, s:s, s:s, s:s, s:s}}",
      "clayfit_compare", 1, "a", entry_json(&c->a), "b", entry_json(&c->b), "params", params,
      "render", "max_abs_difference", c->max_abs_difference, "rms_difference", c->rms_difference,
      "difference_scale", cf_library_difference_scale(c), "difference_png",
      "each pixel's channel difference A - B of largest magnitude on ColorBrewer RdBu: white 0, "
      "red A brighter, blue B brighter, full colour at +-difference_scale (linear radiance)",
      "view", "the thumbnail's: 256 px, the standard light (docs/report.md)", "files", "a",
      "a.png", "b", "b.png", "difference", "difference.png", "a_linear", "a.exr", "b_linear",
      "b.exr", "difference_linear", "difference.exr");
  if (!doc) return cf_error_set(err, CF_ENOMEM, "out of memory");
  cf_status s = json_write_file(doc, path, JSON_INDENT(2) | JSON_REAL_PRECISION(17), err);
  json_decref(doc);
  return s;
}

/* ---- compare.html ---- */

typedef struct page {
  char *text;
  size_t length, size;
  int failed;
} page;

static void put(page *p, const char *format, ...) __attribute__((format(printf, 2, 3)));
static void put(page *p, const char *format, ...) {
  va_list args;
  for (int attempt = 0; attempt < 2 && !p->failed; ++attempt) {
    va_start(args, format);
    int n = vsnprintf(p->text + p->length, p->size - p->length, format, args);
    va_end(args);
    if (n < 0) p->failed = 1;
    if (n < 0 || (size_t)n < p->size - p->length) {
      if (n >= 0) p->length += (size_t)n;
      return;
    }
    size_t size = 2 * p->size + (size_t)n + 1;
    char *text = realloc(p->text, size);
    if (!text) p->failed = 1;
    else p->text = text, p->size = size;
  }
}

/* "0.5 ± 0.01", "0.05 (no sd)", or "—" when absent. */
static void value_cell(page *p, int present, double value, double sd) {
  if (!present) put(p, "<td class=\"absent\">not in the model</td>");
  else if (isfinite(sd)) put(p, "<td>%.6g ± %.3g</td>", value, sd);
  else put(p, "<td>%.6g (no sd)</td>", value);
}

static void param_rows(page *p, const cf_library_comparison *c) {
  static const char *const channel[3] = {" r", " g", " b"};
  for (size_t i = 0; i < c->count; ++i) {
    const cf_library_param_diff *d = &c->diffs[i];
    put(p, "<tr><th>%s%s</th>", d->name, d->components == 3 ? channel[d->component] : "");
    value_cell(p, d->in_a, d->a, d->sd_a);
    value_cell(p, d->in_b, d->b, d->sd_b);
    if (isfinite(d->z)) put(p, "<td>%.3g</td></tr>\n", d->z);
    else put(p, "<td>—</td></tr>\n");
  }
}

static cf_status write_html(const cf_library_comparison *c, const char *path, cf_error *err) {
  page p = {0};
  const char *ma = cf_model_info_get(c->a.model)->code, *mb = cf_model_info_get(c->b.model)->code;
  double scale = cf_library_difference_scale(c);
  /* Entry names are [A-Za-z0-9._-] (checked when read): nothing to escape. */
  put(&p, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
          "<title>clayfit library compare: %s and %s</title><style>"
          "body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse}"
          "td,th{padding:.2em .8em;text-align:left;border-bottom:1px solid #ddd}"
          ".absent{color:#888}figure{display:inline-block;vertical-align:top;width:256px;"
          "margin:0 1em 1em 0}"
          ".legend{width:256px;height:12px;background:linear-gradient(to right,#2166ac,#67a9cf,"
          "#f7f7f7,#ef8a62,#b2182b)}.ends{display:flex;justify-content:space-between;width:256px}"
          "</style></head><body>\n<h1>A: %s, B: %s</h1>\n",
      c->a.name, c->b.name, c->a.name, c->b.name);
  put(&p, "<figure><img src=\"a.png\" width=\"256\" height=\"256\" alt=\"A\"><figcaption>A: %s"
          "</figcaption></figure>\n<figure><img src=\"b.png\" width=\"256\" height=\"256\" "
          "alt=\"B\"><figcaption>B: %s</figcaption></figure>\n<figure><img src=\"difference.png\""
          " width=\"256\" height=\"256\" alt=\"A - B\"><div class=\"legend\"></div><div "
          "class=\"ends\"><span>%.3g</span><span>0</span><span>+%.3g</span></div><figcaption>"
          "A − B (linear radiance, each pixel's largest channel difference; red: A brighter)"
          "<br>max |A − B| %.3g, RMS %.3g</figcaption></figure>\n",
      c->a.name, c->b.name, -scale, scale, c->max_abs_difference, c->rms_difference);
  put(&p, "<table><tr><th></th><th>A: %s</th><th>B: %s</th><th>(A − B) / sd</th></tr>\n"
          "<tr><th>model</th><td>%s</td><td>%s</td><td></td></tr>\n<tr><th>relative RMSE</th>"
          "<td>%.3g %%</td><td>%.3g %%</td><td></td></tr>\n",
      c->a.name, c->b.name, ma, mb, 100.0 * c->a.relative_rmse, 100.0 * c->b.relative_rmse);
  param_rows(&p, c);
  put(&p, "</table>\n<p>sd = sqrt(sd<sub>A</sub>² + sd<sub>B</sub>²); a parameter without sd "
          "(held, at a bound) counts 0; — where a model lacks the parameter or neither has an "
          "sd.</p>\n</body></html>\n");
  cf_status s = p.failed ? cf_error_set(err, CF_ENOMEM, "out of memory")
                         : cf_write_file(path, p.text, p.length, err);
  free(p.text);
  return s;
}

/* ---- the folder ---- */

static cf_status write_linear(const cf_image *image, const char *dir, const char *file,
                              cf_error *err) {
  char path[4096];
  cf_status s = cf_path_join(dir, file, path, sizeof path, err);
  if (s == CF_OK) s = cf_image_write(path, image, 32, err);
  return s;
}

static cf_status write_display(const cf_image *image, const char *dir, const char *file,
                               cf_error *err) {
  char path[4096];
  cf_status s = cf_path_join(dir, file, path, sizeof path, err);
  if (s == CF_OK) s = cf_sphere_write_png(image, path, err);
  return s;
}

cf_status cf_library_comparison_write(const cf_library_comparison *c, const char *dir,
                                      cf_error *err) {
  char path[4096];
  cf_status s = cf_make_dirs(dir, err);
  if (s == CF_OK) s = write_display(&c->render_a, dir, "a.png", err);
  if (s == CF_OK) s = write_display(&c->render_b, dir, "b.png", err);
  if (s == CF_OK) s = write_linear(&c->render_a, dir, "a.exr", err);
  if (s == CF_OK) s = write_linear(&c->render_b, dir, "b.exr", err);
  if (s == CF_OK) s = write_linear(&c->difference, dir, "difference.exr", err);
  if (s == CF_OK) s = cf_path_join(dir, "difference.png", path, sizeof path, err);
  if (s == CF_OK) s = difference_png(c, path, err);
  if (s == CF_OK) s = cf_path_join(dir, "compare.json", path, sizeof path, err);
  if (s == CF_OK) s = write_json(c, path, err);
  if (s == CF_OK) s = cf_path_join(dir, "compare.html", path, sizeof path, err);
  if (s == CF_OK) s = write_html(c, path, err);
  return s;
}
