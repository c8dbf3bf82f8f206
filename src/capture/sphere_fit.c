/* The sphere from its silhouettes in several views, and the normals of a
 * sphere seen orthographically (src/capture/include/capture/sphere_silhouette.h).
 *
 * Every silhouette ray of a view is tangent to the sphere, so the distance
 * from the sphere's centre C to the ray's line equals the radius R. The fit
 * minimises Σ (|(C − O) × d| − R)² over all rays d of all views (origin O)
 * by Levenberg-Marquardt through the least-squares layer (src/lsq, Ceres),
 * from a closed-form start: the least-squares intersection of
 * the views' central rays (Hartley & Zisserman 2004, the "midpoint" of
 * many lines: Σ (I − a aᵀ) C = Σ (I − a aᵀ) O) and the mean of
 * |C − O| sin(mean angle of the rays to the central ray). */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "core/vec.h"
#include "lsq/linalg.h"
#include "lsq/lsq.h"
#include "capture/sphere_silhouette.h"

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

/* ---- small vectors ---- */

/* λmin / λmax of a symmetric positive semi-definite n × n matrix (row-major,
 * n <= 4): 0 when λmax <= 0 or the matrix cannot be decomposed (not
 * finite). */
static double reciprocal_condition(int n, const double *m) {
  double values[4];
  if (!cf_symmetric_eigen(n, m, values, NULL)) return 0.0;
  double lo = values[0], hi = values[n - 1]; /* ascending */
  if (!(hi > 0.0) || !isfinite(hi)) return 0.0;
  return lo > 0.0 ? lo / hi : 0.0;
}

/* ---- the problem ---- */

/* Ray i of a view as a unit vector; its length before normalising. */
static double unit_ray(const cf_silhouette_view *view, size_t i, double d[3]) {
  const double *r = view->rays + 3 * i;
  double len = cf_norm3(r);
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
      double len = cf_norm3(r);
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
      cf_cross3(first, d, c);
      if (cf_norm3(c) > spread) spread = cf_norm3(c);
    }
    if (!(spread > 1e-9))
      return cf_error_set(err, CF_ENUMERIC,
                          "The %zu rays of silhouette view %zu all point the same way (spread "
                          "%.3g rad), so they outline no sphere.",
                          view->count, v, asin(fmin(spread, 1.0)));
  }
  return CF_OK;
}

/* ---- the least squares, through src/lsq (lsq.h) ----
 *
 * Unknowns x = (C, R): the centre and the radius. One residual per ray d
 * (unit) of a view with camera centre O:
 *   r(C, R) = |w × d| − R,  w = C − O,
 * the distance from C to the ray's line less the radius, with the gradient
 *   ∂r/∂C = p / |p|,  ∂r/∂R = −1,  p = w − (w·d) d
 * (p is w's part across the ray, |p| = |w × d|). cf_lsq_solve minimises
 * ½ Σ r² over all views' rays by Levenberg-Marquardt (Ceres), from the
 * cost and the normal equations JᵀJ, Jᵀr.
 *
 * All rays are one residual block. A view alone hardly constrains the
 * sphere (moving C toward its camera while shrinking R keeps its cone to
 * first order), so one block per view would have nearly singular normal
 * equations, and the layer's compression of a block (lsq.h: Λ^(−1/2) Vᵀ
 * Jᵀr) would divide their rounding errors by that small eigenvalue
 * (measured: a cost off by 1e-11 of itself, and solves that stopped up
 * to 5e-8 R short of the minimum; test_sphere_fit's at_minimum); the sum
 * over all views is well conditioned (the fit refuses a reciprocal
 * condition number under RCOND_MIN). */

enum { NUM_UNKNOWNS = 4 }; /* C x, y, z; R */

typedef struct sphere_problem {
  const cf_silhouette_view *views;
  size_t num_views;
} sphere_problem;

/* One view's share of the cost Σ r² (returned) and, when a is not NULL,
 * of JᵀJ and Jᵀr, added to a (4 × 4) and b (4). */
