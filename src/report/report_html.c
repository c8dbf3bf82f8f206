/* index.html: the report as a page that works offline, its pictures and
 * plots beside it (report_internal.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/image.h"
#include "core/text_escape.h"
#include "report_internal.h"
#include "svg.h"

/* Untrusted text (the capture's name, paths, image names, anything read
 * from fit.json) on the page, escaped; a failed write shows in ferror(f),
 * checked when the page is closed. */
static void html(FILE *f, const char *text) {
  text_escape_fputs(f, text_escape_html, text);
}

static double number_at(const json_t *object, const char *key) {
  const json_t *v = json_object_get(object, key);
  return json_is_number(v) ? json_number_value(v) : NAN;
}

static const char *string_at(const json_t *object, const char *key) {
  const json_t *v = json_object_get(object, key);
  return json_is_string(v) ? json_string_value(v) : "";
}

static void head(FILE *f, const report_data *d, const char *fit_path, const char *version) {
  const cf_model_info *m = cf_model_info_get(d->fit->result.model);
  fputs(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>clayfit report: ",
      f);
  html(f, d->fit->capture_name);
  fputs(
      "</title>\n<style>\nbody{font-family:sans-serif;margin:24px;max-width:1400px}\n"
      "table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:3px 8px;"
      "text-align:right}th{background:#f0f0f0}td.l,th.l{text-align:left}\n"
      ".images{display:grid;grid-template-columns:repeat(3,auto) 1fr;gap:6px;align-items:center}"
      "\n.images img{max-width:300px;image-rendering:pixelated}.plots img{margin:4px}\n"
      ".viewer{display:flex;gap:12px;align-items:flex-start}.viewer canvas{cursor:grab}\n"
      "tr.chosen td{font-weight:bold}.warn{color:#a04000}\n</style></head><body>\n",
      f);
  fputs("<h1>clayfit report</h1>\n<p>Fit <code>", f);
  html(f, fit_path);
  fputs("</code> of the capture <code>", f);
  html(f, d->capture_path); /* the capture re-rendered (--capture, else the fit's) */
  fputs("</code> (", f);
  html(f, d->fit->capture_name);
  fprintf(f, "; %zu images, %zu observations): model <b>%s (%s)</b>, radiometry ", d->images,
          d->count, m->code, m->name);
  html(f, d->fit->radiometry);
  fputs(". Fitted by clayfit ", f);
  html(f, d->fit->clayfit_version);
  fputs(" on ", f);
  html(f, d->fit->created);
  fputs("; report by clayfit ", f);
  html(f, version);
  fputs(".</p>\n", f);
}

