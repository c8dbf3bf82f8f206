/* The exact reductions of docs/model.md §4.5: M2 with F0 = 0 is M1 (the exact
 * Fresnel vanishes there, model version 2; under Schlick's it did not);
 * M1 with σ = 0 is M0; M3 with w_c = 0 is
 * M2; M4 with τ = 0 has a = 1; M4 with τ large (exp underflows) is its top
 * specular S(F0_1, r1; l, v), which M2 with ρ = 0 computes independently. */
#include <math.h>
#include <string.h>

#include "model/models.h"
#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { CASES = 20000, MAX_GEOMETRIES = 512 };

/* |a − b| <= 1e-14 |b| (the ladder's nesting; measured: equal to the bit) */
static int nested(double a, double b) {
  return fabs(a - b) <= 1e-14 * fabs(b);
}

/* M2(F0 = 0) == M1 and M1(σ = 0) == M0 at one geometry, with M2's
 * parameters `m2` (F0 and, for the second, σ overwritten). Returns the
 * number of values not equal to the bit. */
static int check_ladder(const char *set, long i, const double *m2_in, const double n[3],
                        const double l[3], const double v[3]) {
  double m2[CF_DIELECTRIC_DIM], f_m2[3], f_m1[3], f_m0[3];
  for (int k = 0; k < CF_DIELECTRIC_DIM; ++k) m2[k] = m2_in[k];
  m2[CF_DIELECTRIC_F0] = 0.0;
  _Static_assert((int)CF_DIELECTRIC_ALBEDO == (int)CF_OREN_NAYAR_ALBEDO &&
                     (int)CF_DIELECTRIC_DIFFUSE_ROUGHNESS == (int)CF_OREN_NAYAR_DIFFUSE_ROUGHNESS,
                 "M2's vector starts with M1's");
  cf_eval(CF_MODEL_DIELECTRIC, m2, n, l, v, f_m2, NULL);
  cf_eval(CF_MODEL_OREN_NAYAR, m2, n, l, v, f_m1, NULL);
  int not_bitwise = 0;
  for (int c = 0; c < 3; ++c) {
    CHECK(nested(f_m2[c], f_m1[c]), "%s case %ld: M2(f0=0) %.17g != M1 %.17g (r %g, sigma %g)", set,
          i, f_m2[c], f_m1[c], m2[CF_DIELECTRIC_ROUGHNESS], m2[CF_DIELECTRIC_DIFFUSE_ROUGHNESS]);
    not_bitwise += f_m2[c] != f_m1[c];
  }
  m2[CF_DIELECTRIC_DIFFUSE_ROUGHNESS] = 0.0;
  cf_eval(CF_MODEL_OREN_NAYAR, m2, n, l, v, f_m1, NULL);
  cf_eval(CF_MODEL_LAMBERT, m2, n, l, v, f_m0, NULL);
  cf_eval(CF_MODEL_DIELECTRIC, m2, n, l, v, f_m2, NULL);
  for (int c = 0; c < 3; ++c) {
    CHECK(nested(f_m1[c], f_m0[c]), "%s case %ld: M1(sigma=0) %.17g != M0 %.17g", set, i, f_m1[c],
          f_m0[c]);
    CHECK(nested(f_m2[c], f_m0[c]), "%s case %ld: M2(f0=0, sigma=0) %.17g != M0 %.17g", set, i,
          f_m2[c], f_m0[c]);
    not_bitwise += (f_m1[c] != f_m0[c]) + (f_m2[c] != f_m0[c]);
  }
  return not_bitwise;
}

/* The ladder's nesting over the hard geometries of §4.1 with random
 * parameters (roughness and albedo at their bounds among them). */
static long ladder_on_hard_geometries(cf_rng *rng) {
  static double n[MAX_GEOMETRIES][3], l[MAX_GEOMETRIES][3], v[MAX_GEOMETRIES][3];
  size_t count = hard_geometries(n, l, v, MAX_GEOMETRIES);
  long not_bitwise = 0;
  for (int rep = 0; rep < 20; ++rep) {
    double m2[CF_DIELECTRIC_DIM];
    random_params(rng, CF_MODEL_DIELECTRIC, 0.3, m2);
    for (size_t i = 0; i < count; ++i)
      not_bitwise += check_ladder("hard", (long)(rep * count + i), m2, n[i], l[i], v[i]);
  }
  return not_bitwise;
}

