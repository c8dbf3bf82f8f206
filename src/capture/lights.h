/* Lights of a capture (docs/model.md §5.2): what each gives a
 * surface point, the direction toward it and the irradiance it brings.
 * Private to src/capture. */
#ifndef CLAYFIT_CAPTURE_LIGHTS_H
#define CLAYFIT_CAPTURE_LIGHTS_H

typedef enum cf_light_kind {
  CF_LIGHT_POINT,      /* isotropic point light at a world position */
  CF_LIGHT_FLASH,      /* isotropic point light fixed to the camera */
  CF_LIGHT_DIRECTIONAL /* distant light: fixed direction and irradiance */
} cf_light_kind;

typedef struct cf_light {
  cf_light_kind kind;
  /* POINT: position in world units. FLASH: offset in camera coordinates
   * (x right, y down, z forward), in world units. */
  double position[3];
  /* DIRECTIONAL: unit vector toward the light, world frame. */
  double direction[3];
  /* POINT, FLASH: radiant intensity I per channel, so that E = I / d².
   * DIRECTIONAL: irradiance E per channel, perpendicular to direction. */
  double intensity[3];
} cf_light;

/* For a surface point x seen by a camera with world-to-camera rotation R
 * (row-major) and centre C: the unit direction l toward the light and the
 * irradiance E (perpendicular to l). Returns 0 where it is undefined (the
 * point is at the light), leaving l and E untouched.
 *   point:       l = (p − x)/|p − x|, E = I/|p − x|²
 *   flash:       p = C + Rᵀ t_flash, then as a point light
 *   directional: l and E as given */
int cf_light_at(const cf_light *light, const double r[9], const double c[3], const double x[3],
                double l[3], double e[3]);

#endif /* CLAYFIT_CAPTURE_LIGHTS_H */
