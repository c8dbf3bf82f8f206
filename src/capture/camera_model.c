/* COLMAP 3.8's camera models (src/base/camera_models.h): names and
 * parameter lists, the checks a camera must pass, projection through each
 * model's distortion, and its exact inverse by Newton iteration.
 *
 * Projection is COLMAP's WorldToImage transcribed operation for operation,
 * so that clayfit and COLMAP put a point on the same pixel. Unprojection
 * solves D(x) = m, where m is the distorted normalised point and D the
 * model's distortion on the plane it is defined on: the perspective plane
 * p = (X/Z, Y/Z), or for the fisheye models the equidistant plane
 * q = θ p/|p| (θ the angle to the optical axis) on which their distortion
 * is a polynomial and which stays finite up to θ = π/2. COLMAP's
 * BaseCameraModel::IterativeUndistortion is the same Newton iteration with
 * central differences, stopped on the step size; this one stops on the
 * residual (to 1e-12), backtracks when a step does not reduce it, and
 * rejects solutions past a fold of the distortion (det J <= 0). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "colmap_internal.h"
#include "clayfit/colmap.h"
#include "core/vec.h"

typedef struct camera_model_info {
  const char *name;
  int param_count;
  const char *param_names;
} camera_model_info;

static const camera_model_info model_table[CF_CAMERA_MODEL_COUNT] = {
#define CF__CAMERA_ROW(ID, number, name, count, params) [number] = {name, count, params},
    CF_CAMERA_MODEL_MAP(CF__CAMERA_ROW)
#undef CF__CAMERA_ROW
};

static const camera_model_info *model_info(cf_camera_model model) {
  if ((int)model < 0 || model >= CF_CAMERA_MODEL_COUNT) return NULL;
  return &model_table[model];
}

/* ---- names and parameter lists ---- */

const char *cf_camera_model_name(cf_camera_model model) {
  const camera_model_info *info = model_info(model);
  return info ? info->name : NULL;
}

int cf_camera_model_param_count(cf_camera_model model) {
  const camera_model_info *info = model_info(model);
  return info ? info->param_count : -1;
}

const char *cf_camera_model_param_names(cf_camera_model model) {
  const camera_model_info *info = model_info(model);
  return info ? info->param_names : NULL;
}

const char *cf__camera_model_list(int with_ids, char *buf, size_t size) {
  size_t used = 0;
  buf[0] = '\0';
  for (int m = 0; m < CF_CAMERA_MODEL_COUNT && used < size; ++m) {
    int n =
        with_ids
            ? snprintf(buf + used, size - used, "%s%d (%s)", m ? ", " : "", m, model_table[m].name)
            : snprintf(buf + used, size - used, "%s%s", m ? ", " : "", model_table[m].name);
    if (n < 0) break;
    used += (size_t)n;
  }
  return buf;
}

const char *cf__camera_param_name(cf_camera_model model, int k, char *buf, size_t size) {
  const camera_model_info *info = model_info(model);
  if (info && k >= 0 && k < info->param_count) {
    const char *p = info->param_names;
    for (int skip = 0; skip < k; ++skip) p = strchr(p, ',') + 2; /* ", " separates them */
    size_t length = strcspn(p, ",");
    snprintf(buf, size, "%.*s", (int)length, p);
  } else {
    snprintf(buf, size, "params[%d]", k);
  }
  return buf;
}

cf_status cf_camera_model_find(const char *name, cf_camera_model *model, cf_error *err) {
  for (int m = 0; name && m < CF_CAMERA_MODEL_COUNT; ++m) {
    if (strcmp(name, model_table[m].name) == 0) {
      *model = (cf_camera_model)m;
      return CF_OK;
    }
  }
  char known[512];
  return cf_error_set(err, CF_ENOTFOUND, "unknown camera model '%s'; the known models are %s",
                      name ? name : "(null)", cf__camera_model_list(0, known, sizeof known));
}

/* The models whose parameters start "f, cx, cy" (one focal length). */
static int has_single_focal(cf_camera_model model) {
  return strncmp(model_table[model].param_names, "f,", 2) == 0;
}

/* ---- checks ---- */

