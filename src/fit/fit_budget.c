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
  size_t stride[2], taken[2] = {0, 0}, seen[2] = {0, 0}, m = 0;
  for (int t = 0; t < 2; ++t) stride[t] = want[t] > 0 && size[t] > want[t] ? size[t] / want[t] : 1;
  for (size_t i = 0; i < n && m < budget + 2; ++i) {
    int t = stratum[i];
    if (want[t] == 0 || seen[t]++ % stride[t] != 0 || taken[t] >= want[t] + 1) continue;
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