int main(void) {
  cf_rng rng = cf_rng_seed(77);
  long lit = 0, not_bitwise = 0;
  double worst_top = 0.0;
  for (int i = 0; i < CASES; ++i) {
    double n[3], l[3], v[3];
    random_directions(&rng, 0.1, 0.02, n, l, v);
    cf_geometry g = cf_geometry_from_directions(n, l, v);
    lit += cf_geometry_is_lit(&g);

    /* M1(σ = 0) == M0, to the bit */
    double on[CF_OREN_NAYAR_DIM], f_on[3], f_l[3];
    random_params(&rng, CF_MODEL_OREN_NAYAR, 0.1, on);
    on[CF_OREN_NAYAR_DIFFUSE_ROUGHNESS] = 0.0;
    cf_eval(CF_MODEL_OREN_NAYAR, on, n, l, v, f_on, NULL);
    cf_eval(CF_MODEL_LAMBERT, on, n, l, v, f_l, NULL); /* albedo is slot 0 in both */
    for (int c = 0; c < 3; ++c)
      CHECK(f_on[c] == f_l[c], "case %d: M1(sigma=0) %.17g != M0 %.17g", i, f_on[c], f_l[c]);

    /* M2(F0 = 0) == M1, M1(σ = 0) == M0 (and M2 at both == M0), to 1e-14 */
    double dielectric[CF_DIELECTRIC_DIM];
    random_params(&rng, CF_MODEL_DIELECTRIC, 0.1, dielectric);
    not_bitwise += check_ladder("random", i, dielectric, n, l, v);

    /* M3(w_c = 0) == M2, to the bit */
    double cc[CF_CLEARCOAT_DIM], f_cc[3], f_d[3];
    random_params(&rng, CF_MODEL_CLEARCOAT, 0.1, cc);
    cc[CF_CLEARCOAT_COAT_WEIGHT] = 0.0;
    cf_eval(CF_MODEL_CLEARCOAT, cc, n, l, v, f_cc, NULL);
    cf_eval(CF_MODEL_DIELECTRIC, cc, n, l, v, f_d, NULL); /* M3 extends M2's vector */
    for (int c = 0; c < 3; ++c)
      CHECK(f_cc[c] == f_d[c], "case %d: M3(w_c=0) %.17g != M2 %.17g", i, f_cc[c], f_d[c]);

    /* M4(τ = 0): a = 1 and f = top + T T base / η1² */
    double clay[CF_CLAY_DIM], f_clay[3];
    random_params(&rng, CF_MODEL_CLAY, 0.1, clay);
    for (int c = 0; c < 3; ++c) clay[CF_CLAY_OPTICAL_DEPTH + c] = 0.0;
    cf_clay_terms t;
    cf_clay_terms_eval(clay, &g, &t);
    cf_eval(CF_MODEL_CLAY, clay, n, l, v, f_clay, NULL);
    if (cf_geometry_is_lit(&g)) {
      for (int c = 0; c < 3; ++c) {
        CHECK(t.absorption[c] == 1.0, "case %d: tau = 0 but a = %.17g", i, t.absorption[c]);
        double expected = t.top + t.transmission * t.inv_eta2 * t.base[c];
        CHECK(fabs(f_clay[c] - expected) <= 1e-15 * expected,
              "case %d: M4(tau=0) %.17g != top + T T base/eta^2 %.17g", i, f_clay[c], expected);
      }
    }

    /* M4(τ >= 400) == S(F0_1, r1; l, v) == M2(ρ = 0, F0 = F0_1, r = r1) */
    static const double large_tau[] = {400.0, 1e3};
    for (int j = 0; j < 2; ++j) {
      for (int c = 0; c < 3; ++c) clay[CF_CLAY_OPTICAL_DEPTH + c] = large_tau[j];
      double m2[CF_DIELECTRIC_DIM] = {0.0,
                                      0.0,
                                      0.0,
                                      clay[CF_CLAY_DIFFUSE_ROUGHNESS],
                                      clay[CF_CLAY_FILM_ROUGHNESS],
                                      clay[CF_CLAY_FILM_F0]};
      double f_top[3];
      cf_eval(CF_MODEL_CLAY, clay, n, l, v, f_clay, NULL);
      cf_eval(CF_MODEL_DIELECTRIC, m2, n, l, v, f_top, NULL);
      for (int c = 0; c < 3; ++c) {
        double diff = fabs(f_clay[c] - f_top[c]);
        if (f_top[c] > 0.0) worst_top = fmax(worst_top, diff / f_top[c]);
        CHECK(diff <= 1e-300 + 1e-14 * f_top[c], "case %d: M4(tau=%g) %.17g != top specular %.17g",
              i, large_tau[j], f_clay[c], f_top[c]);
      }
    }
  }
  not_bitwise += ladder_on_hard_geometries(&rng);
  printf(
      "%d cases (%ld lit); M4 at large tau vs M2(rho=0): worst relative "
      "difference %.3g; ladder M2(f0=0) = M1, M1(sigma=0) = M0: %ld values not equal to the "
      "bit (within 1e-14)\n",
      CASES, lit, worst_top, not_bitwise);
  return check_finish("test_reductions");
}
