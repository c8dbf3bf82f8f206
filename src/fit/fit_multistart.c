/* The start of a fit (fit_multistart.h). */
#include "fit_multistart.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"
#include "fit_residuals.h"
#include "fit_sample.h"
#include "fit_starts.h"
#include "core/parallel.h"

/* Every start runs to convergence (START_ITERATIONS at most) on a
 * subsample of about SUBSAMPLE_TARGET observations spread over the
 * images. */
enum {
  SUBSAMPLE_TARGET = 4000, /* fd063f4; at 2000 or 8000 all 10 screened fits move (study) */
  START_ITERATIONS = 300   /* reached by 5 of 4686 starts in the fit tests */
};

/* A start only has to find its basin: the best is refined on more
 * observations and then on all of them. It stops when an iteration
 * changes the cost by less than this, relative (Δχ² about 0.1 on the
 * subsample's scale of about 10⁶), not lsq.h's 1e-10. */
#define START_TOLERANCE 1e-7

/* ... and takes a step only when it lowers the cost by 5 % of the decrease
 * its quadratic model predicts (Ceres' 1e-3 for the fit itself): far from
 * a minimum, steps across a bound or along a curved valley that keep 0.1 %
 * of their promise otherwise halve the trust region one accepted step at a
 * time. Measured on the starts of synthetic M4 captures: 299 and 451
 * iterations become 184 and 304, the minima found the same; on DiLiGenT
 * 238 become 255. (For the fit on every observation it broke two hard
 * cases: a noise-free F0 went to its bound.) */
#define START_MIN_RELATIVE_DECREASE 0.05

/* ρ per channel of a Lambertian fit to the least specular half of the
 * observations (those whose half vector is farthest from the normal). */
static void lambert_albedo(const fit_problem *p, double rho[3]) {
  size_t n = fit_problem_count(p);
  const double *y = fit_problem_measured(p);
  double *specularity = malloc(n * sizeof *specularity), *sorted = malloc(n * sizeof *sorted);
  rho[0] = rho[1] = rho[2] = 0.5;
  if (!specularity || !sorted || n == 0) {
    free(specularity);
    free(sorted);
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    double most = 0.0;
    const cf_geometry *g;
    const double *w;
    size_t slots = fit_problem_pairs(p, i, &g, &w);
    for (size_t j = 0; j < slots; ++j)
      if (cf_geometry_is_lit(&g[j])) most = fmax(most, g[j].cos2_h);
    specularity[i] = sorted[i] = most;
  }
  double threshold = order_kth_smallest(sorted, n, n / 2); /* the median */
  double num[3] = {0}, den[3] = {0};
  for (size_t i = 0; i < n; ++i) {
    if (specularity[i] > threshold) continue;
    const cf_geometry *g;
    const double *w;
    size_t slots = fit_problem_pairs(p, i, &g, &w);
    for (int c = 0; c < 3; ++c) {
      double q = 0.0; /* the Lambertian prediction with ρ = 1 */
      for (size_t j = 0; j < slots; ++j) q += w[3 * j + (size_t)c] / 3.14159265358979;
      num[c] += y[3 * i + (size_t)c] * q;
      den[c] += q * q;
    }
  }
  for (int c = 0; c < 3; ++c) rho[c] = den[c] > 0.0 ? num[c] / den[c] : 0.5;
  free(specularity);
  free(sorted);
}

/* The base start: the albedo (and, with a free scale, the scale that puts
 * the albedo inside [0, 1]); held slots at their held values. */
