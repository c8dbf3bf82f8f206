/* The four invariants of (n, l, v) that every model is written in
 * (include/clayfit/model.h, cf_geometry). */
#include "clayfit/model.h"

static inline double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

cf_geometry cf_geometry_from_directions(const double n[3], const double l[3],
                                        const double v[3]) {
  cf_geometry g;
  g.cos_i = dot3(n, l);
  g.cos_o = dot3(n, v);
  double lt[3], vt[3], t[3];
  for (int k = 0; k < 3; ++k) {
    lt[k] = l[k] - g.cos_i * n[k];
    vt[k] = v[k] - g.cos_o * n[k];
    t[k] = lt[k] + vt[k];
  }
  g.t_sq = dot3(t, t);
  g.g = dot3(lt, vt);
  return g;
}
