/* Cameras of a capture: every image matched to its COLMAP pose and camera
 * (or to the orthographic camera), its size checked, its exposure found. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

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
  double t = info->exposure_time, iso = info->iso, n = info->f_number;
  if (!(t > 0.0 && isfinite(t)) || !(iso > 0.0 && isfinite(iso)) || !(n > 0.0 && isfinite(n)))
    return cf_error_set(err, CF_ENOTFOUND,
                        "%s: colour.exposure is \"exif\" but the image's EXIF lacks a positive "
                        "%s (exposure time %g s, ISO %g, f-number %g)",
                        spec->image_paths[k],
                        !(t > 0.0 && isfinite(t))       ? "exposure time"
                        : !(iso > 0.0 && isfinite(iso)) ? "ISO"
                                                        : "f-number",
                        t, iso, n);
  *exposure = t * iso / (n * n);
  return CF_OK;
}