static double view_share(const cf_silhouette_view *view, const double x[NUM_UNKNOWNS], double *a,
                         double *b) {
  const double w[3] = {x[0] - view->origin[0], x[1] - view->origin[1], x[2] - view->origin[2]};
  double sum = 0.0;
  for (size_t i = 0; i < view->count; ++i) {
    double d[3];
    unit_ray(view, i, d);
    double wd = cf_dot3(w, d);
    double p[3] = {w[0] - wd * d[0], w[1] - wd * d[1], w[2] - wd * d[2]};
    double distance = cf_norm3(p);
    double r = distance - x[3];
    sum += r * r;
    if (!a) continue;
    double g[4] = {0.0, 0.0, 0.0, -1.0};
    if (distance > 0.0)
      for (int k = 0; k < 3; ++k) g[k] = p[k] / distance;
    for (int j = 0; j < 4; ++j) {
      b[j] += g[j] * r;
      for (int k = 0; k < 4; ++k) a[j * 4 + k] += g[j] * g[k];
    }
  }
  return sum;
}

/* The one residual block, all rays, at x = (C, R) (cf_lsq_evaluate): its
 * cost ½ Σ r² and, when jtj is not NULL, JᵀJ (4 × 4) and Jᵀr (4). A
 * radius at or below 0 is no sphere: not finite there, so that the solver
 * rejects a step that takes it there. */
static int all_rays(void *user, const double *x, size_t block, double *cost, double *jtj,
                    double *jtu) {
  const sphere_problem *problem = user;
  (void)block;
  if (!(x[3] > 0.0)) return CF_LSQ_NOT_FINITE;
  double sum = 0.0, a[16] = {0}, b[4] = {0};
  for (size_t v = 0; v < problem->num_views; ++v)
    sum += view_share(&problem->views[v], x, jtj ? a : NULL, b);
  *cost = 0.5 * sum;
  if (!isfinite(*cost)) return CF_LSQ_NOT_FINITE;
  if (jtj) {
    memcpy(jtj, a, sizeof a);
    memcpy(jtu, b, sizeof b);
  }
  return CF_LSQ_EVALUATED;
}

/* The block's residuals depend on all four unknowns. */
static int all_unknowns(void *user, size_t block, const int **columns) {
  static const int every[NUM_UNKNOWNS] = {0, 1, 2, 3};
  (void)user;
  (void)block;
  *columns = every;
  return NUM_UNKNOWNS;
}

/* Ray i of a view as a unit vector on the same side as ray 0 (a ray is a
 * line here). */
static void oriented_ray(const cf_silhouette_view *view, size_t i, double d[3]) {
  double d0[3];
  unit_ray(view, 0, d0);
  unit_ray(view, i, d);
  if (cf_dot3(d, d0) < 0.0)
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
  return cf_norm3(axis);
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
  double rcond = reciprocal_condition(3, a);
  double x[3];
  if (rcond < RCOND_MIN || !cf_cholesky_solve(3, a, b, x))
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
      double d[3];
      oriented_ray(view, i, d);
      angle_sum += cf_angle3(axis, d);
    }
    double w[3] = {x[0] - view->origin[0], x[1] - view->origin[1], x[2] - view->origin[2]};
    radius_sum += cf_norm3(w) * sin(angle_sum / (double)view->count);
  }
  for (int k = 0; k < 3; ++k) center[k] = x[k];
  *radius = radius_sum / (double)num_views;
  return CF_OK;
}

double cf_sphere_ray_error_px(const cf_silhouette_view *view, const double ray[3],
                              const cf_sphere_fit *fit) {
  double w[3] = {fit->center[0] - view->origin[0], fit->center[1] - view->origin[1],
                 fit->center[2] - view->origin[2]};
  double length = cf_norm3(ray), d[3], c[3];
  for (int k = 0; k < 3; ++k) d[k] = ray[k] / length;
  cf_cross3(w, d, c);
  double ray_angle =
      atan2(cf_norm3(c), fabs(cf_dot3(w, d))); /* a ray is a line: its sign is free */
  double cone_angle = asin(fmin(1.0, fit->radius / cf_norm3(w)));
  return fabs(ray_angle - cone_angle) * view->focal_px;
}

/* rms_px and max_px over all rays (cf_sphere_ray_error_px); CF_ENUMERIC
 * when the sphere contains a camera. */
