/* The specular lobe alone, for its benchmark (clayfit/lobe.h). A file of its
 * own: the lobes are called out of line (tailed.c), as the benchmark has
 * always timed them. */
#include <stdlib.h>

#include "clayfit/lobe.h"
#include "tailed.h"

struct cf_lobe {
  cf_std_lobe_prep prep;
};

cf_lobe *cf_lobe_new(double roughness, double gamma) {
  cf_lobe *lobe = malloc(sizeof *lobe);
  if (lobe) cf_std_lobe_prepare(&lobe->prep, roughness * roughness * roughness * roughness, gamma);
  return lobe;
}

void cf_lobe_free(cf_lobe *lobe) {
  free(lobe);
}

double cf_lobe_sum(const cf_lobe *lobe, cf_lobe_kind kind, size_t count,
                   const cf_geometry *geometry, int grad) {
  const cf_std_lobe_prep *p = &lobe->prep;
  double sum = 0.0;
  for (size_t i = 0; i < count; ++i) {
    const cf_geometry *g = &geometry[i];
    if (kind == CF_LOBE_STD_EXACT) { /* F = 1: F0 = 1 */
      cf_std_lobe s =
          cf_std_lobe_eval(&p->tail, 1.0, 0.0, g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, grad);
      sum += s.value + 1e-30 * (s.d_a2 + s.d_gamma + s.d_ci + s.d_co + s.d_sin2);
    } else {
      cf_std_dv s =
          kind == CF_LOBE_GGX
              ? cf_ggx_dv_eval(p->tail.a2, g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, grad)
              : cf_std_dv_eval(&p->tail, &p->table, g->sin2_h, g->cos2_h, g->cos_i, g->cos_o, grad);
      sum += s.value + 1e-30 * (s.d_a2 + s.d_gamma + s.d_ci + s.d_co + s.d_sin2);
    }
  }
  return sum;
}

double cf_lobe_tabulate(cf_lobe *lobe, double gamma, int exact) {
  if (exact)
    cf_std_table_build_exact(&lobe->prep.table, gamma);
  else
    cf_std_table_build(&lobe->prep.table, gamma);
  return lobe->prep.table.step[0].c[0];
}