static void parameter_table(FILE *f, const report_data *d) {
  const cf_fit_result *r = &d->fit->result;
  const cf_model_info *m = cf_model_info_get(r->model);
  fputs(
      "<h2>Parameters</h2>\n<table><tr><th class=\"l\">parameter</th><th>value</th>"
      "<th>standard deviation</th><th class=\"l\">unit</th><th class=\"l\">status</th></tr>\n",
      f);
  int unconstrained = 0;
  for (int k = 0; k < m->dim; ++k) {
    char name[48];
    cf_model_slot_name(r->model, k, name, sizeof name);
    const char *unit = cf_model_slot_param(r->model, k, NULL)->unit;
    char sd[48];
    if (isfinite(r->sd[k]))
      snprintf(sd, sizeof sd, "&plusmn; %.3g", r->sd[k]);
    else
      snprintf(sd, sizeof sd, "none (at a bound)");
    fprintf(f,
            "<tr><td class=\"l\">%s</td><td>%.6g</td><td>%s</td><td class=\"l\">%s</td>"
            "<td class=\"l\">%s</td></tr>\n",
            name, r->params[k], sd, unit, cf_param_status_name(r->status[k]));
    unconstrained += r->status[k] == CF_PARAM_UNCONSTRAINED;
  }
  if (r->scale_fitted)
    fprintf(f,
            "<tr><td class=\"l\">scale</td><td>%.6g</td><td>&plusmn; %.3g</td>"
            "<td class=\"l\">1</td><td class=\"l\">fitted (%s)</td></tr>\n",
            r->scale, r->scale_sd,
            r->response_fitted ? "the level: an unknown tone curve" : "relative radiometry");
  for (int j = 0; r->response_fitted && j < CF_RESPONSE_MODEL_KNOTS; ++j)
    fprintf(f,
            "<tr><td class=\"l\">response slope at x = %s%g</td><td>%.6g</td>"
            "<td>&plusmn; %.3g</td><td class=\"l\">1</td><td class=\"l\">fitted (unknown tone "
            "curve)</td></tr>\n",
            j ? "1/" : "", 1.0 / cf_response_model_knot(j), r->response[j],
            sqrt(fmax(0.0, r->response_covariance[j * (CF_RESPONSE_MODEL_KNOTS + 1)])));
  fputs("</table>\n<p>Not constrained by this capture (held at their defaults): ", f);
  if (!unconstrained) fputs("none", f);
  for (int k = 0, first = 1; k < m->dim; ++k) {
    if (r->status[k] != CF_PARAM_UNCONSTRAINED) continue;
    char name[48];
    fprintf(f, "%s<code>%s</code>", first ? "" : ", ",
            cf_model_slot_name(r->model, k, name, sizeof name));
    first = 0;
  }
  fputs(".</p>\n", f);
  const json_t *warnings = d->doc ? json_object_get(d->doc, "warnings") : NULL;
  for (size_t i = 0; json_is_array(warnings) && i < json_array_size(warnings); ++i) {
    fputs("<p class=\"warn\">Warning: ", f);
    html(f, json_string_value(json_array_get(warnings, i)));
    fputs("</p>\n", f);
  }
}

static void residual_summary(FILE *f, const report_data *d) {
  const cf_fit_result *r = &d->fit->result;
  fprintf(f,
          "<h2>Residuals</h2>\n<p>Relative RMSE %.4g %% over all observations and channels "
          "(RMSE %.4g in radiance units).",
          100.0 * r->relative_rmse, r->rmse);
  const json_t *cores =
      d->doc ? json_object_get(json_object_get(d->doc, "residuals"), "highlight_cores") : NULL;
  if (cores)
    fprintf(f,
            " Within %g px of each image's brightest observation (the highlight's core): %.4g "
            "%%; elsewhere: %.4g %%.",
            number_at(cores, "radius_px"), 100.0 * number_at(cores, "relative_rmse"),
            100.0 * number_at(json_object_get(cores, "rest"), "relative_rmse"));
  double share = report_rejected_share(d, 0), clustered = report_rejected_share(d, 1);
  if (isfinite(share))
    fprintf(f,
            " %.3g %% of the observations beyond the robust loss's scale (green in the maps) lie "
            "in one connected region per image (its largest, 8-connected), %.3g %% in regions of "
            "%d pixels or more: %s.",
            100.0 * share, 100.0 * clustered, REPORT_CLUSTER_PX,
            clustered >= REPORT_SYSTEMATIC_SHARE ? "a systematic misfit, not outliers"
                                                 : "scattered, outliers rather than a misfit");
  fputs("</p>\n", f);
}

/* The fitted per-image gains e_k ± sd (--fit-exposures), six images to a
 * row; nothing when they were not fitted (every sd 0). */
static void gains_table(FILE *f, const report_data *d) {
  const cf_fit_result *r = &d->fit->result;
  enum { PER_ROW = 6 };
  double worst = 0.0;
  for (size_t k = 0; r->exposure_sd && k < r->images; ++k)
    worst = fmax(worst, r->exposure_sd[k] / r->exposures[k]);
  if (!(worst > 0.0) || r->images != d->images) return;
  fprintf(f,
          "<h2>Per-image gains</h2>\n<p>Each image's gain e<sub>k</sub> (its exposure or "
          "light intensity relative to the capture's, fitted with <code>--fit-exposures</code>; "
          "their mean log is 0) &plusmn; its standard deviation (at most %.2g %%); with "
          "<code>--fit-gains per-image-rgb</code> also its white balance, red's and blue's "
          "gains against green's.</p>\n<table>",
          100.0 * worst);
  for (size_t k = 0; k < r->images; ++k) {
    if (k % PER_ROW == 0) fputs(k ? "</tr>\n<tr>" : "<tr>", f);
    fputs("<td class=\"l\">", f);
    html(f, cf_capture_image_at(d->capture, k)->name);
    fprintf(f, "</td><td>%.4f &plusmn; %.4f", r->exposures[k], r->exposure_sd[k]);
    if (r->white_balance_fitted && r->white_balance && r->white_balance_sd)
      fprintf(f, "<br>red %.4f &plusmn; %.4f, blue %.4f &plusmn; %.4f", r->white_balance[3 * k],
              r->white_balance_sd[3 * k], r->white_balance[3 * k + 2],
              r->white_balance_sd[3 * k + 2]);
    fputs("</td>", f);
  }
  fputs("</tr></table>\n", f);
}

