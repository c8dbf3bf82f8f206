/* Populations, samples and the pixel budget (fit_sample.h). */
#include "fit_sample.h"

#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"

static size_t member(const fit_population *from, size_t i) {
  return from->index ? from->index[i] : i;
}

void fit_sample_free(fit_sample *sample) {
  free(sample->index);
  free(sample->weight);
  memset(sample, 0, sizeof *sample);
}

/* The population whole, weights 1 (capacity count at least). */
static void take_whole(const fit_population *from, fit_sample *sample) {
  for (size_t i = 0; i < from->count; ++i) {
    sample->index[i] = (uint32_t)member(from, i);
    sample->weight[i] = 1.0;
  }
  sample->count = from->count;
}

/* The strata: 0 the highlights (the 1/16 of the population whose half
 * vector comes nearest the normal for any light; with `silhouette` also
 * the silhouette region, n·v < 0.3), 1 the rest. */
static cf_status highlight_strata(const cf_observations *obs, const fit_population *from,
                                  int silhouette, uint8_t *stratum, cf_error *err) {
  size_t n = from->count;
  double *score = malloc((n ? n : 1) * sizeof *score),
         *sorted = malloc((n ? n : 1) * sizeof *sorted);
  if (!score || !sorted) {
    free(score);
    free(sorted);
    return cf_error_set(err, CF_ENOMEM, "out of memory for a sample of %zu observations", n);
  }
  for (size_t i = 0; i < n; ++i)
    score[i] = sorted[i] = cf_observation_specularity(obs, member(from, i));
  /* the highlights: the `top` nearest (1/16: fd063f4, 1/8 or 1/32 moves 10 of 10 fits; n·v < 0.3:
   * 7bdb164, 0.15 or 0.6 moves m2_importance 1.1 or 3.1 sd) */
  size_t top = n / 16 > 0 ? n / 16 : 1;
  double threshold = n ? order_kth_smallest(sorted, n, n - top) : 0.0;
  for (size_t i = 0; i < n; ++i) {
    size_t k = member(from, i);
    const double *nrm = obs->normal + 3 * k, *v = obs->view + 3 * k;
    double cos_o = nrm[0] * v[0] + nrm[1] * v[1] + nrm[2] * v[2];
    stratum[i] = (uint8_t)(score[i] >= threshold || (silhouette && cos_o < 0.3) ? 0 : 1);
  }
  free(score);
  free(sorted);
  return CF_OK;
}

/* want[t] of each stratum t's size[t] members, spread evenly over it (at
 * most `capacity` in all), each weighed size[t] / taken[t]. */
static void take_strata(const fit_population *from, const uint8_t *stratum, const size_t want[2],
                        size_t capacity, fit_sample *sample) {
  size_t size[2] = {0, 0}, taken[2] = {0, 0}, spread[2] = {0, 0}, m = 0;
  for (size_t i = 0; i < from->count; ++i) ++size[stratum[i]];
  for (size_t i = 0; i < from->count && m < capacity; ++i) {
    int t = stratum[i];
    if (want[t] == 0 || !fit_spread_take(&spread[t], want[t], size[t])) continue;
    sample->index[m] = (uint32_t)member(from, i);
    sample->weight[m++] = (double)t; /* the stratum, for now */
    ++taken[t];
  }
  for (size_t i = 0; i < m; ++i) {
    int t = (int)sample->weight[i];
    sample->weight[i] = (double)size[t] / (double)taken[t];
  }
  sample->count = m;
}

/* Room for a sample of `capacity`, and the strata (n). */
static cf_status sample_room(fit_sample *sample, size_t capacity, uint8_t **stratum, size_t n,
                             cf_error *err) {
  memset(sample, 0, sizeof *sample);
  sample->index = malloc((capacity ? capacity : 1) * sizeof *sample->index);
  sample->weight = malloc((capacity ? capacity : 1) * sizeof *sample->weight);
  *stratum = malloc(n ? n : 1);
  if (sample->index && sample->weight && *stratum) return CF_OK;
  free(*stratum);
  *stratum = NULL;
  fit_sample_free(sample);
  return cf_error_set(err, CF_ENOMEM, "out of memory for a sample of %zu observations", capacity);
}

cf_status fit_sample_draw(const cf_observations *obs, const fit_population *from, size_t target,
                          fit_sample *sample, cf_error *err) {
  size_t n = from->count, capacity = n <= target ? n : target + 2;
  uint8_t *stratum;
  cf_status s = sample_room(sample, capacity, &stratum, n, err);
  if (s == CF_OK && n <= target) take_whole(from, sample);
  if (s == CF_OK && n > target) s = highlight_strata(obs, from, 0, stratum, err);
  if (s == CF_OK && n > target) {
    /* a quarter for the highlights (fd063f4; ½ or ⅛ moves 10 of 10 fits), one at least (below 4
     * a quarter is none, and their weight would be lost) */
    size_t highlights = target / 4 > 0 ? target / 4 : target > 1;
    size_t want[2] = {highlights, target - highlights};
    take_strata(from, stratum, want, capacity, sample);
  }
  free(stratum);
  if (s != CF_OK) fit_sample_free(sample);
  return s;
}

