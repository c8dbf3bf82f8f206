/* Pixel budgets (fit_budget.h). */
#include "fit_budget.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"

static size_t member(const fit_population *from, size_t i) {
  return from->index ? from->index[i] : i;
}

/* The importance strata: 0 kept whole (a highlight: among the 1/16 of the
 * population nearest one; or the silhouette region, n·v < 0.3), 1 the
 * rest. */
static cf_status importance_strata(const cf_observations *obs, const fit_population *from,
                                   uint8_t *stratum, cf_error *err) {
  size_t n = from->count;
  double *score = malloc((n ? n : 1) * sizeof *score),
         *sorted = malloc((n ? n : 1) * sizeof *sorted);
  if (!score || !sorted) {
    free(score);
    free(sorted);
    return cf_error_set(err, CF_ENOMEM, "out of memory for a budget of %zu observations", n);
  }
  for (size_t i = 0; i < n; ++i)
    score[i] = sorted[i] = cf_observation_specularity(obs, member(from, i));
  size_t top = n / 16 > 0 ? n / 16 : 1; /* the highlights: the `top` nearest */
  double threshold = n ? order_kth_smallest(sorted, n, n - top) : 0.0;
  for (size_t i = 0; i < n; ++i) {
    size_t k = member(from, i);
    const double *nrm = obs->normal + 3 * k, *v = obs->view + 3 * k;
    double cos_o = nrm[0] * v[0] + nrm[1] * v[1] + nrm[2] * v[2];
    stratum[i] = (uint8_t)(score[i] >= threshold || cos_o < 0.3 ? 0 : 1);
  }
  free(score);
  free(sorted);
  return CF_OK;
}

cf_status fit_budget_draw(const cf_observations *obs, const fit_population *from, size_t budget,
                          cf_sampling sampling, fit_sample *sample, cf_error *err) {
  if (sampling == CF_SAMPLING_STRATIFIED || from->count <= budget)
    return fit_sample_draw(obs, from, budget, sample, err);
  memset(sample, 0, sizeof *sample);
  size_t n = from->count;
  uint8_t *stratum = calloc(n, 1);
  sample->index = malloc((budget + 2) * sizeof *sample->index);
  sample->weight = malloc((budget + 2) * sizeof *sample->weight);
  cf_status s = stratum && sample->index && sample->weight
                    ? CF_OK
                    : cf_error_set(err, CF_ENOMEM, "out of memory for a budget of %zu", budget);
  if (s == CF_OK && sampling == CF_SAMPLING_IMPORTANCE)
    s = importance_strata(obs, from, stratum, err);
  else if (s == CF_OK)
    memset(stratum, 1, n); /* uniform: one stratum, the rest */
  if (s != CF_OK) {
    free(stratum);
    fit_sample_free(sample);
    return s;
  }
  /* per stratum: its size, what it gets (uniform: one stratum, all of it) */
  size_t size[2] = {0, 0};
  for (size_t i = 0; i < n; ++i) ++size[stratum[i]];
  size_t want[2];
  if (sampling == CF_SAMPLING_IMPORTANCE) {
    want[0] = size[0] < budget / 2 ? size[0] : budget / 2;
    want[1] = budget - want[0];
  } else {
    want[0] = 0, want[1] = budget;
  }
  size_t taken[2] = {0, 0}, spread[2] = {0, 0}, m = 0;
  for (size_t i = 0; i < n && m < budget + 2; ++i) {
    int t = stratum[i];
    if (want[t] == 0 || !fit_spread_take(&spread[t], want[t], size[t])) continue;
    sample->index[m] = (uint32_t)member(from, i);
    sample->weight[m++] = (double)t;
    ++taken[t];
  }
  for (size_t i = 0; i < m; ++i) {
    int t = (int)sample->weight[i];
    sample->weight[i] = (double)size[t] / (double)taken[t];
  }
  sample->count = m;
  free(stratum);
  return CF_OK;
}

/* The population's members grouped by image (a counting sort): image k's
 * are order[begin[k] .. begin[k + 1]). */
static cf_status group_by_image(const cf_observations *obs, const fit_population *from,
                                size_t images, uint32_t **order, size_t **begin, cf_error *err) {
  size_t n = from->count;
  *order = malloc((n ? n : 1) * sizeof **order);
  *begin = calloc(images + 2, sizeof **begin);
  if (!*order || !*begin) {
    free(*order);
    free(*begin);
    return cf_error_set(err, CF_ENOMEM, "out of memory grouping %zu observations by image", n);
  }
  for (size_t i = 0; i < n; ++i) ++(*begin)[obs->image[member(from, i)] + 2];
  for (size_t k = 0; k < images; ++k) (*begin)[k + 2] += (*begin)[k + 1];
  for (size_t i = 0; i < n; ++i) {
    size_t k = member(from, i);
    (*order)[(*begin)[obs->image[k] + 1]++] = (uint32_t)k;
  }
  return CF_OK;
}

/* sample += part (the arrays grown; part freed). */
static cf_status append_sample(fit_sample *sample, fit_sample *part, cf_error *err) {
  size_t count = sample->count + part->count;
  uint32_t *index = realloc(sample->index, (count ? count : 1) * sizeof *index);
  if (index) sample->index = index;
  double *weight = index ? realloc(sample->weight, (count ? count : 1) * sizeof *weight) : NULL;
  if (weight) sample->weight = weight;
  if (!index || !weight) {
    fit_sample_free(part);
    return cf_error_set(err, CF_ENOMEM, "out of memory for a sample of %zu observations", count);
  }
  memcpy(sample->index + sample->count, part->index, part->count * sizeof *index);
  memcpy(sample->weight + sample->count, part->weight, part->count * sizeof *weight);
  sample->count = count;
  fit_sample_free(part);
  return CF_OK;
}

cf_status fit_budget_draw_images(const cf_observations *obs, const fit_population *from,
                                 size_t images, size_t budget, size_t floor, cf_sampling sampling,
                                 fit_sample *sample, cf_error *err) {
  memset(sample, 0, sizeof *sample);
  uint32_t *order;
  size_t *begin;
  cf_status s = group_by_image(obs, from, images, &order, &begin, err);
  for (size_t k = 0; s == CF_OK && k < images; ++k) {
    size_t count = begin[k + 1] - begin[k];
    if (count == 0) continue;
    size_t share = (size_t)((double)budget * (double)count / (double)from->count + 0.5);
    fit_population image = {order + begin[k], count, NULL};
    fit_sample part;
    s = fit_budget_draw(obs, &image, share > floor ? share : floor, sampling, &part, err);
    if (s == CF_OK) s = append_sample(sample, &part, err);
  }
  free(order);
  free(begin);
  if (s != CF_OK) fit_sample_free(sample);
  return s;
}
