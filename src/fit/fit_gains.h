/* Per-image and per-light gains (--fit-exposures, --fit-gains,
 * docs/model.md §5.4): their standard deviations from a fit's
 * covariance, and the check before any fit that the capture can tell them
 * from the material (cf_fit_check_gains, include/clayfit/fit.h). Private
 * to src/fit. */
#ifndef CLAYFIT_FIT_GAINS_H
#define CLAYFIT_FIT_GAINS_H

#include "fit_problem.h"
#include "fit_sample.h"

/* The refusal's threshold: a gain whose predicted standard deviation is
 * above 10 % is not told from the material (issue 17). */
#define FIT_GAIN_SD_MOST 0.10

/* The sd of each image's gain e_k (images; 0 where the exposures are not
 * free) from the covariance of the problem's unknowns (num_unknowns²):
 * e_k sd(log e_k), the last image's log e = −Σ of the others' (their
 * mean log is 0), so its variance is the sum of their covariance. */
void fit_gains_sd(const fit_problem *p, const double *covariance, double *sd);

/* The white balance into r (white_balance, white_balance_sd: 3 × images,
 * allocated; green's 1 ± 0, and red's and blue's 1 ± 0 unless fitted) from
 * the problem's values and the covariance of its unknowns; the last
 * image's variance is the sum of the others' covariance (its log is minus
 * their sum). */
cf_status fit_balance_of(const fit_problem *p, int fitted, const double *covariance,
                         cf_fit_result *r, cf_error *err);

/* The gains per light inside the sums (fit_kind_light free; else nothing)
 * into r (light_count, light_gains, light_gains_sd, light_names:
 * allocated): g_l, g_l sd(log g_l) (the last light's variance the sum of
 * the others' covariance) and each light's cf_capture_light_name. */
cf_status fit_light_gains_of(const fit_problem *p, const double *covariance, cf_fit_result *r,
                             cf_error *err);

/* cf_fit_check_gains on the observations of a budget drawn for the fit
 * (fit_budget_for with these options), before the fit. */
cf_status fit_check_gains(const cf_capture *capture, const cf_fit_options *o,
                          const fit_budget *budget, cf_error *err);

#endif /* CLAYFIT_FIT_GAINS_H */