/* The fitted gains per light g_l ± sd (--fit-gains per-light where a
 * photo has several lights); nothing otherwise. */
static void light_gains_table(FILE *f, const report_data *d) {
  const cf_fit_result *r = &d->fit->result;
  if (r->light_count == 0 || !r->light_gains || !r->light_gains_sd || !r->light_names) return;
  fputs(
      "<h2>Per-light gains</h2>\n<p>Each light's gain g<sub>l</sub> inside every photo's sum "
      "over its lights (<code>--fit-gains per-light</code>; their mean log is 0) &plusmn; its "
      "standard deviation.</p>\n<table>",
      f);
  for (size_t l = 0; l < r->light_count; ++l) {
    fputs("<tr><td class=\"l\">", f);
    html(f, r->light_names[l]);
    fprintf(f, "</td><td>%.4f &plusmn; %.4f</td></tr>\n", r->light_gains[l], r->light_gains_sd[l]);
  }
  fputs("</table>\n", f);
}

static void choice_table(FILE *f, const report_data *d) {
  const json_t *choice = d->doc ? json_object_get(d->doc, "choice") : NULL;
  const json_t *list = json_object_get(choice, "candidates");
  fputs("<h2>Model choice</h2>\n", f);
  if (!json_is_array(list) || json_array_size(list) == 0) {
    fputs("<p>The model was forced (<code>--model</code>): no choice was made.</p>\n", f);
    const char *reading = json_string_value(json_object_get(choice, "reading"));
    if (reading) {
      fputs("<p>Meaning: ", f);
      html(f, reading);
      fputs(".</p>\n", f);
    }
    return;
  }
  fputs("<p>Held out: ", f);
  html(f, string_at(choice, "heldout"));
  /* with a fitted response curve the held-out score is in decoded units
   * (times σ's geometric mean: docs/model.md §6.8) */
  fprintf(f,
          ".</p>\n<table><tr><th class=\"l\">model</th><th>unknowns</th><th>BIC</th>"
          "<th>held-out RMS (%s)</th><th>held-out relative RMSE</th><th>training relative "
          "RMSE</th><th>time (s)</th><th class=\"l\">parameters</th><th class=\"l\">verdict</th>"
          "</tr>\n",
          d->fit->result.response_fitted ? "decoded units" : "&sigma;");
  for (size_t i = 0; i < json_array_size(list); ++i) {
    const json_t *c = json_array_get(list, i);
    fprintf(f, "<tr%s><td class=\"l\">",
            json_is_true(json_object_get(c, "chosen")) ? " class=\"chosen\"" : "");
    html(f, string_at(c, "model"));
    fprintf(f,
            "</td><td>%.0f</td><td>%.6g</td><td>%.4g</td><td>%.4g %%</td><td>%.4g %%</td>"
            "<td>%.3g</td><td class=\"l\">",
            number_at(c, "unknowns"), number_at(c, "bic"), number_at(c, "heldout_score"),
            100.0 * number_at(c, "heldout_relative_rmse"),
            100.0 * number_at(c, "train_relative_rmse"), number_at(c, "seconds"));
    const char *key;
    const json_t *p;
    json_object_foreach((json_t *)json_object_get(c, "params"), key, p) {
      const json_t *v = json_object_get(p, "value");
      html(f, key);
      fputs(" ", f);
      if (json_is_array(v))
        for (size_t j = 0; j < json_array_size(v); ++j)
          fprintf(f, "%s%.4g", j ? "," : "", json_number_value(json_array_get(v, j)));
      else
        fprintf(f, "%.4g", json_number_value(v));
      fputs("; ", f);
    }
    fputs("</td><td class=\"l\">", f);
    if (json_is_true(json_object_get(c, "chosen"))) fputs("chosen: ", f);
    html(f, string_at(c, "note"));
    fputs("</td></tr>\n", f);
  }
  fputs("</table>\n", f);
  /* what the chosen model's parameters mean (an M4 whose film is a lobe) */
  const char *reading = json_string_value(json_object_get(choice, "reading"));
  if (reading) {
    fputs("<p>Meaning: ", f);
    html(f, reading);
    fputs(".</p>\n", f);
  }
  /* a tailed choice: what GGX's lobe would cost (its twin's row) */
  const char *ggx_cost =
      json_string_value(json_object_get(json_object_get(choice, "ggx_cost"), "meaning"));
  if (ggx_cost) {
    fputs("<p>", f);
    html(f, ggx_cost);
    fputs(".</p>\n", f);
  }
}

