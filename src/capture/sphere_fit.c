/* The sphere from its silhouettes in several views, and the normals of a
 * sphere seen orthographically (src/capture/sphere_silhouette.h).
 *
 * Every silhouette ray of a view is tangent to the sphere, so the distance
 * from the sphere's centre C to the ray's line equals the radius R. The fit
 * minimises Σ (|(C − O) × d| − R)² over all rays d of all views (origin O)
 * by Levenberg-Marquardt (Marquardt 1963, with the diagonal scaling of
 * Moré 1978), from a closed-form start: the least-squares intersection of
 * the views' central rays (Hartley & Zisserman 2004, the "midpoint" of
 * many lines: Σ (I − a aᵀ) C = Σ (I − a aᵀ) O) and the mean of
 * |C − O| sin(mean angle of the rays to the central ray). */
#include <math.h>
#include <stddef.h>

#include "sphere_silhouette.h"

/* A reciprocal condition number below this makes a matrix singular here. */
#define RCOND_MIN 1e-12
#define MAX_ITERATIONS 200

int cf_sphere_normal_orthographic(const cf_ellipse *circle, double x, double y, double n[3]) {
  if (!circle) return 0;
  double r = 0.5 * (circle->a + circle->b);
  if (!(r > 0.0) || !isfinite(r) || !isfinite(circle->cx) || !isfinite(circle->cy)) return 0;
  double nx = (x - circle->cx) / r;
  double ny = -(y - circle->cy) / r;
  double s = nx * nx + ny * ny;
  if (!(s <= 1.0)) return 0;
  n[0] = nx;
  n[1] = ny;
  n[2] = sqrt(1.0 - s);
  return 1;
}

/* ---- small dense linear algebra ---- */

static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static double norm3(const double a[3]) {
  return sqrt(dot3(a, a));
}

/* Eigenvalues of a symmetric n×n matrix (n <= 4, row-major) by cyclic
 * Jacobi rotations (Golub & Van Loan, "Matrix Computations", §8.5). */
static void symmetric_eigenvalues(const double *m, int n, double *eigenvalues) {
  double a[16];
  for (int k = 0; k < n * n; ++k) a[k] = m[k];
  for (int sweep = 0; sweep < 64; ++sweep) {
    double off = 0.0, total = 0.0;
    for (int p = 0; p < n; ++p)
      for (int q = 0; q < n; ++q) {
        total += a[p * n + q] * a[p * n + q];
        if (p != q) off += a[p * n + q] * a[p * n + q];
      }
    if (off <= 1e-30 * total) break;
    for (int p = 0; p < n - 1; ++p)
      for (int q = p + 1; q < n; ++q) {
        double apq = a[p * n + q];
        if (apq == 0.0) continue;
        double theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
        double t = (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
        double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < n; ++k) { /* columns p, q */
          double akp = a[k * n + p], akq = a[k * n + q];
          a[k * n + p] = c * akp - s * akq;
          a[k * n + q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; ++k) { /* rows p, q */
          double apk = a[p * n + k], aqk = a[q * n + k];
          a[p * n + k] = c * apk - s * aqk;
          a[q * n + k] = s * apk + c * aqk;
        }
      }
  }
  for (int k = 0; k < n; ++k) eigenvalues[k] = a[k * n + k];
}

/* λmin / λmax of a symmetric positive semi-definite matrix (0 if λmax <= 0). */
static double reciprocal_condition(const double *m, int n) {
  double ev[4];
  symmetric_eigenvalues(m, n, ev);
  double lo = ev[0], hi = ev[0];
  for (int k = 1; k < n; ++k) {
    if (ev[k] < lo) lo = ev[k];
    if (ev[k] > hi) hi = ev[k];
  }
  if (!(hi > 0.0) || !isfinite(hi)) return 0.0;
  return lo > 0.0 ? lo / hi : 0.0;
}

/* Solve m x = b (symmetric positive definite, n <= 4) by Cholesky; 0 if a
 * pivot is not positive. */
static int cholesky_solve(const double *m, const double *b, int n, double *x) {
  double l[16] = {0};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j <= i; ++j) {
      double s = m[i * n + j];
      for (int k = 0; k < j; ++k) s -= l[i * n + k] * l[j * n + k];
      if (i == j) {
        if (!(s > 0.0)) return 0;
        l[i * n + i] = sqrt(s);
      } else {
        l[i * n + j] = s / l[j * n + j];
      }
    }
  double y[4];
  for (int i = 0; i < n; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= l[i * n + k] * y[k];
    y[i] = s / l[i * n + i];
  }
  for (int i = n - 1; i >= 0; --i) {
    double s = y[i];
    for (int k = i + 1; k < n; ++k) s -= l[k * n + i] * x[k];
    x[i] = s / l[i * n + i];
  }
  return 1;
}

