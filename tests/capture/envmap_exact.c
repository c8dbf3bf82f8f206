/* envmap_exact DIR STRIDE [S]: how far a `synth --environment` capture in
 * DIR (noiseless, EXR, rendered with --supersample S, default 1; the model,
 * its values, the map and its rotation from DIR/truth.json) is from the
 * map's exact integral, every map pixel a light: L = Σ_pixels f(n, l, v)
 * L_p dω_p (n·l)+ (docs/model.md (5), the median cut's quadrature replaced
 * by the map's own). Every STRIDE-th observation; prints the relative RMSE
 * √(Σ(obs − exact)² / Σ exact²) and the ratio of the sums. The measuring
 * tool of docs/captures.md's convergence table and of
 * cli_synth_environment_exact. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/envmap.h"
#include "clayfit/capture.h"
#include "clayfit/image.h"
#include "clayfit/model.h"

typedef struct map_light {
  double l[3], e[3];
} map_light;

/* Every map pixel with light, as a directional light in the world frame. */
static map_light *map_lights(const cf_image *map, const double r[9], size_t *count) {
  map_light *lights = malloc((size_t)map->width * (size_t)map->height * sizeof *lights);
  *count = 0;
  for (int y = 0; lights && y < map->height; ++y) {
    const double d_omega =
        (2.0 * M_PI / map->width) * (M_PI / map->height) * sin(M_PI * (y + 0.5) / map->height);
    for (int x = 0; x < map->width; ++x) {
      const float *p =
          map->pixels + ((size_t)y * (size_t)map->width + (size_t)x) * (size_t)map->channels;
      double d[3], e[3], sum = 0.0;
      for (int c = 0; c < 3; ++c)
        sum += e[c] = isfinite(p[c]) && p[c] > 0.0f ? p[c] * d_omega : 0.0;
      if (!(sum > 0.0)) continue;
      cf_envmap_direction(map->width, map->height, x, y, d);
      map_light *m = &lights[(*count)++];
      for (int i = 0; i < 3; ++i) {
        m->l[i] = r[3 * i] * d[0] + r[3 * i + 1] * d[1] + r[3 * i + 2] * d[2];
        m->e[i] = e[i];
      }
    }
  }
  return lights;
}

/* truth.json's model, parameter vector, map path (joined to dir) and
 * rotation. */
static int read_truth(const char *dir, cf_model_id *model, double *params, char *map,
                      size_t map_size, double r[9]) {
  char path[4096];
  snprintf(path, sizeof path, "%s/truth.json", dir);
  json_t *truth = json_load_file(path, 0, NULL);
  json_t *env = json_object_get(truth, "environment");
  cf_error err = {0};
  if (!env ||
      cf_model_find(json_string_value(json_object_get(truth, "code")), model, &err) != CF_OK)
    return 0;
  const cf_model_info *m = cf_model_info_get(*model);
  json_t *values = json_object_get(truth, "params");
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *p = cf_param_info_get(m->params[j]);
    json_t *v = json_object_get(values, p->name);
    for (int c = 0; c < p->components; ++c)
      params[m->offsets[j] + c] = json_number_value(json_is_array(v) ? json_array_get(v, c) : v);
  }
  for (int i = 0; i < 9; ++i)
    r[i] = json_number_value(json_array_get(json_object_get(env, "rotation"), i));
  const char *file = json_string_value(json_object_get(env, "file"));
  if (!file) return 0;
  if (file[0] == '/') /* synth writes an absolute path where no relative one exists */
    snprintf(map, map_size, "%s", file);
  else
    snprintf(map, map_size, "%s/%s", dir, file);
  json_decref(truth);
  return 1;
}

