/* A light probe from a photo of a chrome (mirror) ball: exposure brackets
 * merged to radiance, and the ball unwrapped into the equirectangular
 * environment map that a capture's `environment` light reads
 * (src/capture/envmap.h, docs/lights.md "Light probe"). Capture's
 * interface to the layers above (src/capture/include): the CLI is its user.
 *
 * Frames: the ball's photo is orthographic, looking down −z, with x right,
 * y up and z toward the camera (DiLiGenT's frame): the view direction is
 * v = (0, 0, 1) for every pixel, and image rows grow downward. The map's
 * frame is that frame (a capture's `rotation` of identity). Pixel
 * coordinates are COLMAP's continuous ones: pixel (x, y) has its centre at
 * (x + 0.5, y + 0.5). */
#ifndef CLAYFIT_CAPTURE_LIGHT_PROBE_H
#define CLAYFIT_CAPTURE_LIGHT_PROBE_H

#include <stddef.h>

#include "clayfit/image.h"
#include "clayfit/status.h"

/* ---- exposure brackets merged to radiance ---- */

/* How the brackets' stored values are read. Stored codes s are in [0, 1]
 * (cf_image_read's scaling); a channel with s >= saturated is clipped, one
 * with s <= dark is below the noise: both are dropped. */
typedef struct cf_bracket_options {
  cf_transfer transfer; /* the brackets' tone curve (known, declared) */
  double gamma;         /* for CF_TRANSFER_GAMMA, > 0 */
  double dark;          /* in [0, saturated) */
  double saturated;     /* in (dark, 1] */
} cf_bracket_options;

enum { CF_MAX_BRACKETS = 64 };

typedef struct cf_bracket_report {
  size_t saturated_everywhere; /* pixels with a channel clipped in every bracket */
  size_t dark_everywhere;      /* pixels with a channel dark in every bracket */
  /* measured_ratio[k]: bracket k+1's decoded value over bracket k's, the
   * median over the channels whose codes are in [0.1, 0.9] in both (NaN
   * with fewer than CF_BRACKET_MIN_SAMPLES of them: not checked); the
   * declared ratio is exposures[k+1] / exposures[k] */
  double measured_ratio[CF_MAX_BRACKETS - 1];
  size_t ratio_samples[CF_MAX_BRACKETS - 1];
} cf_bracket_report;

/* The exposures check: at least this many samples, and a measured ratio
 * within this factor of the declared one. Camera shutter speeds are nominal
 * (1/60 s is 1/64 s on a ×2 ladder: 6 %); one stop (×2) misplaced, a bracket
 * missing from a ladder of ×2 or more, or brackets out of order are all
 * beyond it. */
#define CF_BRACKET_MIN_SAMPLES 100
#define CF_BRACKET_RATIO_TOLERANCE 1.5

/* The range of an exposure (seconds or any relative unit). Cameras expose
 * from 1/32000 s to hours (3e-5 to 1e4 s); a relative unit widens that.
 * Within it, every 8- or 16-bit code over its exposure (1/65535 to 1e9)
 * stays far inside a float's normal range (1.2e-38 to 3.4e38): 1e306 made
 * every radiance 0. */
#define CF_BRACKET_MIN_EXPOSURE 1e-9
#define CF_BRACKET_MAX_EXPOSURE 1e9

/* Merge `count` brackets (1..64) of one scene, exposures[k] in
 * [CF_BRACKET_MIN_EXPOSURE, CF_BRACKET_MAX_EXPOSURE] strictly increasing (seconds or any relative
 * unit; the radiance is per that unit), into a 3-channel linear radiance image (Debevec & Malik
 * 1997, eq. 6, with their response known rather than recovered): E = Σ_k w(s_k) f⁻¹(s_k) / t_k  /
 * Σ_k w(s_k)   per channel, w(s) = min(s − dark, saturated − s)  (their hat, on the stored code),
 * brackets whose code is dropped weighing 0. A channel clipped in every
 * bracket gets f⁻¹(saturated) / t_min (a lower bound), one dark in every
 * bracket f⁻¹(s) / t_max of its longest bracket; both are counted in
 * *report (may be NULL) for the caller to warn. Brackets of 1 or 2
 * channels are grey. `names` (may be NULL) name the brackets in messages.
 * CF_EINVAL: a count, exposure or option out of range, exposures not
 * increasing (or equal), brackets of different sizes, a bracket with a
 * non-finite value, and adjacent brackets whose measured ratio is more
 * than CF_BRACKET_RATIO_TOLERANCE from the declared one (the wrong order,
 * a bracket missing, a wrong exposure or tone curve). *radiance is
 * allocated (cf_image_free). */
