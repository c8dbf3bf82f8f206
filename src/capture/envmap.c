/* Environment maps reduced to directional lights by median cut
 * (src/capture/envmap.h). After P. Debevec, "A Median Cut Algorithm for
 * Light Probe Sampling", SIGGRAPH 2005 poster / technical report:
 *
 *   1. the map is one region;
 *   2. split a region in two along its longer side (measured on the
 *      sphere: a latitude-longitude width shrinks by sin θ) at the median
 *      of its energy, so that both halves hold about half of it;
 *   3. repeat until there are k regions; place a light at each region's
 *      energy centroid carrying the region's light.
 *
 * Debevec splits every region at each step (2^n lights); here the region
 * of the largest energy is split next, so any k works and the brightest
 * parts of the map get the most lights. Energy is luminance (ITU-R BT.709:
 * Y = 0.2126 R + 0.7152 G + 0.0722 B) times solid angle. A summed-area
 * table of the energy makes every region's energy, and every candidate
 * cut, a four-term look-up: building it is one pass over the map, the
 * median of a region a binary search, and the lights one more pass. */
#include <math.h>
#include <stdlib.h>

#include "core/vec.h"
#include "envmap.h"
#define MAX_LIGHTS CF_ENVMAP_MAX_LIGHTS

void cf_envmap_direction(int width, int height, double x, double y, double d[3]) {
  const double theta = CF_PI * (y + 0.5) / height;
  const double phi = 2.0 * CF_PI * (x + 0.5) / width;
  d[0] = -sin(theta) * cos(phi);
  d[1] = cos(theta);
  d[2] = -sin(theta) * sin(phi);
}

static double luminance(const double rgb[3]) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

/* A value the map may use: negative values count as 0 (non-finite ones
 * were refused by check_finite). */
static double usable(float value) {
  return value > 0.0f ? (double)value : 0.0;
}

/* CF_EINVAL at the first NaN or infinity of the first three channels (a
 * 4th is ignored): a map is radiance, and a non-finite texel is a broken
 * file, not a light to guess at. */
static cf_status check_finite(const cf_image *map, cf_error *err) {
  const size_t pixels = (size_t)map->width * (size_t)map->height;
  size_t count = 0, first = 0;
  int first_channel = 0;
  for (size_t i = 0; i < pixels; ++i)
    for (int c = 0; c < 3; ++c)
      if (!isfinite(map->pixels[i * (size_t)map->channels + (size_t)c]) && count++ == 0)
        first = i, first_channel = c;
  if (count == 0) return CF_OK;
  const float v = map->pixels[first * (size_t)map->channels + (size_t)first_channel];
  return cf_error_set(err, CF_EINVAL,
                      "environment map: %zu non-finite value%s (NaN or infinity); the first is "
                      "%s at texel (%zu, %zu) (column, row from the top-left), channel %d (%c)",
                      count, count == 1 ? "" : "s", isnan(v) ? "NaN" : "an infinity",
                      first % (size_t)map->width, first / (size_t)map->width, first_channel,
                      "RGB"[first_channel]);
}

/* The map's geometry: per-row solid angle and polar angle, per-column
 * azimuth, and the summed-area table of energy,
 *   sat[y (W + 1) + x] = Σ energy over rows < y and columns < x. */
typedef struct geometry {
  int width, height, channels;
  const float *pixels;
  double *sin_theta, *cos_theta, *d_omega; /* per row */
  double *cos_phi, *sin_phi;               /* per column */
  double *sat;
} geometry;

typedef struct region {
  int x0, y0, x1, y1; /* pixels [x0, x1) × [y0, y1) */
  double energy;
} region;

static double rect_energy(const geometry *g, int x0, int y0, int x1, int y1) {
  const size_t stride = (size_t)g->width + 1;
  const double *s = g->sat;
  double e = s[(size_t)y1 * stride + (size_t)x1] - s[(size_t)y0 * stride + (size_t)x1] -
             s[(size_t)y1 * stride + (size_t)x0] + s[(size_t)y0 * stride + (size_t)x0];
  return e > 0.0 ? e : 0.0; /* rounding of the differences */
}

