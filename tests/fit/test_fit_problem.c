/* The fit's least-squares problem (fit_problem.h, private to src/fit):
 *   - the unknowns' arrays hold as many unknowns as are declared (they were
 *     fixed at 1036: a capture of more images with --fit-exposures wrote
 *     past them, issue 15);
 *   - a block's evaluation gives the same numbers, to the last bit, on many
 *     threads at once (more than its pool of scratch buffers) as on one;
 *   - its cost is the one of fit_problem_predict's predictions (one
 *     prediction formula), with a response curve too (plus its smoothness
 *     prior);
 *   - its gradient Jᵀu is the cost's by central differences, with every
 *     unknown free, the response curve's slopes too;
 *   - with two lights in every image (a directional light added to the
 *     flash), each slot gets its light (cf_capture_light_ids, named by
 *     cf_capture_light_name), and with a gain per light inside the sums
 *     (fit_problem_free_light_gains) the same three checks hold: threads,
 *     cost against the predictions, gradient against central differences
 *     (with a response curve: the chain rule through it);
 *   - cf_model_slot_param agrees with the model table;
 *   - with a response curve, the noise model's σ is the sensor's carried
 *     through the curve, R'(x) √(read² + shot x) at x = R⁻¹(y) (it was
 *     √(read² + shot y), in the curve's output units). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/model.h"
#include "problem/problem.h"
#include "fit_support.h"
#include "lsq/lsq.h"
#include "core/parallel.h"
#include "support/check.h"

CHECK_MAIN_STATE;

/* Every slot of every model: its owner and component from the table. */
static void test_slot_param(void) {
  for (int id = 0; id < CF_MODEL_COUNT; ++id) {
    const cf_model_info *m = cf_model_info_get((cf_model_id)id);
    for (int j = 0; j < m->param_count; ++j) {
      const cf_param_info *owner = cf_param_info_get(m->params[j]);
      for (int c = 0; c < owner->components; ++c) {
        int k = m->offsets[j] + c, component = -1;
        CHECK(cf_model_slot_param((cf_model_id)id, k, &component) == owner && component == c,
              "%s slot %d: not %s[%d]", m->code, k, owner->name, c);
        CHECK(cf_model_slot_param((cf_model_id)id, k, NULL) == owner, "%s slot %d", m->code, k);
      }
    }
    CHECK(cf_model_slot_param((cf_model_id)id, -1, NULL) == NULL, "%s slot -1", m->code);
    CHECK(cf_model_slot_param((cf_model_id)id, m->dim, NULL) == NULL, "%s slot dim", m->code);
  }
  CHECK(cf_model_slot_param(CF_MODEL_COUNT, 0, NULL) == NULL, "an invalid model");
}

/* Far more unknowns than the old arrays' 1036, each with its own bounds:
 * every one kept (the old arrays overlapped beyond it), and the blocks
 * built over them. */
static void test_many_unknowns(const cf_capture *capture) {
  enum { MANY = 2500 };
  fit_problem *p;
  cf_error err = {0};
  CHECK(fit_problem_new(&p, capture, CF_MODEL_LAMBERT, NULL, 0, 1, &err) == CF_OK, "init: %s",
        err.message);
  if (!p) return;
  for (int round = 0; round < 2; ++round) { /* declared twice: the arrays kept */
    fit_problem_clear_unknowns(p);
    for (int i = 0; i < MANY; ++i) fit_problem_free_slot(p, i % 3);
    CHECK(fit_problem_finish(p, &err) == CF_OK, "finish: %s", err.message);
    CHECK(p->unknowns.num == MANY, "%d unknowns declared, %d kept", MANY, p->unknowns.num);
    int kept = 1;
    for (int i = 0; i < p->unknowns.num; ++i)
      kept = kept && p->unknowns.unknown[i].kind == &fit_kind_material &&
             p->unknowns.unknown[i].slot == i % 3 &&
             p->unknowns.lower[i] == log(FIT_ALBEDO_FLOOR) && p->unknowns.upper[i] == 0.0 &&
             p->unknowns.at_bound[i] == 0;
    CHECK(kept, "an unknown or its bounds overwritten");
    size_t columns = p->blocks.column_begin[p->blocks.count] - p->blocks.column_begin[0];
    CHECK(columns == (size_t)MANY * p->blocks.count, "%zu block columns", columns);
  }
  fit_problem_free(p);
}

/* Every block's cost, JᵀJ and Jᵀu at x, for cf_parallel_for. */
typedef struct block_job {
  fit_problem *p;
  const double *x;
  size_t k; /* the most columns of a block */
  double *cost, *jtj, *jtu;
  int *status;
} block_job;