void fit_base_start(const fit_problem *p, const fit_plan *plan, const cf_fit_options *o,
                    double *params, double *log_scale) {
  cf_model_id model = fit_problem_model(p);
  const cf_model_info *m = cf_model_info_get(model);
  cf_model_default_params(model, params);
  for (int k = 0; k < m->dim; ++k)
    if (plan->status[k] != CF_PARAM_FITTED && o->hold[k]) params[k] = o->hold_value[k];
  int sk = fit_scale_slot(model);
  if (sk >= 0 && plan->status[sk] == CF_PARAM_HELD_FOR_SCALE && !o->hold[sk])
    params[sk] = FIT_SCALE_F0;
  double rho[3];
  lambert_albedo(p, rho);
  double largest = fmax(rho[0], fmax(rho[1], rho[2]));
  *log_scale = 0.0;
  if (plan->scale && largest > 0.0) { /* the largest albedo at 0.5, its default (model.h) */
    *log_scale = log(largest / 0.5);
    for (int c = 0; c < 3; ++c) rho[c] /= largest / 0.5;
  }
  for (int c = 0; c < 3; ++c) /* a start inside the bounds (2 %, as fit_starts.c's albedos) */
    if (plan->status[c] == CF_PARAM_FITTED) params[c] = fmin(0.98, fmax(0.02, rho[c]));
}

/* A start has found an earlier start's minimum again, and stops there
 * instead of converging to it (its cost is then a little above the
 * earlier start's), when it comes
 *   - within START_SAME_BASIN of every unknown's range (1 for an unbounded
 *     one, in log units) of where the earlier start ended, or
 *   - within the noise of it: ½ dᵀ H d, the cost above that minimum by its
 *     normal matrix H, below σ² (Δχ² < 2; σ² ≈ 2 cost / residuals there),
 *     and the cost itself no more than 2 σ² above it. Along a valley the
 *     data barely constrain (a film's optical depth against the albedo
 *     under it) a start otherwise crawls to the minimum for tens of
 *     iterations. */
#define START_SAME_BASIN 0.01 /* 65bb077; 0.005, 0.02: no chosen fit's value moves (study) */

typedef struct earlier_ends {
  const fit_problem *p;
  double *x;      /* count × num_unknowns */
  double *h;      /* count × num_unknowns²: the normal matrix there, or NaN */
  double *cost;   /* count */
  double *sigma2; /* count: 2 cost / residuals */
  int count;
} earlier_ends;

static int within_noise(const earlier_ends *e, int j, const double *x, double cost) {
  int n = fit_problem_unknown_count(e->p);
  const double *end = e->x + (size_t)j * (size_t)n, *h = e->h + (size_t)j * (size_t)n * (size_t)n;
  if (!(e->sigma2[j] > 0.0) || !isfinite(h[0]) || cost > e->cost[j] + 2.0 * e->sigma2[j]) return 0;
  double quadratic = 0.0;
  for (int a = 0; a < n; ++a) {
    double row = 0.0;
    for (int b = 0; b < n; ++b) row += h[a * n + b] * (x[b] - end[b]);
    quadratic += (x[a] - end[a]) * row;
  }
  return 0.5 * quadratic < e->sigma2[j];
}

static int reached_earlier_end(void *user, const double *x, double cost) {
  const earlier_ends *e = user;
  const fit_problem *p = e->p;
  int n = fit_problem_unknown_count(p);
  for (int j = 0; j < e->count; ++j) {
    const double *end = e->x + (size_t)j * (size_t)n;
    int near = 1;
    for (int i = 0; i < n && near; ++i) {
      double lower = fit_problem_lower(p, i), upper = fit_problem_upper(p, i);
      double width = isfinite(lower) && isfinite(upper) ? upper - lower : 1.0;
      near = fabs(x[i] - end[i]) <= START_SAME_BASIN * width;
    }
    if (near || within_noise(e, j, x, cost)) return 1;
  }
  return 0;
}

/* One start, on a fork of the subsample's problem (fit_problem_fork: its
 * observations shared, its values its own). */
typedef struct start_job {
  fit_problem *problem;
  cf_fit_options options;
  cf_lsq_summary summary;
  double *h; /* the normal matrix at a minimum (NaN: none) */
  cf_status status;
  cf_error err;
} start_job;

