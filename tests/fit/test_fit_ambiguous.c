/* The multi-start's ambiguity test (fit_multistart.h, private to src/fit):
 * a start far from the best within the noise of its cost is ambiguous;
 * two local minima far above the best that tie with each other are not
 * (the demo's default capture warned of those), nor is a start stopped at
 * an earlier minimum. */
#include <string.h>

#include "clayfit/fit.h"
#include "fit_multistart.h"
#include "support/check.h"

CHECK_MAIN_STATE;

/* A start of M2 (albedo r, g, b, diffuse roughness, roughness, f0) ending
 * at albedo `albedo` with cost `cost`. */
static void set_start(cf_fit_result *r, int i, double albedo, double cost, int stopped) {
  cf_fit_start *s = &r->start[i];
  double end[CF_MAX_DIM] = {albedo, albedo, albedo, 0.2, 0.3, 0.05};
  memcpy(s->start, end, sizeof end);
  memcpy(s->end, end, sizeof end);
  s->cost = cost;
  s->iterations = 5;
  s->stopped = stopped;
}

int main(void) {
  static cf_fit_result r;
  r.model = CF_MODEL_DIELECTRIC;
  r.starts = 3;
  r.best_start = 0;
  set_start(&r, 0, 0.5, 100.0, 0);
  set_start(&r, 1, 0.8, 234.0, 0); /* two minima far above the best, tied */
  set_start(&r, 2, 0.2, 234.5, 0);
  CHECK(!fit_ambiguous(&r, CF_MODEL_DIELECTRIC, 1.0), "two tied minima far above the best");
  r.starts = 4;
  set_start(&r, 3, 0.6, 100.5, 1); /* within the noise of the best, but stopped there */
  CHECK(!fit_ambiguous(&r, CF_MODEL_DIELECTRIC, 1.0), "a start stopped at an earlier minimum");
  r.start[3].stopped = 0; /* a second minimum 0.1 of albedo away, Δcost 0.5 */
  CHECK(fit_ambiguous(&r, CF_MODEL_DIELECTRIC, 1.0), "a distant minimum within the noise");
  CHECK(!fit_ambiguous(&r, CF_MODEL_DIELECTRIC, 0.25), "Δcost 0.5 is 2 σ² when σ² = 0.25");
  set_start(&r, 3, 0.52, 100.5, 0); /* near the best: the same minimum */
  CHECK(!fit_ambiguous(&r, CF_MODEL_DIELECTRIC, 1.0), "a near minimum");
  r.starts = 0;
  CHECK(!fit_ambiguous(&r, CF_MODEL_DIELECTRIC, 1.0), "no starts");
  return check_finish("test_fit_ambiguous");
}
