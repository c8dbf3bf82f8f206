/* The lights of docs/model.md §5.2 (src/capture/lights.h). */
#include "lights.h"

#include <math.h>

/* The flash's world position: C + Rᵀ t_flash. */
static void flash_position(const double r[9], const double c[3], const double offset[3],
                           double p[3]) {
  for (int k = 0; k < 3; ++k)
    p[k] = c[k] + r[0 * 3 + k] * offset[0] + r[1 * 3 + k] * offset[1] + r[2 * 3 + k] * offset[2];
}

static int point_light_at(const double p[3], const double intensity[3], const double x[3],
                          double l[3], double e[3]) {
  double d[3] = {p[0] - x[0], p[1] - x[1], p[2] - x[2]};
  double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  if (!(d2 > 0.0) || !isfinite(d2)) return 0;
  double inv = 1.0 / sqrt(d2);
  for (int k = 0; k < 3; ++k) {
    l[k] = d[k] * inv;
    e[k] = intensity[k] / d2;
  }
  return 1;
}

int cf_light_at(const cf_light *light, const double r[9], const double c[3], const double x[3],
                double l[3], double e[3]) {
  switch (light->kind) {
    case CF_LIGHT_POINT:
      return point_light_at(light->position, light->intensity, x, l, e);
    case CF_LIGHT_FLASH: {
      double p[3];
      flash_position(r, c, light->position, p);
      return point_light_at(p, light->intensity, x, l, e);
    }
    case CF_LIGHT_DIRECTIONAL:
      for (int k = 0; k < 3; ++k) {
        l[k] = light->direction[k];
        e[k] = light->intensity[k];
      }
      return 1;
  }
  return 0;
}
