/* The capture's images and lights as the gains group them (fit_groups,
 * fit_problem.h). */
#include <stdlib.h>
#include <string.h>

#include "problem.h"

/* Per image: how many distinct lights it has, the first image of its
 * only light (light_of_image; −1: none or several), and the most any
 * image has. 0: no memory. */
static int image_lights(fit_groups *g) {
  size_t lights = (size_t)g->lights;
  long *first = malloc((g->light_count ? g->light_count : 1) * sizeof *first);
  if (!first) return 0;
  for (size_t l = 0; l < g->light_count; ++l) first[l] = -1;
  for (size_t k = 0; k < g->images; ++k) {
    const long *id = g->slot_light + k * lights;
    int distinct = 0;
    long only = -1;
    for (size_t j = 0; j < lights; ++j) {
      int seen = id[j] < 0;
      for (size_t i = 0; i < j && !seen; ++i) seen = id[i] == id[j];
      if (!seen) distinct += 1, only = id[j];
    }
    if (distinct == 1 && first[only] < 0) first[only] = (long)k;
    g->light_of_image[k] = distinct == 1 ? first[only] : -1;
    g->image_lights = distinct > g->image_lights ? distinct : g->image_lights;
  }
  g->several_lights = g->image_lights > 1;
  free(first);
  return 1;
}

cf_status fit_groups_init(fit_groups *g, const cf_capture *capture, int lights, cf_error *err) {
  memset(g, 0, sizeof *g);
  g->images = cf_capture_image_count(capture);
  g->lights = lights;
  size_t images = g->images ? g->images : 1;
  g->group = malloc(images * sizeof *g->group);
  g->group_image = malloc(images * sizeof *g->group_image);
  g->light_of_image = malloc(images * sizeof *g->light_of_image);
  g->slot_light = malloc(images * (lights ? (size_t)lights : 1) * sizeof *g->slot_light);
  if (g->slot_light) g->light_count = cf_capture_light_ids(capture, g->slot_light);
  if (!g->group || !g->group_image || !g->light_of_image || !g->slot_light || !image_lights(g)) {
    fit_groups_release(g);
    return cf_error_set(err, CF_ENOMEM, "out of memory for the images' gain groups");
  }
  return CF_OK;
}

void fit_groups_release(fit_groups *g) {
  free(g->group);
  free(g->group_image);
  free(g->light_of_image);
  free(g->slot_light);
  memset(g, 0, sizeof *g);
}

void fit_problem_group_gains(fit_problem *p, int per_light) {
  fit_groups *g = &p->groups;
  g->count = 0;
  for (size_t k = 0; k < g->images; ++k) {
    long light = per_light ? g->light_of_image[k] : -1;
    size_t group = g->count;
    if (light >= 0 && (size_t)light < k) group = g->group[light]; /* (light: its first image) */
    if (group == g->count) g->group_image[g->count++] = (uint32_t)k;
    g->group[k] = (uint32_t)group;
  }
}
