/* The report's plot of a fitted camera response curve (report_internal.h):
 * the linear value x = R⁻¹(y) against the decoded photo value y, with its
 * band of ±2 sd from the slopes' covariance (clayfit/response_model.h),
 * beside the identity (a linear camera). Only when the response was fitted. */
#include <math.h>
#include <stdio.h>

#include "clayfit/response_model.h"
#include "report_internal.h"
#include "svg.h"

const report_plot report_response_plot_info = {
    "response", "The camera response recovered (unknown tone curve)", "plots/response.svg"};

enum { SAMPLES = 129 };

cf_status report_response_plot(const report_data *d, const char *dir, cf_error *err) {
  const cf_fit_result *r = &d->fit->result;
  if (!r->response_fitted) return CF_OK;
  double y[SAMPLES], x[SAMPLES], lower[SAMPLES], upper[SAMPLES], ends[2] = {0.0, 1.0};
  for (int i = 0; i < SAMPLES; ++i) {
    y[i] = (i + 1.0) / SAMPLES, x[i] = 0.0;
    double sd_log;
    x[i] = cf_response_model_inverse(r->response, r->response_covariance, y[i], &sd_log);
    lower[i] = x[i] * exp(-2.0 * sd_log), upper[i] = x[i] * exp(2.0 * sd_log);
  }
  double top = 1.0;
  for (int i = 0; i < SAMPLES; ++i) top = fmax(top, fmin(upper[i], 4.0));
  svg_plot plot = {0};
  char path[4096];
  cf_status s = report_plot_begin(&plot, dir, &report_response_plot_info, path, sizeof path, err);
  if (s != CF_OK) return s;
  plot.x0 = 0.0, plot.x1 = 1.0, plot.y0 = 0.0, plot.y1 = top;
  svg_axes(&plot, "decoded photo value y (the declared curve's linear value; 1: the top code)",
           "relative radiance x = R^-1(y)");
  svg_line(&plot, ends, ends, 2, "#888888", 1.0, "4 3");
  svg_line(&plot, y, lower, SAMPLES, "#d08000", 1.0, NULL);
  svg_line(&plot, y, upper, SAMPLES, "#d08000", 1.0, NULL);
  svg_line(&plot, y, x, SAMPLES, "#1040c0", 2.0, NULL);
  svg_legend(&plot, 0, "#1040c0", "fitted: x = R^-1(y)");
  svg_legend(&plot, 1, "#d08000", "+/- 2 sd (the slopes' covariance)");
  svg_legend(&plot, 2, "#888888", "identity (declared curve right)");
  return svg_end(&plot, path, err);
}
