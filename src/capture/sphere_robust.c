/* The sphere from silhouettes, robust to outline points that are not the
 * sphere's (sphere_silhouette.h, cf_sphere_from_silhouettes_robust). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"
#include "capture/sphere_silhouette.h"

enum { MAX_ROUNDS = 20, MIN_RAYS = 5 };

cf_status cf_sphere_from_silhouettes_robust(const cf_silhouette_view *views, size_t num_views,
                                            double min_px, cf_sphere_fit *fit, double *kept,
                                            cf_error *err) {
  cf_status s = cf_sphere_from_silhouettes(views, num_views, fit, err);
  if (s != CF_OK) return s;
  size_t total = 0;
  for (size_t v = 0; v < num_views; ++v) total += views[v].count;
  double *deviations = malloc(total * sizeof *deviations);
  double *sorted = malloc(total * sizeof *sorted);
  double *rays = malloc(3 * total * sizeof *rays);
  unsigned char *in = calloc(total, 1), *was = calloc(total, 1);
  cf_silhouette_view *subset = malloc(num_views * sizeof *subset);
  if (!deviations || !sorted || !rays || !in || !was || !subset)
    s = cf_error_set(err, CF_ENOMEM, "out of memory for %zu silhouette rays", total);
  size_t inliers = total;
  for (int round = 0; s == CF_OK && round < MAX_ROUNDS; ++round) {
    /* deviations from the current sphere, and the threshold */
    for (size_t v = 0, i = 0; v < num_views; ++v)
      for (size_t r = 0; r < views[v].count; ++r, ++i)
        deviations[i] = sorted[i] = cf_sphere_ray_error_px(&views[v], views[v].rays + 3 * r, fit);
    double threshold = fmax(min_px, 2.5 * order_kth_smallest(sorted, total, total / 2));
    /* the kept rays of each view, views with too few dropped */
    size_t used_views = 0, used_rays = 0;
    memcpy(was, in, total);
    for (size_t v = 0, i = 0; v < num_views; ++v) {
      size_t first = used_rays, count = 0;
      for (size_t r = 0; r < views[v].count; ++r, ++i) {
        in[i] = deviations[i] <= threshold;
        if (!in[i]) continue;
        memcpy(rays + 3 * (first + count), views[v].rays + 3 * r, 3 * sizeof *rays);
        ++count;
      }
      if (count < MIN_RAYS) {
        for (size_t r = i - views[v].count; r < i; ++r) in[r] = 0;
        continue;
      }
      subset[used_views] = views[v];
      subset[used_views].rays = rays + 3 * first;
      subset[used_views].count = count;
      ++used_views;
      used_rays += count;
    }
    if (used_views < 2) {
      s = cf_error_set(err, CF_ENUMERIC,
                       "the sphere's silhouettes disagree: after rejecting outline points "
                       "more than %.3g px off the fitted sphere, %zu view%s keep %d points",
                       threshold, used_views, used_views == 1 ? "" : "s", MIN_RAYS);
      break;
    }
    if (round > 0 && memcmp(in, was, total) == 0) break; /* converged */
    double center[3] = {fit->center[0], fit->center[1], fit->center[2]};
    s = cf_sphere_refine_silhouettes(subset, used_views, center, fit->radius, fit, err);
    inliers = used_rays;
  }
  if (s == CF_OK && kept) *kept = (double)inliers / (double)total;
  free(deviations);
  free(sorted);
  free(rays);
  free(in);
  free(was);
  free(subset);
  return s;
}
