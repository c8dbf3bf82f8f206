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
 *   viewer/             the fitted material under the capture's lighting:
 *                       clayfit.png (clayfit's rendering), material.mjs
 *                       (the glsl export), material.js (it as a classic
 *                       script) and three_viewer.js (three.js, rotatable);
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
  const char *fit_path; /* fit.json, named in the report */
  const char *version;  /* clayfit's */
  cf_progress_fn progress;
  void *progress_user;
  const char *capture_path;  /* the capture re-rendered, as opened (NULL: the fit's) */
  const char *capture_check; /* how it was found to be the fit's capture, for
                                report.json (cf_report_compare_captures); NULL: "" */
  const char *viewer_bundle; /* three.js and the material viewer as one classic
                                script (clayfit-report-viewer.js, built beside
                                clayfit), copied into DIR/viewer/; NULL or
                                unreadable: the page says the interactive view
                                is absent, and why */
} cf_report_options;

/* Write the report of `fit` on `capture` into the folder dir, whole or not
 * at all: it is built in DIR.tmp-PID beside dir, then exchanged with dir
 * in one rename (where the file system cannot exchange, the earlier report
 * is moved aside to DIR.old-PID first), and the earlier report removed. A
 * run killed at any point leaves dir with the earlier report or the new
 * one, complete, and at most such a leftover, which the next report into
 * dir removes (only folders of exactly those names whose process is gone).
 * dir is refused as cf_report_check_dir says. Every write is checked;
 * errors name the file and the reason, and leave dir as it was. */
cf_status cf_report_write(const cf_capture *capture, const cf_fit_file *fit, const char *dir,
                          const cf_report_options *options, cf_error *err);

/* CF_OK if dir may receive a report: it does not exist (it is created, with
 * its parents), or it is an empty folder, or an earlier report (report.json
 * of clayfit's, and beside it nothing but index.html, images/ *.png,
 * plots/ *.svg and viewer/ *.png, *.js, *.mjs). Else CF_EINVAL with what is wrong and what to do: a
 * file, a symbolic link, or a folder holding anything else is never replaced. */
cf_status cf_report_check_dir(const char *dir, cf_error *err);

/* CF_OK if `capture` (opened from capture_path) is the same capture as
 * `fit_capture`, the capture the fit was made on (opened from fit_path's
 * capture.path): the same images (count, names, exposures, light counts),
 * the same observations (pixels), the same lights (each observation's light
 * directions and irradiances: the lights' directions, intensities and
 * positions), the same colours (each observation's RGB and clip flags: what
 * the colour block makes of the photos) and the same noise model and
 * radiometry. Else CF_EINVAL naming the first difference. Values agree
 * within a relative 1e-6. */
cf_status cf_report_compare_captures(const cf_capture *capture, const char *capture_path,
                                     const cf_capture *fit_capture, const char *fit_capture_path,
                                     cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_REPORT_H */