cf_status cf_camera_check(const cf_camera *camera, cf_error *err) {
  const camera_model_info *info = model_info(camera->model);
  char known[512];
  if (!info)
    return cf_error_set(
        err, CF_EINVAL, "camera %u: unknown camera model id %d; the known ids are %s",
        camera->camera_id, (int)camera->model, cf__camera_model_list(1, known, sizeof known));
  if (camera->num_params != info->param_count)
    return cf_error_set(
        err, CF_EINVAL, "camera %u (%s): %d parameters, but the model takes %d (%s)",
        camera->camera_id, info->name, camera->num_params, info->param_count, info->param_names);
  char name[32];
  for (int k = 0; k < info->param_count; ++k) {
    if (!isfinite(camera->params[k]))
      return cf_error_set(err, CF_EINVAL, "camera %u (%s): parameter %s is %g; it must be finite",
                          camera->camera_id, info->name,
                          cf__camera_param_name(camera->model, k, name, sizeof name),
                          camera->params[k]);
  }
  int focal_count = has_single_focal(camera->model) ? 1 : 2;
  for (int k = 0; k < focal_count; ++k) {
    if (!(camera->params[k] > 0.0))
      return cf_error_set(
          err, CF_ERANGE, "camera %u (%s): focal length %s is %.17g; it must be > 0",
          camera->camera_id, info->name, cf__camera_param_name(camera->model, k, name, sizeof name),
          camera->params[k]);
  }
  const uint64_t max_side = (uint64_t)1 << 20;
  if (camera->width < 1 || camera->width > max_side)
    return cf_error_set(err, CF_ERANGE, "camera %u (%s): width %llu is outside [1, %llu]",
                        camera->camera_id, info->name, (unsigned long long)camera->width,
                        (unsigned long long)max_side);
  if (camera->height < 1 || camera->height > max_side)
    return cf_error_set(err, CF_ERANGE, "camera %u (%s): height %llu is outside [1, %llu]",
                        camera->camera_id, info->name, (unsigned long long)camera->height,
                        (unsigned long long)max_side);
  return CF_OK;
}

/* A camera the projection code may index without checking further. */
static int usable(const cf_camera *camera) {
  const camera_model_info *info = model_info(camera->model);
  return info && camera->num_params == info->param_count;
}

/* ---- COLMAP's distortion functions, transcribed from camera_models.h ---- */

/* SimpleRadialCameraModel::Distortion */
static void simple_radial_distortion(const double *k, double u, double v, double *du, double *dv) {
  const double u2 = u * u;
  const double v2 = v * v;
  const double r2 = u2 + v2;
  const double radial = k[0] * r2;
  *du = u * radial;
  *dv = v * radial;
}

/* RadialCameraModel::Distortion */
static void radial_distortion(const double *k, double u, double v, double *du, double *dv) {
  const double u2 = u * u;
  const double v2 = v * v;
  const double r2 = u2 + v2;
  const double radial = k[0] * r2 + k[1] * r2 * r2;
  *du = u * radial;
  *dv = v * radial;
}

/* OpenCVCameraModel::Distortion: k1, k2, p1, p2 */
static void opencv_distortion(const double *k, double u, double v, double *du, double *dv) {
  const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3];
  const double u2 = u * u;
  const double uv = u * v;
  const double v2 = v * v;
  const double r2 = u2 + v2;
  const double radial = k1 * r2 + k2 * r2 * r2;
  *du = u * radial + 2.0 * p1 * uv + p2 * (r2 + 2.0 * u2);
  *dv = v * radial + 2.0 * p2 * uv + p1 * (r2 + 2.0 * v2);
}

/* OpenCVFisheyeCameraModel::Distortion (k1..k4), and with the higher
 * coefficients zero SimpleRadialFisheyeCameraModel (k) and
 * RadialFisheyeCameraModel (k1, k2): θd = θ (1 + k1 θ² + k2 θ⁴ + ...). */