cf_status cf_brackets_merge(const cf_image *brackets, const double *exposures, int count,
                            const char *const *names, const cf_bracket_options *options,
                            cf_image *radiance, cf_bracket_report *report, cf_error *err);

/* ---- the ball unwrapped into an equirectangular map ---- */

typedef struct cf_probe_ball {
  double cx, cy, radius; /* the ball's outline in the photo, pixels */
} cf_probe_ball;

/* The least reflectance of a mirror ball: below black glass's 0.04 (chrome
 * reflects about 0.6). 1e-300 made 126,232 texels per channel infinite. */
#define CF_PROBE_MIN_REFLECTANCE 0.01

typedef struct cf_probe_options {
  int width;            /* map width, even, 8..16384; the height is width / 2 */
  double margin_px;     /* the outline's band not used, >= 0 (edge pixels mix ball
                           and background) */
  double reflectance;   /* chrome's reflectance, one constant in
                           [CF_PROBE_MIN_REFLECTANCE, 1]: the map is the
                           reflection divided by it (Fresnel ignored) */
  const cf_image *mask; /* optional, the photo's size: non-zero = ball; every
                           bilinear tap must be on it */
} cf_probe_options;

typedef struct cf_probe_report {
  double invalid_fraction; /* of the sphere's solid angle with alpha 0 (Σ (1 − α) dω / 4π) */
  double max_reflection_deg; /* the largest angle from v observed; the cap
                                beyond it, around −v, is not */
  int supersample;           /* S: S × S directions averaged per map pixel */
} cf_probe_report;

/* The direction d (map frame) of a mirror ball's point seen at normal n
 * (n_z >= 0) from v = (0, 0, 1): d = 2 (n·v) n − v. */
void cf_probe_reflect(const double n[3], double d[3]);

/* Pixel coordinates (x, y), continuous, of the map direction d (unit) in a
 * W × H equirectangular map: the inverse of cf_envmap_direction. */
void cf_envmap_pixel(int width, int height, const double d[3], double *x, double *y);

/* Unwrap the ball of `photo` (linear radiance, 1..4 channels; grey for 1
 * or 2) into an RGBA map (width × width/2, cf_envmap_direction's
 * convention): each map pixel averages S × S directions d inside it, and
 * each d is read where the ball reflects the view ray into d, at normal
 * n = (d + v)/|d + v|, pixel (cx + r n_x, cy − r n_y), by bilinear
 * interpolation. S = clamp(ceil(π r / (2 H)), 1, 8): the map's row spacing
 * π/H over the ball's central pixel spacing 2/r (reflection doubles
 * angles), so no photo pixel is skipped. A direction is observable when its
 * ball point is at most r − margin_px from the centre (and, with a mask,
 * its four taps are on the mask): alpha is the observable share of the
 * pixel's S × S directions and RGB their mean; unobservable pixels (the
 * cap around −v, behind the ball) are RGB 0, alpha 0 — the `environment`
 * light ignores alpha, so it sees no light from there. CF_EINVAL: bad
 * options, a ball not wholly inside the photo, a mask of another size, a
 * non-finite photo value, no observable direction, and a map that is no
 * usable light: a texel not finite (the photo's radiance over the
 * reflectance beyond a float's range) or every texel below a float's
 * smallest normal value (FLT_MIN: a black ball). */
cf_status cf_probe_unwrap(const cf_image *photo, const cf_probe_ball *ball,
                          const cf_probe_options *options, cf_image *map, cf_probe_report *report,
                          cf_error *err);

#endif /* CLAYFIT_CAPTURE_LIGHT_PROBE_H */