/* ---- the problem ---- */

/* Ray i of a view as a unit vector; its length before normalising. */
static double unit_ray(const cf_silhouette_view *view, size_t i, double d[3]) {
  const double *r = view->rays + 3 * i;
  double len = norm3(r);
  for (int k = 0; k < 3; ++k) d[k] = r[k] / len;
  return len;
}

static cf_status check_views(const cf_silhouette_view *views, size_t num_views, cf_error *err) {
  if (!views || num_views < 2)
    return cf_error_set(err, CF_EINVAL,
                        "The sphere needs silhouettes from at least 2 views; %zu %s given.",
                        views ? num_views : (size_t)0, num_views == 1 ? "was" : "were");
  for (size_t v = 0; v < num_views; ++v) {
    const cf_silhouette_view *view = &views[v];
    if (!view->rays || view->count < 5)
      return cf_error_set(err, CF_EINVAL,
                          "Silhouette view %zu has %zu rays; at least 5 are needed to fit a "
                          "sphere.",
                          v, view->rays ? view->count : (size_t)0);
    if (!(view->focal_px > 0.0) || !isfinite(view->focal_px))
      return cf_error_set(err, CF_EINVAL,
                          "Silhouette view %zu has focal length %g px; it must be positive and "
                          "finite.",
                          v, view->focal_px);
    if (!isfinite(view->origin[0]) || !isfinite(view->origin[1]) || !isfinite(view->origin[2]))
      return cf_error_set(err, CF_EINVAL, "Silhouette view %zu has a non-finite camera centre.", v);
    for (size_t i = 0; i < view->count; ++i) {
      const double *r = view->rays + 3 * i;
      double len = norm3(r);
      if (!isfinite(r[0]) || !isfinite(r[1]) || !isfinite(r[2]) || !(len > 0.0) || !isfinite(len))
        return cf_error_set(err, CF_EINVAL,
                            "Silhouette view %zu, ray %zu is (%g, %g, %g): rays must be finite "
                            "and non-zero.",
                            v, i, r[0], r[1], r[2]);
    }
  }
  /* a view whose rays all coincide (as lines) outlines nothing */
  for (size_t v = 0; v < num_views; ++v) {
    const cf_silhouette_view *view = &views[v];
    double first[3], spread = 0.0;
    unit_ray(view, 0, first);
    for (size_t i = 1; i < view->count; ++i) {
      double d[3], c[3];
      unit_ray(view, i, d);
      cross3(first, d, c);
      if (norm3(c) > spread) spread = norm3(c);
    }
    if (!(spread > 1e-9))
      return cf_error_set(err, CF_ENUMERIC,
                          "The %zu rays of silhouette view %zu all point the same way (spread "
                          "%.3g rad), so they outline no sphere.",
                          view->count, v, asin(fmin(spread, 1.0)));
  }
  return CF_OK;
}

/* The normal equations of the Gauss-Newton step at (center, radius):
 * jtj = JᵀJ, jtr = Jᵀr; returns the cost Σ r². The residual of a ray is
 * |w × d| − R with w = C − O; its gradient is ((w − (w·d) d)/|w × d|, −1). */
static double normal_equations(const cf_silhouette_view *views, size_t num_views,
                               const double center[3], double radius, double jtj[16],
                               double jtr[4]) {
  double cost = 0.0;
  for (int k = 0; k < 16; ++k) jtj[k] = 0.0;
  for (int k = 0; k < 4; ++k) jtr[k] = 0.0;
  for (size_t v = 0; v < num_views; ++v) {
    const cf_silhouette_view *view = &views[v];
    double w[3] = {center[0] - view->origin[0], center[1] - view->origin[1],
                   center[2] - view->origin[2]};
    for (size_t i = 0; i < view->count; ++i) {
      double d[3];
      unit_ray(view, i, d);
      double wd = dot3(w, d);
      double perp[3] = {w[0] - wd * d[0], w[1] - wd * d[1], w[2] - wd * d[2]};
      double dist = norm3(perp);
      double res = dist - radius;
      double g[4] = {0.0, 0.0, 0.0, -1.0};
      if (dist > 0.0)
        for (int k = 0; k < 3; ++k) g[k] = perp[k] / dist;
      for (int p = 0; p < 4; ++p) {
        jtr[p] += g[p] * res;
        for (int q = 0; q < 4; ++q) jtj[p * 4 + q] += g[p] * g[q];
      }
      cost += res * res;
    }
  }
  return cost;
}

static double cost_at(const cf_silhouette_view *views, size_t num_views, const double center[3],
                      double radius) {
  double jtj[16], jtr[4];
  return normal_equations(views, num_views, center, radius, jtj, jtr);
}