static void evaluate_block(void *user, int i) {
  const block_job *job = user;
  size_t b = (size_t)i % job->p->blocks.count;
  job->status[i] =
      fit_problem_evaluate(job->p, job->x, b, &job->cost[i], job->jtj + (size_t)i * job->k * job->k,
                           job->jtu + (size_t)i * job->k);
}

/* The blocks evaluated one at a time, then REPEAT times over on THREADS
 * threads at once: the same bits each time. */
static void test_threads(fit_problem *p, const double *x) {
  enum { THREADS = 24, REPEAT = 6 };
  size_t k = (size_t)p->unknowns.num, n = p->blocks.count, calls = n * (REPEAT + 1);
  block_job job = {p,
                   x,
                   k,
                   malloc(calls * sizeof(double)),
                   calloc(calls * k * k, sizeof(double)),
                   calloc(calls * k, sizeof(double)),
                   malloc(calls * sizeof(int))};
  if (!job.cost || !job.jtj || !job.jtu || !job.status) {
    CHECK(0, "out of memory");
    goto done;
  }
  cf_parallel_for((int)n, 1, evaluate_block, &job);
  block_job rest = job; /* calls n.. on the threads */
  rest.cost += n, rest.jtj += n * k * k, rest.jtu += n * k, rest.status += n;
  cf_parallel_for((int)(n * REPEAT), THREADS, evaluate_block, &rest);
  int same = 1;
  for (size_t i = 0; i < calls; ++i) {
    const int *column;
    size_t b = i % n, columns = (size_t)fit_problem_block_columns(p, b, &column);
    CHECK(job.status[i] == CF_LSQ_EVALUATED, "call %zu (block %zu): %d", i, b, job.status[i]);
    same =
        same && memcmp(&job.cost[i], &job.cost[b], sizeof(double)) == 0 &&
        memcmp(job.jtu + i * k, job.jtu + b * k, columns * sizeof(double)) == 0 &&
        memcmp(job.jtj + i * k * k, job.jtj + b * k * k, columns * columns * sizeof(double)) == 0;
  }
  CHECK(same, "a block evaluated on %d threads differs from the same block on one", THREADS);
done:
  free(job.cost);
  free(job.jtj);
  free(job.jtu);
  free(job.status);
}

/* Σ of the blocks' costs at x against ½ Σ ((μ − y)/σ)² from
 * fit_problem_predict at the values x stands for (no loss, σ = 1, nothing
 * censored: the synthetic capture clips nothing). */
static void test_cost_is_prediction(fit_problem *p, const double *x, const char *what) {
  size_t k = (size_t)p->unknowns.num, m = 3 * p->rows.count;
  double total = 0.0, expected = 0.0, cost;
  double *jtj = malloc(k * k * sizeof *jtj), *jtu = malloc(k * sizeof *jtu);
  double *prediction = malloc(m * sizeof *prediction), *measured = malloc(m * sizeof *measured);
  cf_error err = {0};
  if (!jtj || !jtu || !prediction || !measured) {
    CHECK(0, "out of memory");
    goto done;
  }
  for (size_t b = 0; b < p->blocks.count; ++b) {
    CHECK(fit_problem_evaluate(p, x, b, &cost, b % 2 ? jtj : NULL, jtu) == CF_LSQ_EVALUATED,
          "%s: block %zu", what, b);
    total += cost;
  }
  fit_problem_set_x(p, x);
  CHECK(fit_problem_predict(p, prediction, measured, &err) == CF_OK, "%s: %s", what, err.message);
  for (size_t i = 0; i < m; ++i)
    expected += 0.5 * (prediction[i] - measured[i]) * (prediction[i] - measured[i]);
  int response_free = 0;
  for (int u = 0; u < p->unknowns.num; ++u) response_free |= p->unknowns.unknown[u].kind == &fit_kind_response;
  for (int j = 0; response_free && j + 1 < CF_RESPONSE_MODEL_KNOTS; ++j) {
    double r = (p->values.response[j + 1] - p->values.response[j]) / FIT_RESPONSE_PRIOR_SD;
    expected += 0.5 * r * r; /* the smoothness prior's */
  }
  CHECK(fabs(total - expected) <= 1e-9 * expected, "%s: cost %.17g, from the predictions %.17g",
        what, total, expected);
done:
  free(jtj);
  free(jtu);
  free(prediction);
  free(measured);
}

