/* Pixel footprints in the fit: each observation's pairs over its pixel
 * (fit_problem.h). */

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/memory.h"
#include "core/parallel.h"
#include "core/vec.h"
#include "problem.h"

/* The observations split into this many parts per thread (the integrated
 * ones cluster in the highlight: small parts even the threads' work). */
enum { PARTS_PER_THREAD = 8 }; /* 2abd51c measured threads, not the 8; 2, 32: no fit moves */

static int parts_for(const fit_problem *p) {
  int threads = p->threads > 1 ? p->threads : 1;
  /* (one thread below 1024 observations: 2abd51c; 512, 2048: no fit moves, time not measured) */
  return threads > 1 && p->rows.count >= 1024 ? threads * PARTS_PER_THREAD : 1;
}

/* Per image, an upper bound on how far the normal turns across one pixel:
 * 1.5 × the largest turn between horizontally adjacent observations
 * (cf_capture_image's adjacent_turn), for choosing which observations can
 * need samples before measuring each. */
static cf_status turn_bounds(const cf_capture *capture, double **bound, cf_error *err) {
  size_t images = cf_capture_image_count(capture);
  *bound = calloc(images ? images : 1, sizeof **bound);
  if (!*bound) return cf_error_set(err, CF_ENOMEM, "out of memory");
  /* 1.5: a margin for turns not seen (99730e9; 1: DiLiGenT moves 0.01 sd; 3: no fit moves) */
  for (size_t k = 0; k < images; ++k)
    (*bound)[k] = 1.5 * cf_capture_image_at(capture, k)->adjacent_turn;
  return CF_OK;
}

/* How far the normal turns across observation k's pixel: the larger of
 * the turns between the midpoints of its opposite edges. */
static double pixel_turn(const cf_capture *capture, size_t k, double fallback, double *scratch,
                         int lights) {
  static const double edge[4][2] = {{-0.5, 0.0}, {0.5, 0.0}, {0.0, -0.5}, {0.0, 0.5}};
  double n[4][3], view[3];
  for (int e = 0; e < 4; ++e)
    if (!cf_capture_footprint_at(capture, k, edge[e][0], edge[e][1], n[e], view, scratch,
                                 scratch + 3 * (size_t)lights))
      return fallback;
  return fmax(cf_angle3(n[0], n[1]), cf_angle3(n[2], n[3]));
}

/* Observations [begin, end) of choose_samples' adaptive S. */
typedef struct choose_job {
  fit_problem *p;
  const cf_fit_options *o;
  double width;
  int *samples;
  int parts;
  double *scratch; /* 6 × lights per part */
} choose_job;

static void choose_part(void *user, int part) {
  choose_job *job = user;
  fit_problem *p = job->p;
  fit_rows *r = &p->rows;
  size_t begin, end;
  cf_part_range(r->count, job->parts, part, &begin, &end);
  double *scratch = job->scratch + 6 * (size_t)r->lights * (size_t)part;
  const double *bound = r->turn_bound;
  for (size_t i = begin; i < end; ++i) {
    size_t k = fit_rows_observation(r, i);
    double cos_h = cf_observation_specularity(p->obs, k);
    if (cos_h <= -1.0) continue; /* unlit */
    double theta_h = acos(fmin(1.0, cos_h)), delta_max = bound[p->obs->image[k]];
    /* the centre is enough even for a lobe of no width at the image's
     * largest turn (the bound grows with both): no turn to measure */
    if (cf_footprint_error(0.0, delta_max, theta_h, 1) <= job->o->footprint_tolerance) continue;
    if (isnan(r->pixel_turn[i]))
      r->pixel_turn[i] = pixel_turn(p->capture, k, delta_max, scratch, r->lights);
    double delta = r->pixel_turn[i];
    int want = cf_footprint_samples(job->width, delta, theta_h, job->o->footprint_tolerance,
                                    CF_FIT_FOOTPRINT_MAX_SAMPLES);
    if (want > job->samples[i]) job->samples[i] = want;
  }
}

