/* The gains as unknowns (kind.h): the global scale s, a gain e per group
 * of images (--fit-exposures, --fit-gains per-image or per-light where
 * each image has one light) and the white balance b of each image's red
 * and blue against its green. Each multiplies the prediction of an
 * image's channel (docs/model.md (40)): they take the derivative in its
 * log gain. The exposures' and the balances' mean log over their groups
 * is 0: the last one's is minus the sum of the others'. */
#include <math.h>

#include "problem.h"

/* ---- the scale ---- */

void fit_problem_free_scale(fit_problem *p) {
  fit_unknowns_add(p, &fit_kind_scale, 0, -HUGE_VAL, HUGE_VAL);
}

static double scale_get(const fit_problem *p, const fit_values *v, int slot) {
  (void)p, (void)slot;
  return v->log_scale;
}

static void scale_set(const fit_problem *p, const double *x, const fit_unknown *u, int count,
                      fit_values *v) {
  (void)p, (void)u, (void)count;
  v->log_scale = x[0];
}

static int scale_targets(const fit_problem *p, const fit_run *run, const int *place,
                         uint32_t image, int c, int *column, double *sign) {
  (void)p, (void)image, (void)c;
  column[0] = place[run->first];
  sign[0] = 1.0;
  return 1;
}

const fit_kind fit_kind_scale = {.name = "scale",
                                 .handle = FIT_HANDLE_GAIN,
                                 .get = scale_get,
                                 .set = scale_set,
                                 .gain_targets = scale_targets};

/* ---- a gain per group of images ---- */

void fit_problem_free_exposures(fit_problem *p) {
  for (size_t g = 0; g + 1 < p->groups.count; ++g) /* (contiguous, in the groups' order) */
    fit_unknowns_add(p, &fit_kind_exposure, (int)g, -HUGE_VAL, HUGE_VAL);
}

static double exposure_get(const fit_problem *p, const fit_values *v, int slot) {
  return v->log_exposures[p->groups.group_image[slot]];
}

/* log e_k of every image, its group's (group g at x[g]; the last group's
 * minus the others' sum). */
static void exposure_set(const fit_problem *p, const double *x, const fit_unknown *u, int count,
                         fit_values *v) {
  (void)u, (void)count;
  const fit_groups *g = &p->groups;
  double sum = 0.0;
  for (size_t group = 0; group + 1 < g->count; ++group) sum += x[group];
  for (size_t k = 0; k < g->images; ++k)
    v->log_exposures[k] = g->group[k] + 1 == g->count ? -sum : x[g->group[k]];
}

/* A group's gain is in the blocks that hold its images, and every gain in
 * those that hold the last group's images (its gain is minus their sum). */
static int exposure_columns(const fit_problem *p, size_t begin, size_t end, int first, int count,
                            unsigned char *mark, int *column) {
  const fit_groups *g = &p->groups;
  for (size_t i = begin; i < end; ++i) mark[g->group[p->rows.image[i]]] = 1;
  int has_last = g->count > 0 && mark[g->count - 1], k = 0;
  for (int i = 0; i < count; ++i)
    if (has_last || mark[p->unknowns.unknown[first + i].slot]) column[k++] = first + i;
  for (size_t i = begin; i < end; ++i) mark[g->group[p->rows.image[i]]] = 0;
  return k;
}

static int exposure_targets(const fit_problem *p, const fit_run *run, const int *place,
                            uint32_t image, int c, int *column, double *sign) {
  (void)c;
  uint32_t group = p->groups.group[image];
  int n = 0;
  if (group + 1 != p->groups.count) {
    column[n] = place[run->first + (int)group], sign[n++] = 1.0;
    return n;
  }
  for (int g = 0; g < run->count; ++g) column[n] = place[run->first + g], sign[n++] = -1.0;
  return n;
}

const fit_kind fit_kind_exposure = {.name = "exposure",
                                    .handle = FIT_HANDLE_GAIN,
                                    .get = exposure_get,
                                    .set = exposure_set,
                                    .columns = exposure_columns,
                                    .gain_targets = exposure_targets};

/* ---- the white balance: image k's red (slot 2k) and blue (2k + 1) ---- */

void fit_problem_free_balance(fit_problem *p) {
  for (size_t k = 0; k + 1 < p->groups.images; ++k)
    for (int j = 0; j < 2; ++j)
      fit_unknowns_add(p, &fit_kind_balance, (int)(2 * k) + j, -HUGE_VAL, HUGE_VAL);
}

static double balance_get(const fit_problem *p, const fit_values *v, int slot) {
  (void)p;
  return v->log_balance[3 * (slot / 2) + 2 * (slot % 2)];
}

/* log b of every image's red and blue (the last image's minus the others'
 * sum; green's stays 0). */
static void balance_set(const fit_problem *p, const double *x, const fit_unknown *u, int count,
                        fit_values *v) {
  (void)u, (void)count;
  size_t images = p->groups.images;
  double sum[2] = {0.0, 0.0};
  for (size_t k = 0; k + 1 < images; ++k)
    for (int j = 0; j < 2; ++j) sum[j] += v->log_balance[3 * k + 2 * (size_t)j] = x[2 * k + (size_t)j];
  v->log_balance[3 * (images - 1)] = -sum[0];
  v->log_balance[3 * (images - 1) + 2] = -sum[1];
}

/* An image's balance is in the blocks that hold it, every one in those
 * that hold the last image. */
static int balance_columns(const fit_problem *p, size_t begin, size_t end, int first, int count,
                           unsigned char *mark, int *column) {
  for (size_t i = begin; i < end; ++i) mark[p->rows.image[i]] = 1;
  int has_last = p->groups.images > 0 && mark[p->groups.images - 1], k = 0;
  for (int i = 0; i < count; ++i)
    if (has_last || mark[p->unknowns.unknown[first + i].slot / 2]) column[k++] = first + i;
  for (size_t i = begin; i < end; ++i) mark[p->rows.image[i]] = 0;
  return k;
}

/* Red's (c 0) and blue's (c 2) balance of the image (for the last image,
 * minus every other image's); green has none. */
static int balance_targets(const fit_problem *p, const fit_run *run, const int *place,
                           uint32_t image, int c, int *column, double *sign) {
  if (c == 1) return 0;
  int j = c / 2, n = 0;
  if (image + 1 != p->groups.images) {
    column[n] = place[run->first + 2 * (int)image + j], sign[n++] = 1.0;
    return n;
  }
  for (size_t k = 0; k + 1 < p->groups.images; ++k)
    column[n] = place[run->first + 2 * (int)k + j], sign[n++] = -1.0;
  return n;
}

const fit_kind fit_kind_balance = {.name = "white balance",
                                   .handle = FIT_HANDLE_GAIN,
                                   .get = balance_get,
                                   .set = balance_set,
                                   .columns = balance_columns,
                                   .gain_targets = balance_targets};