static void fisheye_distortion(int count, const double *k, double u, double v, double *du,
                               double *dv) {
  const double r = sqrt(u * u + v * v);
  if (r > DBL_EPSILON) {
    const double theta = atan(r);
    const double theta2 = theta * theta;
    double thetad;
    if (count == 1) {
      thetad = theta * (1.0 + k[0] * theta2);
    } else if (count == 2) {
      const double theta4 = theta2 * theta2;
      thetad = theta * (1.0 + k[0] * theta2 + k[1] * theta4);
    } else {
      const double theta4 = theta2 * theta2;
      const double theta6 = theta4 * theta2;
      const double theta8 = theta4 * theta4;
      thetad = theta * (1.0 + k[0] * theta2 + k[1] * theta4 + k[2] * theta6 + k[3] * theta8);
    }
    *du = u * thetad / r - u;
    *dv = v * thetad / r - v;
  } else {
    *du = 0.0;
    *dv = 0.0;
  }
}

/* FullOpenCVCameraModel::Distortion: k1, k2, p1, p2, k3, k4, k5, k6 */
static void full_opencv_distortion(const double *k, double u, double v, double *du, double *dv) {
  const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3];
  const double k3 = k[4], k4 = k[5], k5 = k[6], k6 = k[7];
  const double u2 = u * u;
  const double uv = u * v;
  const double v2 = v * v;
  const double r2 = u2 + v2;
  const double r4 = r2 * r2;
  const double r6 = r4 * r2;
  const double radial = (1.0 + k1 * r2 + k2 * r4 + k3 * r6) / (1.0 + k4 * r2 + k5 * r4 + k6 * r6);
  *du = u * radial + 2.0 * p1 * uv + p2 * (r2 + 2.0 * u2) - u;
  *dv = v * radial + 2.0 * p2 * uv + p1 * (r2 + 2.0 * v2) - v;
}

/* FOVCameraModel::Distortion: unlike the others it returns the distorted
 * point itself, p · atan(2 r tan(ω/2)) / (r ω), with COLMAP's Taylor
 * expansions for small ω and small r. (For ω² < 1e-4 COLMAP 3.8 uses
 * 1 + ω² (r²/3 − 1/12), the expansion of the inverse, where the formula's
 * is 1 − ω² (r²/3 − 1/12): kept, since COLMAP's cameras were fitted with
 * it. The r² < 1e-4 branch leaves a step of ~1e-11 in normalised
 * coordinates at r = 0.01; pixels in that ring, narrower than 1e-7 px,
 * have no exact preimage and do not unproject.) */
static void fov_distortion(const double *k, double u, double v, double *x, double *y) {
  const double omega = k[0];
  const double epsilon = 1e-4; /* "Chosen arbitrarily." */
  const double radius2 = u * u + v * v;
  const double omega2 = omega * omega;
  double factor;
  if (omega2 < epsilon) {
    factor = (omega2 * radius2) / 3.0 - omega2 / 12.0 + 1.0;
  } else if (radius2 < epsilon) {
    const double tan_half_omega = tan(omega / 2.0);
    factor = (-2.0 * tan_half_omega * (4.0 * radius2 * tan_half_omega * tan_half_omega - 3.0)) /
             (3.0 * omega);
  } else {
    const double radius = sqrt(radius2);
    const double numerator = atan(radius * 2.0 * tan(omega / 2.0));
    factor = numerator / (radius * omega);
  }
  *x = u * factor;
  *y = v * factor;
}

/* FOVCameraModel::Undistortion: COLMAP's closed-form inverse (exact off its
 * Taylor branches), used here as the starting point of the iteration. */
static void fov_undistortion(const double *k, double u, double v, double *x, double *y) {
  const double omega = k[0];
  const double epsilon = 1e-4;
  const double radius2 = u * u + v * v;
  const double omega2 = omega * omega;
  double factor;
  if (omega2 < epsilon) {
    factor = (omega2 * radius2) / 3.0 - omega2 / 12.0 + 1.0;
  } else if (radius2 < epsilon) {
    factor = (omega * (omega * omega * radius2 + 3.0)) / (6.0 * tan(omega / 2.0));
  } else {
    const double radius = sqrt(radius2);
    const double numerator = tan(radius * omega);
    factor = numerator / (radius * 2.0 * tan(omega / 2.0));
  }
  *x = u * factor;
  *y = v * factor;
}

/* ThinPrismFisheyeCameraModel::Distortion: k1, k2, p1, p2, k3, k4, sx1, sy1,
 * applied on the equidistant plane. */
