/* Everything the BRDF needs of (n, l, v), once per observation
 * (include/clayfit/model.h, cf_geometry). */
#include "terms.h"

cf_geometry cf_geometry_from_directions(const double n[3], const double l[3], const double v[3]) {
  cf_geometry g = {0};
  g.cos_i = cf_dot3(n, l);
  g.cos_o = cf_dot3(n, v);
  double lt[3], vt[3], t[3];
  for (int k = 0; k < 3; ++k) {
    lt[k] = l[k] - g.cos_i * n[k];
    vt[k] = v[k] - g.cos_o * n[k];
    t[k] = lt[k] + vt[k];
  }
  g.t_sq = cf_dot3(t, t);
  g.g = cf_dot3(lt, vt);
  if (!cf_geometry_is_lit(&g)) return g;

  cf_half_vector h = half_vector(g.t_sq, g.cos_i + g.cos_o);
  g.sin2_h = h.sin2_h;
  g.cos2_h = h.cos2_h;
  g.c_d = h.c_d;
  g.weight_d = schlick_weight(h.c_d);
  g.on_angular = oren_nayar_angular(g.g, g.cos_i, g.cos_o);
  g.coat_visibility = smith_ggx_separable(CF_COAT_VISIBILITY_A2, g.cos_i, g.cos_o);
  return g;
}
