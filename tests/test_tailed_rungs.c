/* The tailed rungs contain their GGX twins exactly (issue 18; docs/model.md
 * §4.5): M2T and M4T at tail 2 equal M2 and M4 to the bit, value and every
 * gradient entry the twin has; and the tail moves the value elsewhere. */
#include <math.h>
#include <string.h>

#include "model/models.h"
#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { CASES = 4000 };

/* The twin of `tailed`, at tail 2, against the twin: value and gradient. */
static void check_twin(cf_model_id tailed, int i, const double n[3], const double l[3],
                       const double v[3], cf_rng *rng, int *moved) {
  const cf_model_info *m = cf_model_info_get(tailed);
  const cf_model_info *twin = cf_model_info_get(m->ggx_twin);
  double p[CF_MAX_DIM], f_t[3], f_g[3];
  double grad_t[3 * CF_MAX_DIM], grad_g[3 * CF_MAX_DIM];
  random_params(rng, tailed, 0.1, p);
  p[m->tail_slot] = 2.0;
  cf_eval(tailed, p, n, l, v, f_t, grad_t);
  cf_eval(twin->id, p, n, l, v, f_g, grad_g); /* the twin's vector is the prefix */
  for (int c = 0; c < 3; ++c) {
    CHECK(f_t[c] == f_g[c], "case %d: %s(tail=2) %.17g != %s %.17g", i, m->code, f_t[c], twin->code,
          f_g[c]);
    for (int k = 0; k < twin->dim; ++k)
      CHECK(grad_t[c * m->dim + k] == grad_g[c * twin->dim + k],
            "case %d: %s(tail=2) d/d%d %.17g != %s's %.17g", i, m->code, k, grad_t[c * m->dim + k],
            twin->code, grad_g[c * twin->dim + k]);
    CHECK(isfinite(grad_t[c * m->dim + m->tail_slot]), "case %d: %s's d/dtail not finite", i,
          m->code);
  }
  /* away from 2 the tail changes the lobe */
  p[m->tail_slot] = 1.7;
  cf_eval(tailed, p, n, l, v, f_t, NULL);
  if (f_g[0] > 0.0 && f_t[0] != f_g[0]) ++*moved;
}

int main(void) {
  cf_rng rng = cf_rng_seed(1818);
  int moved[2] = {0, 0};
  long lit = 0;
  for (int i = 0; i < CASES; ++i) {
    double n[3], l[3], v[3];
    random_directions(&rng, 0.1, 0.02, n, l, v);
    cf_geometry g = cf_geometry_from_directions(n, l, v);
    lit += cf_geometry_is_lit(&g);
    check_twin(CF_MODEL_DIELECTRIC_TAILED, i, n, l, v, &rng, &moved[0]);
    check_twin(CF_MODEL_CLAY_TAILED, i, n, l, v, &rng, &moved[1]);
  }
  CHECK(moved[0] > lit / 2, "M2T at tail 1.7 equals M2 in %ld of %ld lit cases", lit - moved[0],
        lit);
  CHECK(moved[1] > lit / 2, "M4T at tail 1.7 equals M4 in %ld of %ld lit cases", lit - moved[1],
        lit);
  printf("%d cases (%ld lit): M2T and M4T at tail 2 equal M2 and M4 to the bit\n", CASES, lit);
  return check_finish("test_tailed_rungs");
}