/* The cost over every block at x, and with g its gradient Σ Jᵀu (k). */
static double total_cost(fit_problem *p, const double *x, double *g) {
  size_t k = (size_t)p->unknowns.num;
  double *jtj = malloc(k * k * sizeof *jtj), *jtu = malloc(k * sizeof *jtu), total = 0.0, cost;
  for (size_t a = 0; g && a < k; ++a) g[a] = 0.0;
  for (size_t b = 0; jtj && jtu && b < p->blocks.count; ++b) {
    fit_problem_evaluate(p, x, b, &cost, g ? jtj : NULL, jtu);
    total += cost;
    const int *column;
    int columns = fit_problem_block_columns(p, b, &column);
    for (int c = 0; g && c < columns; ++c) g[column[c]] += jtu[c];
  }
  free(jtj);
  free(jtu);
  return total;
}

/* The analytic gradient against central differences of the cost, every
 * unknown; a wrong ∂R/∂a_j or chain rule shows here. */
static void test_gradient(fit_problem *p, const double *x) {
  size_t k = (size_t)p->unknowns.num;
  double g[64], y[64], scale = 0.0;
  total_cost(p, x, g);
  for (size_t a = 0; a < k; ++a) scale = fmax(scale, fabs(g[a]));
  for (size_t a = 0; a < k; ++a) {
    double h = 1e-6 * fmax(1.0, fabs(x[a]));
    memcpy(y, x, k * sizeof *y);
    y[a] = x[a] + h;
    double up = total_cost(p, y, NULL);
    y[a] = x[a] - h;
    double down = total_cost(p, y, NULL);
    double fd = (up - down) / (2.0 * h);
    double off = fabs(fd - g[a]) / fmax(fabs(g[a]), 1e-3 * scale);
    CHECK(off < 1e-4, "unknown %zu (%s, slot %d): gradient %.9g, central difference %.9g", a,
          p->unknowns.unknown[a].kind->name, p->unknowns.unknown[a].slot, g[a], fd);
  }
}

/* M2 with every slot, the scale and the exposures free, a little off the
 * truth (and again with a response curve). */
static void test_evaluate(const cf_capture *capture) {
  fit_problem *p;
  cf_error err = {0};
  if (fit_problem_new(&p, capture, CF_MODEL_DIELECTRIC, NULL, 0, 2, &err) != CF_OK) {
    CHECK(0, "init: %s", err.message);
    return;
  }
  fit_problem_set_sigma(p, 1.0);
  p->loss = CF_LOSS_NONE;
  p->blocks.size = 256; /* blocks of one image, and of two */
  fit_problem_clear_unknowns(p);
  for (int k = 0; k < p->dim; ++k) fit_problem_free_slot(p, k);
  fit_problem_free_scale(p);
  fit_problem_free_exposures(p);
  CHECK(fit_problem_finish(p, &err) == CF_OK, "finish: %s", err.message);
  double x[64];
  CHECK(p->unknowns.num <= 64, "%d unknowns", p->unknowns.num);
  fit_problem_get_x(p, x);
  for (int u = 0; u < p->unknowns.num; ++u) x[u] += 0.01 * (u % 5 - 2); /* inside the bounds */
  test_threads(p, x);
  test_cost_is_prediction(p, x, "linear");
  const double slopes[CF_RESPONSE_MODEL_KNOTS] = {0.8, 0.7, 0.9, 1.1, 1.3, 1.2};
  memcpy(p->values.response, slopes, sizeof slopes);
  fit_problem_clear_unknowns(p);
  for (int k = 0; k < p->dim; ++k) fit_problem_free_slot(p, k);
  fit_problem_free_scale(p);
  fit_problem_free_exposures(p);
  fit_problem_free_response(p);
  CHECK(fit_problem_finish(p, &err) == CF_OK, "finish: %s", err.message);
  fit_problem_get_x(p, x);
  test_threads(p, x);
  test_cost_is_prediction(p, x, "with a response curve");
  test_gradient(p, x);
  fit_problem_free(p);
}

/* A gain per light inside the sums: a capture whose images each have a
 * directional light (slot 0) and the flash (slot 1). */
