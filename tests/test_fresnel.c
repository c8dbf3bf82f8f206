/* The exact dielectric Fresnel of docs/model.md (8) and its hemispherical
 * mean (27), term by term (src/model/terms.h):
 *   - values against 40-digit references (mpmath, the textbook form of
 *     Walter et al. 2007 eq. 22 with η from (7)), to 1e-14;
 *   - F(0, c) == 0 exactly, F(F0, 1) == F0, F -> 1 at grazing;
 *   - ∂F/∂c and ∂F/∂F0 against central differences over the range, at
 *     F0 = 1e-6 and, at F0 = 0, the limit (1 + (1 − 2c²)²)/(2c⁴) against a
 *     one-sided difference extrapolated in √h (F = a F0 + b F0^{3/2} + ...:
 *     F is smooth in F0 but not twice differentiable at 0);
 *   - finite partials down to c = 1e-300;
 *   - the closed-form mean against 40-digit quadrature, to 1e-14, and its
 *     derivative against a central difference. */
#include <math.h>

#include "model/terms.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static cf_fresnel fresnel_at(double f0, double c) {
  cf_fresnel_eta e = fresnel_eta(f0);
  return fresnel_dielectric(&e, c, fresnel_root(&e, c));
}

/* {F0, c, F} computed with 40 digits (mpmath) from the textbook form. */
static const double reference[][3] = {
    {1e-6, 1e-3, 0.93865591348806628},  {1e-6, 0.1, 0.0069014681283549504},
    {1e-6, 0.5, 9.8578136655339466e-6}, {1e-6, 0.9, 1.0547510670171593e-6},
    {0.004, 1e-3, 0.99151319805461233}, {0.004, 0.1, 0.42951703542412465},
    {0.004, 0.5, 0.020051740353586469}, {0.004, 0.9, 0.0041609604548241978},
    {0.02, 1e-3, 0.99370325194522778},  {0.02, 0.1, 0.53882664133323903},
    {0.02, 0.5, 0.059018291507879972},  {0.02, 0.9, 0.02054140298343872},
    {0.04, 1e-3, 0.99420557250850128},  {0.04, 0.1, 0.5715925203424492},
    {0.04, 0.5, 0.089186712802212783},  {0.04, 0.9, 0.040791887937218349},
    {0.25, 1e-3, 0.99296973987150629},  {0.25, 0.1, 0.56795248785564893},
    {0.25, 0.5, 0.27180527968040226},   {0.25, 0.9, 0.25042132600852717},
};

/* {F0, ∫ F 2c dc} with 40 digits (mpmath quad of the textbook form). */
static const double mean_reference[][2] = {
    {0.01, 0.048166037914002776}, {0.02, 0.065840730314599047}, {0.04, 0.091777959342351212},
    {0.1, 0.15077707149308849},   {0.25, 0.27620340999750291},
};

static void check_values(void) {
  double worst = 0.0;
  for (size_t i = 0; i < sizeof reference / sizeof reference[0]; ++i) {
    double f = fresnel_at(reference[i][0], reference[i][1]).value, want = reference[i][2];
    double rel = fabs(f - want) / want;
    worst = fmax(worst, rel);
    CHECK(rel <= 1e-14, "F(%g, %g) = %.17g, reference %.17g", reference[i][0], reference[i][1], f,
          want);
  }
  printf("values: worst relative error against the references %.3g\n", worst);
  for (int j = 0; j <= 300; ++j) {
    double c = pow(10.0, -j);
    cf_fresnel z = fresnel_at(0.0, c);
    CHECK(z.value == 0.0 && z.transmission == 1.0 && z.d_c == 0.0,
          "F(0, %g) = %g, T = %g, dF/dc = %g (want exactly 0, 1, 0)", c, z.value, z.transmission,
          z.d_c);
    CHECK(isfinite(z.d_f0) && z.d_f0 > 0.0, "dF/dF0 at F0 = 0, c = %g: %g", c, z.d_f0);
    for (double f0 = 1e-12; f0 <= 0.25; f0 *= 3.0) {
      cf_fresnel f = fresnel_at(f0, c);
      CHECK(isfinite(f.value) && f.value >= 0.0 && f.value <= 1.0 + 4.0 * DBL_EPSILON &&
                f.transmission >= 0.0 && f.transmission <= 1.0 && isfinite(f.d_c) &&
                isfinite(f.d_f0),
            "F(%g, %g) = %.17g, T %g, dF/dc %g, dF/dF0 %g", f0, c, f.value, f.transmission, f.d_c,
            f.d_f0);
      CHECK(fabs(f.value + f.transmission - 1.0) <= 16.0 * DBL_EPSILON,
            "F(%g, %g) = %.17g + T %.17g != 1", f0, c, f.value, f.transmission);
    }
  }
  for (double f0 = 0.0; f0 <= 0.25; f0 += 0.01) {
    double at_normal = fresnel_at(f0, 1.0).value;
    CHECK(fabs(at_normal - f0) <= 1e-15, "F(%g, 1) = %.17g != F0", f0, at_normal);
    if (f0 > 0.0) {
      double grazing = fresnel_at(f0, 1e-12).value;
      CHECK(fabs(grazing - 1.0) <= 1e-10, "F(%g, 1e-12) = %.17g, not 1", f0, grazing);
    }
  }
}

