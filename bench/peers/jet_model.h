// M2 (dielectric) and M4 (clay) written a second time, straight from
// the vector formulas of docs/model.md §3 (half vectors, refracted direction vectors
// l', v', the textbook forms of D and ON), templated on the scalar so that
// ceres::Jet differentiates them (forward-mode automatic differentiation)
// and ceres::NumericDiffCostFunction evaluates them in double. Independent
// of the C evaluator (src/model), which works in the geometric invariants
// of cf_geometry: tests/test_jet_clay.cpp checks one against the other, and
// the peers benchmark (clayfit-peers) uses this as the idiomatic Ceres
// model. Header-only, C++17.
#ifndef CLAYFIT_BENCH_PEERS_JET_MODEL_H
#define CLAYFIT_BENCH_PEERS_JET_MODEL_H

#include <cmath>

extern "C" {
#include "clayfit/model.h"
}

namespace clayfit_jet {

constexpr double kPi = 3.14159265358979323846;

template <typename T>
struct Vec3 {
  T x, y, z;
};

template <typename T, typename U>
auto Dot(const Vec3<T> &a, const Vec3<U> &b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// The exact unpolarised dielectric Fresnel (docs/model.md (8), model
// version 2), in the textbook form of Walter et al. 2007 eq. 22 with η
// from F0 (7): g = sqrt(η² − 1 + c²),
//   F = ½ (g − c)²/(g + c)² (1 + ((c (g + c) − 1)/(c (g − c) + 1))²).
// At F0 = 0 (η = 1) F is 0 and √F0's derivative infinite: F is returned
// as its first-order term (1 + (1 − 2c²)²)/(2c⁴) · F0, whose Jet carries
// the limit of ∂F/∂F0 (docs/model.md §2.1).
template <typename T, typename C>
T Fresnel(const T &f0, const C &c) {
  using std::sqrt;
  if (f0 == T(0.0)) {
    C m = 1.0 - 2.0 * c * c;
    return f0 * ((1.0 + m * m) / (2.0 * c * c * c * c));
  }
  T sq = sqrt(f0);
  T eta = (1.0 + sq) / (1.0 - sq);
  T g = sqrt(eta * eta - 1.0 + c * c);
  T a = (g - c) / (g + c);
  T b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  return 0.5 * a * a * (1.0 + b * b);
}

// Its cosine-weighted hemispherical mean ∫ F 2c dc for light from outside,
// in closed form (docs/model.md (27); Stern 1964), for η > 1.
template <typename T>
T FresnelMean(const T &eta) {
  using std::log;
  T e2 = eta * eta, e4 = e2 * e2;
  return 0.5 + (eta - 1.0) * (3.0 * eta + 1.0) / (6.0 * (eta + 1.0) * (eta + 1.0)) +
         e2 * (e2 - 1.0) * (e2 - 1.0) / ((e2 + 1.0) * (e2 + 1.0) * (e2 + 1.0)) *
             log((eta - 1.0) / (eta + 1.0)) -
         2.0 * e2 * eta * (e2 + 2.0 * eta - 1.0) / ((e2 + 1.0) * (e4 - 1.0)) +
         8.0 * e4 * (e4 + 1.0) / ((e2 + 1.0) * (e4 - 1.0) * (e4 - 1.0)) * log(eta);
}

template <typename T, typename C>
T GgxD(const T &alpha, const C &c_h) {
  T a2 = alpha * alpha;
  T q = (a2 - T(1.0)) * c_h * c_h + T(1.0);
  return a2 / (kPi * q * q);
}

template <typename T, typename C>
T SmithV(const T &alpha, const C &c_i, const C &c_o) {
  using std::sqrt;
  T a2 = alpha * alpha;
  return T(0.5) /
         (c_o * sqrt(c_i * c_i * (T(1.0) - a2) + a2) + c_i * sqrt(c_o * c_o * (T(1.0) - a2) + a2));
}

// S(F0, r; l, v) = F(F0, c_d) D(r², c_h) V(r²; c_i, c_o).
template <typename T, typename C>
T Specular(const T &f0, const T &r, const Vec3<C> &n, const Vec3<C> &l, const Vec3<C> &v) {
  using std::sqrt;
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

// docs/model.md (20), M2: S(F0, r) + (1 − F(F0, c_i))(1 − F(F0, c_o)) ON(ρ, σ).
template <typename T>
void Dielectric(const T *p, const Vec3<double> &n, const Vec3<double> &l, const Vec3<double> &v,
                T f[3]) {
  const T sigma = p[CF_DIELECTRIC_DIFFUSE_ROUGHNESS];
  const T r = p[CF_DIELECTRIC_ROUGHNESS], f0 = p[CF_DIELECTRIC_F0];
  const double c_i = Dot(n, l), c_o = Dot(n, v);
  T specular = Specular(f0, r, n, l, v);
  T transmission = (1.0 - Fresnel(f0, c_i)) * (1.0 - Fresnel(f0, c_o));
  for (int c = 0; c < 3; ++c)
    f[c] = specular + transmission * OrenNayar(p[CF_DIELECTRIC_ALBEDO + c], sigma, n, l, v);
}

// docs/model.md §3.5, M4's steps 1-8 ((22)-(30)), in vectors.
template <typename T>
void Clay(const T *p, const Vec3<double> &n, const Vec3<double> &l, const Vec3<double> &v, T f[3]) {
  using std::exp;
  using std::sqrt;
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
  T fbar_e = FresnelMean(eta);                                               // step 6
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

// The model `id` (M2 or M4) at one (n, l, v); f = 0 where the pair is not
// lit and seen (include/clayfit/model.h, "Conventions"). Returns 0 for a
// model this header does not have.
template <typename T>
int Eval(cf_model_id id, const T *p, const Vec3<double> &n, const Vec3<double> &l,
         const Vec3<double> &v, T f[3]) {
  const double c_i = Dot(n, l), c_o = Dot(n, v);
  if (!(c_i > 0.0 && c_o > 0.0 && c_i * c_o >= DBL_MIN)) {
    f[0] = f[1] = f[2] = T(0.0);
    return id == CF_MODEL_DIELECTRIC || id == CF_MODEL_CLAY;
  }
  if (id == CF_MODEL_DIELECTRIC) return Dielectric(p, n, l, v, f), 1;
  if (id == CF_MODEL_CLAY) return Clay(p, n, l, v, f), 1;
  return 0;
}

}  // namespace clayfit_jet

#endif  // CLAYFIT_BENCH_PEERS_JET_MODEL_H
