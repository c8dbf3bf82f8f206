/* clayfit: a fitted material as a thumbnail, the sphere under the standard
 * light (docs/report.md, "The gallery and thumbnails"), for the material
 * library's gallery and for comparing two entries.
 *
 * The scene, fixed so that thumbnails of different materials compare:
 *   - an orthographic camera looking down −z at a sphere centred in an
 *     N × N image; the camera frame has x right, y up, z toward the camera,
 *     so every pixel sees along v = (0, 0, 1);
 *   - two white directional lights (CF_SPHERE_LIGHTS), the key from the
 *     upper left, in front, l = (−4, 4, 7)/9, irradiance 0.8π, and a fill
 *     from the right, a little below, l = (6, −2, 3)/7, irradiance 0.2π (a
 *     quarter of the key: two stops under). The fill does not reach the
 *     point that faces the key (l_key·l_fill = −11/63), so an albedo-1
 *     Lambertian sphere renders there at exactly 0.8 (linear);
 *   - a neutral background of a fixed linear colour (the view's).
 * The linear render is the radiance L = Σ_lights f(n, l, v) E max(0, n·l)
 * per linear-RGB channel, with the fitted BRDF f through the C evaluator
 * (cf_eval_batch). The fit's global scale and exposures (a property of the
 * capture's radiometry, not of the material) are not applied.
 *
 * A pixel is the mean over its footprint: pixels that the silhouette
 * crosses are sampled edge_samples × edge_samples (samples off the sphere
 * take the background); a highlight narrower than a pixel is integrated as
 * the fit integrates it (cf_footprint_samples, the Gauss-Legendre pairs of
 * docs/model.md §5.6); elsewhere a pixel is its centre's value.
 *
 * For display (cf_sphere_write_png) the linear values go through a fixed
 * tone curve: unchanged up to the knee 0.8, above it compressed smoothly
 * toward 1 (0.8 + 0.2 (1 − exp(−(x − 0.8)/0.2)), slope 1 at the knee), then
 * the sRGB transfer curve, 8 bits. */
#ifndef CLAYFIT_THUMBNAIL_H
#define CLAYFIT_THUMBNAIL_H

#include "clayfit/fit.h"
#include "clayfit/image.h"
#include "clayfit/model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The standard light: directions (unit, camera frame) and irradiances. */
typedef struct cf_sphere_light {
  double direction[3];
  double irradiance;
} cf_sphere_light;

enum { CF_SPHERE_LIGHT_COUNT = 2 };

/* The key and the fill, in that order (a table of CF_SPHERE_LIGHT_COUNT). */
const cf_sphere_light *cf_sphere_lights(void);

/* The display curve's knee: linear values up to it are shown as they are
 * (an albedo-1 Lambertian sphere facing the key). */
#define CF_SPHERE_KNEE 0.8

enum { CF_SPHERE_MAX_SIZE = 4096, CF_SPHERE_MAX_SAMPLES = 16, CF_SPHERE_MAX_LIGHTS = 32 };

typedef struct cf_sphere_view {
  int size;             /* pixels per side, 1..CF_SPHERE_MAX_SIZE */
  double radius;        /* the sphere's radius over half the image's side, (0, 1] */
  double background[3]; /* linear RGB, finite */
  int edge_samples;     /* per side, on pixels the silhouette crosses, 1..CF_SPHERE_MAX_SAMPLES */
  double footprint_tolerance; /* of the highlight's integration (cf_footprint_samples);
                                 0: pixel centres only */
  int footprint_max;          /* samples per side at most there, 1..CF_SPHERE_MAX_SAMPLES */
  /* Other lights than the standard (the report's view of the material under
   * a capture's lighting): light_count 0..CF_SPHERE_MAX_LIGHTS directional
   * lights, light_count × 3 unit directions (camera frame) and linear RGB
   * irradiances, finite and >= 0. 0: the standard light. */
  int light_count;
  const double *light_direction, *light_irradiance;
} cf_sphere_view;

/* The gallery's view: 256 pixels, radius 0.92, background 0.18 (middle
 * grey), 3 × 3 samples at the silhouette, tolerance 2e-3, at most 8; the
 * standard light. */
void cf_sphere_view_default(cf_sphere_view *view);

/* Render `model` at `params` (model dim entries, within their ranges:
 * cf_params_check) into out: a new size × size image of 3 channels, linear
 * (free it with cf_image_free). CF_EINVAL (out empty) for an unknown model,
 * parameters out of range or not finite, or a view outside the ranges
 * above; CF_ENOMEM. */
cf_status cf_sphere_render(cf_model_id model, const double *params, const cf_sphere_view *view,
                           cf_image *out, cf_error *err);

/* cf_sphere_render of a fit's model and parameters (result->model,
 * result->params). view NULL: cf_sphere_view_default. */
cf_status cf_report_render_sphere(const cf_fit_result *result, const cf_sphere_view *view,
                                  cf_image *out, cf_error *err);

/* The display value (0..1, before the sRGB curve) of a linear value: the
 * tone curve above; 0 for a negative value or NaN. */
double cf_sphere_tone(double linear);

/* Write a linear render (3 channels) as an 8-bit sRGB PNG through the tone
 * curve, whole or not at all: into PATH.tmp-PID.png beside it, renamed into
 * place; on an error the temporary is removed and path left as it was.
 * CF_EINVAL for an empty image; CF_EIO naming the file and the reason. */
cf_status cf_sphere_write_png(const cf_image *linear, const char *path, cf_error *err);

/* Render a fit's thumbnail and write it (cf_report_render_sphere, then
 * cf_sphere_write_png). view NULL: the default. */
cf_status cf_report_write_thumbnail(const cf_fit_result *result, const cf_sphere_view *view,
                                    const char *path, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_THUMBNAIL_H */
