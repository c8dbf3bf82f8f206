/* The sphere found from the photos: its silhouette in each image (OpenCV),
 * then its centre and radius from all views by least squares. Capture's
 * interface to the layers above (src/capture/include), for the chrome
 * ball's outline (chrome_ball.h).
 *
 * Pixel coordinates here are COLMAP's continuous ones: pixel (x, y) of a
 * cf_image (column x, row y, top row first) covers [x, x+1) × [y, y+1) and
 * has its centre at (x + 0.5, y + 0.5). (OpenCV puts pixel centres at
 * integers; sphere_detect.cpp converts.) */
#ifndef CLAYFIT_CAPTURE_SPHERE_SILHOUETTE_H
#define CLAYFIT_CAPTURE_SPHERE_SILHOUETTE_H

#include <stddef.h>

#include "clayfit/image.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* An ellipse in COLMAP's continuous pixel coordinates. */
typedef struct cf_ellipse {
  double cx, cy; /* centre */
  double a, b;   /* semi-axes, a >= b > 0, pixels */
  double angle;  /* of the a axis from +x toward +y, radians, in (−π/2, π/2] */
} cf_ellipse;

/* Where to look. All optional (0 / NULL = unknown). */
typedef struct cf_silhouette_hint {
  const cf_image *mask; /* non-zero = sphere (first channel), same size as the image */
  double center[2];     /* expected centre, pixels; valid if radius > 0 */
  double radius;        /* expected radius, pixels */
} cf_silhouette_hint;

/* Detect the sphere's silhouette in one image (linear RGB or grey): with a
 * mask, the ellipse fitted to the mask's largest outer contour; without,
 * the most significant circle of the image's edges (cv::HoughCircles on a
 * smoothed 8-bit rendition, re-ranked), refined by fitting an ellipse to
 * the edge points near it. `boundary` receives up to max_points points of the
 * silhouette (x, y pairs, pixels) on which the ellipse was fitted, and
 * *num_points their count. CF_ENOTFOUND when there is no plausible sphere
 * (message says why). `name` is for messages.
 *
 * Details:
 * - image: channels 1..4; the grey level is the mean of the first three
 *   channels (the first channel for 1 or 2 channels). Non-finite values
 *   count as 0. `image` may be NULL when the hint has a mask.
 * - hint may be NULL. With a mask (same size as the image, else CF_EINVAL)
 *   the image's pixels are not looked at. The mask's boundary points are
 *   the midpoints of the pixel edges between the largest component (holes
 *   filled) and the outside, so a mask drawn by "pixel centre inside"
 *   gives an unbiased ellipse. CF_ENOTFOUND if the mask is empty or its
 *   largest component is too small (under 5 boundary points).
 * - Without a mask and with hint->radius > 0, circles are looked for with
 *   radius in [0.7, 1.4] × hint->radius and centre within 0.6 ×
 *   hint->radius of hint->center; without a hint, radius in
 *   [max(4, min(w, h)/50), min(w, h)/2] anywhere (the sphere must be wholly in
 *   the image).
 * - Without a mask the boundary points are sub-pixel edge points (maxima
 *   of the gradient magnitude of the blurred linear grey along its
 *   gradient, Devernay 1995) kept by an iterative outlier rejection; the
 *   edge of a shaded sphere may sit a few tenths of a pixel inside the
 *   true outline where the shading rises steeply from the limb. Where the
 *   limb is a dark band against a brighter background, the band's outer
 *   edge is taken for the outline, not its inner one (often the stronger
 *   in sRGB), if it is at most max(3 px, 0.03 r) further out and at least
 *   half as strong. A
 *   detection is refused (CF_ENOTFOUND, saying which check failed) when
 *   its points cover less than 35% of the outline's directions, or not
 *   10 binomial standard deviations more of them than outlines a few px
 *   inside and outside it do (clutter), or fit it with an RMS over 0.35 ×
 *   max(2, r/50) px, or are not 3 times as strong as the image's median
 *   gradient, or it is an ellipse with b < a/2.
 * - Images wider or taller than 1200 px are searched for circles at a
 *   reduced size; the refinement is at full size.
 * - boundary may be NULL when max_points is 0; num_points may be NULL.
 *   The points are sorted by their angle around the ellipse's centre
 *   (atan2(y − cy, x − cx), from −π);
 *   when there are more than max_points, an evenly spaced subset of them
 *   is returned.
 * - CF_EINVAL: no image and no mask, an image or mask without pixels or
 *   with channels outside 1..4, a mask of another size, ellipse NULL.
 *   OpenCV's exceptions become CF_ENUMERIC (CF_ENOMEM for bad_alloc). */
