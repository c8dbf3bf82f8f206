/* Helmholtz reciprocity as docs/model.md (32) states it:
 *   |f(l, v) − f(v, l)| <= 1e-12 · max(|f(l, v)|, |f(v, l)|)
 * on 10^5 random direction pairs with random in-range parameters for every
 * model, including l = v and grazing pairs. */
#include <math.h>

#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { PAIRS = 100000 };
static const double tolerance = 1e-12;

int main(void) {
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    cf_model_id model = (cf_model_id)m;
    cf_rng rng = cf_rng_seed(1000 + (uint64_t)m);
    double worst = 0.0;
    long exact = 0;
    for (int i = 0; i < PAIRS; ++i) {
      double params[CF_MAX_DIM], n[3], l[3], v[3], f_lv[3], f_vl[3];
      random_params(&rng, model, 0.1, params);
      random_directions(&rng, 0.1, 0.02, n, l, v);
      cf_eval(model, params, n, l, v, f_lv, NULL);
      cf_eval(model, params, n, v, l, f_vl, NULL);
      for (int c = 0; c < 3; ++c) {
        double diff = fabs(f_lv[c] - f_vl[c]);
        double scale = fmax(fabs(f_lv[c]), fabs(f_vl[c]));
        exact += diff == 0.0;
        if (scale > 0.0) worst = fmax(worst, diff / scale);
        CHECK(diff <= tolerance * scale, "%s pair %d channel %d: f(l,v) = %.17g, f(v,l) = %.17g",
              cf_model_info_get(model)->code, i, c, f_lv[c], f_vl[c]);
      }
    }
    printf(
        "%s: %d pairs, worst relative difference %.3g (tolerance %.0e), %ld of %d "
        "values identical to the bit\n",
        cf_model_info_get(model)->code, PAIRS, worst, tolerance, exact, 3 * PAIRS);
  }
  return check_finish("test_reciprocity");
}
