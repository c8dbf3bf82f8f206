/* COLMAP's camera models: for every model with realistic, non-trivial
 * distortion, unprojection undoes projection to 1e-6 px over the whole
 * image and for random rays in the field of view; projection agrees with
 * the models' formulas written out independently here (from the
 * definitions cited in camera_models.h: OpenCV's pinhole and fisheye
 * models, Devernay & Faugeras' FOV model, Weng et al.'s thin prism); and
 * the checks reject bad cameras with messages that say why. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/colmap.h"
#include "core/rng.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static const double pi = 3.14159265358979323846;

typedef struct test_camera {
  const char *label;
  cf_camera camera;
} test_camera;

static cf_camera make_camera(cf_camera_model model, const double *params) {
  cf_camera c = {0};
  c.camera_id = 1 + (uint32_t)model;
  c.model = model;
  c.width = 1600;
  c.height = 1200;
  c.num_params = cf_camera_model_param_count(model);
  for (int k = 0; k < c.num_params; ++k) c.params[k] = params[k];
  return c;
}

/* ---- the reference projection: the models' definitions, written from the
 * ray (θ from atan2, so independent of COLMAP's p = (X/Z, Y/Z) route) ---- */

/* OpenCV's radial-tangential distortion of a point (a, b) on a plane. */
static void radial_tangential(double a, double b, double radial, double p1, double p2, double *x,
                              double *y) {
  double r2 = a * a + b * b;
  *x = a * radial + 2 * p1 * a * b + p2 * (r2 + 2 * a * a);
  *y = b * radial + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b;
}

static void reference_project(const cf_camera *c, const double X[3], double uv[2]) {
  const double *p = c->params;
  /* "f, cx, cy, ..." or "fx, fy, cx, cy, ..." */
  const int single = c->model == CF_CAMERA_SIMPLE_PINHOLE || c->model == CF_CAMERA_SIMPLE_RADIAL ||
                     c->model == CF_CAMERA_RADIAL || c->model == CF_CAMERA_SIMPLE_RADIAL_FISHEYE ||
                     c->model == CF_CAMERA_RADIAL_FISHEYE;
  const double fx = p[0], fy = single ? p[0] : p[1];
  const double cx = single ? p[1] : p[2], cy = single ? p[2] : p[3];
  const double *k = single ? p + 3 : p + 4;
  double a = X[0] / X[2], b = X[1] / X[2], r2 = a * a + b * b;
  double rho = hypot(X[0], X[1]), theta = atan2(rho, X[2]);
  double dir[2] = {rho > 0 ? X[0] / rho : 0, rho > 0 ? X[1] / rho : 0};
  double x = a, y = b;
  switch (c->model) {
    case CF_CAMERA_SIMPLE_PINHOLE:
    case CF_CAMERA_PINHOLE:
      break;
    case CF_CAMERA_SIMPLE_RADIAL:
      radial_tangential(a, b, 1 + k[0] * r2, 0, 0, &x, &y);
      break;
    case CF_CAMERA_RADIAL:
      radial_tangential(a, b, 1 + k[0] * r2 + k[1] * r2 * r2, 0, 0, &x, &y);
      break;
    case CF_CAMERA_OPENCV:
      radial_tangential(a, b, 1 + k[0] * r2 + k[1] * r2 * r2, k[2], k[3], &x, &y);
      break;
    case CF_CAMERA_FULL_OPENCV: {
      double r4 = r2 * r2, r6 = r4 * r2;
      double radial =
          (1 + k[0] * r2 + k[1] * r4 + k[4] * r6) / (1 + k[5] * r2 + k[6] * r4 + k[7] * r6);
      radial_tangential(a, b, radial, k[2], k[3], &x, &y);
      break;
    }
    case CF_CAMERA_OPENCV_FISHEYE:
    case CF_CAMERA_SIMPLE_RADIAL_FISHEYE:
    case CF_CAMERA_RADIAL_FISHEYE: {
      /* θd = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸), along the ray's azimuth */
      int n = c->model == CF_CAMERA_OPENCV_FISHEYE   ? 4
              : c->model == CF_CAMERA_RADIAL_FISHEYE ? 2
                                                     : 1;
      double poly = 1, power = 1;
      for (int j = 0; j < n; ++j) {
        power *= theta * theta;
        poly += k[j] * power;
      }
      x = theta * poly * dir[0];
      y = theta * poly * dir[1];
      break;
    }
    case CF_CAMERA_FOV: {
      /* r_d = atan(2 r tan(ω/2)) / ω. For ω² < 1e-4 COLMAP 3.8's
       * FOVCameraModel::Distortion uses r_d/r = 1 + ω² (r²/3 − 1/12), the
       * expansion of its Undistortion (the true one is 1 − ω² (r²/3 −
       * 1/12)); clayfit follows COLMAP, so the reference does too. */
      double r = sqrt(r2), w = k[0];
      double rd =
          w * w < 1e-4 ? r * (1 + w * w * (r2 / 3 - 1.0 / 12)) : atan(2 * r * tan(w / 2)) / w;
      x = rd * dir[0];
      y = rd * dir[1];
      break;
    }
    case CF_CAMERA_THIN_PRISM_FISHEYE: {
      /* equidistant point q = θ dir, then radial (k1 k2 k3 k4 on r², r⁴, r⁶,
       * r⁸), tangential (p1 p2) and thin prism (sx1 sy1) terms */
      double qa = theta * dir[0], qb = theta * dir[1], s2 = qa * qa + qb * qb;
      double radial =
          1 + k[0] * s2 + k[1] * s2 * s2 + k[4] * s2 * s2 * s2 + k[5] * s2 * s2 * s2 * s2;
      radial_tangential(qa, qb, radial, k[2], k[3], &x, &y);
      x += k[6] * s2;
      y += k[7] * s2;
      break;
    }
    default:
      break;
  }
  uv[0] = fx * x + cx;
  uv[1] = fy * y + cy;
}

