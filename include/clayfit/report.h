/* clayfit: the residual report of a fit (clayfit report FIT.json -o DIR).
 *
 * What it writes into DIR:
 *   index.html          a self-contained page (works offline; the images
 *                       and plots beside it): the parameter table with
 *                       uncertainties and the "not constrained" list, the
 *                       model-choice table, the plots, the fit's speed,
 *                       and for every image its photo, the re-rendering
 *                       with the fitted parameters and a signed residual
 *                       heat map with its colour scale, side by side;
 *   report.json         what the page shows, as data
 *                       (data_schema/report.schema.json);
 *   images/NNN_photo.png, NNN_render.png, NNN_residual.png
 *                       each image's crop around the sphere, 8-bit sRGB
 *                       (written through OpenImageIO);
 *   plots/NAME.svg      residual against half-angle and against view
 *                       angle, the residual histogram, the fitted lobe in
 *                       the plane of incidence for three light angles, the
 *                       multi-start and solver costs, the stages' times.
 *
 * Residuals are shown in units of the noise σ (the capture's noise model
 * at the prediction, or the fit's estimated σ): r_c = (prediction −
 * measurement) / σ per channel, combined over the m channels that are not
 * censored as Σ r_c / √m, so that noise alone gives N(0, 1). */
#ifndef CLAYFIT_REPORT_H
#define CLAYFIT_REPORT_H

#include "clayfit/capture.h"
#include "clayfit/fit_file.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The heat map's colour scale: ±CF_REPORT_SIGMA_RANGE σ from blue through
 * white to red (a display range: larger residuals show at its ends and are
 * counted in report.json). */
#define CF_REPORT_SIGMA_RANGE 5.0

typedef struct cf_report_options {
  const char *fit_path; /* fit.json, named in the report and read for the
                           model choice, the solver and the timings */
  const char *version;  /* clayfit's */
  cf_progress_fn progress;
  void *progress_user;
} cf_report_options;

/* Write the report of `fit` (read from options->fit_path) on its capture
 * into dir (created). Errors name the file. */
cf_status cf_report_write(const cf_capture *capture, const cf_fit_file *fit, const char *dir,
                          const cf_report_options *options, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_REPORT_H */