static void run_job(void *user, int i) {
  start_job *job = &((start_job *)user)[i];
  job->status = fit_solve(job->problem, &job->options, START_ITERATIONS, &job->summary, &job->err);
  job->h[0] = NAN;
  if (job->status == CF_OK && !job->summary.stopped &&
      fit_normal_equations(job->problem, 1, job->h, NULL, NULL, &job->err) != CF_OK)
    job->h[0] = NAN; /* no test within the noise of this minimum */
}

/* Job j of a batch: its fork of the subsample's problem at its start, a
 * trust region of its own. */
static void prepare_job(start_job *job, const fit_problem *sub, const cf_fit_options *o,
                        const double *start, double log_scale, int width) {
  fit_problem_copy_values(job->problem, sub);
  fit_values *v = fit_problem_values(job->problem);
  memcpy(v->params, start, sizeof v->params);
  v->log_scale = log_scale;
  fit_problem_forget_radius(job->problem); /* a start far from the last one's end */
  job->options = *o;
  if (width > 1) job->options.threads = 1;
}

/* Run `count` starts of `model` on the problem to convergence (or to an
 * earlier start's minimum); the best is r->start[r->best_start]. With two
 * threads or more the starts run in batches of that many side by side,
 * each on one thread; a start compares itself with the minima of the
 * batches before its own only, so the result does not depend on which
 * finishes first. */