static void thin_prism_distortion(const double *k, double u, double v, double *du, double *dv) {
  const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3];
  const double k3 = k[4], k4 = k[5], sx1 = k[6], sy1 = k[7];
  const double u2 = u * u;
  const double uv = u * v;
  const double v2 = v * v;
  const double r2 = u2 + v2;
  const double r4 = r2 * r2;
  const double r6 = r4 * r2;
  const double r8 = r6 * r2;
  const double radial = k1 * r2 + k2 * r4 + k3 * r6 + k4 * r8;
  *du = u * radial + 2.0 * p1 * uv + p2 * (r2 + 2.0 * u2) + sx1 * r2;
  *dv = v * radial + 2.0 * p2 * uv + p1 * (r2 + 2.0 * v2) + sy1 * r2;
}

/* ---- the pieces of a model ---- */

typedef struct intrinsics {
  double fx, fy, cx, cy;
  const double *extra; /* the distortion parameters */
} intrinsics;

static intrinsics intrinsics_of(const cf_camera *camera) {
  const double *p = camera->params;
  if (has_single_focal(camera->model)) return (intrinsics){p[0], p[0], p[1], p[2], p + 3};
  return (intrinsics){p[0], p[1], p[2], p[3], p + 4};
}

static int is_distortion_free(cf_camera_model model) {
  return model == CF_CAMERA_SIMPLE_PINHOLE || model == CF_CAMERA_PINHOLE;
}

/* The fisheye models, whose distortion unprojection inverts on the
 * equidistant plane q = θ p/|p|. */
static int uses_equidistant_plane(cf_camera_model model) {
  return model == CF_CAMERA_OPENCV_FISHEYE || model == CF_CAMERA_SIMPLE_RADIAL_FISHEYE ||
         model == CF_CAMERA_RADIAL_FISHEYE || model == CF_CAMERA_THIN_PRISM_FISHEYE;
}

/* The *CameraModel::WorldToImage of camera_models.h up to the focal
 * lengths: the perspective point (u, v) to the distorted normalised point
 * (x, y), in COLMAP's order of operations. */
static void world_to_distorted(cf_camera_model model, const double *k, double u, double v,
                               double *x, double *y) {
  double du = 0.0, dv = 0.0;
  switch (model) {
    case CF_CAMERA_SIMPLE_PINHOLE:
    case CF_CAMERA_PINHOLE:
      break;
    case CF_CAMERA_SIMPLE_RADIAL:
      simple_radial_distortion(k, u, v, &du, &dv);
      break;
    case CF_CAMERA_RADIAL:
      radial_distortion(k, u, v, &du, &dv);
      break;
    case CF_CAMERA_OPENCV:
      opencv_distortion(k, u, v, &du, &dv);
      break;
    case CF_CAMERA_OPENCV_FISHEYE:
      fisheye_distortion(4, k, u, v, &du, &dv);
      break;
    case CF_CAMERA_FULL_OPENCV:
      full_opencv_distortion(k, u, v, &du, &dv);
      break;
    case CF_CAMERA_FOV:
      fov_distortion(k, u, v, x, y);
      return;
    case CF_CAMERA_SIMPLE_RADIAL_FISHEYE:
      fisheye_distortion(1, k, u, v, &du, &dv);
      break;
    case CF_CAMERA_RADIAL_FISHEYE:
      fisheye_distortion(2, k, u, v, &du, &dv);
      break;
    case CF_CAMERA_THIN_PRISM_FISHEYE: {
      /* ThinPrismFisheyeCameraModel::WorldToImage: to the equidistant plane
       * first, then the distortion there */
      const double r = sqrt(u * u + v * v);
      double uu = u, vv = v;
      if (r > DBL_EPSILON) {
        const double theta = atan(r);
        uu = theta * u / r;
        vv = theta * v / r;
      }
      thin_prism_distortion(k, uu, vv, &du, &dv);
      *x = uu + du;
      *y = vv + dv;
      return;
    }
    case CF_CAMERA_MODEL_COUNT:
      break;
  }
  *x = u + du;
  *y = v + dv;
}

/* D, the map unprojection inverts: from the plane the model's distortion
 * lives on (perspective, or equidistant for the fisheye models) to the
 * distorted normalised point. On the equidistant plane the fisheye models
 * of OpenCVFisheyeCameraModel::Distortion are q (1 + k1 θ² + ... ) with
 * θ = |q|, the same map as COLMAP's written without the atan. */
