/* The multi-start grid (fit_starts.h). Its values are fd063f4's, not measured one by one; the
 * grid as a whole earns its place: without it (--no-multistart) 7 of 25 screened fits end
 * elsewhere, 4 at a higher RMSE (M2 with Cauchy loss: 0.045 -> 2.25; tuned-constants study). */
#include "fit_starts.h"

#include <string.h>

/* Set a slot unless it is held. */
static void put(double *x, const int *held, int slot, double value) {
  if (!held[slot]) x[slot] = value;
}

/* A value inside [lo, hi], for a start. */
static double inside(double x, double lo, double hi) {
  return x < lo ? lo : x > hi ? hi : x;
}

/* M4 from a fitted M2 (ρ, σ, r, F0): its lobe as the film's or the base's. */
static int clay_from_dielectric(const double *base, const int *held, const double *m2,
                                double (*starts)[CF_MAX_DIM], int max) {
  static const double base_roughness[] = {0.25, 0.6, 0.95}, base_f0[] = {0.005, 0.03};
  static const double film_roughness[] = {0.08, 0.9}, tau[] = {0.05, 0.5};
  double r = m2[CF_DIELECTRIC_ROUGHNESS], f0 = m2[CF_DIELECTRIC_F0];
  /* σ's derivative vanishes at 0 (docs/model.md §6.6): from near 0, start at 0.15 */
  double sigma =
      m2[CF_DIELECTRIC_DIFFUSE_ROUGHNESS] > 0.05 ? m2[CF_DIELECTRIC_DIFFUSE_ROUGHNESS] : 0.15;
  int n = 0;
  for (int order = 0; order < 2; ++order)
    for (int t = 0; t < 2; ++t)
      for (int a = 0; a < (order == 0 ? 3 : 2); ++a)
        for (int b = 0; b < (order == 0 ? 2 : 1) && n < max; ++b, ++n) {
          double *x = starts[n];
          memcpy(x, base, sizeof starts[0]);
          for (int c = 0; c < 3; ++c) {
            put(x, held, CF_CLAY_ALBEDO + c, inside(m2[CF_DIELECTRIC_ALBEDO + c], 0.02, 0.98));
            put(x, held, CF_CLAY_OPTICAL_DEPTH + c, tau[t]);
          }
          put(x, held, CF_CLAY_DIFFUSE_ROUGHNESS, sigma);
          if (order == 0) { /* M2's lobe is the film's */
            put(x, held, CF_CLAY_FILM_ROUGHNESS, r);
            put(x, held, CF_CLAY_FILM_F0, inside(f0, 0.01, 0.25));
            put(x, held, CF_CLAY_BASE_ROUGHNESS, base_roughness[a]);
            put(x, held, CF_CLAY_BASE_F0, base_f0[b]);
          } else { /* M2's lobe is the base's, under a sharp or a rough film */
            put(x, held, CF_CLAY_BASE_ROUGHNESS, r);
            put(x, held, CF_CLAY_BASE_F0, inside(f0, 0.0, 0.25));
            put(x, held, CF_CLAY_FILM_ROUGHNESS, film_roughness[a]);
            put(x, held, CF_CLAY_FILM_F0, 0.02);
          }
        }
  return n;
}

/* M3 from a fitted M2: its interface kept, the coat's weight and gloss
 * explored. */
static int clearcoat_from_dielectric(const double *base, const int *held, const double *m2,
                                     double (*starts)[CF_MAX_DIM], int max) {
  static const double weight[] = {0.1, 0.5}, gloss[] = {0.3, 0.8};
  int n = 0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2 && n < max; ++j, ++n) {
      memcpy(starts[n], base, sizeof starts[0]);
      for (int k = 0; k < CF_DIELECTRIC_DIM; ++k) put(starts[n], held, k, m2[k]);
      for (int c = 0; c < 3; ++c)
        put(starts[n], held, CF_CLEARCOAT_ALBEDO + c,
            inside(m2[CF_DIELECTRIC_ALBEDO + c], 0.02, 0.98));
      if (m2[CF_DIELECTRIC_DIFFUSE_ROUGHNESS] < 0.05)
        put(starts[n], held, CF_CLEARCOAT_DIFFUSE_ROUGHNESS, 0.15);
      put(starts[n], held, CF_CLEARCOAT_COAT_WEIGHT, weight[i]);
      put(starts[n], held, CF_CLEARCOAT_COAT_GLOSS, gloss[j]);
    }
  return n;
}