/* |a − b| <= tol max(|a|, |b|, floor) */
static int close_to(double a, double b, double tol, double floor) {
  return fabs(a - b) <= tol * fmax(fmax(fabs(a), fabs(b)), floor);
}

static void check_derivatives(void) {
  double worst_c = 0.0, worst_f0 = 0.0, worst_zero = 0.0;
  static const double f0s[] = {1e-6, 1e-4, 0.004, 0.02, 0.04, 0.1, 0.17, 0.2499};
  for (size_t i = 0; i < sizeof f0s / sizeof f0s[0]; ++i) {
    for (double c = 0.005; c < 0.9999; c *= 1.25) {
      double f0 = f0s[i];
      cf_fresnel f = fresnel_at(f0, c);
      double hc = 1e-6 * c;
      double fd_c = (fresnel_at(f0, c + hc).value - fresnel_at(f0, c - hc).value) / (2.0 * hc);
      double hf = 1e-4 * f0;
      double fd_f0 = (fresnel_at(f0 + hf, c).value - fresnel_at(f0 - hf, c).value) / (2.0 * hf);
      worst_c = fmax(worst_c, fabs(f.d_c - fd_c) / fmax(fabs(f.d_c), 1e-12));
      worst_f0 = fmax(worst_f0, fabs(f.d_f0 - fd_f0) / fmax(fabs(f.d_f0), f.value / f0));
      CHECK(close_to(f.d_c, fd_c, 1e-7, 1e-12), "dF/dc at (%g, %g): %.12g, fd %.12g", f0, c, f.d_c,
            fd_c);
      /* scale F/F0: ∂F/∂F0 changes sign at some (F0, c) */
      CHECK(close_to(f.d_f0, fd_f0, 1e-7, f.value / f0), "dF/dF0 at (%g, %g): %.12g, fd %.12g", f0,
            c, f.d_f0, fd_f0);
    }
  }
  /* F0 = 0: D(h) = F(h)/h = a + b√h + O(h), so 2 D(h/4) − D(h) = a + O(h).
   * The expansion holds where (η² − 1)/c² = 4√h/c² is small. */
  for (double c = 0.3; c <= 1.0; c += 0.05) {
    double h = 1e-10;
    double d1 = fresnel_at(h, c).value / h, d4 = fresnel_at(0.25 * h, c).value / (0.25 * h);
    double limit = 2.0 * d4 - d1;
    cf_fresnel z = fresnel_at(0.0, c);
    double cl = c * c, m = 1.0 - 2.0 * cl;
    double closed = (1.0 + m * m) / (2.0 * cl * cl);
    worst_zero = fmax(worst_zero, fabs(z.d_f0 - limit) / z.d_f0);
    CHECK(close_to(z.d_f0, limit, 1e-6, 0.0), "dF/dF0 at F0 = 0, c = %g: %.12g, extrapolated %.12g",
          c, z.d_f0, limit);
    CHECK(close_to(z.d_f0, closed, 1e-15, 0.0), "dF/dF0 at F0 = 0, c = %g: %.17g, closed %.17g", c,
          z.d_f0, closed);
    /* continuity: the positive branch tends to the limit */
    cf_fresnel tiny = fresnel_at(1e-20, c);
    CHECK(close_to(tiny.d_f0, z.d_f0, 1e-8, 0.0), "dF/dF0 at F0 = 1e-20, c = %g: %.17g, at 0 %.17g",
          c, tiny.d_f0, z.d_f0);
  }
  printf(
      "derivatives: worst relative difference from central differences: d/dc %.3g, d/dF0 %.3g; "
      "at F0 = 0 from the extrapolated one-sided difference %.3g\n",
      worst_c, worst_f0, worst_zero);
}

static void check_mean(void) {
  double worst = 0.0, worst_d = 0.0;
  for (size_t i = 0; i < sizeof mean_reference / sizeof mean_reference[0]; ++i) {
    double f0 = mean_reference[i][0], s = sqrt(f0), eta = (1.0 + s) / (1.0 - s);
    cf_fresnel_mean m = fresnel_dielectric_mean(eta);
    double rel = fabs(m.value - mean_reference[i][1]) / mean_reference[i][1];
    worst = fmax(worst, rel);
    CHECK(rel <= 1e-14, "mean F at F0 %g: %.17g, quadrature %.17g", f0, m.value,
          mean_reference[i][1]);
  }
  for (double f0 = 0.01; f0 <= 0.25; f0 += 0.02) {
    double s = sqrt(f0), eta = (1.0 + s) / (1.0 - s), h = 1e-5 * eta;
    cf_fresnel_mean m = fresnel_dielectric_mean(eta);
    double fd =
        (fresnel_dielectric_mean(eta + h).value - fresnel_dielectric_mean(eta - h).value) / (2 * h);
    worst_d = fmax(worst_d, fabs(m.d_eta - fd) / fabs(m.d_eta));
    CHECK(close_to(m.d_eta, fd, 1e-8, 0.0), "d mean / d eta at F0 %g: %.12g, fd %.12g", f0, m.d_eta,
          fd);
  }
  printf("hemispherical mean: worst relative error %.3g, derivative %.3g\n", worst, worst_d);
}

int main(void) {
  check_values();
  check_derivatives();
  check_mean();
  return check_finish("test_fresnel");
}
