/* JPEG's coding error, modelled (docs/model.md §6.2, "JPEG's coding"):
 * what the codec makes of the fitted prediction, so that the fit compares
 * the photos with the prediction as the camera's JPEG would have coded it.
 * Private to src/fit. */
#ifndef CLAYFIT_FIT_JPEG_H
#define CLAYFIT_FIT_JPEG_H

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "fit_problem.h"

/* Noise draws per image, in antithetic pairs: the codec's error on the
 * prediction is averaged over this many draws of the noise model (its
 * rounding depends on the noise it codes). 8 draws gave the same 2-sd
 * coverage as 4 on 12 synthetic JPEG captures (86 and 89 %) at twice the
 * cost. */
#define FIT_JPEG_DRAWS 4

/* Does the capture hold a JPEG whose coding is known (its quality read
 * from its tables)? */
int fit_jpeg_modelled(const cf_capture *capture);

/* For every JPEG image whose coding is known: the photo with the sphere's
 * observed pixels replaced by p's prediction at its current values (plus
 * a draw of the noise model), coded and decoded as the file was
 * (cf_image_jpeg_roundtrip at its quality and subsampling), FIT_JPEG_DRAWS
 * times; the mean change at each observed pixel is the codec's expected
 * error there, b. p's measurements become decode(stored − b) (a clipped
 * channel's stay), so the fit that follows compares the photos less the
 * codec's error with the prediction. The measurements are replaced from
 * the originals each call (b is not added up over calls). r receives the
 * correction's size (jpeg_images, jpeg_bias_rms, jpeg_bias_mean, in
 * stored codes of 1/255). */
cf_status fit_jpeg_correct(fit_problem *p, const cf_capture *capture, const cf_fit_options *o,
                           cf_fit_result *r, cf_error *err);

#endif /* CLAYFIT_FIT_JPEG_H */
