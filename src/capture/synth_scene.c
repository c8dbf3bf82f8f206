/* The synthetic scene: intersections, procedural textures and shading
 * (synth_scene.h). */
#include "synth_scene.h"

#include <math.h>
#include <string.h>

#include "core/vec.h"

static const double ground_z = SYNTH_GROUND_Z;
static const double backdrop_radius = 6.0, backdrop_top = 5.0;

double synth_hit_sphere(const double origin[3], const double d[3]) {
  double b = cf_dot3(d, origin), c = cf_dot3(origin, origin) - 1.0;
  double discriminant = b * b - c;
  if (discriminant < 0.0 || c <= 0.0) return -1.0;
  return -b - sqrt(discriminant);
}

/* ---- textures: value noise on an integer lattice (hash per corner,
 * smoothstep interpolation), several octaves, plus sharp blotches, so that
 * SIFT finds corners at every scale of the orbit ---- */

static uint64_t hash3(int64_t x, int64_t y, uint64_t seed) {
  uint64_t h = seed ^ ((uint64_t)x * 0x9e3779b97f4a7c15ULL) ^ ((uint64_t)y * 0xc2b2ae3d27d4eb4fULL);
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdULL;
  h ^= h >> 33;
  h *= 0xc4ceb9fe1a85ec53ULL;
  return h ^ (h >> 33);
}

static double lattice(int64_t x, int64_t y, uint64_t seed) {
  return (double)(hash3(x, y, seed) >> 11) * 0x1.0p-53;
}

static double value_noise(double x, double y, uint64_t seed) {
  double fx = floor(x), fy = floor(y);
  int64_t ix = (int64_t)fx, iy = (int64_t)fy;
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0 - 2.0 * tx);
  ty = ty * ty * (3.0 - 2.0 * ty);
  double a = lattice(ix, iy, seed), b = lattice(ix + 1, iy, seed);
  double c = lattice(ix, iy + 1, seed), e = lattice(ix + 1, iy + 1, seed);
  return (a + (b - a) * tx) + ((c + (e - c) * tx) - (a + (b - a) * tx)) * ty;
}

/* Albedo in [0.08, 0.9] per channel at texture coordinates (s, t): smooth
 * noise plus crisp blotches at three scales (a factor 2.7 apart), so that
 * SIFT finds corners and blobs at every scale the orbit sees. */
static void texture(double s, double t, uint64_t seed, double albedo[3]) {
  double smooth = 0.0, amplitude = 0.5, frequency = 1.0;
  for (int octave = 0; octave < 4; ++octave) {
    smooth += amplitude * value_noise(s * frequency, t * frequency, seed + (uint64_t)octave);
    amplitude *= 0.5;
    frequency *= 2.3;
  }
  double blotches = 0.0;
  for (int scale = 0; scale < 3; ++scale) {
    double f = 0.9 * pow(2.7, scale);
    blotches += value_noise(s * f, t * f, seed + 17 + (uint64_t)scale) > 0.58 ? 1.0 / 3.0 : 0.0;
  }
  double grey = 0.08 + 0.82 * fmin(1.0, fmax(0.0, 0.45 * smooth + 0.75 * blotches));
  for (int c = 0; c < 3; ++c)
    albedo[c] = grey * (0.8 + 0.2 * value_noise(s * 0.7, t * 0.7, seed + 31 + (uint64_t)c));
}

int synth_in_shadow(const double x[3], const cf_light *light) {
  double l[3], e[3];
  if (!cf_light_at(light, NULL, NULL, x, l, e)) return 1;
  double t = synth_hit_sphere(x, l);
  if (light->kind == CF_LIGHT_DIRECTIONAL) return t > 1e-9;
  double d[3] = {light->position[0] - x[0], light->position[1] - x[1], light->position[2] - x[2]};
  return t > 1e-9 && t < cf_norm3(d);
}

/* Lambertian radiance at x with normal n and albedo, every light with the
 * sphere's shadow. */
static void lambert(const synth_scene *scene, const double x[3], const double n[3],
                    const double albedo[3], double radiance[3]) {
  double irradiance[3] = {0.0, 0.0, 0.0};
  for (int j = 0; j < scene->light_count; ++j) {
    double l[3], e[3];
    if (!cf_light_at(&scene->lights[j], NULL, NULL, x, l, e)) continue;
    double cos_i = cf_dot3(l, n);
    if (!(cos_i > 0.0) || synth_in_shadow(x, &scene->lights[j])) continue;
    for (int c = 0; c < 3; ++c) irradiance[c] += e[c] * cos_i;
  }
  for (int c = 0; c < 3; ++c) radiance[c] = albedo[c] / CF_PI * irradiance[c];
}

/* docs/model.md (5) summed over the lights: L = Σ_j f(n, l_j, v) E_j (n·l_j)+,
 * lights below the horizon skipped (their term is 0). The lights go to the
 * evaluator in batches, which prepare the parameters once (a tailed model
 * builds its masking table there: per light, M2T under 4096 lights took
 * 354 s against M2's 34). */