/* Geometry tables and the summed-area table; counts the negative values
 * and sums Σ L dω per channel. */
static void build(geometry *g, cf_envmap_report *report) {
  const int w = g->width, h = g->height;
  const double d_theta = CF_PI / h, d_phi = 2.0 * CF_PI / w;
  for (int y = 0; y < h; ++y) {
    const double theta = CF_PI * (y + 0.5) / h;
    g->sin_theta[y] = sin(theta);
    g->cos_theta[y] = cos(theta);
    g->d_omega[y] = d_phi * d_theta * g->sin_theta[y];
  }
  for (int x = 0; x < w; ++x) {
    const double phi = 2.0 * CF_PI * (x + 0.5) / w;
    g->cos_phi[x] = cos(phi);
    g->sin_phi[x] = sin(phi);
  }
  const size_t stride = (size_t)w + 1;
  for (int x = 0; x <= w; ++x) g->sat[x] = 0.0;
  size_t clamped = 0;
  double total[3] = {0.0, 0.0, 0.0};
  for (int y = 0; y < h; ++y) {
    const float *row = g->pixels + (size_t)y * (size_t)w * (size_t)g->channels;
    double *above = g->sat + (size_t)y * stride, *here = above + stride;
    double running = 0.0;
    here[0] = 0.0;
    for (int x = 0; x < w; ++x) {
      double rgb[3];
      for (int c = 0; c < 3; ++c) {
        const float v = row[(size_t)x * (size_t)g->channels + (size_t)c];
        rgb[c] = usable(v);
        if (v < 0.0f) ++clamped;
        total[c] += rgb[c] * g->d_omega[y];
      }
      running += luminance(rgb) * g->d_omega[y];
      here[x + 1] = above[x + 1] + running;
    }
  }
  report->clamped = clamped;
  for (int c = 0; c < 3; ++c) report->total[c] = total[c];
}

/* Split r at the median of its energy along its longer side on the
 * sphere (its width scaled by sin θ at its middle row) into r and *out. */
static void split(const geometry *g, region *r, region *out) {
  const int w = r->x1 - r->x0, h = r->y1 - r->y0;
  const double theta_mid = CF_PI * 0.5 * (r->y0 + r->y1) / g->height;
  const double width_on_sphere = w * (2.0 * CF_PI / g->width) * sin(theta_mid);
  const double height_on_sphere = h * (CF_PI / g->height);
  const int along_x = w >= 2 && (width_on_sphere >= height_on_sphere || h < 2);
  const int lo = along_x ? r->x0 : r->y0, hi = along_x ? r->x1 : r->y1;

  /* part(c): the energy of the part before the cut c, for c in [lo+1, hi-1] */
#define PART(c) \
  (along_x ? rect_energy(g, r->x0, r->y0, (c), r->y1) : rect_energy(g, r->x0, r->y0, r->x1, (c)))
  int cut;
  if (!(r->energy > 0.0)) {
    cut = lo + (hi - lo) / 2; /* no light: halve it */
  } else {
    const double half = 0.5 * r->energy;
    int a = lo + 1, b = hi - 1;
    if (PART(b) < half) {
      a = b;
    } else {
      while (a < b) { /* the first cut with at least half before it */
        const int m = a + (b - a) / 2;
        if (PART(m) >= half)
          b = m;
        else
          a = m + 1;
      }
    }
    cut = a;
    if (cut - 1 >= lo + 1 && half - PART(cut - 1) < PART(cut) - half) --cut;
  }
#undef PART

  *out = *r;
  if (along_x) {
    r->x1 = cut;
    out->x0 = cut;
  } else {
    r->y1 = cut;
    out->y0 = cut;
  }
  r->energy = rect_energy(g, r->x0, r->y0, r->x1, r->y1);
  out->energy = rect_energy(g, out->x0, out->y0, out->x1, out->y1);
}

/* The light of one region: Σ L dω per channel, at the energy-weighted
 * mean direction; where that mean vanishes (a region without light, or
 * one whose light balances out, such as a whole uniform map), at the
 * direction of the region's centre. */
