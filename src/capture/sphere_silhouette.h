/* The sphere found from the photos: its silhouette in each image (OpenCV),
 * then its centre and radius from all views by least squares. Private to
 * src/capture. */
#ifndef CLAYFIT_CAPTURE_SPHERE_SILHOUETTE_H
#define CLAYFIT_CAPTURE_SPHERE_SILHOUETTE_H

#include <stddef.h>

#include "clayfit/image.h"
#include "clayfit/status.h"

/* An ellipse in COLMAP's continuous pixel coordinates. */
typedef struct cf_ellipse {
  double cx, cy;  /* centre */
  double a, b;    /* semi-axes, a >= b > 0, pixels */
  double angle;   /* of the a axis from +x toward +y, radians */
} cf_ellipse;

/* Where to look. All optional (0 / NULL = unknown). */
typedef struct cf_silhouette_hint {
  const cf_image *mask;   /* non-zero = sphere (first channel), same size as the image */
  double center[2];       /* expected centre, pixels; valid if radius > 0 */
  double radius;          /* expected radius, pixels */
} cf_silhouette_hint;

/* Detect the sphere's silhouette in one image (linear RGB or grey): with a
 * mask, the ellipse fitted to the mask's largest outer contour; without,
 * the strongest circle of the image's edges (cv::HoughCircles on a
 * smoothed 8-bit rendition), refined by fitting an ellipse to the edge
 * points near it. `boundary` receives up to max_points points of the
 * silhouette (x, y pairs, pixels) on which the ellipse was fitted, and
 * *num_points their count. CF_ENOTFOUND when there is no plausible sphere
 * (message says why). `name` is for messages. */
cf_status cf_detect_sphere_silhouette(const cf_image *image, const cf_silhouette_hint *hint,
                                      const char *name, cf_ellipse *ellipse, double *boundary,
                                      size_t max_points, size_t *num_points, cf_error *err);

/* One view of the silhouette: the camera centre and unit rays (world
 * frame) through silhouette points, each tangent to the sphere.
 * focal_px converts angles to pixels for the report. */
typedef struct cf_silhouette_view {
  double origin[3];
  const double *rays; /* 3 × count */
  size_t count;
  double focal_px;
} cf_silhouette_view;

typedef struct cf_sphere_fit {
  double center[3], radius;
  double rms_px;      /* RMS over all rays of the angle between the ray and the
                         sphere's tangent cone, times focal_px */
  double max_px;      /* largest such error */
  int iterations;
} cf_sphere_fit;

/* Least squares over all rays of (distance(center, ray) − radius), by
 * Gauss-Newton/Levenberg-Marquardt from a closed-form start (the point
 * nearest to the views' central rays and the mean angular radius). Needs
 * at least 2 views with 5 rays each; CF_ENUMERIC if the views do not
 * constrain the sphere (for example, all centres on one line with it). */
cf_status cf_sphere_from_silhouettes(const cf_silhouette_view *views, size_t num_views,
                                     cf_sphere_fit *fit, cf_error *err);

#endif /* CLAYFIT_CAPTURE_SPHERE_SILHOUETTE_H */
