/* Values finite and non-negative, gradients finite, on the grid of hard
 * cases (docs/model.md §4.1): cosines down to
 * 1e-300 on either side, l = v, l mirrored about n, l + v = 0 at the
 * horizon, every parameter at its bounds and default, optical depth 1e3. */
#include <math.h>

#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { MAX_GEOMETRIES = 512 };
static double normals[MAX_GEOMETRIES][3], lights[MAX_GEOMETRIES][3], views[MAX_GEOMETRIES][3];
static size_t geometry_count;

typedef struct grid_state {
  cf_model_id model;
  long evaluations, lit;
} grid_state;

static void visit(const double *params, void *user) {
  grid_state *s = user;
  const int dim = cf_model_info_get(s->model)->dim;
  for (size_t i = 0; i < geometry_count; ++i) {
    double f[3], grad[3 * CF_MAX_DIM];
    cf_eval(s->model, params, normals[i], lights[i], views[i], f, grad);
    cf_geometry g = cf_geometry_from_directions(normals[i], lights[i], views[i]);
    ++s->evaluations;
    s->lit += cf_geometry_is_lit(&g);
    for (int c = 0; c < 3; ++c) {
      CHECK(isfinite(f[c]) && f[c] >= 0.0, "model %d geometry %zu (c_i %g, c_o %g): f[%d] = %g",
            (int)s->model, i, g.cos_i, g.cos_o, c, f[c]);
      if (g.cos_i <= 0.0 || g.cos_o <= 0.0)
        CHECK(f[c] == 0.0, "model %d geometry %zu below the horizon: f = %g", (int)s->model, i,
              f[c]);
      for (int k = 0; k < dim; ++k) {
        char name[48];
        CHECK(isfinite(grad[c * dim + k]),
              "model %d geometry %zu (c_i %g, c_o %g): d f[%d] / d %s = %g", (int)s->model, i,
              g.cos_i, g.cos_o, c, cf_model_slot_name(s->model, k, name, sizeof name),
              grad[c * dim + k]);
      }
    }
  }
}

int main(void) {
  geometry_count = hard_geometries(normals, lights, views, MAX_GEOMETRIES);
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    grid_state s = {(cf_model_id)m, 0, 0};
    long sets = for_each_extreme_params(s.model, visit, &s);
    printf("%s: %ld parameter sets x %zu geometries = %ld evaluations (%ld lit)\n",
           cf_model_info_get(s.model)->code, sets, geometry_count, s.evaluations, s.lit);
  }
  return check_finish("test_hard_cases");
}
