/* The synthetic scene of include/clayfit/synth.h: a clay sphere (centre at
 * the origin, radius 1) on a textured ground (z = -1) inside a textured
 * cylindrical backdrop (radius 6, up to z = 5), lit by a point light (the
 * flash) or by directional lights (an environment map's median cut).
 * Private to src/capture. */
#ifndef CLAYFIT_CAPTURE_SYNTH_SCENE_H
#define CLAYFIT_CAPTURE_SYNTH_SCENE_H

#include <stdint.h>

#include "clayfit/model.h"
#include "lights.h"

typedef enum synth_surface {
  SYNTH_NOTHING,
  SYNTH_SPHERE,
  SYNTH_GROUND,
  SYNTH_BACKDROP,
  SYNTH_CARD /* the reference card on the ground */
} synth_surface;

typedef struct synth_scene {
  cf_model_id model;
  const double *params;
  /* CF_LIGHT_POINT (the flash at its world position) or CF_LIGHT_DIRECTIONAL
   * (cf_light_at needs no camera for either) */
  const cf_light *lights;
  int light_count;
  uint64_t seed; /* texture layout */
  /* a grey Lambertian card on the ground (card_albedo 0: none): the
   * square |x - card_center[0]| <= card_half, |y - card_center[1]| <=
   * card_half of the plane z = -1 */
  double card_albedo, card_center[2], card_half;
} synth_scene;

/* The ground plane's height (world z). */
#define SYNTH_GROUND_Z (-1.0)

/* Shade the ray origin + t d (d unit): the radiance it carries back, per
 * channel (docs/model.md (5): L = Σ_j f E_j c_i over the lights, l and E from
 * cf_light_at as the fit's observations have them; the sphere is not shadowed
 * by the ground, as the fit's image formation has no shadows; the ground and
 * the backdrop are Lambertian with a procedural albedo and are shadowed by
 * the sphere, from every light). Returns what the ray hit first. */
synth_surface synth_shade(const synth_scene *scene, const double origin[3], const double d[3],
                          double radiance[3]);

/* Is the way from x to the light blocked by the sphere? */
int synth_in_shadow(const double x[3], const cf_light *light);

/* The distance along the ray to the sphere, or a negative number if it
 * misses (the first hit; the origin must be outside the sphere). */
double synth_hit_sphere(const double origin[3], const double d[3]);

#endif /* CLAYFIT_CAPTURE_SYNTH_SCENE_H */