enum { SHADE_BATCH = 64 };

typedef struct shade_batch {
  double n[3 * SHADE_BATCH], l[3 * SHADE_BATCH], v[3 * SHADE_BATCH];
  double e[3 * SHADE_BATCH], cos_i[SHADE_BATCH], f[3 * SHADE_BATCH];
  int count;
} shade_batch;

static void shade_flush(const synth_scene *scene, shade_batch *b, double radiance[3]) {
  if (!b->count) return;
  cf_eval_batch_directions(scene->model, scene->params, (size_t)b->count, b->n, b->l, b->v, b->f,
                           NULL);
  for (int k = 0; k < b->count; ++k)
    for (int c = 0; c < 3; ++c) radiance[c] += b->f[3 * k + c] * b->e[3 * k + c] * b->cos_i[k];
  b->count = 0;
}

static void shade_sphere(const synth_scene *scene, const double x[3], const double v[3],
                         double radiance[3]) {
  const double *n = x; /* unit sphere at the origin */
  radiance[0] = radiance[1] = radiance[2] = 0.0;
  shade_batch b;
  b.count = 0;
  for (int j = 0; j < scene->light_count; ++j) {
    double *l = b.l + 3 * b.count, *e = b.e + 3 * b.count;
    if (!cf_light_at(&scene->lights[j], NULL, NULL, x, l, e)) continue;
    double cos_i = cf_dot3(n, l);
    if (!(cos_i > 0.0)) continue;
    memcpy(b.n + 3 * b.count, n, 3 * sizeof *n);
    memcpy(b.v + 3 * b.count, v, 3 * sizeof *v);
    b.cos_i[b.count] = cos_i;
    if (++b.count == SHADE_BATCH) shade_flush(scene, &b, radiance);
  }
  shade_flush(scene, &b, radiance);
}

synth_surface synth_shade(const synth_scene *scene, const double origin[3], const double d[3],
                          double radiance[3]) {
  radiance[0] = radiance[1] = radiance[2] = 0.0;
  double t_sphere = synth_hit_sphere(origin, d);
  /* the ground plane */
  double t_ground = d[2] < 0.0 ? (ground_z - origin[2]) / d[2] : -1.0;
  /* the backdrop: |(o + t d)_xy| = R, the far root (we are inside) */
  double a = d[0] * d[0] + d[1] * d[1], b = origin[0] * d[0] + origin[1] * d[1];
  double c = origin[0] * origin[0] + origin[1] * origin[1] - backdrop_radius * backdrop_radius;
  double t_backdrop = a > 0.0 ? (-b + sqrt(fmax(0.0, b * b - a * c))) / a : -1.0;

  double best = INFINITY;
  synth_surface hit = SYNTH_NOTHING;
  if (t_sphere > 0.0 && t_sphere < best) best = t_sphere, hit = SYNTH_SPHERE;
  if (t_ground > 0.0 && t_ground < best) {
    double x = origin[0] + t_ground * d[0], y = origin[1] + t_ground * d[1];
    if (x * x + y * y < backdrop_radius * backdrop_radius) best = t_ground, hit = SYNTH_GROUND;
  }
  if (t_backdrop > 0.0 && t_backdrop < best && origin[2] + t_backdrop * d[2] <= backdrop_top)
    best = t_backdrop, hit = SYNTH_BACKDROP;

  double x[3] = {origin[0] + best * d[0], origin[1] + best * d[1], origin[2] + best * d[2]};
  double albedo[3];
  switch (hit) {
    case SYNTH_SPHERE: {
      double v[3] = {-d[0], -d[1], -d[2]};
      shade_sphere(scene, x, v, radiance);
      break;
    }
    case SYNTH_GROUND: {
      static const double up[3] = {0.0, 0.0, 1.0};
      if (scene->card_albedo > 0.0 && fabs(x[0] - scene->card_center[0]) <= scene->card_half &&
          fabs(x[1] - scene->card_center[1]) <= scene->card_half) {
        albedo[0] = albedo[1] = albedo[2] = scene->card_albedo;
        hit = SYNTH_CARD;
      } else {
        texture(6.0 * x[0], 6.0 * x[1], scene->seed, albedo);
      }
      lambert(scene, x, up, albedo, radiance);
      break;
    }
    case SYNTH_BACKDROP: {
      double inward[3] = {-x[0] / backdrop_radius, -x[1] / backdrop_radius, 0.0};
      texture(4.0 * backdrop_radius * atan2(x[1], x[0]), 4.0 * x[2], scene->seed + 1000, albedo);
      lambert(scene, x, inward, albedo, radiance);
      break;
    }
    case SYNTH_CARD: /* not a hit yet: the card is found on the ground */
    case SYNTH_NOTHING:
      break;
  }
  return hit;
}