static cf_status run_starts(fit_problem *sub, const cf_fit_options *o, const fit_plan *plan,
                            double (*starts)[CF_MAX_DIM], int count, double log_scale,
                            cf_fit_result *r, double *log_scales, cf_error *err) {
  cf_status s = fit_declare(sub, plan, err);
  fit_solve_settings *settings = fit_problem_settings(sub);
  settings->function_tolerance = START_TOLERANCE;
  settings->min_relative_decrease = START_MIN_RELATIVE_DECREASE;
  int width = o->threads >= 2 ? (o->threads < count ? o->threads : count) : 1;
  if (width < 1) width = 1;
  size_t n = (size_t)fit_problem_unknown_count(sub);
  earlier_ends ends = {sub, NULL, NULL, NULL, NULL, 0};
  settings->stop = reached_earlier_end;
  settings->stop_user = &ends;
  start_job *jobs = s == CF_OK ? calloc((size_t)width, sizeof *jobs) : NULL;
  if (s == CF_OK && !jobs) s = cf_error_set(err, CF_ENOMEM, "out of memory");
  for (int j = 0; s == CF_OK && j < width; ++j) {
    s = fit_problem_fork(sub, &jobs[j].problem, err);
    if (s == CF_OK && !(jobs[j].h = malloc((n ? n * n : 1) * sizeof(double))))
      s = cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  if (s == CF_OK) {
    ends.x = malloc((size_t)count * (n ? n : 1) * sizeof *ends.x);
    ends.h = malloc((size_t)count * (n ? n * n : 1) * sizeof *ends.h);
    ends.cost = malloc((size_t)count * sizeof *ends.cost);
    ends.sigma2 = malloc((size_t)count * sizeof *ends.sigma2);
    if (!ends.x || !ends.h || !ends.cost || !ends.sigma2)
      s = cf_error_set(err, CF_ENOMEM, "out of memory");
  }
  r->starts = 0;
  r->best_start = 0;
  for (int i = 0; s == CF_OK && i < count; i += width) {
    fit_progress(o, "multi-start", (size_t)i, (size_t)count);
    int batch = count - i < width ? count - i : width;
    for (int j = 0; j < batch; ++j) prepare_job(&jobs[j], sub, o, starts[i + j], log_scale, width);
    cf_parallel_for(batch, width, run_job, jobs);
    for (int j = 0; s == CF_OK && j < batch; ++j) { /* in the starts' order */
      start_job *job = &jobs[j];
      if (job->status != CF_OK) {
        *err = job->err;
        s = job->status;
        break;
      }
      cf_fit_start *start = &r->start[r->starts++];
      memcpy(start->start, starts[i + j], sizeof starts[i + j]);
      const fit_values *end = fit_problem_read_values(job->problem);
      memcpy(start->end, end->params, sizeof end->params);
      start->cost = job->summary.final_cost;
      start->iterations = job->summary.iterations;
      start->stopped = job->summary.stopped;
      log_scales[i + j] = end->log_scale;
      if (start->cost < r->start[r->best_start].cost) r->best_start = i + j;
      if (!job->summary.stopped) {
        int e = ends.count++;
        fit_problem_get_x(job->problem, ends.x + (size_t)e * n);
        memcpy(ends.h + (size_t)e * n * n, job->h, n * n * sizeof *job->h);
        ends.cost[e] = job->summary.final_cost;
        size_t count_sub = fit_problem_count(sub);
        ends.sigma2[e] =
            count_sub ? 2.0 * job->summary.final_cost / (3.0 * (double)count_sub) : 0.0;
      }
    }
  }
  settings->stop = NULL;
  settings->stop_user = NULL;
  for (int j = 0; jobs && j < width; ++j) {
    fit_problem_free(jobs[j].problem);
    free(jobs[j].h);
  }
  free(jobs);
  free(ends.x);
  free(ends.h);
  free(ends.cost);
  free(ends.sigma2);
  fit_progress(o, "multi-start", (size_t)count, (size_t)count);
  return s;
}

/* M2's fit on the subsample, for the warm starts of M3 and M4. */
static cf_status warm_dielectric(const cf_capture *capture, const cf_fit_options *o,
                                 const fit_sample *sample, double *m2, cf_error *err) {
  cf_fit_options o2 = *o;
  memset(o2.hold, 0, sizeof o2.hold);
  memset(o2.free, 0, sizeof o2.free);
  o2.model = CF_MODEL_DIELECTRIC;
  fit_plan plan;
  fit_plan_for(capture, &o2, &plan);
  fit_problem *sub;
  cf_status s =
      fit_problem_new(&sub, capture, CF_MODEL_DIELECTRIC, sample->index, sample->count, 1, err);
  if (s != CF_OK) return s;
  s = fit_problem_set_sample_weights(sub, sample->weight, err);
  double base[CF_MAX_DIM], log_scale, starts[CF_FIT_MAX_STARTS][CF_MAX_DIM],
      log_scales[CF_FIT_MAX_STARTS];
  fit_base_start(sub, &plan, &o2, base, &log_scale);
  int held[CF_MAX_DIM], dim = fit_problem_dim(sub);
  for (int k = 0; k < CF_MAX_DIM; ++k) held[k] = k < dim && plan.status[k] != CF_PARAM_FITTED;
  int count = fit_starts(CF_MODEL_DIELECTRIC, base, held, NULL, starts, CF_FIT_MAX_STARTS);
  cf_fit_result *r = s == CF_OK ? calloc(1, sizeof *r) : NULL;
  if (s == CF_OK)
    s = r ? run_starts(sub, &o2, &plan, starts, count, log_scale, r, log_scales, err)
          : cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) memcpy(m2, r->start[r->best_start].end, sizeof r->start[0].end);
  free(r);
  fit_problem_free(sub);
  return s;
}

/* The multi-start on a subsample; returns the best start's values and σ
 * estimated there. */
