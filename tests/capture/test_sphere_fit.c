/* The sphere from silhouette rays (cf_sphere_from_silhouettes): synthetic
 * scenes of a known sphere seen by pinhole cameras on an orbit (COLMAP's
 * axes: x right, y down, z forward), its exact tangent rays projected to
 * pixels, optionally disturbed there, and cast back. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture/sphere_silhouette.h"
#include "core/rng.h"
#include "lsq/linalg.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PI 3.14159265358979323846
#define MAX_VIEWS 24
#define MAX_RAYS 640

static const double kCenter[3] = {0.3, -0.2, 1.1};
static const double kRadius = 0.25;
static const double kFocal = 800.0, kCx = 320.0, kCy = 240.0;

typedef struct scene {
  size_t num_views;
  cf_silhouette_view views[MAX_VIEWS];
  double rays[MAX_VIEWS][3 * MAX_RAYS];
} scene;

/* A copy whose views point at its own rays. */
static void copy_scene(scene *dst, const scene *src) {
  *dst = *src;
  for (size_t v = 0; v < dst->num_views; ++v) dst->views[v].rays = dst->rays[v];
}

static void normalize(double v[3]) {
  double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int k = 0; k < 3; ++k) v[k] /= n;
}

static void cross(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static double gaussian(cf_rng *rng) {
  double u = cf_rng_uniform(rng), v = cf_rng_uniform(rng);
  return sqrt(-2.0 * log(1.0 - u)) * cos(2.0 * PI * v);
}

/* One camera at `origin` looking at the sphere (world-to-camera rotation
 * rows: x right, y down, z forward with world "up" = −y... any up works).
 * Rays through `count` points of the silhouette, covering the arc
 * [phi0, phi0 + arc), disturbed by Gaussian pixel noise of sigma_px per
 * image axis. */
static void add_view(scene *s, const double origin[3], size_t count, double phi0, double arc,
                     double sigma_px, cf_rng *rng) {
  size_t v = s->num_views++;
  cf_silhouette_view *view = &s->views[v];
  double z[3] = {kCenter[0] - origin[0], kCenter[1] - origin[1], kCenter[2] - origin[2]};
  double distance = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
  normalize(z);
  double up[3] = {0.0, 0.0, 1.0}, x[3], y[3];
  cross(z, up, x); /* right */
  normalize(x);
  cross(z, x, y); /* down */
  /* the tangent cone around z: half angle asin(R / D) */
  double alpha = asin(kRadius / distance);
  for (size_t i = 0; i < count; ++i) {
    double phi = phi0 + arc * (double)i / (double)count;
    double cam[3] = {sin(alpha) * cos(phi), sin(alpha) * sin(phi), cos(alpha)};
    /* project (camera frame), add pixel noise, cast back */
    double u = kFocal * cam[0] / cam[2] + kCx + sigma_px * gaussian(rng);
    double w = kFocal * cam[1] / cam[2] + kCy + sigma_px * gaussian(rng);
    double back[3] = {(u - kCx) / kFocal, (w - kCy) / kFocal, 1.0};
    normalize(back);
    double *ray = s->rays[v] + 3 * i;
    for (int k = 0; k < 3; ++k) ray[k] = back[0] * x[k] + back[1] * y[k] + back[2] * z[k];
  }
  memcpy(view->origin, origin, sizeof view->origin);
  view->rays = s->rays[v];
  view->count = count;
  view->focal_px = kFocal;
}

/* num_views cameras on an orbit around the sphere, alternately above and
 * below its equator, at distances between 1.6 and 2.6. */
static void orbit(scene *s, size_t num_views, size_t rays, double arc, double sigma_px,
                  cf_rng *rng) {
  s->num_views = 0;
  for (size_t v = 0; v < num_views; ++v) {
    double theta = 2.0 * PI * (double)v / (double)num_views;
    double elevation = (v % 2 ? 0.35 : -0.2);
    double d = 1.6 + (double)(v % 3) * 0.5;
    double origin[3] = {kCenter[0] + d * cos(elevation) * cos(theta),
                        kCenter[1] + d * cos(elevation) * sin(theta),
                        kCenter[2] + d * sin(elevation)};
    add_view(s, origin, rays, 0.37 * (double)v, arc, sigma_px, rng);
  }
}

static double center_error(const cf_sphere_fit *fit) {
  double d[3] = {fit->center[0] - kCenter[0], fit->center[1] - kCenter[1],
                 fit->center[2] - kCenter[2]};
  return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

static void report(const char *what, const cf_sphere_fit *fit) {
  printf(
      "%-34s centre error %.3e R, radius error %.3e R, rms %.4f px, max %.4f px, %d iterations\n",
      what, center_error(fit) / kRadius, fabs(fit->radius - kRadius) / kRadius, fit->rms_px,
      fit->max_px, fit->iterations);
}

static void noise_free(cf_rng *rng) {
  static const size_t counts[] = {8, 16, 24};
  for (size_t c = 0; c < 3; ++c) {
    scene s;
    orbit(&s, counts[c], 48, 2.0 * PI, 0.0, rng);
    cf_sphere_fit fit;
    cf_error err = {0};
    cf_status st = cf_sphere_from_silhouettes(s.views, s.num_views, &fit, &err);
    CHECK(st == CF_OK, "%zu views: %s", counts[c], err.message);
    if (st != CF_OK) continue;
    char what[64];
    snprintf(what, sizeof what, "noise-free, %zu views:", counts[c]);
    report(what, &fit);
    CHECK(center_error(&fit) < 1e-9 * kRadius, "centre error %g", center_error(&fit));
    CHECK(fabs(fit.radius - kRadius) < 1e-9 * kRadius, "radius %.17g", fit.radius);
    CHECK(fit.rms_px < 1e-6 && fit.max_px < 1e-6, "rms %g max %g px", fit.rms_px, fit.max_px);
    CHECK(fit.iterations >= 1 && fit.iterations < 50, "iterations %d", fit.iterations);
  }
}

/* A ray is a line: negating some rays changes nothing. */
static void signs_ignored(cf_rng *rng) {
  scene s;
  orbit(&s, 8, 24, 2.0 * PI, 0.0, rng);
  for (size_t v = 0; v < s.num_views; ++v)
    for (size_t i = 0; i < s.views[v].count; i += 3)
      for (int k = 0; k < 3; ++k) s.rays[v][3 * i + k] = -s.rays[v][3 * i + k];
  cf_sphere_fit fit;
  cf_error err = {0};
  cf_status st = cf_sphere_from_silhouettes(s.views, s.num_views, &fit, &err);
  CHECK(st == CF_OK, "negated rays: %s", err.message);
  if (st != CF_OK) return;
  report("noise-free, every third ray negated:", &fit);
  CHECK(center_error(&fit) < 1e-9 * kRadius, "centre error %g", center_error(&fit));
  CHECK(fabs(fit.radius - kRadius) < 1e-9 * kRadius, "radius %.17g", fit.radius);
}

static void noisy(cf_rng *rng) {
  for (int trial = 0; trial < 5; ++trial) {
    scene s;
    orbit(&s, 16, 64, 2.0 * PI, 0.5, rng);
    cf_sphere_fit fit;
    cf_error err = {0};
    cf_status st = cf_sphere_from_silhouettes(s.views, s.num_views, &fit, &err);
    CHECK(st == CF_OK, "noisy: %s", err.message);
    if (st != CF_OK) continue;
    report("0.5 px noise, 16 views x 64 rays:", &fit);
    /* tolerances: centre within 0.5% of R, radius within 0.5%, rms within
     * 20% of the 0.5 px put in, max under 5 sigma */
    CHECK(center_error(&fit) < 0.005 * kRadius, "centre error %g R", center_error(&fit) / kRadius);
    CHECK(fabs(fit.radius - kRadius) < 0.005 * kRadius, "radius %g", fit.radius);
    CHECK(fit.rms_px > 0.4 && fit.rms_px < 0.6, "rms %g px, expected about 0.5", fit.rms_px);
    CHECK(fit.max_px > fit.rms_px && fit.max_px < 2.5, "max %g px", fit.max_px);
  }
}

static void two_views(cf_rng *rng) {
  for (int noise = 0; noise < 2; ++noise) {
    scene s = {0};
    double a[3] = {kCenter[0] + 2.0, kCenter[1], kCenter[2] + 0.3};
    double b[3] = {kCenter[0] - 0.4, kCenter[1] + 1.8, kCenter[2] - 0.2};
    add_view(&s, a, 40, 0.0, 2.0 * PI, noise ? 0.5 : 0.0, rng);
    add_view(&s, b, 40, 0.1, 2.0 * PI, noise ? 0.5 : 0.0, rng);
    cf_sphere_fit fit;
    cf_error err = {0};
    cf_status st = cf_sphere_from_silhouettes(s.views, s.num_views, &fit, &err);
    CHECK(st == CF_OK, "two views: %s", err.message);
    if (st != CF_OK) continue;
    report(noise ? "2 views, 0.5 px noise:" : "2 views, noise-free:", &fit);
    double tol = noise ? 0.01 : 1e-9; /* 1% of R with noise: 80 rays only */
    CHECK(center_error(&fit) < tol * kRadius, "centre error %g R", center_error(&fit) / kRadius);
    CHECK(fabs(fit.radius - kRadius) < tol * kRadius, "radius %.17g", fit.radius);
  }
}

/* How much the Gauss-Newton step from (C, R) would still lower the cost
 * ½ Σ (|(C − O) × d| − R)² over the scene's rays, as a fraction of that
 * cost: the Newton decrement ½ gᵀ (JᵀJ)⁻¹ g / cost, g = Jᵀr (HUGE_VAL when
 * JᵀJ is singular). Free of the scene's units and noise: a fit at the
 * least-squares minimum has it at rounding level. */
static double relative_decrement(const scene *s, const double center[3], double radius) {
  double jtj[16] = {0}, jtr[4] = {0}, step[4], cost = 0.0;
  for (size_t v = 0; v < s->num_views; ++v) {
    const cf_silhouette_view *view = &s->views[v];
    double w[3] = {center[0] - view->origin[0], center[1] - view->origin[1],
                   center[2] - view->origin[2]};
    for (size_t i = 0; i < view->count; ++i) {
      double d[3] = {view->rays[3 * i], view->rays[3 * i + 1], view->rays[3 * i + 2]};
      normalize(d);
      double wd = w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
      double p[3] = {w[0] - wd * d[0], w[1] - wd * d[1], w[2] - wd * d[2]};
      double distance = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      double g[4] = {p[0] / distance, p[1] / distance, p[2] / distance, -1.0};
      cost += 0.5 * (distance - radius) * (distance - radius);
      for (int j = 0; j < 4; ++j) {
        jtr[j] += g[j] * (distance - radius);
        for (int k = 0; k < 4; ++k) jtj[j * 4 + k] += g[j] * g[k];
      }
    }
  }
  if (!cf_cholesky_solve(4, jtj, jtr, step)) return HUGE_VAL;
  return 0.5 * (step[0] * jtr[0] + step[1] * jtr[1] + step[2] * jtr[2] + step[3] * jtr[3]) / cost;
}

/* The fit ends at the least-squares minimum, as far as the cost can tell:
 * a Gauss-Newton step from it would lower the cost by under 1e-13 of
 * itself (a solve that stopped where rounding errors of its own model hid
 * the last steps left 1e-11 of the cost, and 5e-8 R, on a real capture's
 * silhouettes). */
static void at_minimum(cf_rng *rng) {
  static const double sigma_px[] = {0.3, 1.0, 3.0};
  static scene s;
  for (int k = 0; k < 3; ++k) {
    orbit(&s, 12, MAX_RAYS, 2.0 * PI, sigma_px[k], rng);
    cf_sphere_fit fit;
    cf_error err = {0};
    cf_status st = cf_sphere_from_silhouettes(s.views, s.num_views, &fit, &err);
    CHECK(st == CF_OK, "%g px noise: %s", sigma_px[k], err.message);
    if (st != CF_OK) continue;
    double decrement = relative_decrement(&s, fit.center, fit.radius);
    printf(
        "%g px noise, 12 views x %d rays: a Gauss-Newton step from the fit would lower the "
        "cost by %.3g of itself\n",
        sigma_px[k], MAX_RAYS, decrement);
    CHECK(decrement < 1e-13, "%g px noise: the fit is not at the minimum (decrement %.3g)",
          sigma_px[k], decrement);
  }
}

static void degenerate(cf_rng *rng) {
  scene s;
  cf_sphere_fit fit;
  cf_error err = {0};
  orbit(&s, 8, 16, 2.0 * PI, 0.0, rng);

  /* one view */
  CHECK(cf_sphere_from_silhouettes(s.views, 1, &fit, &err) == CF_EINVAL, "1 view");
  printf("1 view: %s\n", err.message);
  CHECK(strstr(err.message, "at least 2 views") != NULL, "message: %s", err.message);

  /* too few rays in one view */
  scene t;
  copy_scene(&t, &s);
  t.views[3].count = 4;
  CHECK(cf_sphere_from_silhouettes(t.views, t.num_views, &fit, &err) == CF_EINVAL, "4 rays");
  printf("4 rays: %s\n", err.message);
  CHECK(strstr(err.message, "view 3") && strstr(err.message, "at least 5"), "message: %s",
        err.message);

  /* a NaN ray */
  copy_scene(&t, &s);
  t.rays[2][3 * 5 + 1] = NAN;
  CHECK(cf_sphere_from_silhouettes(t.views, t.num_views, &fit, &err) == CF_EINVAL, "NaN");
  printf("NaN ray: %s\n", err.message);
  CHECK(strstr(err.message, "view 2, ray 5") != NULL, "message: %s", err.message);

  /* no focal length */
  copy_scene(&t, &s);
  t.views[1].focal_px = 0.0;
  CHECK(cf_sphere_from_silhouettes(t.views, t.num_views, &fit, &err) == CF_EINVAL, "focal 0");
  CHECK(strstr(err.message, "focal") != NULL, "message: %s", err.message);

  /* all rays of each view identical (the central ray repeated) */
  copy_scene(&t, &s);
  for (size_t v = 0; v < t.num_views; ++v) {
    double axis[3] = {kCenter[0] - t.views[v].origin[0], kCenter[1] - t.views[v].origin[1],
                      kCenter[2] - t.views[v].origin[2]};
    normalize(axis);
    for (size_t i = 0; i < t.views[v].count; ++i) memcpy(t.rays[v] + 3 * i, axis, sizeof axis);
  }
  CHECK(cf_sphere_from_silhouettes(t.views, t.num_views, &fit, &err) == CF_ENUMERIC,
        "identical rays");
  printf("identical rays: %s\n", err.message);
  CHECK(strstr(err.message, "all point the same way") != NULL, "message: %s", err.message);
  /* ... also from a given start */
  double start[3] = {kCenter[0] + 0.01, kCenter[1], kCenter[2]};
  memset(&err, 0, sizeof err);
  CHECK(
      cf_sphere_refine_silhouettes(t.views, t.num_views, start, kRadius, &fit, &err) == CF_ENUMERIC,
      "identical rays, given start");
  printf("identical rays, given start: %s\n", err.message);
  CHECK(strstr(err.message, "all point the same way") != NULL, "message: %s", err.message);

  /* the same view twice: one cone, centres on one line with the sphere */
  copy_scene(&t, &s);
  t.views[1] = t.views[0];
  CHECK(cf_sphere_from_silhouettes(t.views, 2, &fit, &err) == CF_ENUMERIC, "same view twice");
  printf("same view twice: %s\n", err.message);
  CHECK(strstr(err.message, "do not constrain") != NULL, "message: %s", err.message);
  CHECK(cf_sphere_refine_silhouettes(t.views, 2, start, kRadius, &fit, &err) == CF_ENUMERIC,
        "same view twice, given start");
  printf("same view twice, given start: %s\n", err.message);
  CHECK(strstr(err.message, "singular") != NULL, "message: %s", err.message);

  /* a bad given start */
  CHECK(cf_sphere_refine_silhouettes(s.views, s.num_views, start, -1.0, &fit, &err) == CF_EINVAL,
        "negative start radius");
  CHECK(strstr(err.message, "positive radius") != NULL, "message: %s", err.message);
}

static void bad_start(cf_rng *rng) {
  scene s;
  orbit(&s, 12, 48, 2.0 * PI, 0.5, rng);
  static const double offsets[3][4] = {
      {0.6, -0.5, 0.3, 3.0}, /* centre 3.4 R away, radius ×3 */
      {-0.3, 0.4, -0.2, 0.2},
      {0.0, 0.0, 0.9, 1.5},
  };
  for (int k = 0; k < 3; ++k) {
    double c0[3] = {kCenter[0] + offsets[k][0], kCenter[1] + offsets[k][1],
                    kCenter[2] + offsets[k][2]};
    cf_sphere_fit fit;
    cf_error err = {0};
    cf_status st =
        cf_sphere_refine_silhouettes(s.views, s.num_views, c0, offsets[k][3] * kRadius, &fit, &err);
    CHECK(st == CF_OK, "bad start %d: %s", k, err.message);
    if (st != CF_OK) continue;
    report("bad start, 0.5 px noise:", &fit);
    CHECK(center_error(&fit) < 0.005 * kRadius, "centre error %g R", center_error(&fit) / kRadius);
    CHECK(fabs(fit.radius - kRadius) < 0.005 * kRadius, "radius %g", fit.radius);
  }
  /* half silhouettes: every view sees one side of the outline only, so
   * its central ray misses the centre and the closed-form start is off */
  orbit(&s, 12, 32, PI, 0.0, rng);
  cf_sphere_fit fit;
  cf_error err = {0};
  cf_status st = cf_sphere_from_silhouettes(s.views, s.num_views, &fit, &err);
  CHECK(st == CF_OK, "half silhouettes: %s", err.message);
  if (st == CF_OK) {
    report("half silhouettes, noise-free:", &fit);
    CHECK(center_error(&fit) < 1e-9 * kRadius, "centre error %g R", center_error(&fit) / kRadius);
    CHECK(fabs(fit.radius - kRadius) < 1e-9 * kRadius, "radius %.17g", fit.radius);
  }
}

static void orthographic_normals(void) {
  cf_ellipse circle = {100.5, 80.5, 20.0, 20.0, 0.0};
  double n[3];
  CHECK(cf_sphere_normal_orthographic(&circle, 100.5, 80.5, n) == 1, "centre");
  CHECK(n[0] == 0.0 && n[1] == 0.0 && n[2] == 1.0, "centre normal %g %g %g", n[0], n[1], n[2]);
  CHECK(cf_sphere_normal_orthographic(&circle, 110.5, 80.5, n) == 1, "right");
  CHECK(fabs(n[0] - 0.5) < 1e-15 && n[1] == 0.0 && fabs(n[2] - sqrt(0.75)) < 1e-15,
        "right normal %g %g %g", n[0], n[1], n[2]);
  /* y grows downward in the image, up in the normal's frame */
  CHECK(cf_sphere_normal_orthographic(&circle, 100.5, 70.5, n) == 1 && fabs(n[1] - 0.5) < 1e-15,
        "above the centre: ny %g", n[1]);
  CHECK(cf_sphere_normal_orthographic(&circle, 100.5, 101.0, n) == 0, "outside");
  cf_ellipse bad = {0, 0, 0, 0, 0};
  CHECK(cf_sphere_normal_orthographic(&bad, 0, 0, n) == 0, "zero radius");
}

int main(void) {
  cf_rng rng = cf_rng_seed(20240611);
  noise_free(&rng);
  signs_ignored(&rng);
  noisy(&rng);
  two_views(&rng);
  degenerate(&rng);
  bad_start(&rng);
  at_minimum(&rng);
  orthographic_normals();
  return check_finish("test_sphere_fit");
}