static void region_light(const geometry *g, const region *r, const double rotation[9],
                         cf_directional_light *light) {
  double rgb_sum[3] = {0.0, 0.0, 0.0}, mean[3] = {0.0, 0.0, 0.0}, energy = 0.0;
  for (int y = r->y0; y < r->y1; ++y) {
    const float *row = g->pixels + (size_t)y * (size_t)g->width * (size_t)g->channels;
    const double d_omega = g->d_omega[y];
    double row_rgb[3] = {0.0, 0.0, 0.0}, row_mean[3] = {0.0, 0.0, 0.0}, row_energy = 0.0;
    for (int x = r->x0; x < r->x1; ++x) {
      const float *p = row + (size_t)x * (size_t)g->channels;
      const double rgb[3] = {usable(p[0]), usable(p[1]), usable(p[2])};
      const double e = luminance(rgb);
      for (int c = 0; c < 3; ++c) row_rgb[c] += rgb[c];
      row_energy += e;
      row_mean[0] -= e * g->cos_phi[x];
      row_mean[2] -= e * g->sin_phi[x];
    }
    for (int c = 0; c < 3; ++c) rgb_sum[c] += row_rgb[c] * d_omega;
    energy += row_energy * d_omega;
    mean[0] += row_mean[0] * g->sin_theta[y] * d_omega;
    mean[1] += row_energy * g->cos_theta[y] * d_omega;
    mean[2] += row_mean[2] * g->sin_theta[y] * d_omega;
  }
  const double length = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
  double d[3];
  if (energy > 0.0 && length > 1e-9 * energy) {
    for (int c = 0; c < 3; ++c) d[c] = mean[c] / length;
  } else {
    cf_envmap_direction(g->width, g->height, 0.5 * (r->x0 + r->x1) - 0.5,
                        0.5 * (r->y0 + r->y1) - 0.5, d);
  }
  double world[3];
  for (int i = 0; i < 3; ++i)
    world[i] = rotation[3 * i] * d[0] + rotation[3 * i + 1] * d[1] + rotation[3 * i + 2] * d[2];
  const double n = sqrt(world[0] * world[0] + world[1] * world[1] + world[2] * world[2]);
  for (int c = 0; c < 3; ++c) {
    light->direction[c] = world[c] / n;
    light->irradiance[c] = rgb_sum[c];
  }
}

cf_status cf_envmap_check_rotation(const double rotation[9], cf_error *err) {
  const double *r = rotation;
  for (int i = 0; i < 9; ++i)
    if (!isfinite(r[i]))
      return cf_error_set(err, CF_EINVAL, "environment map rotation: entry %d is not finite", i);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double dot = 0.0;
      for (int c = 0; c < 3; ++c) dot += r[3 * i + c] * r[3 * j + c];
      if (fabs(dot - (i == j ? 1.0 : 0.0)) > 1e-6)
        return cf_error_set(err, CF_EINVAL,
                            "environment map rotation is not orthonormal: rows %d and %d have "
                            "dot product %.9g",
                            i, j, dot);
    }
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                     r[2] * (r[3] * r[7] - r[4] * r[6]);
  if (det < 0.0)
    return cf_error_set(err, CF_EINVAL,
                        "environment map rotation has determinant %.9g: a mirror, not a rotation "
                        "(the map is read as Blender and three.js read it, docs/captures.md; "
                        "a mirror was needed only before 2026-11-27)",
                        det);
  return CF_OK;
}

/* The queue of splittable regions, a binary max-heap of their indices:
 * the largest energy first, the lower index among equals (the order of a
 * linear search; k = 65536 would take 2^31 steps of it). */
static int queue_before(const region *r, int a, int b) {
  return r[a].energy > r[b].energy || (r[a].energy == r[b].energy && a < b);
}

static void queue_push(const region *r, int *heap, int *n, int index) {
  if ((long long)(r[index].x1 - r[index].x0) * (r[index].y1 - r[index].y0) < 2) return;
  int i = (*n)++;
  while (i > 0 && queue_before(r, index, heap[(i - 1) / 2])) {
    heap[i] = heap[(i - 1) / 2];
    i = (i - 1) / 2;
  }
  heap[i] = index;
}

