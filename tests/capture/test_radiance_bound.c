/* capture_radiance_bound (src/capture/capture_screen.c), the brightest
 * radiance per unit irradiance any material of the ladder reflects, seen at
 * c_o = n·v: a search over every model, its parameters inside their ranges
 * (docs/model.md §1.6; a third at each bound) and the light's direction,
 * climbing from the best of 3000 draws, never exceeds it; and the bound is
 * within 2.5 times the largest found at c_o from 1 down to 0.1, so that it
 * screens (issue 30, item 6: a patch of 1e6 under a flash was kept). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "capture/capture_internal.h"
#include "clayfit/model.h"
#include "core/rng.h"
#include "core/vec.h"
#include "support/check.h"

CHECK_MAIN_STATE;

typedef struct point {
  double params[CF_MAX_DIM];
  double tilt, azimuth; /* the light from the mirror direction */
} point;

/* max over channels of f·c_i at view cosine co, n = z */
static double reflected(cf_model_id model, const point *p, double co) {
  double so = sqrt(1.0 - co * co), n[3] = {0.0, 0.0, 1.0}, v[3] = {so, 0.0, co};
  double theta = acos(co) + p->tilt, l[3] = {-sin(theta) * cos(p->azimuth),
                                             -sin(theta) * sin(p->azimuth), cos(theta)};
  if (!(l[2] > 0.0)) return 0.0;
  double f[3];
  if (cf_eval(model, p->params, n, l, v, f, NULL) != CF_OK) return INFINITY;
  return fmax(f[0], fmax(f[1], f[2])) * l[2];
}

static void slot_range(cf_model_id model, int k, double *lower, double *upper) {
  int component = 0;
  const cf_param_info *info = cf_model_slot_param(model, k, &component);
  *lower = info->lower;
  *upper = info->upper;
}

static double search(cf_model_id model, double co, cf_rng *rng) {
  int dim = cf_model_info_get(model)->dim;
  point best = {{0}, 0.0, 0.0}, p;
  double top = -1.0;
  for (int draw = 0; draw < 3000; ++draw) {
    for (int k = 0; k < dim; ++k) {
      double lo, hi, u = cf_rng_uniform(rng);
      slot_range(model, k, &lo, &hi);
      p.params[k] = u < 0.33 ? lo : u < 0.67 ? hi : lo + (hi - lo) * cf_rng_uniform(rng);
    }
    p.tilt = draw % 2 ? 0.0 : 0.2 * (cf_rng_uniform(rng) - 0.5);
    p.azimuth = draw % 2 ? 0.0 : 2.0 * CF_PI * cf_rng_uniform(rng);
    double value = reflected(model, &p, co);
    if (value > top) top = value, best = p;
  }
  double step = 0.2;
  for (int move = 0; move < 20000; ++move) {
    p = best;
    int k = (int)(cf_rng_uniform(rng) * (dim + 2));
    double u = 2.0 * cf_rng_uniform(rng) - 1.0;
    if (k < dim) {
      double lo, hi;
      slot_range(model, k, &lo, &hi);
      p.params[k] = fmin(hi, fmax(lo, p.params[k] + (hi - lo) * step * u));
    } else if (k == dim) {
      p.tilt += 0.02 * step * u;
    } else {
      p.azimuth += step * u;
    }
    double value = reflected(model, &p, co);
    if (value > top) top = value, best = p;
    if (move % 2000 == 1999) step *= 0.5;
  }
  return top;
}

int main(void) {
  const double cosines[] = {1.0, 0.93, 0.7, 0.5, 0.33, 0.2, 0.1, 0.063, 0.03};
  cf_rng rng = cf_rng_seed(30);
  for (size_t c = 0; c < sizeof cosines / sizeof *cosines; ++c) {
    double co = cosines[c], bound = capture_radiance_bound(co), top = 0.0;
    for (int m = 0; m < CF_MODEL_COUNT; ++m) {
      double found = search((cf_model_id)m, co, &rng);
      CHECK(found <= bound, "%s at c_o %g: pi f c_i %g above the bound's %g",
            cf_model_info_get((cf_model_id)m)->code, co, CF_PI * found, CF_PI * bound);
      top = fmax(top, found);
    }
    if (co >= 0.1)
      CHECK(bound < 2.5 * top, "c_o %g: the bound pi %g is %g times the largest found", co,
            CF_PI * bound, bound / top);
    printf("c_o %-5g  largest pi f c_i %-10.4g bound %-10.4g (%.2f times)\n", co, CF_PI * top,
           CF_PI * bound, bound / top);
  }
  CHECK(isinf(capture_radiance_bound(0.0)) && isinf(capture_radiance_bound(-0.5)), "c_o <= 0");
  return check_finish("test_radiance_bound");
}