static void plots_and_speed(FILE *f, const report_data *d) {
  fputs("<h2>Plots</h2>\n<div class=\"plots\">\n", f);
  for (int p = 0; p < REPORT_PLOT_COUNT; ++p)
    fprintf(f, "<img src=\"%s\" alt=\"%s\" width=\"560\" height=\"340\">\n", report_plots[p].file,
            report_plots[p].title);
  if (d->fit->result.response_fitted)
    fprintf(f, "<a href=\"%s\"><img src=\"%s\" alt=\"%s\" width=\"560\" height=\"340\"></a>\n",
            report_response_plot_info.file, report_response_plot_info.file,
            report_response_plot_info.title);
  fputs("</div>\n<h2>Speed</h2>\n", f);
  const json_t *timing = d->doc ? json_object_get(d->doc, "timing") : NULL;
  const json_t *solver = d->doc ? json_object_get(d->doc, "solver") : NULL;
  fprintf(f,
          "<p>Load %.3g s, fit %.3g s (model choice %.3g s), in all %.3g s. Solver: %.0f "
          "Levenberg-Marquardt iterations in %.0f solves, %.3g s, ",
          number_at(timing, "load_s"), number_at(timing, "fit_s"), number_at(timing, "choice_s"),
          number_at(timing, "total_s"), number_at(solver, "iterations"),
          number_at(solver, "solves"), number_at(solver, "seconds"));
  html(f, string_at(solver, "termination"));
  fprintf(f, ". Observations: %zu", d->count);
  const json_t *sample = d->doc ? json_object_get(d->doc, "sample") : NULL;
  if (json_is_object(sample)) {
    fprintf(f, "; the fit used a pixel budget of %.0f of them (",
            number_at(sample, "observations"));
    html(f, string_at(sample, "sampling"));
    fputs(
        "), each weighed by the inverse of its chance: its standard deviations are the "
        "sample's; the residuals on this page are every observation's",
        f);
  }
  fputs(".</p>\n", f);
}

/* The colour scale of the heat maps, inline. */
static void colour_scale(FILE *f) {
  fputs(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"420\" height=\"46\" "
      "font-family=\"sans-serif\" font-size=\"11\"><defs><linearGradient id=\"scale\">",
      f);
  for (int i = 0; i <= 10; ++i) {
    float rgb[3];
    report_residual_colour(CF_REPORT_SIGMA_RANGE * (i / 5.0 - 1.0), rgb);
    /* the stops in sRGB, as the PNGs hold them */
    int c8[3];
    for (int c = 0; c < 3; ++c) {
      c8[c] = (int)lround(255.0 * cf_linear_to_srgb(rgb[c]));
    }
    fprintf(f, "<stop offset=\"%d%%\" stop-color=\"rgb(%d,%d,%d)\"/>", i * 10, c8[0], c8[1], c8[2]);
  }
  fprintf(f,
          "</linearGradient></defs><rect x=\"10\" y=\"4\" width=\"400\" height=\"16\" "
          "fill=\"url(#scale)\" stroke=\"black\"/><text x=\"10\" y=\"34\">&minus;%g &sigma; "
          "(render darker)</text><text x=\"210\" y=\"34\" "
          "text-anchor=\"middle\">0</text><text x=\"410\" y=\"34\" text-anchor=\"end\">+%g "
          "&sigma; (brighter)</text></svg>\n",
          CF_REPORT_SIGMA_RANGE, CF_REPORT_SIGMA_RANGE);
}