/* Ray i of a view as a unit vector on the same side as ray 0 (a ray is a
 * line here). */
static void oriented_ray(const cf_silhouette_view *view, size_t i, double d[3]) {
  double d0[3];
  unit_ray(view, 0, d0);
  unit_ray(view, i, d);
  if (dot3(d, d0) < 0.0)
    for (int k = 0; k < 3; ++k) d[k] = -d[k];
}

/* A view's central direction: the sum of its rays, all oriented toward the
 * sphere (not normalised); returns its length. */
static double view_axis(const cf_silhouette_view *view, double axis[3]) {
  axis[0] = axis[1] = axis[2] = 0.0;
  for (size_t i = 0; i < view->count; ++i) {
    double d[3];
    oriented_ray(view, i, d);
    for (int k = 0; k < 3; ++k) axis[k] += d[k];
  }
  return norm3(axis);
}

/* The closed-form start: the point nearest to the central rays, and the
 * mean angular radius turned into a distance from there. */
static cf_status closed_form_start(const cf_silhouette_view *views, size_t num_views,
                                   double center[3], double *radius, cf_error *err) {
  double a[9] = {0}, b[3] = {0};
  for (size_t v = 0; v < num_views; ++v) {
    const cf_silhouette_view *view = &views[v];
    double axis[3];
    double len = view_axis(view, axis);
    if (!(len > 1e-9 * (double)view->count))
      return cf_error_set(err, CF_ENUMERIC,
                          "The rays of silhouette view %zu point in opposite directions, so they "
                          "have no central ray; they cannot outline one sphere.",
                          v);
    for (int k = 0; k < 3; ++k) axis[k] /= len;
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) {
        double m = (p == q ? 1.0 : 0.0) - axis[p] * axis[q];
        a[p * 3 + q] += m;
        b[p] += m * view->origin[q];
      }
  }
  double rcond = reciprocal_condition(a, 3);
  double x[3];
  if (rcond < RCOND_MIN || !cholesky_solve(a, b, 3, x))
    return cf_error_set(err, CF_ENUMERIC,
                        "The central rays of the %zu silhouette views are parallel or coincide "
                        "(reciprocal condition number %.3g), so they do not locate the sphere: "
                        "the views do not constrain it.",
                        num_views, rcond);
  double radius_sum = 0.0;
  for (size_t v = 0; v < num_views; ++v) {
    const cf_silhouette_view *view = &views[v];
    double axis[3];
    double len = view_axis(view, axis);
    for (int k = 0; k < 3; ++k) axis[k] /= len;
    double angle_sum = 0.0;
    for (size_t i = 0; i < view->count; ++i) {
      double d[3], c[3];
      oriented_ray(view, i, d);
      cross3(axis, d, c);
      angle_sum += atan2(norm3(c), dot3(axis, d));
    }
    double w[3] = {x[0] - view->origin[0], x[1] - view->origin[1], x[2] - view->origin[2]};
    radius_sum += norm3(w) * sin(angle_sum / (double)view->count);
  }
  for (int k = 0; k < 3; ++k) center[k] = x[k];
  *radius = radius_sum / (double)num_views;
  return CF_OK;
}

/* rms_px and max_px: the angle between each ray and the tangent cone from
 * its view's origin, times focal_px. */
static cf_status report_errors(const cf_silhouette_view *views, size_t num_views,
                               cf_sphere_fit *fit, cf_error *err) {
  double sum2 = 0.0, max_px = 0.0;
  size_t count = 0;
  for (size_t v = 0; v < num_views; ++v) {
    const cf_silhouette_view *view = &views[v];
    double w[3] = {fit->center[0] - view->origin[0], fit->center[1] - view->origin[1],
                   fit->center[2] - view->origin[2]};
    double distance = norm3(w);
    if (!(distance > fit->radius))
      return cf_error_set(err, CF_ENUMERIC,
                          "The fitted sphere (centre %g %g %g, radius %g) contains the camera of "
                          "silhouette view %zu, so it cannot be the sphere those views see.",
                          fit->center[0], fit->center[1], fit->center[2], fit->radius, v);
    double half_angle = asin(fit->radius / distance);
    for (size_t i = 0; i < view->count; ++i) {
      double d[3], c[3];
      unit_ray(view, i, d);
      cross3(w, d, c);
      double angle = atan2(norm3(c), fabs(dot3(w, d)));
      double e = fabs(angle - half_angle) * view->focal_px;
      sum2 += e * e;
      if (e > max_px) max_px = e;
      ++count;
    }
  }
  fit->rms_px = sqrt(sum2 / (double)count);
  fit->max_px = max_px;
  return CF_OK;
}

