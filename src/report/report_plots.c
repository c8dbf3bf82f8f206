/* The report's plots (report_internal.h), as SVG. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/vec.h"
#include "report_internal.h"
#include "svg.h"

const report_plot report_plots[REPORT_PLOT_COUNT] = {
    {"residual_vs_half_angle", "Residual against half-angle", "plots/residual_vs_half_angle.svg"},
    {"residual_vs_view_angle", "Residual against view angle", "plots/residual_vs_view_angle.svg"},
    {"residual_histogram", "Residual histogram", "plots/residual_histogram.svg"},
    {"lobe", "The fitted lobe in the plane of incidence", "plots/lobe.svg"},
    {"convergence", "Convergence: the multi-start and the solver", "plots/convergence.svg"},
    {"timing", "Where the fit's time went", "plots/timing.svg"},
};

enum { ANGLE_BINS = 45, HISTOGRAM_BINS = 64 };

cf_status report_plot_begin(svg_plot *plot, const char *dir, const report_plot *info, char *path,
                            size_t size, cf_error *err) {
  snprintf(path, size, "%s/%s", dir, info->file);
  return svg_begin(plot, path, REPORT_PLOT_WIDTH, REPORT_PLOT_HEIGHT, info->title, err);
}

/* Mean and RMS of the residual in bins of an angle (0–90°). */
static cf_status angle_plot(const report_data *d, const float *angle, int which,
                            const char *x_label, const char *dir, cf_error *err) {
  double x[ANGLE_BINS], mean[ANGLE_BINS], rms[ANGLE_BINS],
      sum[ANGLE_BINS] = {0}, sum2[ANGLE_BINS] = {0}, count[ANGLE_BINS] = {0}, zero[2] = {0.0, 0.0},
      ends[2] = {0, 90};
  for (size_t i = 0; i < d->count; ++i) {
    if (!isfinite(angle[i]) || !isfinite(d->residual[i])) continue;
    int b = (int)(angle[i] / 90.0 * ANGLE_BINS);
    if (b < 0 || b >= ANGLE_BINS) continue;
    sum[b] += d->residual[i];
    sum2[b] += (double)d->residual[i] * d->residual[i];
    count[b] += 1.0;
  }
  double lo = -1.0, hi = 1.0;
  for (int b = 0; b < ANGLE_BINS; ++b) {
    x[b] = (b + 0.5) * 90.0 / ANGLE_BINS;
    mean[b] = count[b] > 0 ? sum[b] / count[b] : NAN;
    rms[b] = count[b] > 0 ? sqrt(sum2[b] / count[b]) : NAN;
    if (isfinite(rms[b])) lo = fmin(lo, -rms[b]), hi = fmax(hi, rms[b]);
  }
  double minus[ANGLE_BINS];
  for (int b = 0; b < ANGLE_BINS; ++b) minus[b] = -rms[b];
  svg_plot plot = {0};
  char path[4096];
  cf_status s = report_plot_begin(&plot, dir, &report_plots[which], path, sizeof path, err);
  if (s != CF_OK) return s;
  plot.x0 = 0.0, plot.x1 = 90.0, plot.y0 = lo * 1.1, plot.y1 = hi * 1.1;
  svg_axes(&plot, x_label, "residual (prediction - photo) / sigma");
  svg_line(&plot, ends, zero, 2, "#888888", 1.0, "4 3");
  svg_line(&plot, x, rms, ANGLE_BINS, "#d08000", 1.5, NULL);
  svg_line(&plot, x, minus, ANGLE_BINS, "#d08000", 1.5, NULL);
  svg_line(&plot, x, mean, ANGLE_BINS, "#1040c0", 2.0, NULL);
  svg_legend(&plot, 0, "#1040c0", "mean in 2-degree bins");
  svg_legend(&plot, 1, "#d08000", "+/- RMS");
  return svg_end(&plot, path, err);
}

static cf_status histogram_plot(const report_data *d, const char *dir, cf_error *err) {
  const double lo = -8.0, hi = 8.0, w = (hi - lo) / HISTOGRAM_BINS;
  double x[HISTOGRAM_BINS], y[HISTOGRAM_BINS] = {0}, total = 0.0, peak = 1.0;
  for (size_t i = 0; i < d->count; ++i) {
    if (!isfinite(d->residual[i])) continue;
    total += 1.0;
    int b = (int)floor((d->residual[i] - lo) / w);
    if (b >= 0 && b < HISTOGRAM_BINS) y[b] += 1.0;
  }
  double gx[161], gy[161];
  for (int b = 0; b < HISTOGRAM_BINS; ++b) x[b] = lo + b * w, peak = fmax(peak, y[b]);
  for (int i = 0; i <= 160; ++i) { /* the noise alone: N(0, 1) */
    gx[i] = lo + (hi - lo) * i / 160.0;
    gy[i] = total * w * exp(-0.5 * gx[i] * gx[i]) / sqrt(2.0 * CF_PI);
    peak = fmax(peak, gy[i]);
  }
  svg_plot plot = {0};
  char path[4096];
  cf_status s = report_plot_begin(&plot, dir, &report_plots[2], path, sizeof path, err);
  if (s != CF_OK) return s;
  plot.x0 = lo, plot.x1 = hi, plot.y0 = 0.0, plot.y1 = peak * 1.1;
  svg_axes(&plot, "residual / sigma (channels combined: sum / sqrt(count))", "observations");
  svg_bars(&plot, x, y, HISTOGRAM_BINS, w, "#7090d0");
  svg_line(&plot, gx, gy, 161, "#c02020", 1.5, NULL);
  svg_legend(&plot, 0, "#7090d0", "observations");
  svg_legend(&plot, 1, "#c02020", "noise alone, N(0, 1)");
  return svg_end(&plot, path, err);
}