static cf_status report_errors(const cf_silhouette_view *views, size_t num_views,
                               cf_sphere_fit *fit, cf_error *err) {
  double sum2 = 0.0, max_px = 0.0;
  size_t count = 0;
  for (size_t v = 0; v < num_views; ++v) {
    const cf_silhouette_view *view = &views[v];
    double w[3] = {fit->center[0] - view->origin[0], fit->center[1] - view->origin[1],
                   fit->center[2] - view->origin[2]};
    if (!(cf_norm3(w) > fit->radius))
      return cf_error_set(err, CF_ENUMERIC,
                          "The fitted sphere (centre %g %g %g, radius %g) contains the camera of "
                          "silhouette view %zu, so it cannot be the sphere those views see.",
                          fit->center[0], fit->center[1], fit->center[2], fit->radius, v);
    for (size_t i = 0; i < view->count; ++i) {
      double e = cf_sphere_ray_error_px(view, view->rays + 3 * i, fit);
      sum2 += e * e;
      if (e > max_px) max_px = e;
      ++count;
    }
  }
  fit->rms_px = sqrt(sum2 / (double)count);
  fit->max_px = max_px;
  return CF_OK;
}

/* The message of a normal matrix JᵀJ too ill-conditioned `where` ("at the
 * start", "at the solution"). */
static cf_status singular(cf_error *err, const char *where, double rcond, size_t num_views) {
  return cf_error_set(err, CF_ENUMERIC,
                      "The sphere fit's normal matrix is singular %s (reciprocal condition "
                      "number %.3g): the %zu silhouette views do not constrain the sphere's "
                      "centre and radius (for example, they all see it from one place or along "
                      "one line).",
                      where, rcond, num_views);
}

/* The solve's options: one thread (the problem is one block), and
 * tolerances just above rounding, so that the solve ends where the cost
 * stops telling steps apart: a step under 1e-13 of |x|, or a change of the
 * cost under 1e-14 of itself (its rounding errors at the minimum, measured
 * on silhouettes of synthetic captures: up to 4e-15; below that, steps are
 * rejected on rounding alone until the trust region collapses). */
static void solve_options(cf_lsq_options *options, double *final_jtj) {
  cf_lsq_default_options(options);
  options->max_iterations = MAX_ITERATIONS;
  options->threads = 1;
  options->function_tolerance = 1e-14;
  options->parameter_tolerance = 1e-13;
  options->gradient_tolerance = 0.0;
  options->final_jtj = final_jtj;
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

  double x[NUM_UNKNOWNS] = {center0[0], center0[1], center0[2], radius0};
  const double lower[NUM_UNKNOWNS] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  const double upper[NUM_UNKNOWNS] = {HUGE_VAL, HUGE_VAL, HUGE_VAL, HUGE_VAL};
  sphere_problem data = {views, num_views};
  cf_lsq_problem problem = {NUM_UNKNOWNS, x, lower, upper, 1, all_rays, all_unknowns, &data, NULL};
  double jtj[NUM_UNKNOWNS * NUM_UNKNOWNS], cost;
  double rcond = cf_lsq_normal_equations(&problem, 1, jtj, NULL, &cost) == CF_LSQ_EVALUATED
                     ? reciprocal_condition(NUM_UNKNOWNS, jtj)
                     : 0.0;
  if (rcond < RCOND_MIN) return singular(err, "at the start", rcond, num_views);

  cf_lsq_options options;
  solve_options(&options, jtj);
  cf_lsq_summary summary;
  status = cf_lsq_solve(&problem, &options, &summary, err);
  if (status != CF_OK) {
    cf_error_prefix(err, "The sphere fit from %zu silhouette views", num_views);
    return status;
  }
  if (!summary.converged)
    return cf_error_set(err, CF_ENUMERIC,
                        "The sphere fit did not converge in %d iterations (last centre %g %g %g, "
                        "radius %g).",
                        summary.iterations, x[0], x[1], x[2], x[3]);
  if (!(x[3] > 0.0) || !isfinite(x[3]))
    return cf_error_set(err, CF_ENUMERIC, "The sphere fit ended with radius %g.", x[3]);
  if (!summary.final_normal &&
      cf_lsq_normal_equations(&problem, 1, jtj, NULL, &cost) != CF_LSQ_EVALUATED)
    return cf_error_set(err, CF_ENUMERIC,
                        "The sphere fit's cost is not finite at its solution (centre %g %g %g, "
                        "radius %g).",
                        x[0], x[1], x[2], x[3]);
  rcond = reciprocal_condition(NUM_UNKNOWNS, jtj);
  if (rcond < RCOND_MIN) return singular(err, "at the solution", rcond, num_views);

  cf_sphere_fit result = {{x[0], x[1], x[2]}, x[3], 0.0, 0.0, summary.iterations};
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
