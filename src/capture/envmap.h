/* An environment map reduced to K directional lights by median cut
 * (Debevec 2005, "A Median Cut Algorithm for Light Probe Sampling"), for
 * the image formation of docs/model.md §5.2 (an environment map approximated by K
 * directional lights). Private to src/capture. */
#ifndef CLAYFIT_CAPTURE_ENVMAP_H
#define CLAYFIT_CAPTURE_ENVMAP_H

#include <stddef.h>

#include "clayfit/capture.h" /* CF_ENVMAP_MAX_LIGHTS */
#include "clayfit/image.h"
#include "clayfit/status.h"

/* A directional light: the unit direction toward the light (world frame)
 * and its irradiance E per linear-RGB channel, measured perpendicular to
 * the direction (docs/model.md (5): L = f E c_i). */
typedef struct cf_directional_light {
  double direction[3];
  double irradiance[3];
} cf_directional_light;

/* Equirectangular (latitude-longitude) convention of the map's own frame,
 * y up: pixel column x (left to right) and row y (top to bottom) of a W × H
 * map have their centres at u = (x + 0.5)/W, v = (y + 0.5)/H, and
 *   θ = π v          (polar angle from +y: the top row looks up),
 *   φ = 2π u         (azimuth),
 *   d = (−sin θ cos φ, cos θ, −sin θ sin φ).
 * This is three.js' frame and lookup (equirectUv): a panorama seen from
 * inside, going right across the picture turns right (from −x at u = 0
 * through −z at u = ¼; before 2026-11-27 d_x had the other sign, a mirror).
 * Blender's world (z up) sees the same texel along (x, −z, y) of d.
 * A pixel subtends dω = (2π/W)(π/H) sin θ. The map's values are radiance.
 * `rotation` (row-major 3 × 3, a proper rotation) takes map-frame directions to
 * the world frame: d_world = rotation · d_map. */
void cf_envmap_direction(int width, int height, double x, double y, double d[3]);

typedef struct cf_envmap_report {
  size_t clamped;  /* negative values set to 0 */
  double total[3]; /* Σ L dω over the map, per channel (irradiance units) */
} cf_envmap_report;

/* A map-to-world rotation, row-major: finite, orthonormal (to 1e-6) and
 * proper (determinant +1; a mirror is refused, saying so). CF_EINVAL. */
cf_status cf_envmap_check_rotation(const double rotation[9], cf_error *err);

/* Reduce a linear-RGB equirectangular map (3 or 4 channels; a 4th is
 * ignored) to k directional lights, k in [1, CF_ENVMAP_MAX_LIGHTS] and at most the map's
 * pixel count. Regions are split at the median of their energy
 * (luminance·dω, BT.709 luminance 0.2126 R + 0.7152 G + 0.0722 B) along
 * their longer side (measured on the sphere: widths scaled by sin θ at
 * the region's middle row), always splitting the region of the largest
 * energy next, so any k works. Each light is at its region's
 * energy-weighted mean direction (normalised) and carries the region's
 * Σ L dω per channel, so the lights' total equals the map's. Where that
 * mean vanishes (a region without light, or whose light balances out, as
 * a whole uniform map does for k = 1) the light is at the region's centre.
 * Negative values (of the first three channels) count as 0 and are
 * reported (the caller warns); a NaN or infinity there is refused, naming
 * the first one's texel and channel. `lights` holds k entries; rotation
 * NULL means the identity; report may be NULL. CF_EINVAL for a bad map
 * (non-finite values too), k, or a rotation that is not orthonormal (to
 * 1e-6) or not finite. */
cf_status cf_envmap_median_cut(const cf_image *map, const double rotation[9], int k,
                               cf_directional_light *lights, cf_envmap_report *report,
                               cf_error *err);

/* The map at `path` (read by cf_image_read, RGB or RGBA) reduced by
 * cf_envmap_median_cut: what a capture's `environment` light and
 * `clayfit synth --environment` both use. Errors start with the path. */
cf_status cf_envmap_load(const char *path, const double rotation[9], int k,
                         cf_directional_light *lights, cf_envmap_report *report, cf_error *err);

#endif /* CLAYFIT_CAPTURE_ENVMAP_H */