cf_status cf_sphere_refine_silhouettes(const cf_silhouette_view *views, size_t num_views,
                                       const double center0[3], double radius0, cf_sphere_fit *fit,
                                       cf_error *err) {
  cf_status status = check_views(views, num_views, err);
  if (status != CF_OK) return status;
  if (!center0 || !fit)
    return cf_error_set(err, CF_EINVAL, "The sphere fit needs a start centre and an output.");
  if (!isfinite(center0[0]) || !isfinite(center0[1]) || !isfinite(center0[2]) || !(radius0 > 0.0) ||
      !isfinite(radius0))
    return cf_error_set(err, CF_EINVAL,
                        "The sphere fit's start (centre %g %g %g, radius %g) must be finite with "
                        "a positive radius.",
                        center0[0], center0[1], center0[2], radius0);

  double p[4] = {center0[0], center0[1], center0[2], radius0};
  double jtj[16], jtr[4];
  double cost = normal_equations(views, num_views, p, p[3], jtj, jtr);
  double rcond = reciprocal_condition(jtj, 4);
  if (rcond < RCOND_MIN)
    return cf_error_set(err, CF_ENUMERIC,
                        "The sphere fit's normal matrix is singular at the start (reciprocal "
                        "condition number %.3g): the %zu silhouette views do not constrain the "
                        "sphere's centre and radius (for example, they all see it from one place "
                        "or along one line).",
                        rcond, num_views);

  double lambda = 1e-3;
  int iterations = 0, converged = 0;
  while (iterations < MAX_ITERATIONS && !converged) {
    ++iterations;
    double damped[16], rhs[4], step[4];
    for (int k = 0; k < 16; ++k) damped[k] = jtj[k];
    for (int k = 0; k < 4; ++k) {
      damped[k * 4 + k] += lambda * (jtj[k * 4 + k] > 1e-300 ? jtj[k * 4 + k] : 1e-300);
      rhs[k] = -jtr[k];
    }
    int solved = cholesky_solve(damped, rhs, 4, step);
    double trial[4];
    for (int k = 0; k < 4; ++k) trial[k] = p[k] + (solved ? step[k] : 0.0);
    double trial_cost =
        solved && trial[3] > 0.0 ? cost_at(views, num_views, trial, trial[3]) : INFINITY;
    if (trial_cost < cost && isfinite(trial_cost)) {
      double step_norm =
          sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2] + step[3] * step[3]);
      double scale = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) + p[3];
      double decrease = cost - trial_cost;
      for (int k = 0; k < 4; ++k) p[k] = trial[k];
      cost = normal_equations(views, num_views, p, p[3], jtj, jtr);
      lambda = fmax(lambda * 0.1, 1e-12);
      if (step_norm <= 1e-13 * scale || decrease <= 1e-16 * cost) converged = 1;
    } else {
      lambda *= 10.0;
      /* No step decreases the cost even when it is nearly a tiny gradient
       * step: the cost is at its minimum to machine precision. */
      if (lambda > 1e16) converged = 1;
    }
  }
  if (!converged)
    return cf_error_set(err, CF_ENUMERIC,
                        "The sphere fit did not converge in %d iterations (last centre %g %g %g, "
                        "radius %g).",
                        MAX_ITERATIONS, p[0], p[1], p[2], p[3]);
  if (!(p[3] > 0.0) || !isfinite(p[3]))
    return cf_error_set(err, CF_ENUMERIC, "The sphere fit ended with radius %g.", p[3]);
  rcond = reciprocal_condition(jtj, 4);
  if (rcond < RCOND_MIN)
    return cf_error_set(err, CF_ENUMERIC,
                        "The sphere fit's normal matrix is singular at the solution (reciprocal "
                        "condition number %.3g): the %zu silhouette views do not constrain the "
                        "sphere's centre and radius (for example, they all see it from one place "
                        "or along one line).",
                        rcond, num_views);

  cf_sphere_fit result = {{p[0], p[1], p[2]}, p[3], 0.0, 0.0, iterations};
  status = report_errors(views, num_views, &result, err);
  if (status != CF_OK) return status;
  *fit = result;
  return CF_OK;
}

cf_status cf_sphere_from_silhouettes(const cf_silhouette_view *views, size_t num_views,
                                     cf_sphere_fit *fit, cf_error *err) {
  cf_status status = check_views(views, num_views, err);
  if (status != CF_OK) return status;
  if (!fit) return cf_error_set(err, CF_EINVAL, "The sphere fit needs an output.");
  double center[3] = {0.0, 0.0, 0.0}, radius = 0.0;
  status = closed_form_start(views, num_views, center, &radius, err);
  if (status != CF_OK) return status;
  return cf_sphere_refine_silhouettes(views, num_views, center, radius, fit, err);
}
