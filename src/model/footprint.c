/* How finely a pixel's footprint must be sampled for a model's lobes
 * (include/clayfit/model.h, "Pixel footprints"). */
#include <math.h>

#include "terms.h"

/* GTR1's width a = 0.1 + (0.001 − 0.1) · gloss (MODEL.md, "Building
 * blocks"), as D1 uses it. */
static double gtr1_width(double gloss) {
  return 0.1 + (0.001 - 0.1) * gloss;
}

double cf_model_lobe_width(cf_model_id model, const double *params) {
  switch (model) {
    case CF_MODEL_LAMBERT:
    case CF_MODEL_OREN_NAYAR:
      return INFINITY;
    case CF_MODEL_DIELECTRIC: {
      double r = params[CF_DIELECTRIC_ROUGHNESS];
      return r * r;
    }
    case CF_MODEL_CLEARCOAT: {
      double r = params[CF_CLEARCOAT_ROUGHNESS];
      double coat = params[CF_CLEARCOAT_COAT_WEIGHT] > 0.0
                        ? fabs(gtr1_width(params[CF_CLEARCOAT_COAT_GLOSS]))
                        : INFINITY;
      return fmin(r * r, coat);
    }
    case CF_MODEL_CLAY: {
      /* the base lobe is seen through the film, where a turn of the normal
       * moves the refracted half vector less (by about 1/η1): taking its α
       * as it is errs on the side of more samples */
      double r1 = params[CF_CLAY_FILM_ROUGHNESS], r2 = params[CF_CLAY_BASE_ROUGHNESS];
      return fmin(r1 * r1, r2 * r2);
    }
    case CF_MODEL_COUNT:
      break;
  }
  return INFINITY;
}

int cf_footprint_samples(double width, double delta, double theta_h, double tolerance,
                         int max_samples) {
  if (max_samples < 1) return 1;
  if (!(delta > 0.0) || !(tolerance > 0.0) || isinf(width)) return 1;
  /* the nearest the half vector comes to the normal inside the pixel */
  double theta = theta_h - 0.5 * sqrt(2.0) * delta;
  theta = theta > 0.0 ? theta : 0.0;
  double scale_sq = width * width + theta * theta;
  if (!(scale_sq > 0.0)) return max_samples;
  double s = delta * sqrt(5.0 / (3.0 * tolerance * scale_sq));
  if (!(s < (double)max_samples)) return max_samples;
  int samples = (int)ceil(s);
  return samples < 1 ? 1 : samples;
}
