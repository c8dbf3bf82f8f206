/* The batch entry points give exactly what one-at-a-time evaluation gives,
 * in the documented layout, and reject an unknown model. */
#include <string.h>

#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { COUNT = 257 };

int main(void) {
  cf_rng rng = cf_rng_seed(9);
  static double n[COUNT][3], l[COUNT][3], v[COUNT][3];
  static cf_geometry geometry[COUNT];
  for (int i = 0; i < COUNT; ++i) {
    random_directions(&rng, 0.1, 0.02, n[i], l[i], v[i]);
    if (i % 17 == 0) l[i][0] = -l[i][0], l[i][1] = -l[i][1], l[i][2] = -l[i][2];
    geometry[i] = cf_geometry_from_directions(n[i], l[i], v[i]);
  }
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    cf_model_id model = (cf_model_id)m;
    int dim = cf_model_info_get(model)->dim;
    double params[CF_MAX_DIM];
    random_params(&rng, model, 0.0, params);
    static double f_batch[3 * COUNT], g_batch[3 * CF_MAX_DIM * COUNT];
    static double f_dirs[3 * COUNT], g_dirs[3 * CF_MAX_DIM * COUNT], f_value[3 * COUNT];
    CHECK(cf_eval_batch(model, params, COUNT, geometry, f_batch, g_batch) == CF_OK, "batch");
    CHECK(cf_eval_batch(model, params, COUNT, geometry, f_value, NULL) == CF_OK, "value");
    CHECK(cf_eval_batch_directions(model, params, COUNT, &n[0][0], &l[0][0], &v[0][0], f_dirs,
                                   g_dirs) == CF_OK,
          "directions");
    for (int i = 0; i < COUNT; ++i) {
      double f[3], g[3 * CF_MAX_DIM];
      cf_eval(model, params, n[i], l[i], v[i], f, g);
      CHECK(memcmp(f, f_batch + 3 * i, sizeof f) == 0, "model %d obs %d value", m, i);
      CHECK(memcmp(f, f_value + 3 * i, sizeof f) == 0, "model %d obs %d value only", m, i);
      CHECK(memcmp(f, f_dirs + 3 * i, sizeof f) == 0, "model %d obs %d from directions", m, i);
      CHECK(memcmp(g, g_batch + 3 * dim * i, 3 * dim * sizeof(double)) == 0,
            "model %d obs %d gradient", m, i);
      CHECK(memcmp(g, g_dirs + 3 * dim * i, 3 * dim * sizeof(double)) == 0,
            "model %d obs %d gradient from directions", m, i);
    }
  }
  double f[3], params[CF_MAX_DIM] = {0};
  double up[3] = {0, 0, 1};
  CHECK(cf_eval(CF_MODEL_COUNT, params, up, up, up, f, NULL) == CF_EINVAL, "bad model");
  CHECK(cf_eval((cf_model_id)-1, params, up, up, up, f, NULL) == CF_EINVAL, "bad model");
  return check_finish("test_batch");
}
