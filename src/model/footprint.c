/* How finely a pixel's footprint must be sampled for a model's lobes
 * (include/clayfit/model.h, "Pixel footprints"). */
#include <math.h>

#include "terms.h"

/* GTR1's width a = 0.1 + (0.001 − 0.1) · gloss (docs/model.md (16)),
 * as D1 uses it. */
static double gtr1_width(double gloss) {
  return 0.1 + (0.001 - 0.1) * gloss;
}

double cf_model_lobe_width(cf_model_id model, const double *params) {
  const cf_model_info *info = cf_model_info_get(model);
  if (!info) return INFINITY;
  /* a tailed twin's vector starts with its GGX twin's; its lobe's α is the
   * GGX one's, and the tail widens the lobe's flanks, not its peak */
  switch (info->ggx_twin) {
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
    default:
      break;
  }
  return INFINITY;
}

/* α² + θ² with θ the nearest the half vector comes to the normal inside
 * the pixel. */
static double lobe_scale_sq(double width, double delta, double theta_h) {
  double theta = theta_h - 0.5 * sqrt(2.0) * delta;
  theta = theta > 0.0 ? theta : 0.0;
  return width * width + theta * theta;
}

/* The relative error bounds (include/clayfit/model.h): the centre's
 * δ² · 5/(3 s²) and P Gauss-Legendre panels' (δ/P)⁴ · 7/(18 s⁴), with
 * s² = α² + θ². */
static double centre_error(double delta_sq, double scale_sq) {
  return delta_sq * 5.0 / (3.0 * scale_sq);
}

static double gauss_error(double delta_sq, double scale_sq, int panels) {
  double ratio = delta_sq / (scale_sq * panels * panels);
  return ratio * ratio * 7.0 / 18.0;
}

double cf_footprint_error(double width, double delta, double theta_h, int samples) {
  if (samples != 1 && (samples < 2 || samples % 2 != 0)) return NAN;
  if (!(delta > 0.0) || isinf(width)) return 0.0;
  double scale_sq = lobe_scale_sq(width, delta, theta_h);
  if (!(scale_sq > 0.0)) return INFINITY;
  double delta_sq = delta * delta;
  return samples == 1 ? centre_error(delta_sq, scale_sq)
                      : gauss_error(delta_sq, scale_sq, samples / 2);
}

int cf_footprint_samples(double width, double delta, double theta_h, double tolerance,
                         int max_samples) {
  int largest = max_samples - max_samples % 2; /* the most (even) samples allowed */
  if (largest < 2) return 1;
  if (!(delta > 0.0) || !(tolerance > 0.0) || isinf(width)) return 1;
  double scale_sq = lobe_scale_sq(width, delta, theta_h);
  if (!(scale_sq > 0.0)) return largest;
  double delta_sq = delta * delta;
  if (centre_error(delta_sq, scale_sq) <= tolerance) return 1;
  /* the least P with (δ/P)⁴ · 7/(18 s⁴) <= tolerance */
  double panels = delta / sqrt(scale_sq) * pow(7.0 / (18.0 * tolerance), 0.25);
  if (!(2.0 * panels < (double)largest)) return largest;
  int p = panels < 1.0 ? 1 : (int)ceil(panels);
  while (p > 1 && gauss_error(delta_sq, scale_sq, p - 1) <= tolerance) --p; /* rounding */
  while (2 * p < largest && gauss_error(delta_sq, scale_sq, p) > tolerance) ++p;
  return 2 * p;
}

double cf_footprint_offset(int samples, int j) {
  if (samples == 1) return j == 0 ? 0.0 : NAN;
  if (samples < 2 || samples % 2 != 0 || j < 0 || j >= samples) return NAN;
  int panels = samples / 2, panel = j / 2;
  double centre = (panel + 0.5) / panels - 0.5;
  double half_gap = 1.0 / (2.0 * sqrt(3.0) * panels);
  return j % 2 == 0 ? centre - half_gap : centre + half_gap;
}
