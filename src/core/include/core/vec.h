/* π and its kin, and the small 3-vector helpers every layer uses: the one
 * definition of each (the shaders' CF_PI is written from this one,
 * src/export/export_shader.c). Header only, C11 + libm; C++ may include
 * it too. */
#ifndef CLAYFIT_CORE_VEC_H
#define CLAYFIT_CORE_VEC_H

#include <math.h>

/* Each the double nearest its value (2π and π/2 are 2.0 * CF_PI and
 * 0.5 * CF_PI exactly). */
#define CF_PI 3.14159265358979323846
#define CF_INV_PI 0.31830988618379067154 /* 1/π */
#define CF_DEGREES (180.0 / CF_PI)       /* degrees per radian */

static inline double cf_dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* c = a × b (c must not be a or b) */
static inline void cf_cross3(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static inline double cf_norm3(const double a[3]) {
  return sqrt(cf_dot3(a, a));
}

/* The angle between a and b in radians, [0, π] (exact near 0 and π, where
 * acos of the normalised dot product is not). */
static inline double cf_angle3(const double a[3], const double b[3]) {
  double c[3];
  cf_cross3(a, b, c);
  return atan2(cf_norm3(c), cf_dot3(a, b));
}

/* v scaled to length 1; 0 (v unchanged) when its length is 0 or not
 * finite. */
static inline int cf_normalize3(double v[3]) {
  double length = cf_norm3(v);
  if (!(length > 0.0) || !isfinite(length)) return 0;
  for (int k = 0; k < 3; ++k) v[k] /= length;
  return 1;
}

#endif /* CLAYFIT_CORE_VEC_H */