/* f (mean over the channels, 1/sr) in the plane of incidence, n = z, for
 * lights at 0, 30 and 60 degrees, on a log radial scale. */
static cf_status lobe_plot(const report_data *d, const char *dir, cf_error *err) {
  enum { N = 179 };
  static const double light_deg[3] = {0.0, 30.0, 60.0};
  static const char *const colours[3] = {"#1040c0", "#10a040", "#c02020"};
  const double deg = CF_PI / 180.0, n[3] = {0.0, 0.0, 1.0};
  double f[3][N], lo = INFINITY, hi = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < N; ++i) {
      double to = (-89.0 + i) * deg, ti = light_deg[a] * deg, rgb[3];
      double l[3] = {sin(ti), 0.0, cos(ti)}, v[3] = {sin(to), 0.0, cos(to)};
      cf_status s = cf_eval(d->fit->result.model, d->fit->result.params, n, l, v, rgb, NULL);
      f[a][i] = s == CF_OK ? (rgb[0] + rgb[1] + rgb[2]) / 3.0 : NAN;
      if (f[a][i] > 0.0) lo = fmin(lo, f[a][i]), hi = fmax(hi, f[a][i]);
    }
  if (!(hi > 0.0)) hi = 1.0, lo = 0.1;
  lo = fmax(lo, hi * 1e-3);
  double decades = log10(hi / lo) > 0.0 ? log10(hi / lo) : 1.0;
  svg_plot plot = {0};
  char path[4096], label[64];
  cf_status s = report_plot_begin(&plot, dir, &report_plots[3], path, sizeof path, err);
  if (s != CF_OK) return s;
  plot.x0 = -1.0, plot.x1 = 1.0, plot.y0 = 0.0, plot.y1 = 1.0;
  plot.width = plot.height * 2.0; /* a half disc: equal scales */
  plot.left = (REPORT_PLOT_WIDTH - plot.width) / 2.0;
  double arc_x[181], arc_y[181];
  for (int ring = 1; ring <= 3; ++ring) {
    for (int i = 0; i <= 180; ++i)
      arc_x[i] = ring / 3.0 * cos(i * deg), arc_y[i] = ring / 3.0 * sin(i * deg);
    svg_line(&plot, arc_x, arc_y, 181, "#cccccc", 1.0, NULL);
    snprintf(label, sizeof label, "%.2g", lo * pow(10.0, decades * ring / 3.0));
    svg_text(&plot, svg_px(&plot, ring / 3.0), svg_py(&plot, 0.0) + 14, "middle", label);
  }
  for (int a = 0; a < 3; ++a) {
    double x[N], y[N];
    for (int i = 0; i < N; ++i) {
      double to = (-89.0 + i) * deg;
      double r = f[a][i] > 0.0 ? fmax(0.0, log10(f[a][i] / lo) / decades) : NAN;
      x[i] = r * sin(to), y[i] = r * cos(to);
    }
    svg_line(&plot, x, y, N, colours[a], 2.0, NULL);
    snprintf(label, sizeof label, "light at %g degrees", light_deg[a]);
    svg_legend(&plot, a, colours[a], label);
  }
  svg_text(&plot, plot.left + plot.width / 2, plot.top + plot.height + 34, "middle",
           "view direction in the plane of incidence; radius: f (1/sr, log scale, channel mean)");
  return svg_end(&plot, path, err);
}

/* A number array of fit.json (at a path of keys), or 0. */
static size_t json_numbers(const json_t *array, double *out, size_t max) {
  size_t n = 0;
  if (!json_is_array(array)) return 0;
  for (size_t i = 0; i < json_array_size(array) && n < max; ++i)
    if (json_is_number(json_array_get(array, i)))
      out[n++] = json_number_value(json_array_get(array, i));
  return n;
}

/* Convergence, as distances on a log scale: each multi-start start's final
 * cost above the best start's, and (where fit.json has the trace) the
 * cost at each solver iteration above the lowest (the weights change
 * between solves, so the trace steps up where a solve begins). */