static void image_rows(FILE *f, const report_data *d, char (*files)[3][64]) {
  fputs(
      "<h2>Every image: photo, re-rendering, residual</h2>\n<p>Residual heat map: "
      "(prediction &minus; photo) / &sigma; per channel, summed over the channels not censored and "
      "divided by &radic;(their number): noise alone gives N(0, 1). Magenta: censored "
      "(a clipped channel the model predicts at or above the clip level); green: beyond the "
      "robust loss's scale (",
      f);
  if (isfinite(d->loss_scale))
    fprintf(f, "%g &sigma;", d->loss_scale);
  else
    fputs("no robust loss", f);
  fputs(
      "); dark grey: not an observation. Photo and rendering share one white point per "
      "image.</p>\n",
      f);
  colour_scale(f);
  fputs("<div class=\"images\">\n", f);
  const cf_fit_result *r = &d->fit->result;
  for (size_t k = 0; k < d->images; ++k) {
    const cf_capture_image *im = cf_capture_image_at(d->capture, k);
    for (int p = 0; p < 3; ++p) {
      fputs("<img src=\"", f);
      html(f, files[k][p]);
      fputs("\" alt=\"", f);
      html(f, im->name);
      fprintf(f, " %s\">", p == 0 ? "photo" : p == 1 ? "render" : "residual");
    }
    fputs("<div>", f);
    html(f, im->name);
    fprintf(f,
            "<br>%zu observations, relative RMSE %.3g %%, RMS %.3g &sigma;<br>%zu censored, "
            "%zu beyond the loss (%zu in its largest region), %zu left out (not radiance)</div>\n",
            d->observations[k], r->image_relative_rmse ? 100.0 * r->image_relative_rmse[k] : NAN,
            d->rms_sigma[k], d->censored[k], d->rejected[k], d->rejected_region[k],
            im->not_radiance);
  }
  fputs("</div>\n", f);
}

/* Counts the images that loaded, into the title and #loaded (what the
 * browser test reads). */
static void load_check(FILE *f) {
  fputs(
      "<p id=\"loaded\">images: not checked (scripts off)</p>\n<script>\n"
      "window.addEventListener('load', function () {\n"
      "  var all = document.images, ok = 0;\n"
      "  for (var i = 0; i < all.length; ++i) if (all[i].complete && all[i].naturalWidth > 0) "
      "++ok;\n"
      "  var line = 'images loaded: ' + ok + ' of ' + all.length;\n"
      "  document.getElementById('loaded').textContent = line;\n"
      "  document.title = line + ' | ' + document.title;\n"
      "});\n</script>\n</body></html>\n",
      f);
}

cf_status report_write_html(const report_data *d, const char *dir, const char *fit_path,
                            const char *version, char (*image_files)[3][64],
                            const report_view *view, cf_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s/index.html", dir);
  FILE *f = fopen(path, "w");
  if (!f) return cf_error_set(err, CF_EIO, "%s: cannot write: %s", path, strerror(errno));
  head(f, d, fit_path, version);
  report_view_html(f, d, view);
  parameter_table(f, d);
  residual_summary(f, d);
  gains_table(f, d);
  light_gains_table(f, d);
  choice_table(f, d);
  plots_and_speed(f, d);
  image_rows(f, d, image_files);
  load_check(f);
  int failed = ferror(f), why = failed ? errno : 0;
  if (fclose(f) != 0) failed = 1, why = errno;
  return failed
             ? cf_error_set(err, CF_EIO, "%s: could not write: %s", path, strerror(why ? why : EIO))
             : CF_OK;
}