cf_status cf_detect_sphere_silhouette(const cf_image *image, const cf_silhouette_hint *hint,
                                      const char *name, cf_ellipse *ellipse, double *boundary,
                                      size_t max_points, size_t *num_points, cf_error *err);

/* The unit normal of a sphere whose outline is `circle` (radius r = (a +
 * b) / 2; the angle is ignored) at pixel coordinates (x, y) of an
 * orthographic view looking down −z with x right and y up (DiLiGenT's
 * frame; image rows grow downward):
 *   nx = (x − cx)/r,  ny = −(y − cy)/r,  nz = sqrt(1 − nx² − ny²).
 * Returns 1 and fills n inside or on the circle, 0 (n untouched) outside
 * it or if the circle is not valid (r <= 0 or not finite). */
int cf_sphere_normal_orthographic(const cf_ellipse *circle, double x, double y, double n[3]);

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
  double rms_px; /* RMS over all rays of the angle between the ray and the
                    sphere's tangent cone, times focal_px */
  double max_px; /* largest such error */
  int iterations;
} cf_sphere_fit;

/* Least squares over all rays of (distance(center, ray) − radius), by
 * Levenberg-Marquardt through the least-squares layer (src/lsq, Ceres)
 * from a closed-form start (the point nearest to the views' central rays
 * and the mean angular radius). Needs
 * at least 2 views with 5 rays each; CF_ENUMERIC if the views do not
 * constrain the sphere (for example, all centres on one line with it).
 *
 * CF_EINVAL: fewer than 2 views, a view with fewer than 5 rays, a
 * non-finite or zero ray or origin, focal_px not positive. CF_ENUMERIC: a
 * view whose rays all point one way (no outline); central rays that are
 * parallel or coincide, so that the closed-form start is undefined (views
 * from one line through the sphere: cf_sphere_refine_silhouettes from a
 * start of your own may still solve it); a normal matrix too
 * ill-conditioned (reciprocal condition number under 1e-12) at the start
 * or the solution; a fitted sphere that contains a camera; no convergence
 * in 200 iterations. Rays are normalised before use. Each ray is a line
 * here (its sign is ignored). Residuals are distances, so far views weigh
 * more per radian than near ones; rms_px and max_px are angles. */
cf_status cf_sphere_from_silhouettes(const cf_silhouette_view *views, size_t num_views,
                                     cf_sphere_fit *fit, cf_error *err);

/* The same least squares from a given start (center0, radius0 > 0)
 * instead of the closed-form one; same errors. */
cf_status cf_sphere_refine_silhouettes(const cf_silhouette_view *views, size_t num_views,
                                       const double center0[3], double radius0, cf_sphere_fit *fit,
                                       cf_error *err);

/* The angle between the line of `ray` (any length; its sign is ignored)
 * from view->origin and the tangent cone of the sphere `fit` from there,
 * times view->focal_px: how far, in pixels, the ray is off the sphere's
 * outline (the error rms_px and max_px sum up). */
double cf_sphere_ray_error_px(const cf_silhouette_view *view, const double ray[3],
                              const cf_sphere_fit *fit);

/* The least squares of cf_sphere_from_silhouettes made robust to parts of
 * an outline that are not the sphere's (its shadow on the background where
 * the limb is dark, clutter): after a first fit, keep each view's rays
 * within max(min_px, 2.5 × the median) of the fitted sphere's tangent cone
 * (in pixels), drop views left with fewer than 5, refit from the current
 * solution, and repeat until the kept rays no longer change (at most 20
 * rounds). fit->rms_px and max_px are over the kept rays; *kept (may be
 * NULL) their fraction of all rays. Same errors as the plain fit, and
 * CF_ENUMERIC if fewer than 2 views keep 5 rays. */
cf_status cf_sphere_from_silhouettes_robust(const cf_silhouette_view *views, size_t num_views,
                                            double min_px, cf_sphere_fit *fit, double *kept,
                                            cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_CAPTURE_SPHERE_SILHOUETTE_H */
