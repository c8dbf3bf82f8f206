// An independent check of the C evaluator's M4 (clay): the model written a
// second time, only for this test, straight from MODEL.md's vector formulas
// (refracted direction vectors l', v', half vectors, the textbook forms of
// D and ON), templated on the scalar and differentiated by ceres::Jet
// (forward-mode automatic differentiation). Values and all 33 derivatives
// must agree with cf_eval's closed-form gradient.
#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

extern "C" {
#include "clayfit/model.h"
#include "core/rng.h"
}

namespace {

constexpr int kDim = CF_CLAY_DIM;
using Jet = ceres::Jet<double, kDim>;
constexpr double kPi = 3.14159265358979323846;

template <typename T>
struct Vec3 {
  T x, y, z;
};

template <typename T, typename U>
auto Dot(const Vec3<T> &a, const Vec3<U> &b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// Schlick (MODEL.md "Building blocks"), c clamped to [0, 1].
template <typename T, typename C>
T Fresnel(const T &f0, C c) {
  if (c > C(1.0)) c = C(1.0);
  if (c < C(0.0)) c = C(0.0);
  C m = C(1.0) - c;
  return f0 + (T(1.0) - f0) * (m * m * m * m * m);
}

template <typename T, typename C>
T GgxD(const T &alpha, const C &c_h) {
  T a2 = alpha * alpha;
  T q = (a2 - T(1.0)) * c_h * c_h + T(1.0);
  return a2 / (kPi * q * q);
}

template <typename T, typename C>
T SmithV(const T &alpha, const C &c_i, const C &c_o) {
  T a2 = alpha * alpha;
  return T(0.5) /
         (c_o * sqrt(c_i * c_i * (T(1.0) - a2) + a2) + c_i * sqrt(c_o * c_o * (T(1.0) - a2) + a2));
}

template <typename T, typename C>
T Specular(const T &f0, const T &r, const Vec3<C> &n, const Vec3<C> &l, const Vec3<C> &v) {
  Vec3<C> s{l.x + v.x, l.y + v.y, l.z + v.z};
  C len = sqrt(Dot(s, s));
  Vec3<C> h{s.x / len, s.y / len, s.z / len};
  return Fresnel(f0, len / 2.0) * GgxD(r * r, Dot(n, h)) * SmithV(r * r, Dot(n, l), Dot(n, v));
}

template <typename T, typename C>
T OrenNayar(const T &rho, const T &sigma, const Vec3<C> &n, const Vec3<C> &l, const Vec3<C> &v) {
  T s2 = sigma * sigma;
  T a = T(1.0) - 0.5 * s2 / (s2 + 0.33);
  T b = 0.45 * s2 / (s2 + 0.09);
  C c_i = Dot(n, l), c_o = Dot(n, v);
  C g = Dot(l, v) - c_i * c_o;
  C angular = g > C(0.0) ? g / (c_i > c_o ? c_i : c_o) : C(0.0);
  return rho / kPi * (a + b * angular);
}

// MODEL.md "M4: the two-layer clay model", steps 1-8, in vectors.
template <typename T>
void Clay(const T *p, const Vec3<double> &n, const Vec3<double> &l, const Vec3<double> &v, T f[3]) {
  const T sigma = p[CF_CLAY_DIFFUSE_ROUGHNESS];
  const T r1 = p[CF_CLAY_FILM_ROUGHNESS], f0_1 = p[CF_CLAY_FILM_F0];
  const T r2 = p[CF_CLAY_BASE_ROUGHNESS], f0_2 = p[CF_CLAY_BASE_F0];
  const double c_i = Dot(n, l), c_o = Dot(n, v);
  const Vec3<T> nt{T(n.x), T(n.y), T(n.z)};

  T top = Specular(f0_1, r1, n, l, v);
  T sq = sqrt(f0_1);
  T eta = (1.0 + sq) / (1.0 - sq);  // step 1
  T eta2_m1 = 4.0 * sq / ((1.0 - sq) * (1.0 - sq));
  T c_ip = sqrt(eta2_m1 + c_i * c_i) / eta;  // step 2
  T c_op = sqrt(eta2_m1 + c_o * c_o) / eta;
  Vec3<T> lp{(l.x - c_i * n.x) / eta + c_ip * n.x,  // step 3
             (l.y - c_i * n.y) / eta + c_ip * n.y, (l.z - c_i * n.z) / eta + c_ip * n.z};
  Vec3<T> vp{(v.x - c_o * n.x) / eta + c_op * n.x, (v.y - c_o * n.y) / eta + c_op * n.y,
             (v.z - c_o * n.z) / eta + c_op * n.z};
  T transmission = (1.0 - Fresnel(f0_1, c_i)) * (1.0 - Fresnel(f0_1, c_o));  // 4
  T fbar_e = f0_1 + (1.0 - f0_1) / 21.0;                                     // step 6
  T fbar_i = 1.0 - (1.0 - fbar_e) / (eta * eta);
  T base_specular = Specular(f0_2, r2, nt, lp, vp);  // step 7
  T base_transmission = (1.0 - Fresnel(f0_2, c_ip)) * (1.0 - Fresnel(f0_2, c_op));
  for (int c = 0; c < 3; ++c) {
    const T rho = p[CF_CLAY_ALBEDO + c], tau = p[CF_CLAY_OPTICAL_DEPTH + c];
    T absorption = exp(-tau * (1.0 / c_ip + 1.0 / c_op));  // step 5
    T k = 1.0 / (1.0 - rho * fbar_i * exp(-4.0 * tau));
    T base = base_specular + k * base_transmission * OrenNayar(rho, sigma, nt, lp, vp);
    f[c] = top + transmission * absorption * base / (eta * eta);  // step 8
  }
}

}  // namespace

int main() {
  cf_rng rng = cf_rng_seed(2718);
  const int kCases = 20000;
  const double kRelValue = 1e-10, kRelGrad = 1e-9;
  long failures = 0, compared = 0;
  double worst_value = 0.0, worst_grad = 0.0;
  for (int i = 0; i < kCases; ++i) {
    double params[kDim];
    const cf_model_info *m = cf_model_info_get(CF_MODEL_CLAY);
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
    cf_eval(CF_MODEL_CLAY, params, n, l, v, f, grad);
    Jet p[kDim], fj[3];
    for (int k = 0; k < kDim; ++k) p[k] = Jet(params[k], k);
    Clay(p, Vec3<double>{n[0], n[1], n[2]}, Vec3<double>{l[0], l[1], l[2]},
         Vec3<double>{v[0], v[1], v[2]}, fj);

    for (int c = 0; c < 3; ++c) {
      double value_error = std::fabs(f[c] - fj[c].a) / std::fabs(fj[c].a);
      worst_value = std::max(worst_value, value_error);
      // the gradient row's scale: its largest entry
      double row_scale = 0.0;
      for (int k = 0; k < kDim; ++k) row_scale = std::max(row_scale, std::fabs(fj[c].v[k]));
      bool ok = value_error <= kRelValue;
      for (int k = 0; k < kDim; ++k) {
        double e = std::fabs(grad[c * kDim + k] - fj[c].v[k]) / row_scale;
        worst_grad = std::max(worst_grad, e);
        ok = ok && e <= kRelGrad;
        ++compared;
      }
      if (!ok && ++failures <= 10) {
        std::fprintf(stderr, "case %d channel %d: value C %.17g, Jet %.17g\n", i, c, f[c], fj[c].a);
        for (int k = 0; k < kDim; ++k) {
          char name[48];
          std::fprintf(stderr, "  d/d%-18s C %+.12e  Jet %+.12e\n",
                       cf_model_slot_name(CF_MODEL_CLAY, k, name, sizeof name), grad[c * kDim + k],
                       fj[c].v[k]);
        }
      }
    }
  }
  std::printf(
      "test_jet_clay: %d random M4 cases, %ld derivatives compared with ceres::Jet; worst "
      "relative value difference %.3g (tolerance %.0e), worst gradient difference %.3g of "
      "the row's largest entry (tolerance %.0e); %ld failed\n",
      kCases, compared, worst_value, kRelValue, worst_grad, kRelGrad, failures);
  return failures ? 1 : 0;
}