static void plane_to_distorted(cf_camera_model model, const double *k, const double x[2],
                               double m[2]) {
  double du = 0.0, dv = 0.0;
  switch (model) {
    case CF_CAMERA_OPENCV_FISHEYE:
    case CF_CAMERA_SIMPLE_RADIAL_FISHEYE:
    case CF_CAMERA_RADIAL_FISHEYE: {
      const double theta2 = x[0] * x[0] + x[1] * x[1];
      const double theta4 = theta2 * theta2;
      double scale;
      if (model == CF_CAMERA_SIMPLE_RADIAL_FISHEYE)
        scale = 1.0 + k[0] * theta2;
      else if (model == CF_CAMERA_RADIAL_FISHEYE)
        scale = 1.0 + k[0] * theta2 + k[1] * theta4;
      else
        scale =
            1.0 + k[0] * theta2 + k[1] * theta4 + k[2] * theta4 * theta2 + k[3] * theta4 * theta4;
      m[0] = x[0] * scale;
      m[1] = x[1] * scale;
      return;
    }
    case CF_CAMERA_THIN_PRISM_FISHEYE:
      thin_prism_distortion(k, x[0], x[1], &du, &dv);
      m[0] = x[0] + du;
      m[1] = x[1] + dv;
      return;
    default:
      world_to_distorted(model, k, x[0], x[1], &m[0], &m[1]);
      return;
  }
}

/* The Jacobian of D (row-major 2x2) by central differences, as in
 * BaseCameraModel::IterativeUndistortion but with steps that do not vanish
 * at the origin. Its error only slows the iteration; the residual, which
 * decides convergence, is exact. */
static void distortion_jacobian(cf_camera_model model, const double *k, const double x[2],
                                double jacobian[4]) {
  for (int j = 0; j < 2; ++j) {
    const double h = 1e-6 * fmax(1.0, fabs(x[j]));
    double forward[2] = {x[0], x[1]}, backward[2] = {x[0], x[1]};
    forward[j] += h;
    backward[j] -= h;
    double mf[2], mb[2];
    plane_to_distorted(model, k, forward, mf);
    plane_to_distorted(model, k, backward, mb);
    const double width = forward[j] - backward[j];
    jacobian[0 * 2 + j] = (mf[0] - mb[0]) / width;
    jacobian[1 * 2 + j] = (mf[1] - mb[1]) / width;
  }
}

/* max |D(x) − m|, or +inf when D(x) is not finite. */
static double residual_norm(cf_camera_model model, const double *k, const double x[2],
                            const double m[2]) {
  double d[2];
  plane_to_distorted(model, k, x, d);
  const double r = fmax(fabs(d[0] - m[0]), fabs(d[1] - m[1]));
  return isfinite(r) ? r : INFINITY;
}

enum { NEWTON_MAX_ITERATIONS = 100, NEWTON_MAX_HALVINGS = 60 };
static const double newton_tolerance = 1e-12; /* normalised coordinates */

/* Solve D(x) = m by Newton's method from the guess in x. 1 when the
 * residual is within newton_tolerance on the unfolded side of D. */
static int solve_distortion(cf_camera_model model, const double *k, const double m[2],
                            double x[2]) {
  const double floor = 4.0 * DBL_EPSILON * fmax(1.0, fmax(fabs(m[0]), fabs(m[1])));
  double norm = residual_norm(model, k, x, m);
  for (int iteration = 0; iteration < NEWTON_MAX_ITERATIONS && norm > floor; ++iteration) {
    double jacobian[4], d[2];
    distortion_jacobian(model, k, x, jacobian);
    plane_to_distorted(model, k, x, d);
    const double det = jacobian[0] * jacobian[3] - jacobian[1] * jacobian[2];
    if (!isfinite(det) || det == 0.0) return 0;
    const double r0 = d[0] - m[0], r1 = d[1] - m[1];
    const double step[2] = {(jacobian[3] * r0 - jacobian[1] * r1) / det,
                            (-jacobian[2] * r0 + jacobian[0] * r1) / det};
    /* backtrack until the residual drops */
    double t = 1.0, trial[2], trial_norm = INFINITY;
    int halvings = 0;
    for (; halvings < NEWTON_MAX_HALVINGS; ++halvings, t *= 0.5) {
      trial[0] = x[0] - t * step[0];
      trial[1] = x[1] - t * step[1];
      trial_norm = residual_norm(model, k, trial, m);
      if (trial_norm < norm) break;
    }
    if (halvings == NEWTON_MAX_HALVINGS) break; /* stalled at rounding level */
    x[0] = trial[0];
    x[1] = trial[1];
    norm = trial_norm;
  }
  if (!(norm <= newton_tolerance)) return 0;
  double jacobian[4];
  distortion_jacobian(model, k, x, jacobian);
  return jacobian[0] * jacobian[3] - jacobian[1] * jacobian[2] > 0.0;
}

