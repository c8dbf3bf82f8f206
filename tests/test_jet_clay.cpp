// An independent check of the C evaluator's M4 (clay) and M2 (dielectric):
// the models written a second time, straight from docs/model.md's vector
// formulas (refracted direction vectors l', v', half vectors, the textbook
// forms of D and ON), templated on the scalar (bench/peers/jet_model.h,
// shared with the peers benchmark) and differentiated by ceres::Jet
// (forward-mode automatic differentiation). Values and all derivatives
// must agree with cf_eval's closed-form gradient.
#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

extern "C" {
#include "clayfit/model.h"
#include "core/rng.h"
}

#include "../bench/peers/jet_model.h"

namespace {

constexpr int kDim = CF_CLAY_DIM;
using Jet = ceres::Jet<double, kDim>;
using clayfit_jet::Vec3;

}  // namespace

int main() {
  const int kCases = 20000;
  const double kRelValue = 1e-10, kRelGrad = 1e-9;
  long failures = 0;
  for (cf_model_id model : {CF_MODEL_CLAY, CF_MODEL_DIELECTRIC}) {
    cf_rng rng = cf_rng_seed(2718);
    const cf_model_info *m = cf_model_info_get(model);
    const int dim = m->dim;
    long model_failures = 0, compared = 0;
    double worst_value = 0.0, worst_grad = 0.0;
    for (int i = 0; i < kCases; ++i) {
      double params[kDim];
      for (int j = 0; j < m->param_count; ++j) {
        const cf_param_info *info = cf_param_info_get(m->params[j]);
        for (int c = 0; c < info->components; ++c)
          params[m->offsets[j] + c] = cf_rng_range(&rng, info->lower, info->upper);
      }
      // directions about a random normal, cosines above 0.02: the textbook
      // forms used here lose digits closer to the horizon
      double n[3], l[3], v[3];
      cf_rng_unit_vector(&rng, n);
      do cf_rng_hemisphere(&rng, n, l);
      while (n[0] * l[0] + n[1] * l[1] + n[2] * l[2] < 0.02);
      do cf_rng_hemisphere(&rng, n, v);
      while (n[0] * v[0] + n[1] * v[1] + n[2] * v[2] < 0.02);

      double f[3], grad[3 * kDim];
      cf_eval(model, params, n, l, v, f, grad);
      Jet p[kDim], fj[3];
      for (int k = 0; k < dim; ++k) p[k] = Jet(params[k], k);
      clayfit_jet::Eval(model, p, Vec3<double>{n[0], n[1], n[2]}, Vec3<double>{l[0], l[1], l[2]},
                        Vec3<double>{v[0], v[1], v[2]}, fj);

      for (int c = 0; c < 3; ++c) {
        double value_error = std::fabs(f[c] - fj[c].a) / std::fabs(fj[c].a);
        worst_value = std::max(worst_value, value_error);
        // the gradient row's scale: its largest entry
        double row_scale = 0.0;
        for (int k = 0; k < dim; ++k) row_scale = std::max(row_scale, std::fabs(fj[c].v[k]));
        bool ok = value_error <= kRelValue;
        for (int k = 0; k < dim; ++k) {
          double e = std::fabs(grad[c * dim + k] - fj[c].v[k]) / row_scale;
          worst_grad = std::max(worst_grad, e);
          ok = ok && e <= kRelGrad;
          ++compared;
        }
        if (!ok && ++model_failures <= 10) {
          std::fprintf(stderr, "%s case %d channel %d: value C %.17g, Jet %.17g\n", m->code, i, c,
                       f[c], fj[c].a);
          for (int k = 0; k < dim; ++k) {
            char name[48];
            std::fprintf(stderr, "  d/d%-18s C %+.12e  Jet %+.12e\n",
                         cf_model_slot_name(model, k, name, sizeof name), grad[c * dim + k],
                         fj[c].v[k]);
          }
        }
      }
    }
    std::printf(
        "test_jet_clay: %d random %s cases, %ld derivatives compared with ceres::Jet; worst "
        "relative value difference %.3g (tolerance %.0e), worst gradient difference %.3g of "
        "the row's largest entry (tolerance %.0e); %ld failed\n",
        kCases, m->code, compared, worst_value, kRelValue, worst_grad, kRelGrad, model_failures);
    failures += model_failures;
  }
  return failures ? 1 : 0;
}