cf_status fit_budget_draw(const cf_observations *obs, const fit_population *from, size_t budget,
                          cf_sampling sampling, fit_sample *sample, cf_error *err) {
  if (sampling == CF_SAMPLING_STRATIFIED || from->count <= budget)
    return fit_sample_draw(obs, from, budget, sample, err);
  uint8_t *stratum;
  cf_status s = sample_room(sample, budget + 2, &stratum, from->count, err);
  if (s == CF_OK && sampling == CF_SAMPLING_IMPORTANCE)
    s = highlight_strata(obs, from, 1, stratum, err);
  else if (s == CF_OK)
    memset(stratum, 1, from->count); /* uniform: one stratum, the rest */
  if (s == CF_OK) {
    size_t highlights = 0, want[2] = {0, budget};
    for (size_t i = 0; i < from->count; ++i) highlights += stratum[i] == 0;
    if (sampling == CF_SAMPLING_IMPORTANCE) {
      want[0] = highlights < budget / 2 ? highlights : budget / 2;
      want[1] = budget - want[0];
    }
    take_strata(from, stratum, want, budget + 2, sample);
  }
  free(stratum);
  if (s != CF_OK) fit_sample_free(sample);
  return s;
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

cf_status fit_population_of_images(const cf_capture *capture, const unsigned char *use_image,
                                   fit_population *population, uint32_t **index, cf_error *err) {
  const cf_observations *obs = cf_capture_observations(capture);
  *index = NULL;
  population->index = NULL;
  population->count = obs->count;
  population->weight = NULL;
  if (!use_image) return CF_OK;
  *index = malloc((obs->count ? obs->count : 1) * sizeof **index);
  if (!*index) return cf_error_set(err, CF_ENOMEM, "out of memory");
  size_t n = 0;
  for (size_t i = 0; i < obs->count; ++i)
    if (use_image[obs->image[i]]) (*index)[n++] = (uint32_t)i;
  population->index = *index;
  population->count = n;
  if (n == 0) return cf_error_set(err, CF_EINVAL, "the images chosen have no observations");
  return CF_OK;
}

cf_status fit_budget_for(const cf_capture *capture, const cf_fit_options *o, fit_budget *budget,
                         cf_error *err) {
  memset(budget, 0, sizeof *budget);
  cf_status s = fit_population_of_images(capture, o->use_image, &budget->population,
                                         &budget->index, err);
  budget->in_use = s == CF_OK ? budget->population.count : 0;
  if (s != CF_OK || !(o->budget > 0 && o->budget < budget->population.count)) return s;
  if ((unsigned)o->sampling >= CF_SAMPLING_COUNT)
    return cf_error_set(err, CF_EINVAL, "invalid sampling %d", (int)o->sampling);
  const cf_observations *obs = cf_capture_observations(capture);
  size_t images = cf_capture_image_count(capture);
  if (o->fit_exposures && images > 1) /* every free gain its own observations */
    s = fit_budget_draw_images(obs, &budget->population, images, o->budget, FIT_GAIN_FLOOR,
                               o->sampling, &budget->sample, err);
  else
    s = fit_budget_draw(obs, &budget->population, o->budget, o->sampling, &budget->sample, err);
  if (s == CF_OK)
    budget->population =
        (fit_population){budget->sample.index, budget->sample.count, budget->sample.weight};
  return s;
}

void fit_budget_free(fit_budget *budget) {
  fit_sample_free(&budget->sample);
  free(budget->index);
  memset(budget, 0, sizeof *budget);
}

int fit_budget_same(const cf_fit_options *a, const cf_fit_options *b) {
  return a->use_image == b->use_image && a->budget == b->budget && a->sampling == b->sampling &&
         !a->fit_exposures == !b->fit_exposures;
}

cf_status fit_sample_problem(fit_problem **p, fit_sample *sample, const cf_capture *capture,
                             cf_model_id model, const fit_population *population, size_t target,
                             cf_error *err) {
  *p = NULL;
  cf_status s = fit_sample_draw(cf_capture_observations(capture), population, target, sample, err);
  if (s == CF_OK) s = fit_problem_new(p, capture, model, sample->index, sample->count, 1, err);
  if (s == CF_OK) s = fit_problem_set_sample_weights(*p, sample->weight, err);
  if (s != CF_OK) {
    fit_problem_free(*p);
    *p = NULL;
    fit_sample_free(sample);
  }
  return s;
}