int fit_starts(cf_model_id model, const double *base, const int *held, const double *warm,
               double (*starts)[CF_MAX_DIM], int max) {
  /* a tailed twin starts as its GGX twin, the tail at base's value (GGX's 2
   * unless given): the tail's gradient there is not 0, and the solve moves it */
  const cf_model_info *info = cf_model_info_get(model);
  if (info && info->tail_slot >= 0)
    return fit_starts(info->ggx_twin, base, held, warm, starts, max);
  if (warm && model == CF_MODEL_CLAY) return clay_from_dielectric(base, held, warm, starts, max);
  if (warm && model == CF_MODEL_CLEARCOAT)
    return clearcoat_from_dielectric(base, held, warm, starts, max);
  int n = 0;
  switch (model) {
    case CF_MODEL_LAMBERT:
      memcpy(starts[n++], base, sizeof starts[0]);
      break;
    case CF_MODEL_OREN_NAYAR: {
      /* σ's derivative vanishes at 0: start away from it */
      static const double sigmas[] = {0.15, 0.6};
      for (int i = 0; i < 2 && n < max; ++i, ++n) {
        memcpy(starts[n], base, sizeof starts[0]);
        put(starts[n], held, CF_OREN_NAYAR_DIFFUSE_ROUGHNESS, sigmas[i]);
      }
      break;
    }
    case CF_MODEL_DIELECTRIC: {
      static const double roughness[] = {0.08, 0.25, 0.6}, f0[] = {0.02, 0.08};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 2 && n < max; ++j, ++n) {
          memcpy(starts[n], base, sizeof starts[0]);
          put(starts[n], held, CF_DIELECTRIC_DIFFUSE_ROUGHNESS, 0.15);
          put(starts[n], held, CF_DIELECTRIC_ROUGHNESS, roughness[i]);
          put(starts[n], held, CF_DIELECTRIC_F0, f0[j]);
        }
      break;
    }
    case CF_MODEL_CLEARCOAT: {
      static const double roughness[] = {0.1, 0.4}, weight[] = {0.2, 0.7}, gloss[] = {0.4, 0.9};
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
          for (int k = 0; k < 2 && n < max; ++k, ++n) {
            memcpy(starts[n], base, sizeof starts[0]);
            put(starts[n], held, CF_CLEARCOAT_DIFFUSE_ROUGHNESS, 0.15);
            put(starts[n], held, CF_CLEARCOAT_ROUGHNESS, roughness[i]);
            put(starts[n], held, CF_CLEARCOAT_F0, 0.04);
            put(starts[n], held, CF_CLEARCOAT_COAT_WEIGHT, weight[j]);
            put(starts[n], held, CF_CLEARCOAT_COAT_GLOSS, gloss[k]);
          }
      break;
    }
    case CF_MODEL_CLAY: {
      /* both orderings of the lobes: sharp film over rough base, and the
       * reverse (a start on the wrong side ends in a false minimum whose
       * residual is within 0.5 % of the true one) */
      static const double lobes[4][2] = {{0.08, 0.5}, {0.5, 0.08}, {0.15, 0.9}, {0.9, 0.15}};
      static const double tau[] = {0.1, 1.0};
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 2 && n < max; ++j, ++n) {
          memcpy(starts[n], base, sizeof starts[0]);
          put(starts[n], held, CF_CLAY_DIFFUSE_ROUGHNESS, 0.15);
          put(starts[n], held, CF_CLAY_FILM_ROUGHNESS, lobes[i][0]);
          put(starts[n], held, CF_CLAY_BASE_ROUGHNESS, lobes[i][1]);
          put(starts[n], held, CF_CLAY_FILM_F0, 0.03);
          put(starts[n], held, CF_CLAY_BASE_F0, 0.01);
          for (int c = 0; c < 3; ++c) put(starts[n], held, CF_CLAY_OPTICAL_DEPTH + c, tau[j]);
        }
      break;
    }
    default:
      break;
  }
  return n;
}