/* ---- projection ---- */

int cf_camera_project(const cf_camera *camera, const double xyz[3], double uv[2]) {
  if (!usable(camera) || !(xyz[2] > 0.0)) return 0;
  const intrinsics in = intrinsics_of(camera);
  double x, y;
  world_to_distorted(camera->model, in.extra, xyz[0] / xyz[2], xyz[1] / xyz[2], &x, &y);
  const double u = in.fx * x + in.cx;
  const double v = in.fy * y + in.cy;
  if (!isfinite(u) || !isfinite(v)) return 0;
  uv[0] = u;
  uv[1] = v;
  return 1;
}

int cf_camera_unproject(const cf_camera *camera, const double uv[2], double ray[3]) {
  if (!usable(camera)) return 0;
  const intrinsics in = intrinsics_of(camera);
  const double m[2] = {(uv[0] - in.cx) / in.fx, (uv[1] - in.cy) / in.fy};
  if (!isfinite(m[0]) || !isfinite(m[1])) return 0;

  double x[2] = {m[0], m[1]}; /* the guess: no distortion */
  if (camera->model == CF_CAMERA_FOV) {
    fov_undistortion(in.extra, m[0], m[1], &x[0], &x[1]);
    if (!isfinite(x[0]) || !isfinite(x[1])) {
      x[0] = m[0];
      x[1] = m[1];
    }
  }
  if (!is_distortion_free(camera->model) && !solve_distortion(camera->model, in.extra, m, x))
    return 0;

  if (uses_equidistant_plane(camera->model)) {
    const double theta = sqrt(x[0] * x[0] + x[1] * x[1]);
    if (!(theta < 0.5 * CF_PI)) return 0; /* no direction in front of the camera */
    const double scale = theta > 0.0 ? sin(theta) / theta : 1.0;
    ray[0] = x[0] * scale;
    ray[1] = x[1] * scale;
    ray[2] = cos(theta);
    return 1;
  }
  const double norm = sqrt(x[0] * x[0] + x[1] * x[1] + 1.0);
  if (!isfinite(norm)) return 0;
  ray[0] = x[0] / norm;
  ray[1] = x[1] / norm;
  ray[2] = 1.0 / norm;
  return 1;
}

/* ---- poses ---- */

/* Eigen's Quaternion::toRotationMatrix (used by COLMAP's
 * QuaternionToRotationMatrix), with 2/|q|² in place of 2 so that a
 * quaternion a rounding error off unit length still gives a rotation. */
void cf_quaternion_to_matrix(const double q[4], double r[9]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double n2 = w * w + x * x + y * y + z * z;
  const double s = n2 > 0.0 ? 2.0 / n2 : 0.0;
  r[0] = 1.0 - s * (y * y + z * z);
  r[1] = s * (x * y - z * w);
  r[2] = s * (x * z + y * w);
  r[3] = s * (x * y + z * w);
  r[4] = 1.0 - s * (x * x + z * z);
  r[5] = s * (y * z - x * w);
  r[6] = s * (x * z - y * w);
  r[7] = s * (y * z + x * w);
  r[8] = 1.0 - s * (x * x + y * y);
}

void cf_colmap_image_center(const cf_colmap_image *image, double center[3]) {
  double r[9];
  cf_quaternion_to_matrix(image->qvec, r);
  const double *t = image->tvec;
  for (int k = 0; k < 3; ++k)
    center[k] = -(r[0 * 3 + k] * t[0] + r[1 * 3 + k] * t[1] + r[2 * 3 + k] * t[2]);
}