static int queue_pop(const region *r, int *heap, int *n) {
  const int top = heap[0], last = heap[--(*n)];
  int i = 0;
  for (;;) {
    int c = 2 * i + 1;
    if (c >= *n) break;
    if (c + 1 < *n && queue_before(r, heap[c + 1], heap[c])) ++c;
    if (!queue_before(r, heap[c], last)) break;
    heap[i] = heap[c];
    i = c;
  }
  if (*n > 0) heap[i] = last;
  return top;
}

cf_status cf_envmap_median_cut(const cf_image *map, const double rotation[9], int k,
                               cf_directional_light *lights, cf_envmap_report *report,
                               cf_error *err) {
  static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (!map || !map->pixels || map->width <= 0 || map->height <= 0)
    return cf_error_set(err, CF_EINVAL, "environment map: an empty image");
  if (map->channels != 3 && map->channels != 4)
    return cf_error_set(err, CF_EINVAL,
                        "environment map: %d channels; it must be linear RGB (3 or 4 channels)",
                        map->channels);
  if (k < 1 || k > MAX_LIGHTS || !lights)
    return cf_error_set(err, CF_EINVAL, "environment map: %d lights asked for; give 1 to %d", k,
                        MAX_LIGHTS);
  if ((long long)k > (long long)map->width * map->height)
    return cf_error_set(err, CF_EINVAL,
                        "environment map: %d lights asked for from a map of only %d x %d pixels", k,
                        map->width, map->height);
  if (!rotation) rotation = identity;
  cf_status status = cf_envmap_check_rotation(rotation, err);
  if (status == CF_OK) status = check_finite(map, err);
  if (status != CF_OK) return status;

  geometry g = {map->width, map->height, map->channels, map->pixels, 0, 0, 0, 0, 0, 0};
  const size_t w = (size_t)map->width, h = (size_t)map->height;
  g.sin_theta = malloc(3 * h * sizeof(double));
  g.cos_phi = malloc(2 * w * sizeof(double));
  g.sat = malloc((w + 1) * (h + 1) * sizeof(double));
  region *regions = malloc((size_t)k * sizeof(region));
  int *heap = malloc((size_t)k * sizeof(int));
  if (!g.sin_theta || !g.cos_phi || !g.sat || !regions || !heap) {
    free(g.sin_theta);
    free(g.cos_phi);
    free(g.sat);
    free(regions);
    free(heap);
    return cf_error_set(err, CF_ENOMEM, "environment map: out of memory for a %d x %d map",
                        map->width, map->height);
  }
  g.cos_theta = g.sin_theta + h;
  g.d_omega = g.cos_theta + h;
  g.sin_phi = g.cos_phi + w;

  cf_envmap_report local;
  if (!report) report = &local;
  build(&g, report);

  regions[0] = (region){0, 0, map->width, map->height, 0.0};
  regions[0].energy = rect_energy(&g, 0, 0, map->width, map->height);
  int queued = 0;
  queue_push(regions, heap, &queued, 0);
  for (int n = 1; n < k; ++n) {
    /* k <= width × height, so some region still has two pixels */
    const int next = queue_pop(regions, heap, &queued);
    split(&g, &regions[next], &regions[n]);
    queue_push(regions, heap, &queued, next);
    queue_push(regions, heap, &queued, n);
  }
  for (int i = 0; i < k; ++i) region_light(&g, &regions[i], rotation, &lights[i]);

  free(g.sin_theta);
  free(g.cos_phi);
  free(g.sat);
  free(regions);
  free(heap);
  return CF_OK;
}

cf_status cf_envmap_load(const char *path, const double rotation[9], int k,
                         cf_directional_light *lights, cf_envmap_report *report, cf_error *err) {
  cf_image map = {0};
  cf_status s = cf_image_read(path, &map, NULL, err);
  if (s != CF_OK) return s;
  if (map.channels < 3)
    s = cf_error_set(err, CF_EINVAL, "%s: an environment map needs RGB, it has %d channel%s", path,
                     map.channels, map.channels == 1 ? "" : "s");
  else if ((s = cf_envmap_median_cut(&map, rotation, k, lights, report, err)) != CF_OK)
    cf_error_prefix(err, "%s", path);
  cf_image_free(&map);
  return s;
}
