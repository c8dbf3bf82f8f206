/* Cameras of a capture: every image matched to its COLMAP pose and camera
 * (or to the orthographic camera), its size checked, its exposure found. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"
#include "capture_internal.h"
#include "core/file.h"

/* The focal length in pixels near the image centre, measured from the
 * projection itself so that it holds for every camera model: the pixel
 * displacement per unit of normalised image coordinate along x and y. */
static double mean_focal_px(const cf_camera *camera) {
  const double h = 1e-6;
  double px[3] = {h, 0.0, 1.0}, mx[3] = {-h, 0.0, 1.0};
  double py[3] = {0.0, h, 1.0}, my[3] = {0.0, -h, 1.0};
  double a[2], b[2], c[2], d[2];
  if (!cf_camera_project(camera, px, a) || !cf_camera_project(camera, mx, b) ||
      !cf_camera_project(camera, py, c) || !cf_camera_project(camera, my, d))
    return camera->params[0];
  return 0.25 * ((a[0] - b[0]) + (c[1] - d[1])) / h;
}

static cf_status load_colmap_views(cf_capture *capture, cf_error *err) {
  cf_capture_spec *spec = &capture->spec;
  cf_status s = cf_colmap_read(spec->colmap_model, 0, &capture->colmap, err);
  if (s != CF_OK) {
    cf_error_prefix(err, "%s: camera.model", spec->path);
    return s;
  }
  for (size_t k = 0; k < spec->num_images; ++k) {
    const cf_colmap_image *image =
        cf_colmap_find_image_by_name(&capture->colmap, spec->image_names[k]);
    if (!image) {
      const char *first = capture->colmap.num_images ? capture->colmap.images[0].name : "(none)";
      char hidden[160];
      cf_path_hidden_characters(spec->image_names[k], hidden, sizeof hidden);
      return cf_error_set(err, CF_ENOTFOUND,
                          "%s: image '%s'%s is not in the COLMAP model %s (%zu images there, "
                          "the first named '%s'); give the names as the model does",
                          spec->path, spec->image_names[k], hidden, spec->colmap_model,
                          capture->colmap.num_images, first);
    }
    capture_view *view = &capture->views[k];
    view->camera = cf_colmap_find_camera(&capture->colmap, image->camera_id);
    cf_quaternion_to_matrix(image->qvec, view->r);
    memcpy(view->t, image->tvec, sizeof view->t);
    cf_colmap_image_center(image, view->c);
    memcpy(capture->images[k].center, view->c, sizeof view->c);
    view->focal_px = mean_focal_px(view->camera);
  }
  return CF_OK;
}

cf_status capture_load_views(cf_capture *capture, cf_error *err) {
  cf_capture_spec *spec = &capture->spec;
  for (size_t k = 0; k < spec->num_images; ++k) {
    capture->images[k].name = spec->image_names[k];
    capture->images[k].path = spec->image_paths[k];
  }
  if (spec->camera == CF_CAMERA_KIND_COLMAP) return load_colmap_views(capture, err);
  for (size_t k = 0; k < spec->num_images; ++k) capture->views[k].focal_px = 1.0;
  return CF_OK;
}

cf_status capture_check_size(cf_capture *capture, size_t k, const cf_image *image, cf_error *err) {
  cf_capture_image *info = &capture->images[k];
  const capture_view *view = &capture->views[k];
  if (view->camera) {
    if ((uint64_t)image->width != view->camera->width ||
        (uint64_t)image->height != view->camera->height)
      return cf_error_set(err, CF_EINVAL,
                          "%s: the image is %d x %d pixels but its COLMAP camera %u is %llu x "
                          "%llu",
                          info->path, image->width, image->height, view->camera->camera_id,
                          (unsigned long long)view->camera->width,
                          (unsigned long long)view->camera->height);
  } else if (k > 0 && (image->width != capture->images[0].width ||
                       image->height != capture->images[0].height)) {
    return cf_error_set(err, CF_EINVAL,
                        "%s: the image is %d x %d pixels but %s is %d x %d; an orthographic "
                        "capture needs images of one size",
                        info->path, image->width, image->height, capture->images[0].path,
                        capture->images[0].width, capture->images[0].height);
  }
  info->width = image->width;
  info->height = image->height;
  return CF_OK;
}