int main(int argc, char **argv) {
  if (argc != 3 && argc != 4) {
    fprintf(stderr, "usage: envmap_exact DIR STRIDE [SUPERSAMPLE]\n");
    return 2;
  }
  const size_t stride = (size_t)atol(argv[2]);
  const int samples = argc == 4 ? atoi(argv[3]) : 1;
  double r[9], params[CF_MAX_DIM];
  cf_model_id model;
  char capture_path[4096], map_path[8192];
  /* the capture with its environment at 1 light: the observations' pixels
   * and geometry without K light slots each (4096 would take 3.6 GB) */
  char source[4096];
  snprintf(source, sizeof source, "%s/capture.json", argv[1]);
  snprintf(capture_path, sizeof capture_path, "%s/capture_exact.json", argv[1]);
  json_t *doc = json_load_file(source, 0, NULL);
  json_object_set_new(json_array_get(json_object_get(doc, "lights"), 0), "count", json_integer(1));
  if (!doc || json_dump_file(doc, capture_path, JSON_REAL_PRECISION(17)) != 0) {
    fprintf(stderr, "envmap_exact: cannot rewrite %s\n", source);
    return 1;
  }
  json_decref(doc);
  if (!read_truth(argv[1], &model, params, map_path, sizeof map_path, r)) {
    fprintf(stderr, "envmap_exact: %s/truth.json: no synth --environment truth\n", argv[1]);
    return 1;
  }
  cf_error err = {0};
  cf_capture *capture = NULL;
  cf_image map = {0};
  if (cf_capture_load(capture_path, NULL, &capture, &err) != CF_OK ||
      cf_image_read(map_path, &map, NULL, &err) != CF_OK) {
    fprintf(stderr, "envmap_exact: %s\n", err.message);
    return 1;
  }
  size_t count;
  map_light *lights = map_lights(&map, r, &count);
  const cf_observations *o = cf_capture_observations(capture);
  if (!lights) return 1;
  double e2 = 0.0, y2 = 0.0, sum_o = 0.0, sum_x = 0.0;
  size_t used = 0;
  for (size_t i = 0; i < o->count; i += stride ? stride : 1) {
    /* synth's S x S grid over the pixel: offsets (j + 1/2)/S - 1/2 */
    double exact[3] = {0.0, 0.0, 0.0};
    int hits = 0;
    for (int sy = 0; sy < samples; ++sy)
      for (int sx = 0; sx < samples; ++sx) {
        double n[3], v[3], l_slot[3], e_slot[3];
        if (!cf_capture_footprint_at(capture, i, (sx + 0.5) / samples - 0.5,
                                     (sy + 0.5) / samples - 0.5, n, v, l_slot, e_slot))
          continue;
        ++hits;
        /* the lit lights in batches (a tailed model prepares its table once a batch) */
        enum { BATCH = 256 };
        double bn[3 * BATCH], bl[3 * BATCH], bv[3 * BATCH], bf[3 * BATCH], bc[BATCH];
        const double *be[BATCH];
        int m = 0;
        for (size_t j = 0; j <= count; ++j) {
          if (j < count) {
            const double *l = lights[j].l;
            double cos_i = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
            if (!(cos_i > 0.0)) continue;
            memcpy(bn + 3 * m, n, sizeof n);
            memcpy(bl + 3 * m, l, 3 * sizeof *l);
            memcpy(bv + 3 * m, v, sizeof v);
            bc[m] = cos_i;
            be[m++] = lights[j].e;
            if (m < BATCH) continue;
          }
          cf_eval_batch_directions(model, params, (size_t)m, bn, bl, bv, bf, NULL);
          for (int k = 0; k < m; ++k)
            for (int c = 0; c < 3; ++c) exact[c] += bf[3 * k + c] * be[k][c] * bc[k];
          m = 0;
        }
      }
    if (hits != samples * samples) continue; /* a pixel the sphere does not cover fully */
    for (int c = 0; c < 3; ++c) exact[c] /= hits;
    for (int c = 0; c < 3; ++c) {
      double d = o->rgb[3 * i + c] - exact[c];
      e2 += d * d;
      y2 += exact[c] * exact[c];
      sum_o += o->rgb[3 * i + c];
      sum_x += exact[c];
    }
    ++used;
  }
  printf(
      "{\"observations\": %zu, \"map_lights\": %zu, \"relative_rmse\": %.6g, \"sum_ratio\": "
      "%.6g}\n",
      used, count, sqrt(e2 / y2), sum_o / sum_x);
  free(lights);
  cf_image_free(&map);
  cf_capture_free(capture);
  return 0;
}
