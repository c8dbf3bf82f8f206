/* The absolute scale of a capture with relative radiometry from a flat
 * matte target of known albedo (capture file: "reference"): in the
 * target's pixels, the measured radiance (decoded as the observations are,
 * divided by the image's exposure) against the radiance a Lambertian
 * target would have under the capture's lights taken at face value,
 *   L_c = ρ_c/π Σ_j E_jc max(0, n·l_j),
 * with E and l at the point the pixel's ray meets the target's plane (for
 * point lights and a flash; directional lights are the same everywhere).
 * The scale s is the median of measured / predicted over every unclipped
 * pixel and channel (one factor for all lights and channels: that is what
 * relative radiometry leaves unknown). It multiplies every light's
 * intensity and every observation's irradiance, after which the capture's
 * radiometry counts as absolute. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/order_statistics.h"
#include "core/vec.h"

enum { MIN_CF_PIXELS = 16 };

/* The channels' median ratios may disagree by this much (relative to s)
 * before a warning says the albedo given may be wrong. */
static const double channel_tolerance = 0.03;

/* Where pixel (x, y)'s centre ray meets the target's plane, in world
 * coordinates (COLMAP cameras with a point on the plane). */
static cf_status target_point(const cf_capture *capture, size_t k, int x, int y, double out[3],
                              cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  const cf_reference_spec *r = &spec->reference;
  const capture_view *view = &capture->views[k];
  double uv[2] = {x + 0.5, y + 0.5}, ray[3], d[3];
  if (!cf_camera_unproject(view->camera, uv, ray))
    return cf_error_set(err, CF_EINVAL,
                        "%s: reference.region: pixel (%d, %d) of %s has no ray through the "
                        "camera's model",
                        spec->path, x, y, spec->image_names[k]);
  for (int i = 0; i < 3; ++i) /* d_world = Rᵀ d_camera */
    d[i] = view->r[i] * ray[0] + view->r[3 + i] * ray[1] + view->r[6 + i] * ray[2];
  double facing = cf_dot3(r->normal, d);
  double to_plane[3] = {r->point[0] - view->c[0], r->point[1] - view->c[1],
                        r->point[2] - view->c[2]};
  double t = cf_dot3(r->normal, to_plane) / facing;
  if (!(facing < 0.0) || !(t > 0.0) || !isfinite(t))
    return cf_error_set(err, CF_EINVAL,
                        "%s: reference: at pixel (%d, %d) of %s the camera sees %s (normal %g %g "
                        "%g, point %g %g %g)",
                        spec->path, x, y, spec->image_names[k],
                        !(facing < 0.0) ? "the back of the target's plane, or along it: the "
                                          "normal must point toward the camera"
                                        : "no target: its plane is behind the camera",
                        r->normal[0], r->normal[1], r->normal[2], r->point[0], r->point[1],
                        r->point[2]);
  for (int i = 0; i < 3; ++i) out[i] = view->c[i] + t * d[i];
  return CF_OK;
}

/* ρ_c/π Σ_j E_jc max(0, n·l_j) at world point x of image k. */
static void predicted_radiance(const cf_capture *capture, size_t k, const double x[3],
                               double out[3]) {
  const cf_reference_spec *r = &capture->spec.reference;
  const capture_view *view = &capture->views[k];
  const cf_light *lights = capture->lights + k * (size_t)capture->max_lights;
  double sum[3] = {0.0, 0.0, 0.0};
  for (int j = 0; j < capture->light_counts[k]; ++j) {
    double l[3], e[3];
    if (!cf_light_at(&lights[j], view->r, view->c, x, l, e)) continue;
    double cosine = cf_dot3(r->normal, l);
    if (cosine > 0.0)
      for (int c = 0; c < 3; ++c) sum[c] += e[c] * cosine;
  }
  for (int c = 0; c < 3; ++c) out[c] = r->albedo[c] / CF_PI * sum[c];
}

/* Every unclipped pixel's measured / predicted ratios, three per pixel,
 * into ratios (pixel-major); *used pixels, *clipped skipped. */