cf_status fit_multistart(const cf_capture *capture, const fit_population *population,
                         const cf_fit_options *o, const fit_plan *plan, cf_fit_result *r,
                         double *best_params, double *best_log_scale, double *sigma,
                         cf_error *err) {
  fit_sample sample;
  fit_problem *sub;
  cf_status s =
      fit_sample_problem(&sub, &sample, capture, o->model, population, SUBSAMPLE_TARGET, err);
  if (s != CF_OK) return s;
  double base[CF_MAX_DIM], log_scale;
  fit_base_start(sub, plan, o, base, &log_scale);
  int held[CF_MAX_DIM], dim = fit_problem_dim(sub);
  for (int k = 0; k < CF_MAX_DIM; ++k) held[k] = k < dim && plan->status[k] != CF_PARAM_FITTED;
  /* M3 and M4 start from the fitted M2 */
  double m2[CF_MAX_DIM];
  cf_model_id twin = cf_model_info_get(o->model)->ggx_twin;
  int warm = o->multistart && (twin == CF_MODEL_CLAY || twin == CF_MODEL_CLEARCOAT);
  if (warm && s == CF_OK) s = warm_dielectric(capture, o, &sample, m2, err);
  double starts[CF_FIT_MAX_STARTS][CF_MAX_DIM], log_scales[CF_FIT_MAX_STARTS];
  int count = s == CF_OK && o->multistart
                  ? fit_starts(o->model, base, held, warm ? m2 : NULL, starts, CF_FIT_MAX_STARTS)
                  : 0;
  if (count == 0) { /* no multi-start: the base alone */
    memcpy(starts[0], base, sizeof base);
    count = 1;
  }
  if (s == CF_OK) s = run_starts(sub, o, plan, starts, count, log_scale, r, log_scales, err);
  if (s == CF_OK) {
    memcpy(best_params, r->start[r->best_start].end, sizeof r->start[0].end);
    *best_log_scale = log_scales[r->best_start];
  }
  /* σ from the residuals at the best start (when the capture has no noise
   * model): the subsample's are as good an estimate as all of them */
  if (s == CF_OK) {
    fit_values *v = fit_problem_values(sub);
    memcpy(v->params, best_params, sizeof v->params);
    v->log_scale = *best_log_scale;
    s = fit_estimate_sigma(sub, sigma, err);
  }
  fit_problem_free(sub);
  fit_sample_free(&sample);
  return s;
}

cf_status fit_start_sigma(const cf_capture *capture, const fit_population *population,
                          const cf_fit_options *o, const double *params, double log_scale,
                          double *sigma, cf_error *err) {
  fit_sample sample;
  fit_problem *sub;
  cf_status s =
      fit_sample_problem(&sub, &sample, capture, o->model, population, SUBSAMPLE_TARGET, err);
  if (s != CF_OK) return s;
  fit_values *v = fit_problem_values(sub);
  memcpy(v->params, params, sizeof v->params);
  v->log_scale = log_scale;
  s = fit_estimate_sigma(sub, sigma, err);
  fit_problem_free(sub);
  fit_sample_free(&sample);
  return s;
}

/* A start that ends far from the best (in units of each parameter's
 * range) with a cost within the noise of the best's (Δcost < 1 in units
 * of σ², that is Δχ² < 2) makes the fit ambiguous. (Two local minima far
 * above the best that tie with each other do not: the demo's two at
 * Δcost 134 above it did.) */
int fit_ambiguous(const cf_fit_result *r, cf_model_id model, double sigma2) {
  const cf_model_info *m = cf_model_info_get(model);
  if (r->starts == 0) return 0;
  int a = r->best_start;
  for (int b = 0; b < r->starts; ++b) {
    if (b == a || r->start[b].stopped) continue; /* a minimum found again */
    if (fabs(r->start[a].cost - r->start[b].cost) / sigma2 >= 1.0) continue;
    double distance = 0.0;
    for (int j = 0; j < m->param_count; ++j) {
      const cf_param_info *info = cf_param_info_get(m->params[j]);
      for (int c = 0; c < info->components; ++c) {
        int k = m->offsets[j] + c;
        double d = (r->start[a].end[k] - r->start[b].end[k]) / (info->upper - info->lower);
        distance = fmax(distance, fabs(d));
      }
    }
    if (distance > 0.05) return 1; /* fd063f4; 0.025, 0.1: no screened fit's flag moves */
  }
  return 0;
}