/* What cameras record, per field of an exposure read from EXIF (or an
 * OpenEXR file's attributes): an exposure time from 1/1,000,000 s (beyond
 * the fastest shutters, 1/32,000 s mechanical or electronic) to 1 hour; an
 * ISO from 1 to 10^7 (the highest extended settings reach 4.1 x 10^6); an
 * f-number from 0.5 (the limit of a lens in air, by the Abbe sine
 * condition) to 256 (beyond large-format lenses' f/128). Outside, the field
 * is not a camera's: a fit would take it at its word (4294967295 s put the
 * albedo at its bound, issue 30). */
typedef struct exif_range {
  const char *field;
  unsigned tag;
  float least, most; /* floats, as the fields are read: 1/1,000,000 s is in */
  const char *unit;
} exif_range;
static const exif_range exif_ranges[3] = {{"exposure time", 0x829A, 1e-6f, 3600.0f, " s"},
                                          {"ISO", 0x8827, 1.0f, 1e7f, ""},
                                          {"f-number", 0x829D, 0.5f, 256.0f, ""}};

cf_status capture_raw_exposure(const cf_capture *capture, size_t k, const cf_image_info *info,
                               double *exposure, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  switch (spec->exposure) {
    case CF_EXPOSURE_NONE:
      *exposure = 1.0;
      return CF_OK;
    case CF_EXPOSURE_GIVEN:
      *exposure = spec->exposures[k];
      return CF_OK;
    case CF_EXPOSURE_EXIF:
      break;
  }
  /* exposure ∝ t S / N² (time, ISO sensitivity, f-number) */
  const double values[3] = {info->exposure_time, info->iso, info->f_number};
  for (int i = 0; i < 3; ++i) {
    const exif_range *r = &exif_ranges[i];
    if (!(values[i] > 0.0 && isfinite(values[i])))
      return cf_error_set(err, CF_ENOTFOUND,
                          "%s: colour.exposure is \"exif\" but the image's EXIF lacks a positive "
                          "%s (exposure time %g s, ISO %g, f-number %g)",
                          spec->image_paths[k], r->field, values[0], values[1], values[2]);
    if (values[i] < (double)r->least || values[i] > (double)r->most)
      return cf_error_set(err, CF_EINVAL,
                          "%s: the EXIF %s (tag 0x%04X) is %.10g%s, outside [%g, %g]%s, the range "
                          "cameras record; colour.exposure is \"exif\"",
                          spec->image_paths[k], r->field, r->tag, values[i], r->unit,
                          (double)r->least, (double)r->most, r->unit);
  }
  const double t = values[0], iso = values[1], n = values[2];
  *exposure = t * iso / (n * n);
  return CF_OK;
}

/* The most an image's EXIF exposure may differ from the capture's median,
 * as a factor either way: 2^16, 16 stops, more than a raw sensor's dynamic
 * range (about 14 stops), so no photo that far from the others shares
 * usable pixels with them; it is a wrong EXIF field, which the fit would
 * take at its word. */
#define MOST_EXPOSURE_SPREAD 65536.0

cf_status capture_check_exposure_spread(const cf_capture *capture, cf_error *err) {
  const size_t n = capture->spec.num_images;
  if (n == 0) return CF_OK;
  double *values = malloc(n * sizeof *values);
  if (!values) return cf_error_set(err, CF_ENOMEM, "out of memory for %zu exposures", n);
  memcpy(values, capture->raw_exposures, n * sizeof *values);
  const double median = order_median(values, n);
  free(values);
  for (size_t k = 0; k < n; ++k) {
    const double e = capture->raw_exposures[k];
    const double ratio = e > median ? e / median : median / e;
    if (ratio > MOST_EXPOSURE_SPREAD)
      return cf_error_set(err, CF_EINVAL,
                          "%s: its EXIF exposure (time x ISO / f-number^2) %.6g is %.3g times %s "
                          "the capture's median %.6g; at most 65536 (16 stops, more than a "
                          "sensor's range) is taken as a camera's, so one of its EXIF fields is "
                          "likely wrong (give the exposures in images.exposures, \"exposure\": \"given\", instead)",
                          capture->spec.image_paths[k], e, ratio, e > median ? "above" : "below",
                          median);
  }
  return CF_OK;
}