/* The S each observation wants (only growing from `current`). */
static cf_status choose_samples(fit_problem *p, const cf_fit_options *o, const int *current,
                                int *samples, cf_error *err) {
  fit_rows *r = &p->rows;
  for (size_t i = 0; i < r->count; ++i) samples[i] = current ? current[i] : 1;
  if (o->footprint == 1) {
    for (size_t i = 0; i < r->count; ++i) samples[i] = 1;
    return CF_OK;
  }
  if (o->footprint >= 2) {
    for (size_t i = 0; i < r->count; ++i) samples[i] = o->footprint;
    return CF_OK;
  }
  double width = cf_model_lobe_width(p->model, p->values.params);
  if (isinf(width)) return CF_OK;
  cf_status s = CF_OK;
  if (!r->turn_bound) s = turn_bounds(p->capture, &r->turn_bound, err);
  if (s == CF_OK && !r->pixel_turn) { /* measured as first needed */
    r->pixel_turn = malloc((r->count ? r->count : 1) * sizeof *r->pixel_turn);
    if (!r->pixel_turn) s = cf_error_set(err, CF_ENOMEM, "out of memory");
    for (size_t i = 0; s == CF_OK && i < r->count; ++i) r->pixel_turn[i] = NAN;
  }
  choose_job job = {p, o, width, samples, parts_for(p), NULL};
  if (s == CF_OK &&
      !(job.scratch = malloc(6 * (size_t)r->lights * (size_t)job.parts * sizeof *job.scratch)))
    s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) cf_parallel_for(job.parts, p->threads, choose_part, &job);
  free(job.scratch);
  return s;
}

/* Where sample j of n sits across the pixel: the Gauss-Legendre pairs of
 * cf_footprint_samples (auto), or the midpoints of an n × n grid (a fixed
 * S, as `clayfit synth --supersample S` renders). */
static double sample_offset(int gauss, int n, int j) {
  return gauss ? cf_footprint_offset(n, j) : (j + 0.5) / n - 0.5;
}

/* Observations [begin, end) of rebuild_pairs: their pairs at begin[i]. */
typedef struct rebuild_job {
  const fit_problem *p;
  const int *samples;
  int gauss;
  const size_t *begin;
  cf_geometry *geometry;
  double *weight;
  int parts;
  double *scratch; /* 6 × lights per part */
  const fit_rows *old; /* the pairs before: a centre there is copied */
} rebuild_job;

/* Row i's pairs at the pixel centre from the pairs before, when it had
 * them there (the same fit_pairs_at, bit for bit: on the demo's report, the
 * centres of 1.2·10⁶ observations took 0.56 s of CPU to compute again);
 * 0 when it had samples. */
static int copy_centre(const fit_rows *old, size_t i, cf_geometry *geometry, double *weight) {
  if (old->samples && old->samples[i] != 1) return 0;
  size_t first, slots = fit_rows_slot_range(old, i, &first);
  memcpy(geometry, old->geometry + first, slots * sizeof *geometry);
  memcpy(weight, old->weight + 3 * first, 3 * slots * sizeof *weight);
  return 1;
}

static void rebuild_part(void *user, int part) {
  rebuild_job *job = user;
  const fit_problem *p = job->p;
  const cf_observations *o = p->obs;
  const int light_count = p->rows.lights;
  const size_t lights = (size_t)light_count;
  const int gauss = job->gauss;
  cf_geometry *geometry = job->geometry;
  double *weight = job->weight;
  size_t first, end;
  cf_part_range(p->rows.count, job->parts, part, &first, &end);
  double *scratch = job->scratch + 6 * lights * (size_t)part;
  for (size_t i = first; i < end; ++i) {
    size_t k = fit_rows_observation(&p->rows, i), at = job->begin[i];
    int n = job->samples[i];
    if (n == 1 && copy_centre(job->old, i, geometry + at, weight + 3 * at)) continue;
    if (n == 1) { /* the pixel centre */
      fit_pairs_at(light_count, o->normal + 3 * k, o->view + 3 * k, o->light_dir + 3 * k * lights,
                   o->irradiance + 3 * k * lights, 1.0, geometry + at, weight + 3 * at);
      continue;
    }
    /* S × S points, equally weighted; a point that misses the sphere (it
     * cannot, clear of the silhouette's margin) gets no weight and the
     * others share it */
    int hits = 0;
    double normal[3], view[3];
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) {
        size_t pair = at + ((size_t)a * (size_t)n + (size_t)b) * lights;
        double du = sample_offset(gauss, n, b), dv = sample_offset(gauss, n, a);
        if (cf_capture_footprint_at(p->capture, k, du, dv, normal, view, scratch,
                                    scratch + 3 * lights)) {
          fit_pairs_at(light_count, normal, view, scratch, scratch + 3 * lights, 1.0, geometry + pair,
                       weight + 3 * pair);
          ++hits;
        } else {
          memset(geometry + pair, 0, lights * sizeof *geometry);
          memset(weight + 3 * pair, 0, 3 * lights * sizeof *weight);
        }
      }
    size_t count = (size_t)n * (size_t)n * lights;
    if (hits == 0) { /* fall back to the centre, with zero-weight padding */
      fit_pairs_at(light_count, o->normal + 3 * k, o->view + 3 * k, o->light_dir + 3 * k * lights,
                   o->irradiance + 3 * k * lights, 1.0, geometry + at, weight + 3 * at);
      continue;
    }
    for (size_t j = 0; j < 3 * count; ++j) weight[3 * at + j] /= hits;
  }
}