/* ---- round trips ---- */

static double norm3(const double v[3]) {
  return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* Unproject then project one pixel: its error, or -1 when it fails. */
static double pixel_round_trip(const test_camera *t, const double uv[2], double *theta) {
  double ray[3], back[2];
  if (!cf_camera_unproject(&t->camera, uv, ray) || !cf_camera_project(&t->camera, ray, back))
    return -1;
  CHECK(fabs(norm3(ray) - 1) < 1e-14 && ray[2] > 0, "%s: ray of (%g, %g) not unit: %.17g", t->label,
        uv[0], uv[1], norm3(ray));
  *theta = atan2(hypot(ray[0], ray[1]), ray[2]);
  return hypot(back[0] - uv[0], back[1] - uv[1]);
}

/* Every 4th pixel centre (with the last row and column) and the image's
 * outer corners and edge midpoints: returns the worst pixel error;
 * *max_theta gets the widest angle seen. */
static double grid_round_trip(const test_camera *t, double *max_theta) {
  const double w = (double)t->camera.width, h = (double)t->camera.height;
  double worst = 0, theta;
  long failures = 0, count = 0;
  *max_theta = 0;
  for (double v = 0.5; v < h + 4; v += 4) {
    for (double u = 0.5; u < w + 4; u += 4) {
      double uv[2] = {fmin(u, w - 0.5), fmin(v, h - 0.5)};
      double e = pixel_round_trip(t, uv, &theta);
      ++count;
      if (e < 0) {
        if (++failures <= 3)
          CHECK(0, "%s: pixel (%g, %g) does not round trip", t->label, uv[0], uv[1]);
        continue;
      }
      if (!(e <= worst)) worst = e;
      if (theta > *max_theta) *max_theta = theta;
    }
  }
  const double outer[8][2] = {{0, 0},     {w, 0},     {0, h},     {w, h},
                              {w / 2, 0}, {w / 2, h}, {0, h / 2}, {w, h / 2}};
  for (int k = 0; k < 8; ++k) {
    double e = pixel_round_trip(t, outer[k], &theta);
    ++count;
    if (e < 0) {
      ++failures;
      CHECK(0, "%s: image corner/edge (%g, %g) does not round trip", t->label, outer[k][0],
            outer[k][1]);
      continue;
    }
    if (!(e <= worst)) worst = e;
    if (theta > *max_theta) *max_theta = theta;
  }
  CHECK(failures == 0, "%s: %ld of %ld pixels fail to unproject", t->label, failures, count);
  return worst;
}

/* Random rays within max_theta whose projection lands in the image:
 * project, unproject, project. Returns the worst pixel error; *ray_error
 * the worst distance between the ray and its unprojection. */
static double random_ray_round_trip(const test_camera *t, double max_theta, cf_rng *rng,
                                    double *ray_error, long *kept) {
  const cf_camera *c = &t->camera;
  double worst = 0;
  *ray_error = 0;
  *kept = 0;
  for (long tries = 0; tries < 200000 && *kept < 3000; ++tries) {
    double theta = max_theta * sqrt(cf_rng_uniform(rng)), phi = cf_rng_range(rng, 0, 2 * pi);
    double ray[3] = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
    double uv[2], ray2[3], back[2];
    if (!cf_camera_project(c, ray, uv)) continue;
    if (uv[0] < 0 || uv[1] < 0 || uv[0] > (double)c->width || uv[1] > (double)c->height) continue;
    ++*kept;
    if (!cf_camera_unproject(c, uv, ray2) || !cf_camera_project(c, ray2, back)) {
      CHECK(0, "%s: ray (%g, %g, %g) at (%g, %g) does not round trip", t->label, ray[0], ray[1],
            ray[2], uv[0], uv[1]);
      continue;
    }
    double e = hypot(back[0] - uv[0], back[1] - uv[1]);
    double d =
        sqrt((ray2[0] - ray[0]) * (ray2[0] - ray[0]) + (ray2[1] - ray[1]) * (ray2[1] - ray[1]) +
             (ray2[2] - ray[2]) * (ray2[2] - ray[2]));
    if (!(e <= worst)) worst = e;
    if (!(d <= *ray_error)) *ray_error = d;
  }
  return worst;
}

/* Projection against the reference at random rays in the image. */
static double reference_error(const test_camera *t, double max_theta, cf_rng *rng) {
  double worst = 0;
  for (int n = 0; n < 500; ++n) {
    double theta = max_theta * sqrt(cf_rng_uniform(rng)), phi = cf_rng_range(rng, 0, 2 * pi);
    double depth = cf_rng_range(rng, 0.5, 20);
    double X[3] = {depth * sin(theta) * cos(phi), depth * sin(theta) * sin(phi),
                   depth * cos(theta)};
    double uv[2], ref[2];
    if (!cf_camera_project(&t->camera, X, uv)) {
      CHECK(0, "%s: projection of a point in front fails", t->label);
      continue;
    }
    reference_project(&t->camera, X, ref);
    double e = hypot(uv[0] - ref[0], uv[1] - ref[1]);
    if (!(e <= worst)) worst = e;
  }
  return worst;
}

static void round_trips(void) {
  /* 1600 x 1200 images; the fisheye ones see up to ~75° off axis */
  static const double simple_pinhole[] = {1400, 800.3, 599.7};
  static const double pinhole[] = {1400, 1410, 801.2, 598.4};
  static const double simple_radial[] = {1400, 800.3, 599.7, -0.08};
  static const double radial[] = {1400, 800.3, 599.7, -0.1, 0.02};
  static const double opencv[] = {1400, 1405, 802, 597, -0.12, 0.05, 0.001, -0.0015};
  static const double opencv_fisheye[] = {700, 702, 800.5, 600.5, 0.05, -0.01, 0.002, -0.0003};
  static const double full_opencv[] = {1400, 1405,  802,   597,  -0.2,  0.08,
                                       8e-4, -5e-4, -0.01, 0.05, -0.01, 0.002};
  static const double fov[] = {900, 902, 799.5, 600.2, 0.9};
  static const double fov_small_omega[] = {1400, 1401, 799.5, 600.2, 0.005};
  static const double simple_radial_fisheye[] = {700, 800, 600, 0.03};
  static const double radial_fisheye[] = {700, 800, 600, 0.04, -0.005};
  static const double thin_prism[] = {700,  702,   800.5, 600.5, 0.03, -0.006,
                                      5e-4, -4e-4, 8e-4,  -1e-4, 6e-4, -5e-4};
  const test_camera cameras[] = {
      {"SIMPLE_PINHOLE", make_camera(CF_CAMERA_SIMPLE_PINHOLE, simple_pinhole)},
      {"PINHOLE", make_camera(CF_CAMERA_PINHOLE, pinhole)},
      {"SIMPLE_RADIAL", make_camera(CF_CAMERA_SIMPLE_RADIAL, simple_radial)},
      {"RADIAL", make_camera(CF_CAMERA_RADIAL, radial)},
      {"OPENCV", make_camera(CF_CAMERA_OPENCV, opencv)},
      {"OPENCV_FISHEYE", make_camera(CF_CAMERA_OPENCV_FISHEYE, opencv_fisheye)},
      {"FULL_OPENCV", make_camera(CF_CAMERA_FULL_OPENCV, full_opencv)},
      {"FOV", make_camera(CF_CAMERA_FOV, fov)},
      {"FOV (small omega)", make_camera(CF_CAMERA_FOV, fov_small_omega)},
      {"SIMPLE_RADIAL_FISHEYE",
       make_camera(CF_CAMERA_SIMPLE_RADIAL_FISHEYE, simple_radial_fisheye)},
      {"RADIAL_FISHEYE", make_camera(CF_CAMERA_RADIAL_FISHEYE, radial_fisheye)},
      {"THIN_PRISM_FISHEYE", make_camera(CF_CAMERA_THIN_PRISM_FISHEYE, thin_prism)},
  };
  int covered[CF_CAMERA_MODEL_COUNT] = {0};
  cf_rng rng = cf_rng_seed(20240611);
  printf("%-22s %12s %12s %12s %12s %8s %10s\n", "model", "grid px", "rays px", "ray dist",
         "vs formula", "rays", "max angle");
  for (size_t n = 0; n < sizeof cameras / sizeof cameras[0]; ++n) {
    const test_camera *t = &cameras[n];
    cf_error err = {0};
    CHECK(cf_camera_check(&t->camera, &err) == CF_OK, "%s: %s", t->label, err.message);
    covered[t->camera.model] = 1;
    double max_theta, ray_error;
    long kept;
    double grid = grid_round_trip(t, &max_theta);
    double rays = random_ray_round_trip(t, max_theta, &rng, &ray_error, &kept);
    /* FOV with small ω: COLMAP's Taylor expansion in ω, not the formula */
    double formula = reference_error(t, max_theta, &rng);
    /* (FOV: COLMAP's Taylor branch for r² < 1e-4 approximates the formula
     * to ~1e-8 px) */
    double formula_tolerance = t->camera.model == CF_CAMERA_FOV ? 1e-7 : 1e-9;
    printf("%-22s %12.3g %12.3g %12.3g %12.3g %8ld %9.1f°\n", t->label, grid, rays, ray_error,
           formula, kept, max_theta * 180 / pi);
    CHECK(grid <= 1e-6, "%s: grid round trip %g px", t->label, grid);
    CHECK(rays <= 1e-6, "%s: ray round trip %g px", t->label, rays);
    CHECK(ray_error <= 1e-9, "%s: rays come back %g apart", t->label, ray_error);
    CHECK(kept >= 1000, "%s: only %ld random rays in the image", t->label, kept);
    CHECK(formula <= formula_tolerance, "%s: %g px from the model's formula", t->label, formula);
    if (t->camera.model >= CF_CAMERA_OPENCV_FISHEYE && t->camera.model != CF_CAMERA_FULL_OPENCV &&
        t->camera.model != CF_CAMERA_FOV)
      CHECK(max_theta > 60 * pi / 180, "%s: the test covers only %g° off axis", t->label,
            max_theta * 180 / pi);
  }
  for (int m = 0; m < CF_CAMERA_MODEL_COUNT; ++m)
    CHECK(covered[m], "model %s has no round-trip test", cf_camera_model_name((cf_camera_model)m));

  /* COLMAP's convention: the principal point is where the optical axis
   * lands, in the same continuous coordinates (pixel centres at +0.5) */
  const cf_camera *c = &cameras[4].camera;
  double axis[3] = {0, 0, 1}, uv[2], ray[3];
  CHECK(cf_camera_project(c, axis, uv) && uv[0] == 802 && uv[1] == 597, "axis at (%g, %g)", uv[0],
        uv[1]);
  double centre[2] = {802, 597};
  CHECK(cf_camera_unproject(c, centre, ray) && ray[0] == 0 && ray[1] == 0 && ray[2] == 1,
        "principal point ray (%g, %g, %g)", ray[0], ray[1], ray[2]);

  /* what has no answer gives 0 */
  double behind[3] = {0.1, 0.2, -1}, on_plane[3] = {1, 0, 0};
  CHECK(!cf_camera_project(c, behind, uv) && !cf_camera_project(c, on_plane, uv), "z <= 0");
  const cf_camera *fov_camera = &cameras[7].camera; /* r_d < π/(2ω) = 1.745: 1571 px */
  double beyond_fov[2] = {799.5 + 1700, 600.2};
  CHECK(!cf_camera_unproject(fov_camera, beyond_fov, ray), "FOV: a pixel beyond 90° unprojects");
  const cf_camera *fisheye = &cameras[10].camera; /* θ = π/2 at θd ≈ 1.5 → 1050 px */
  double beyond_fisheye[2] = {800 + 1200, 600};
  CHECK(!cf_camera_unproject(fisheye, beyond_fisheye, ray),
        "RADIAL_FISHEYE: a pixel beyond 90° unprojects to (%g, %g, %g)", ray[0], ray[1], ray[2]);
  double nan_pixel[2] = {NAN, 3};
  CHECK(!cf_camera_unproject(c, nan_pixel, ray), "NaN pixel");
}

/* ---- names, parameter lists, checks ---- */

static void names_and_checks(void) {
  static const char *const names[] = {"SIMPLE_PINHOLE",
                                      "PINHOLE",
                                      "SIMPLE_RADIAL",
                                      "RADIAL",
                                      "OPENCV",
                                      "OPENCV_FISHEYE",
                                      "FULL_OPENCV",
                                      "FOV",
                                      "SIMPLE_RADIAL_FISHEYE",
                                      "RADIAL_FISHEYE",
                                      "THIN_PRISM_FISHEYE"};
  static const int counts[] = {3, 4, 4, 5, 8, 8, 12, 5, 4, 5, 12};
  CHECK(CF_CAMERA_MODEL_COUNT == 11, "%d models", (int)CF_CAMERA_MODEL_COUNT);
  for (int m = 0; m < CF_CAMERA_MODEL_COUNT; ++m) {
    cf_camera_model found;
    CHECK(strcmp(cf_camera_model_name((cf_camera_model)m), names[m]) == 0, "model %d", m);
    CHECK(cf_camera_model_find(names[m], &found, NULL) == CF_OK && found == (cf_camera_model)m,
          "find %s", names[m]);
    CHECK(cf_camera_model_param_count((cf_camera_model)m) == counts[m], "%s count", names[m]);
    int commas = 0;
    for (const char *p = cf_camera_model_param_names((cf_camera_model)m); *p; ++p)
      commas += *p == ',';
    CHECK(commas + 1 == counts[m], "%s: %s", names[m],
          cf_camera_model_param_names((cf_camera_model)m));
  }
  CHECK(strcmp(cf_camera_model_param_names(CF_CAMERA_THIN_PRISM_FISHEYE),
               "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1") == 0,
        "thin prism order");
  CHECK(cf_camera_model_name(CF_CAMERA_MODEL_COUNT) == NULL &&
            cf_camera_model_param_count((cf_camera_model)-1) == -1,
        "unknown ids");

  cf_error err = {0};
  cf_camera_model found;
  CHECK(cf_camera_model_find("OPENCV_FISHEYES", &found, &err) == CF_ENOTFOUND, "unknown name");
  CHECK(strstr(err.message, "'OPENCV_FISHEYES'") && strstr(err.message, "THIN_PRISM_FISHEYE"),
        "message: %s", err.message);

  static const double opencv[] = {1400, 1405, 802, 597, -0.12, 0.05, 0.001, -0.0015};
  cf_camera c = make_camera(CF_CAMERA_OPENCV, opencv);
  c.camera_id = 7;
  CHECK(cf_camera_check(&c, &err) == CF_OK, "%s", err.message);

  cf_camera bad = c;
  bad.num_params = 5;
  CHECK(cf_camera_check(&bad, &err) == CF_EINVAL, "wrong count");
  CHECK(strstr(err.message, "camera 7") && strstr(err.message, "OPENCV") &&
            strstr(err.message, "5 parameters") && strstr(err.message, "takes 8") &&
            strstr(err.message, "fx, fy, cx, cy, k1, k2, p1, p2"),
        "message: %s", err.message);

  bad = c;
  bad.params[5] = NAN;
  CHECK(cf_camera_check(&bad, &err) == CF_EINVAL, "NaN");
  CHECK(strstr(err.message, "parameter k2") && strstr(err.message, "nan") &&
            strstr(err.message, "finite"),
        "message: %s", err.message);

  bad = c;
  bad.params[1] = 0;
  CHECK(cf_camera_check(&bad, &err) == CF_ERANGE, "zero focal length");
  CHECK(strstr(err.message, "focal length fy is 0") && strstr(err.message, "> 0"), "message: %s",
        err.message);

  bad = c;
  bad.params[0] = -3;
  CHECK(cf_camera_check(&bad, &err) == CF_ERANGE && strstr(err.message, "fx is -3"),
        "negative focal length: %s", err.message);

  bad = c;
  bad.width = 0;
  CHECK(cf_camera_check(&bad, &err) == CF_ERANGE && strstr(err.message, "width 0"),
        "zero width: %s", err.message);
  bad = c;
  bad.height = ((uint64_t)1 << 20) + 1;
  CHECK(cf_camera_check(&bad, &err) == CF_ERANGE && strstr(err.message, "height 1048577"),
        "huge height: %s", err.message);

  bad = c;
  bad.model = (cf_camera_model)42;
  CHECK(cf_camera_check(&bad, &err) == CF_EINVAL, "unknown model");
  CHECK(strstr(err.message, "42") && strstr(err.message, "10 (THIN_PRISM_FISHEYE)"), "message: %s",
        err.message);
  double uv[2] = {1, 2}, ray[3], X[3] = {0, 0, 1};
  CHECK(!cf_camera_unproject(&bad, uv, ray) && !cf_camera_project(&bad, X, uv),
        "an unknown model projects");

  static const double single[] = {0, 800, 600, 0.1};
  cf_camera s = make_camera(CF_CAMERA_SIMPLE_RADIAL, single);
  CHECK(cf_camera_check(&s, &err) == CF_ERANGE && strstr(err.message, "focal length f is 0"),
        "SIMPLE_RADIAL zero f: %s", err.message);
}

/* ---- poses ---- */

static void poses(cf_rng *rng) {
  /* a quarter turn about z: x → y */
  double q[4] = {cos(pi / 4), 0, 0, sin(pi / 4)}, r[9];
  cf_quaternion_to_matrix(q, r);
  static const double quarter[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
  double worst = 0;
  for (int k = 0; k < 9; ++k) worst = fmax(worst, fabs(r[k] - quarter[k]));
  CHECK(worst < 1e-15, "quarter turn off by %g", worst);

  double orthonormality = 0;
  for (int n = 0; n < 1000; ++n) {
    double v[4], len = 0;
    for (int k = 0; k < 4; ++k) {
      v[k] = cf_rng_range(rng, -1, 1);
      len += v[k] * v[k];
    }
    for (int k = 0; k < 4; ++k) v[k] /= sqrt(len);
    cf_quaternion_to_matrix(v, r);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double dot =
            r[i * 3] * r[j * 3] + r[i * 3 + 1] * r[j * 3 + 1] + r[i * 3 + 2] * r[j * 3 + 2];
        orthonormality = fmax(orthonormality, fabs(dot - (i == j)));
      }
    double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                 r[2] * (r[3] * r[7] - r[4] * r[6]);
    CHECK(fabs(det - 1) < 1e-14, "det %.17g", det);
  }
  printf("quaternion to matrix: worst |R Rᵀ − I| %.3g over 1000 random rotations\n",
         orthonormality);
  CHECK(orthonormality < 1e-14, "R Rᵀ off by %g", orthonormality);

  /* C = −Rᵀ t; the centre maps to the camera's origin */
  cf_colmap_image image = {0};
  double qv[4] = {0.5, 0.5, -0.5, 0.5}, tv[3] = {1, -2, 3};
  memcpy(image.qvec, qv, sizeof qv);
  memcpy(image.tvec, tv, sizeof tv);
  double centre[3], cam[3];
  cf_colmap_image_center(&image, centre);
  cf_quaternion_to_matrix(image.qvec, r);
  for (int i = 0; i < 3; ++i)
    cam[i] = r[i * 3] * centre[0] + r[i * 3 + 1] * centre[1] + r[i * 3 + 2] * centre[2] + tv[i];
  CHECK(norm3(cam) < 1e-15, "R C + t = (%g, %g, %g)", cam[0], cam[1], cam[2]);
  memcpy(image.qvec, (double[4]){1, 0, 0, 0}, sizeof image.qvec);
  cf_colmap_image_center(&image, centre);
  CHECK(centre[0] == -1 && centre[1] == 2 && centre[2] == -3, "identity pose centre");
}

int main(void) {
  round_trips();
  names_and_checks();
  cf_rng rng = cf_rng_seed(7);
  poses(&rng);
  return check_finish("test_camera_models");
}
