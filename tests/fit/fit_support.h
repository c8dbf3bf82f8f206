/* What the fit's tests share: small synthetic captures written to a
 * temporary folder and loaded, and the error of a fitted value. */
#ifndef CLAYFIT_TEST_FIT_SUPPORT_H
#define CLAYFIT_TEST_FIT_SUPPORT_H

#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "clayfit/image.h"
#include "clayfit/synth.h"

/* A small capture of `model` at `params`: 8 images of 240 × 180 (focal
 * 290 px: the sphere about 120 px across), float EXR, one sample per pixel
 * (the fit's own footprint), the default noise, seed 1. */
void fit_test_synth_options(cf_synth_options *o, cf_model_id model, const double *params);

/* The fit's default options for a capture rendered with `supersample`
 * samples per pixel side, integrating the pixel footprint the same way:
 * pixel centres for 1 (the default capture above), S × S samples for S. */
void fit_test_fit_options(cf_fit_options *o, cf_model_id model, int supersample);

/* A fresh temporary folder (the path is written into dir, at least 64
 * bytes), and its removal. */
int fit_test_make_dir(char *dir, size_t size);
void fit_test_remove_dir(const char *dir);

/* Render `o` into dir/name and load it; NULL (and a failed CHECK) on an
 * error. */
cf_capture *fit_test_capture(const char *dir, const char *name, const cf_synth_options *o);

/* The steps of fit_test_capture, for captures edited in between: render
 * into dir/name (folder receives the path; 0 on an error, CHECKed), and
 * load folder/capture.json. */
int fit_test_render(const char *dir, const char *name, const cf_synth_options *o, char *folder,
                    size_t size);
cf_capture *fit_test_load(const char *folder);

/* Rewrite folder/sub/NNN.exr for every image k < images: edit(image, k,
 * user) between reading and writing (bits: 32 for images, 16 for masks).
 * 0 on an error (CHECKed). */
typedef void (*fit_test_image_edit)(cf_image *image, int k, void *user);
int fit_test_edit_images(const char *folder, const char *sub, int images, int bits,
                         fit_test_image_edit edit, void *user);

/* Replace the first `from` in folder/file by `to`; 0 (CHECKed) if absent. */
int fit_test_edit_text(const char *folder, const char *file, const char *from, const char *to);

#endif /* CLAYFIT_TEST_FIT_SUPPORT_H */