/* Rebuild the pairs with samples[i]² points per observation. */
static cf_status rebuild_pairs(fit_problem *p, int *samples, int gauss, cf_error *err) {
  fit_rows *r = &p->rows;
  const size_t lights = (size_t)r->lights;
  size_t *begin = malloc((r->count + 1) * sizeof *begin);
  if (!begin) return cf_error_set(err, CF_ENOMEM, "out of memory");
  begin[0] = 0;
  for (size_t i = 0; i < r->count; ++i)
    begin[i + 1] = begin[i] + (size_t)samples[i] * (size_t)samples[i] * lights;
  size_t slots = begin[r->count];
  cf_geometry *geometry = cf_malloc_large((slots ? slots : 1) * sizeof *geometry);
  double *weight = cf_malloc_large(3 * (slots ? slots : 1) * sizeof *weight);
  int parts = parts_for(p);
  double *scratch = malloc(6 * lights * (size_t)parts * sizeof *scratch);
  if (!geometry || !weight || !scratch) {
    free(begin);
    free(geometry);
    free(weight);
    free(scratch);
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu footprint samples", slots);
  }
  rebuild_job job = {p, samples, gauss, begin, geometry, weight, parts, scratch, r};
  cf_parallel_for(parts, p->threads, rebuild_part, &job);
  free(scratch);
  free(r->geometry);
  free(r->weight);
  free(r->slot_begin);
  free(r->samples);
  r->geometry = geometry;
  r->weight = weight;
  r->slot_begin = begin;
  r->slots = slots;
  r->samples = samples;
  return CF_OK;
}

cf_status fit_footprint_update(fit_problem *p, const cf_fit_options *options, int *changed,
                               cf_error *err) {
  const fit_rows *r = &p->rows;
  if (changed) *changed = 0;
  int *samples = malloc((r->count ? r->count : 1) * sizeof *samples);
  if (!samples) return cf_error_set(err, CF_ENOMEM, "out of memory");
  cf_status s = choose_samples(p, options, r->samples, samples, err);
  int same = 1;
  for (size_t i = 0; s == CF_OK && same && i < r->count; ++i)
    same = samples[i] == (r->samples ? r->samples[i] : 1);
  if (s != CF_OK || same) {
    free(samples);
    return s;
  }
  s = rebuild_pairs(p, samples, options->footprint == 0, err); /* takes samples */
  if (s != CF_OK) {
    free(samples);
    return s;
  }
  if (changed) *changed = 1;
  return CF_OK;
}

void fit_footprint_tally(const fit_problem *p, size_t *observations, size_t *samples,
                         int *largest) {
  const fit_rows *r = &p->rows;
  *observations = *samples = 0;
  *largest = 1;
  for (size_t i = 0; r->samples && i < r->count; ++i) {
    if (r->samples[i] < 2) continue;
    ++*observations;
    *samples += (size_t)r->samples[i] * (size_t)r->samples[i];
    if (r->samples[i] > *largest) *largest = r->samples[i];
  }
}
