/* The prediction of every observation at the current values
 * (fit_problem.h): docs/model.md (40), on the problem's threads. */
#include <stdlib.h>

#include "fit_row.h"
#include "fit_scratch.h"
#include "core/parallel.h"

/* A range of rows' predictions, on one thread. */
typedef struct predict_job {
  const fit_problem *p;
  double *prediction, *measured;
  size_t rows_per_part;
  int failed;
} predict_job;

/* Rows [begin, end)'s predictions, their model values in f (from their
 * first pair, first_pair) and s's light arrays. */
static void predict_rows(const fit_problem *p, fit_scratch *s, size_t begin, size_t end,
                         size_t first_pair, double *prediction, double *measured) {
  const fit_values *v = &p->values;
  uint32_t gain_image = UINT32_MAX;
  double gain[3] = {0.0, 0.0, 0.0};
  for (size_t i = begin; i < end; ++i) {
    size_t first;
    size_t slots = fit_rows_slot_range(&p->rows, i, &first);
    if (p->rows.image[i] != gain_image) {
      gain_image = p->rows.image[i];
      for (int c = 0; c < 3; ++c)
        gain[c] = fit_image_gain(v->log_scale, v->log_exposures[gain_image] +
                                                   v->log_balance[3 * (size_t)gain_image + (size_t)c]);
      if (p->light_gains_on) fit_image_slot_gains(p, v->log_light, gain_image, s->slot_gain);
    }
    const double *w = p->rows.weight + 3 * first;
    if (p->light_gains_on)
      w = fit_light_weighted(p, s->slot_gain, w, slots, s->light_w + 3 * (first - first_pair));
    for (int c = 0; c < 3; ++c) {
      const double *dmodel;
      double weight_one;
      double model = fit_model_value(w, s->f, NULL, p->dim, first - first_pair, slots, c, NULL,
                                     &dmodel, &weight_one);
      prediction[3 * i + (size_t)c] =
          fit_predict_channel(p->response_on, v->response, gain[c] * model, NULL, NULL);
      measured[3 * i + (size_t)c] = p->rows.y[3 * i + (size_t)c];
    }
  }
}

static void predict_part(void *user, int part) {
  predict_job *job = user;
  const fit_problem *p = job->p;
  size_t begin = (size_t)part * job->rows_per_part;
  size_t end = begin + job->rows_per_part < p->rows.count ? begin + job->rows_per_part
                                                          : p->rows.count;
  if (begin >= end) return;
  size_t first_pair, last_pair;
  fit_rows_slot_range(&p->rows, begin, &first_pair);
  size_t last_slots = fit_rows_slot_range(&p->rows, end - 1, &last_pair);
  size_t pairs = last_pair + last_slots - first_pair;
  fit_scratch *s = fit_scratch_take(p);
  if (!s || !fit_scratch_fit(s, p, pairs, 0)) {
    fit_scratch_give(s);
    job->failed = 1;
    return;
  }
  cf_eval_batch(p->model, p->values.params, pairs, p->rows.geometry + first_pair, s->f, NULL);
  predict_rows(p, s, begin, end, first_pair, job->prediction, job->measured);
  fit_scratch_give(s);
}

cf_status fit_problem_predict(const fit_problem *p, double *prediction, double *measured,
                              cf_error *err) {
  /* parts of whole blocks, one per thread, for a population worth it (4 blocks: 5cf3abf; 2, 8:
   * no fit moves, time not measured) */
  size_t block = p->blocks.size;
  int parts = p->threads > 1 && p->rows.count >= 4 * block ? p->threads : 1;
  size_t blocks = (p->rows.count + block - 1) / block;
  predict_job job = {p, prediction, measured,
                     ((blocks + (size_t)parts - 1) / (size_t)parts) * block, 0};
  if (job.rows_per_part == 0) job.rows_per_part = 1;
  cf_parallel_for(parts, parts, predict_part, &job);
  return job.failed ? cf_error_set(err, CF_ENOMEM, "out of memory") : CF_OK;
}