static void test_light_gains(const cf_capture *capture) {
  fit_problem *p;
  cf_error err = {0};
  if (fit_problem_new(&p, capture, CF_MODEL_DIELECTRIC, NULL, 0, 2, &err) != CF_OK) {
    CHECK(0, "init: %s", err.message);
    return;
  }
  char name[2][96];
  cf_capture_light_name(capture, 3, 0, name[0], sizeof name[0]);
  cf_capture_light_name(capture, 3, 1, name[1], sizeof name[1]);
  const fit_groups *g = &p->groups;
  CHECK(g->lights == 2 && g->light_count == 2 && g->several_lights && g->image_lights == 2 &&
            g->slot_light[6] == 0 && g->slot_light[7] == 1 && !strcmp(name[0], "light 1") &&
            !strcmp(name[1], "light 2"),
        "two lights in every image: %d slots, %zu lights (%s, %s)", g->lights, g->light_count,
        name[0], name[1]);
  fit_problem_set_sigma(p, 1.0);
  p->loss = CF_LOSS_NONE;
  p->blocks.size = 256;
  const double slopes[CF_RESPONSE_MODEL_KNOTS] = {0.8, 0.7, 0.9, 1.1, 1.3, 1.2};
  /* each pass starts from the same parameters, a little off them: carried
   * over, the second pass put f0 on its bound 0, where the exact Fresnel
   * (model version 2) has a one-sided derivative only and a central
   * difference straddles the bound */
  double start[CF_MAX_DIM];
  memcpy(start, p->values.params, sizeof start);
  for (int curve = 0; curve < 2; ++curve) {
    memcpy(p->values.params, start, sizeof start);
    if (curve) memcpy(p->values.response, slopes, sizeof slopes);
    fit_problem_clear_unknowns(p);
    for (int k = 0; k < p->dim; ++k) fit_problem_free_slot(p, k);
    fit_problem_free_light_gains(p);
    if (curve) fit_problem_free_response(p);
    CHECK(fit_problem_finish(p, &err) == CF_OK, "finish: %s", err.message);
    double x[64];
    fit_problem_get_x(p, x);
    for (int u = 0; u < p->unknowns.num; ++u) x[u] += 0.01 * (u % 5 - 2);
    x[p->unknowns.num - (curve ? 1 + CF_RESPONSE_MODEL_KNOTS : 1)] = 0.2; /* log g of light 1 */
    test_threads(p, x);
    test_cost_is_prediction(p, x, curve ? "light gains, a response curve" : "light gains");
    test_gradient(p, x);
  }
  fit_problem_free(p);
}

/* The noise model's σ at the measurements through the curve R(x) = √x
 * (every slope 1/2): R'(x) √(read² + shot x), x = y², R'(x) = 1/(2y). */
static void test_noise_through_curve(const cf_capture *capture) {
  fit_problem *p;
  cf_error err = {0};
  if (fit_problem_new(&p, capture, CF_MODEL_DIELECTRIC, NULL, 0, 1, &err) != CF_OK) {
    CHECK(0, "init: %s", err.message);
    return;
  }
  cf_capture_summary about;
  cf_capture_summarize(capture, &about);
  CHECK(fit_capture_has_noise(capture), "the capture has a noise model");
  for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j) p->values.response[j] = 0.5;
  fit_problem_clear_unknowns(p);
  fit_problem_free_response(p);
  fit_problem_set_sigma(p, 1.0);
  double read2 = about.noise_read * about.noise_read, worst = 0.0;
  size_t checked = 0;
  for (size_t i = 0; i < 3 * p->rows.count; ++i) {
    double y = p->rows.y[i], x = y * y;
    if (!(x > cf_response_model_knot(CF_RESPONSE_MODEL_KNOTS - 1))) continue;
    double sigma = sqrt(read2 + about.noise_shot * x) / (2.0 * y);
    worst = fmax(worst, fabs(1.0 / p->rows.inv_sigma[i] / sigma - 1.0));
    ++checked;
  }
  CHECK(checked > 100 && worst < 1e-9, "σ through the curve: %zu values, worst relative error %g",
        checked, worst);
  fit_problem_free(p);
}

int main(void) {
  test_slot_param();
  char dir[64];
  if (!fit_test_make_dir(dir, sizeof dir)) return 1;
  double params[CF_MAX_DIM] = {0.6, 0.4, 0.3, 0.3, 0.3, 0.05};
  cf_synth_options o;
  fit_test_synth_options(&o, CF_MODEL_DIELECTRIC, params);
  o.images = 4;
  o.width = 80;
  o.height = 60;
  o.focal_px = 100.0;
  o.read_noise = o.shot_noise = 0.0;
  cf_capture *capture = fit_test_capture(dir, "m2", &o);
  if (capture) {
    test_many_unknowns(capture);
    test_evaluate(capture);
    cf_capture_free(capture);
  }
  char folder[512]; /* the same photos, a directional light added to the flash */
  if (fit_test_render(dir, "two_lights", &o, folder, sizeof folder) &&
      fit_test_edit_text(folder, "capture.json", "\"lights\": [",
                         "\"lights\": [{\"type\": \"directional\", \"direction\": [0.3, -0.5, "
                         "1], \"irradiance\": [1, 1, 1]}, ") &&
      (capture = fit_test_load(folder))) {
    test_light_gains(capture);
    cf_capture_free(capture);
  }
  o.read_noise = 0.002;
  o.shot_noise = 0.0005;
  capture = fit_test_capture(dir, "m2_noise", &o);
  if (capture) {
    test_noise_through_curve(capture);
    cf_capture_free(capture);
  }
  fit_test_remove_dir(dir);
  return check_finish("test_fit_problem");
}