static cf_status measure(cf_capture *capture, const cf_image *image, const cf_decode *decode,
                         double *ratios, size_t *used, size_t *clipped, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  const cf_reference_spec *r = &spec->reference;
  const size_t k = r->image;
  const int *box = r->region;
  size_t on_sphere = 0;
  *used = *clipped = 0;
  for (int y = box[1]; y < box[3]; ++y) {
    for (int x = box[0]; x < box[2]; ++x) {
      surface_point ignored;
      if (capture_surface_at(capture, k, x, y, &ignored) != SURFACE_MISS) {
        ++on_sphere;
        continue;
      }
      const float *stored =
          image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
      double measured[3], predicted[3], point[3] = {0.0, 0.0, 0.0};
      if (cf_decode_pixel(decode, stored, image->channels, measured)) {
        ++*clipped;
        continue;
      }
      if (r->has_point) {
        cf_status s = target_point(capture, k, x, y, point, err);
        if (s != CF_OK) return s;
      }
      predicted_radiance(capture, k, point, predicted);
      for (int c = 0; c < 3; ++c)
        if (!(predicted[c] > 0.0) || !isfinite(predicted[c]))
          return cf_error_set(err, CF_EINVAL,
                              "%s: reference: no light reaches the target at pixel (%d, %d) of "
                              "%s in channel %d (predicted radiance %g): does its normal (%g %g "
                              "%g) face away from the lights?",
                              spec->path, x, y, spec->image_names[k], c, predicted[c], r->normal[0],
                              r->normal[1], r->normal[2]);
      for (int c = 0; c < 3; ++c) ratios[3 * *used + (size_t)c] = measured[c] / predicted[c];
      ++*used;
    }
  }
  if (on_sphere)
    return cf_error_set(err, CF_EINVAL,
                        "%s: reference.region: %zu of its pixels in %s see the sphere; the "
                        "region must show the reference target only",
                        spec->path, on_sphere, spec->image_names[k]);
  if (*used < MIN_CF_PIXELS)
    return cf_error_set(err, CF_EINVAL,
                        "%s: reference.region: only %zu of its %lld pixels in %s are usable (%zu "
                        "clipped); at least %d are needed",
                        spec->path, *used, (long long)(box[2] - box[0]) * (box[3] - box[1]),
                        spec->image_names[k], *clipped, MIN_CF_PIXELS);
  return CF_OK;
}

/* The scale, its robust spread and the channels' scales from the ratios
 * (reordered). */
static cf_status summarise(cf_capture *capture, double *ratios, size_t used, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  double *channel = malloc(used * sizeof *channel);
  if (!channel) return cf_error_set(err, CF_ENOMEM, "out of memory for the reference");
  for (int c = 0; c < 3; ++c) {
    for (size_t i = 0; i < used; ++i) channel[i] = ratios[3 * i + (size_t)c];
    capture->reference_channel_scales[c] = order_median(channel, used);
  }
  free(channel);
  double s = order_median(ratios, 3 * used);
  if (!(s > 0.0) || !isfinite(s))
    return cf_error_set(err, CF_EINVAL,
                        "%s: reference: the target's measured radiance is not positive (median "
                        "ratio to the prediction %g): is the region on the target, and the black "
                        "level right?",
                        spec->path, s);
  for (size_t i = 0; i < 3 * used; ++i) ratios[i] = fabs(ratios[i] - s);
  capture->reference_scale = s;
  capture->reference_spread = 1.4826 * order_median(ratios, 3 * used) / s;
  capture->reference_pixels = used;
  const double *sc = capture->reference_channel_scales;
  double disagreement = (fmax(sc[0], fmax(sc[1], sc[2])) - fmin(sc[0], fmin(sc[1], sc[2]))) / s;
  if (disagreement > channel_tolerance)
    capture_warn(capture,
                 "%s: reference: the channels' scales disagree by %.3g %% (r %.6g, g %.6g, b "
                 "%.6g; one scale %.6g is used): is the albedo given right?",
                 spec->path, 100.0 * disagreement, sc[0], sc[1], sc[2], s);
  return CF_OK;
}

/* Multiply every light and every observation's irradiance by s. */
static void apply_scale(cf_capture *capture, double s) {
  size_t lights = capture->spec.num_images * (size_t)capture->max_lights;
  for (size_t i = 0; i < lights; ++i)
    for (int c = 0; c < 3; ++c) capture->lights[i].intensity[c] *= s;
  cf_observations *o = &capture->obs;
  size_t values = 3 * o->count * (size_t)o->lights;
  for (size_t i = 0; i < values; ++i) o->irradiance[i] *= s;
  capture->from_reference = 1;
}

cf_status capture_apply_reference(cf_capture *capture, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  const cf_reference_spec *r = &spec->reference;
  const size_t k = r->image;
  const char *path = spec->image_paths[k];
  cf_image image = {0};
  cf_image_info info;
  cf_status s = cf_image_read(path, &image, &info, err);
  if (s == CF_OK) s = cf_image_check_finite(&image, path, err);
  if (s == CF_OK && (r->region[2] > image.width || r->region[3] > image.height))
    s = cf_error_set(err, CF_EINVAL,
                     "%s: reference.region: [%d, %d, %d, %d] reaches outside %s, which is %d x "
                     "%d pixels",
                     spec->path, r->region[0], r->region[1], r->region[2], r->region[3],
                     spec->image_names[k], image.width, image.height);
  size_t pixels = (size_t)(r->region[2] - r->region[0]) * (size_t)(r->region[3] - r->region[1]);
  double *ratios = s == CF_OK ? malloc(3 * pixels * sizeof *ratios) : NULL;
  if (s == CF_OK && !ratios)
    s = cf_error_set(err, CF_ENOMEM, "out of memory for the reference's %zu pixels", pixels);
  size_t used = 0, clipped = 0;
  if (s == CF_OK) {
    /* as the observations: divided by the exposure (after the exif
     * exposures' normalisation) */
    cf_decode decode = capture_image_decode(capture, &info, capture->images[k].exposure);
    s = measure(capture, &image, &decode, ratios, &used, &clipped, err);
  }
  if (s == CF_OK) s = summarise(capture, ratios, used, err);
  if (s == CF_OK) apply_scale(capture, capture->reference_scale);
  free(ratios);
  cf_image_free(&image);
  return s;
}