static cf_status convergence_plot(const report_data *d, const char *dir, cf_error *err) {
  enum { MAX = 1024 };
  double start_cost[CF_FIT_MAX_STARTS], start_x[CF_FIT_MAX_STARTS], trace[MAX], trace_x[MAX];
  size_t starts = 0;
  const json_t *list = d->doc ? json_object_get(d->doc, "starts") : NULL;
  for (size_t i = 0; json_is_array(list) && i < json_array_size(list) && starts < CF_FIT_MAX_STARTS;
       ++i) {
    const json_t *cost = json_object_get(json_array_get(list, i), "cost");
    if (json_is_number(cost))
      start_x[starts] = (double)starts, start_cost[starts++] = json_number_value(cost);
  }
  const json_t *solver = d->doc ? json_object_get(d->doc, "solver") : NULL;
  size_t iterations = json_numbers(json_object_get(solver, "trace"), trace, MAX);
  double best = INFINITY, last = INFINITY;
  for (size_t i = 0; i < iterations; ++i) last = fmin(last, trace[i]);
  for (size_t i = 0; i < starts; ++i) best = fmin(best, start_cost[i]);
  double lo = INFINITY, hi = 0.0;
  for (size_t i = 0; i < starts; ++i) {
    start_cost[i] -= best;
    if (start_cost[i] > 0.0) lo = fmin(lo, start_cost[i]), hi = fmax(hi, start_cost[i]);
  }
  for (size_t i = 0; i < iterations; ++i) {
    trace_x[i] = (double)i;
    trace[i] -= last;
    if (trace[i] > 0.0) lo = fmin(lo, trace[i]), hi = fmax(hi, trace[i]);
  }
  if (!(hi > 0.0)) lo = 1e-3, hi = 1.0;
  if (!(hi > lo)) hi = lo * 10.0;
  svg_plot plot = {0};
  char path[4096];
  cf_status s = report_plot_begin(&plot, dir, &report_plots[4], path, sizeof path, err);
  if (s != CF_OK) return s;
  double span = (double)(starts > iterations ? starts : iterations);
  plot.x0 = 0.0, plot.x1 = span > 1.0 ? span : 1.0, plot.y0 = lo / 2.0, plot.y1 = hi * 2.0;
  plot.log_y = 1;
  svg_axes(&plot, "start (bars) / successful iteration (line)", "cost above the best (sigma^2)");
  svg_bars(&plot, start_x, start_cost, (int)starts, 0.8, "#a0b8e0");
  svg_line(&plot, trace_x, trace, (int)iterations, "#c02020", 2.0, NULL);
  svg_legend(&plot, 0, "#a0b8e0", "starts: above the best start");
  svg_legend(&plot, 1, "#c02020",
             iterations ? "iterations: above the lowest" : "no trace recorded");
  return svg_end(&plot, path, err);
}

static cf_status timing_plot(const report_data *d, const char *dir, cf_error *err) {
  static const char *const names[] = {"load", "choice", "start", "refine", "solve", "statistics"};
  double seconds[6] = {0}, x[6], total = 0.0;
  const json_t *timing = d->doc ? json_object_get(d->doc, "timing") : NULL;
  const json_t *stages = json_object_get(timing, "stages");
  for (int i = 0; i < 6; ++i) {
    const json_t *v = i == 0   ? json_object_get(timing, "load_s")
                      : i == 1 ? json_object_get(timing, "choice_s")
                               : json_object_get(stages, names[i]);
    seconds[i] = json_is_number(v) ? json_number_value(v) : 0.0;
    total = fmax(total, seconds[i]);
    x[i] = i;
  }
  svg_plot plot = {0};
  char path[4096], label[64];
  cf_status s = report_plot_begin(&plot, dir, &report_plots[5], path, sizeof path, err);
  if (s != CF_OK) return s;
  plot.x0 = 0.0, plot.x1 = 6.0, plot.y0 = 0.0, plot.y1 = total > 0.0 ? total * 1.15 : 1.0;
  plot.no_x_ticks = 1;
  svg_axes(&plot, "", "wall time (s)");
  svg_bars(&plot, x, seconds, 6, 0.8, "#7090d0");
  for (int i = 0; i < 6; ++i) {
    snprintf(label, sizeof label, "%s %.2f s", names[i], seconds[i]);
    svg_text(&plot, svg_px(&plot, i + 0.4), plot.top + plot.height + 16 + 12 * (i % 2), "middle",
             label);
  }
  return svg_end(&plot, path, err);
}

cf_status report_write_plots(const report_data *d, const char *dir, cf_error *err) {
  cf_status s = angle_plot(d, d->half_angle, 0, "half-angle (degrees between n and h)", dir, err);
  if (s == CF_OK)
    s = angle_plot(d, d->view_angle, 1, "view angle (degrees between n and v)", dir, err);
  if (s == CF_OK) s = histogram_plot(d, dir, err);
  if (s == CF_OK) s = lobe_plot(d, dir, err);
  if (s == CF_OK) s = convergence_plot(d, dir, err);
  if (s == CF_OK) s = timing_plot(d, dir, err);
  if (s == CF_OK) s = report_response_plot(d, dir, err);
  return s;
}
