/* The fit's one sampler (fit_sample.h, private to src/fit), on
 * observations made by hand (one light, the half vector's angle to the
 * normal growing along the population, two images):
 *   - every draw (stratified subsample, budgets drawn uniform, stratified
 *     or by importance, a budget image by image) weighs its observations
 *     so that their weights add up to the population's size (the
 *     Horvitz-Thompson estimate of any total), holds no observation twice
 *     and none outside the population, and stays within its size (+2);
 *   - the stratified draw gives the highlights (the 1/16 nearest the
 *     normal) a quarter of the sample, and one at least (below a target
 *     of 4 a quarter was none, and their weight was lost: an image's share
 *     of 3 drawn from 6 weighed 5);
 *   - a population of fewer than 16 observations drawn below its size:
 *     the highlights' threshold took the (n − n/16)-th smallest, n itself
 *     for n < 16, one past the array (AddressSanitizer: a read out of
 *     bounds); at least one observation is a highlight now;
 *   - a population no larger than the target is taken whole, weights 1;
 *   - image by image, each image gets at least the floor (all it has
 *     when fewer). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fit_sample.h"
#include "support/check.h"

CHECK_MAIN_STATE;

/* n observations, the first half in image 0: normal (0, 0, 1), view
 * (0, 0, 1), the light's direction tilting from the normal to 80° along
 * the population (the half vector's angle grows: the first are the
 * highlights). */
typedef struct population_data {
  cf_observations obs;
  double *normal, *view, *light, *irradiance;
  uint32_t *image;
} population_data;

static int make(population_data *d, size_t n) {
  memset(d, 0, sizeof *d);
  d->normal = malloc(3 * n * sizeof(double));
  d->view = malloc(3 * n * sizeof(double));
  d->light = malloc(3 * n * sizeof(double));
  d->irradiance = malloc(3 * n * sizeof(double));
  d->image = malloc(n * sizeof(uint32_t));
  if (!d->normal || !d->view || !d->light || !d->irradiance || !d->image) return 0;
  for (size_t i = 0; i < n; ++i) {
    double angle = 1.4 * (double)i / (double)n;
    double *nrm = d->normal + 3 * i, *v = d->view + 3 * i, *l = d->light + 3 * i;
    nrm[0] = nrm[1] = v[0] = v[1] = l[1] = 0.0;
    nrm[2] = v[2] = 1.0;
    l[0] = sin(angle);
    l[2] = cos(angle);
    for (int c = 0; c < 3; ++c) d->irradiance[3 * i + (size_t)c] = 1.0;
    d->image[i] = i < n / 2 ? 0 : 1;
  }
  d->obs = (cf_observations){.count = n,
                             .lights = 1,
                             .normal = d->normal,
                             .view = d->view,
                             .light_dir = d->light,
                             .irradiance = d->irradiance,
                             .image = d->image};
  return 1;
}

static void release(population_data *d) {
  free(d->normal);
  free(d->view);
  free(d->light);
  free(d->irradiance);
  free(d->image);
}

/* The sample's weights add up to the population's size, its observations
 * are distinct members, at most `most` of them. */
static void check_sample(const fit_sample *s, size_t n, size_t most, const char *what) {
  double total = 0.0;
  unsigned char *seen = calloc(n ? n : 1, 1);
  int distinct = seen != NULL, inside = 1;
  for (size_t i = 0; i < s->count; ++i) {
    total += s->weight[i];
    inside = inside && s->index[i] < n;
    if (distinct && inside) distinct = !seen[s->index[i]]++;
  }
  free(seen);
  CHECK(s->count > 0 && s->count <= most, "%s: %zu drawn, at most %zu", what, s->count, most);
  CHECK(inside && distinct, "%s: an observation outside the population or drawn twice", what);
  CHECK(fabs(total - (double)n) <= 1e-9 * (double)n, "%s: weights add up to %.12g, not %zu", what,
        total, n);
}

static void test_draws(size_t n, size_t target) {
  population_data d;
  if (!make(&d, n)) {
    CHECK(0, "out of memory");
    release(&d);
    return;
  }
  fit_population all = {NULL, n, NULL};
  cf_error err = {0};
  char what[96];
  fit_sample s;
  snprintf(what, sizeof what, "stratified, %zu of %zu", target, n);
  CHECK(fit_sample_draw(&d.obs, &all, target, &s, &err) == CF_OK, "%s: %s", what, err.message);
  check_sample(&s, n, target + 2, what);
  size_t highlights = 0, top = n / 16 ? n / 16 : 1, want = target / 4 < top ? target / 4 : top;
  for (size_t i = 0; i < s.count; ++i) highlights += s.index[i] < top;
  CHECK(highlights >= 1 && highlights == want, "%s: %zu highlights drawn, %zu wanted", what,
        highlights, want);
  fit_sample_free(&s);
  static const cf_sampling modes[] = {CF_SAMPLING_UNIFORM, CF_SAMPLING_IMPORTANCE};
  for (int m = 0; m < 2; ++m) {
    snprintf(what, sizeof what, "budget %s, %zu of %zu", m ? "importance" : "uniform", target, n);
    CHECK(fit_budget_draw(&d.obs, &all, target, modes[m], &s, &err) == CF_OK, "%s: %s", what,
          err.message);
    check_sample(&s, n, target + 2, what);
    fit_sample_free(&s);
  }
  snprintf(what, sizeof what, "image by image, %zu of %zu", target, n);
  size_t floor = target / 3 + 1;
  CHECK(fit_budget_draw_images(&d.obs, &all, 2, target, floor, CF_SAMPLING_STRATIFIED, &s, &err) ==
            CF_OK,
        "%s: %s", what, err.message);
  check_sample(&s, n, target + 2 * floor + 4, what);
  size_t per_image[2] = {0, 0};
  for (size_t i = 0; i < s.count; ++i) ++per_image[d.image[s.index[i]]];
  for (int k = 0; k < 2; ++k) {
    size_t has = k == 0 ? n / 2 : n - n / 2, least = floor < has ? floor : has;
    CHECK(per_image[k] >= least, "%s: image %d got %zu, at least %zu", what, k, per_image[k],
          least);
  }
  fit_sample_free(&s);
  release(&d);
}

static void test_whole(void) {
  population_data d;
  if (!make(&d, 40)) {
    CHECK(0, "out of memory");
    release(&d);
    return;
  }
  uint32_t index[20];
  for (int i = 0; i < 20; ++i) index[i] = (uint32_t)(2 * i + 1);
  fit_population odd = {index, 20, NULL};
  fit_sample s;
  cf_error err = {0};
  CHECK(fit_sample_draw(&d.obs, &odd, 20, &s, &err) == CF_OK, "%s", err.message);
  int same = s.count == 20;
  for (size_t i = 0; same && i < s.count; ++i) same = s.index[i] == index[i] && s.weight[i] == 1.0;
  CHECK(same, "a population no larger than the target: not taken whole with weights 1");
  fit_sample_free(&s);
  release(&d);
}

int main(void) {
  test_draws(12, 5);
  test_draws(15, 8);
  test_draws(10000, 1000);
  test_draws(9999, 3001);
  test_whole();
  return check_finish("test_fit_sample");
}
