/* The evaluator's entry points: one observation, or a batch with one
 * parameter vector (the fitter's hot path). */
#include <string.h>

#include "models.h"

static const cf_model_impl *const impls[CF_MODEL_COUNT] = {
    [CF_MODEL_LAMBERT] = &cf_lambert_impl,
    [CF_MODEL_OREN_NAYAR] = &cf_oren_nayar_impl,
    [CF_MODEL_DIELECTRIC] = &cf_dielectric_impl,
    [CF_MODEL_CLEARCOAT] = &cf_clearcoat_impl,
    [CF_MODEL_CLAY] = &cf_clay_impl,
    [CF_MODEL_DIELECTRIC_TAILED] = &cf_dielectric_tailed_impl,
    [CF_MODEL_CLAY_TAILED] = &cf_clay_tailed_impl,
};

static const cf_model_impl *impl_of(cf_model_id model) {
  if ((int)model < 0 || model >= CF_MODEL_COUNT) return NULL;
  return impls[model];
}

cf_status cf_eval(cf_model_id model, const double *params, const double n[3], const double l[3],
                  const double v[3], double f[3], double *grad) {
  cf_geometry g = cf_geometry_from_directions(n, l, v);
  return cf_eval_batch(model, params, 1, &g, f, grad);
}

/* One observation: the models are called for lit pairs only; elsewhere
 * f = 0 and its gradient is 0 (model.h, "Conventions"). */
static inline void eval_one(const cf_model_impl *impl, const cf_prepared *prep,
                            const cf_geometry *g, size_t row, double *f, double *grad) {
  if (!cf_geometry_is_lit(g)) {
    f[0] = f[1] = f[2] = 0.0;
    if (grad) memset(grad, 0, row * sizeof *grad);
  } else if (grad) {
    impl->value_grad(prep, g, f, grad);
  } else {
    impl->value(prep, g, f);
  }
}

cf_status cf_eval_batch(cf_model_id model, const double *params, size_t count,
                        const cf_geometry *geometry, double *f, double *grad) {
  const cf_model_impl *impl = impl_of(model);
  if (!impl) return CF_EINVAL;
  cf_prepared prep;
  impl->prepare(params, &prep);
  if (impl->batch && impl->batch(&prep, count, geometry, f, grad)) return CF_OK;
  const size_t row = 3 * (size_t)cf_model_info_get(model)->dim;
  for (size_t i = 0; i < count; ++i)
    eval_one(impl, &prep, &geometry[i], row, f + 3 * i, grad ? grad + row * i : NULL);
  return CF_OK;
}

cf_status cf_eval_batch_directions(cf_model_id model, const double *params, size_t count,
                                   const double *n, const double *l, const double *v, double *f,
                                   double *grad) {
  const cf_model_impl *impl = impl_of(model);
  if (!impl) return CF_EINVAL;
  cf_prepared prep;
  impl->prepare(params, &prep);
  const size_t row = 3 * (size_t)cf_model_info_get(model)->dim;
  if (!impl->batch) {
    for (size_t i = 0; i < count; ++i) {
      cf_geometry g = cf_geometry_from_directions(n + 3 * i, l + 3 * i, v + 3 * i);
      eval_one(impl, &prep, &g, row, f + 3 * i, grad ? grad + row * i : NULL);
    }
    return CF_OK;
  }
  /* a model with a batch path gets the geometry in chunks, so that every
   * entry point gives an observation the same result */
  enum { CHUNK = 64 };
  cf_geometry chunk[CHUNK];
  for (size_t first = 0; first < count; first += CHUNK) {
    size_t m = count - first < CHUNK ? count - first : CHUNK;
    for (size_t i = 0; i < m; ++i) {
      size_t k = 3 * (first + i);
      chunk[i] = cf_geometry_from_directions(n + k, l + k, v + k);
    }
    double *g0 = grad ? grad + row * first : NULL;
    if (impl->batch(&prep, m, chunk, f + 3 * first, g0)) continue;
    for (size_t i = 0; i < m; ++i)
      eval_one(impl, &prep, &chunk[i], row, f + 3 * (first + i), g0 ? g0 + row * i : NULL);
  }
  return CF_OK;
}
