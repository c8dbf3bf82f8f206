/* The pixel loop of a capture: for every pixel of image k that sees the
 * sphere clear of its silhouette (and is inside the mask, if any), decode
 * the photo's value to linear radiance and record the observation: normal,
 * view, every light's direction and irradiance, RGB, flags. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"

/* Make room for `extra` more observations (doubling). */
static cf_status reserve(cf_capture *capture, size_t extra, cf_error *err) {
  cf_observations *o = &capture->obs;
  if (o->count + extra <= capture->obs_capacity) return CF_OK;
  size_t capacity = capture->obs_capacity ? capture->obs_capacity : 4096;
  while (capacity < o->count + extra) capacity *= 2;
  size_t slots = (size_t)(o->lights > 0 ? o->lights : 1);
#define GROW(field, per)                                                                   \
  do {                                                                                     \
    void *grown = realloc(o->field, capacity * (per) * sizeof *o->field);                  \
    if (!grown)                                                                            \
      return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", capacity); \
    o->field = grown;                                                                      \
  } while (0)
  GROW(normal, 3);
  GROW(view, 3);
  GROW(light_dir, 3 * slots);
  GROW(irradiance, 3 * slots);
  GROW(rgb, 3);
  GROW(flags, 1);
  GROW(image, 1);
  GROW(pixel, 2);
#undef GROW
  capture->obs_capacity = capacity;
  return CF_OK;
}

/* Is pixel (x, y) inside the mask (first channel > 0.5)? */
static int in_mask(const cf_image *mask, int x, int y) {
  if (!mask || !mask->pixels) return 1;
  return mask->pixels[((size_t)y * (size_t)mask->width + (size_t)x) * (size_t)mask->channels] >
         0.5f;
}

/* Every light slot's direction and irradiance at a surface point seen in
 * image k (zero for the slots the image does not use); 1 if some light
 * reaches it (n·l > 0). */
static int lights_at(const cf_capture *capture, size_t k, const surface_point *point,
                     double *light_dir, double *irradiance) {
  const capture_view *view = &capture->views[k];
  const int lights = capture->light_counts[k];
  const cf_light *image_lights = capture->lights + k * (size_t)capture->max_lights;
  int lit = 0;
  for (int j = 0; j < capture->obs.lights; ++j) {
    double *l = light_dir + 3 * (size_t)j, *e = irradiance + 3 * (size_t)j;
    memset(l, 0, 3 * sizeof *l);
    memset(e, 0, 3 * sizeof *e);
    if (j >= lights || !cf_light_at(&image_lights[j], view->r, view->c, point->position, l, e))
      continue;
    lit |= l[0] * point->normal[0] + l[1] * point->normal[1] + l[2] * point->normal[2] > 0.0;
  }
  return lit;
}

int cf_capture_footprint_at(const cf_capture *capture, size_t i, double du, double dv,
                            double normal[3], double view[3], double *light_dir,
                            double *irradiance) {
  const cf_observations *o = &capture->obs;
  if (i >= o->count || !isfinite(du) || !isfinite(dv)) return 0;
  size_t k = o->image[i];
  surface_point point;
  double u = (double)o->pixel[2 * i] + du, v = (double)o->pixel[2 * i + 1] + dv;
  if (capture_surface_at_uv(capture, k, u, v, &point) == SURFACE_MISS) return 0;
  memcpy(normal, point.normal, sizeof point.normal);
  memcpy(view, point.view, sizeof point.view);
  lights_at(capture, k, &point, light_dir, irradiance);
  return 1;
}

double cf_observation_specularity(const cf_observations *obs, size_t k) {
  const double *n = obs->normal + 3 * k, *v = obs->view + 3 * k;
  double best = -1.0;
  for (int j = 0; j < obs->lights; ++j) {
    size_t slot = k * (size_t)obs->lights + (size_t)j;
    const double *l = obs->light_dir + 3 * slot, *e = obs->irradiance + 3 * slot;
    if (e[0] + e[1] + e[2] <= 0.0 || n[0] * l[0] + n[1] * l[1] + n[2] * l[2] <= 0.0) continue;
    double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
    double length = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    if (length > 0.0) best = fmax(best, (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / length);
  }
  return best;
}

cf_status capture_add_observations(cf_capture *capture, size_t k, const cf_image *image,
                                   const cf_image *mask, const cf_decode *decode, cf_error *err) {
  cf_observations *o = &capture->obs;
  cf_capture_image *info = &capture->images[k];
  const size_t slots = (size_t)o->lights;
  int bounds[4];
  capture_surface_bounds(capture, k, image->width, image->height, bounds);
  cf_status s =
      reserve(capture, (size_t)(bounds[2] - bounds[0]) * (size_t)(bounds[3] - bounds[1]), err);
  if (s != CF_OK) return s;
  for (int y = bounds[1]; y < bounds[3]; ++y) {
    for (int x = bounds[0]; x < bounds[2]; ++x) {
      surface_point point;
      surface_hit hit = capture_surface_at(capture, k, x, y, &point);
      if (hit == SURFACE_MISS) continue;
      ++info->sphere_pixels;
      if (hit == SURFACE_MARGIN || !in_mask(mask, x, y)) continue;

      size_t i = o->count;
      const float *stored =
          image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
      unsigned clipped = cf_decode_pixel(decode, stored, image->channels, o->rgb + 3 * i);
      int lit = lights_at(capture, k, &point, o->light_dir + 3 * slots * i,
                          o->irradiance + 3 * slots * i);
      memcpy(o->normal + 3 * i, point.normal, sizeof point.normal);
      memcpy(o->view + 3 * i, point.view, sizeof point.view);
      o->flags[i] = (uint8_t)(clipped | (lit ? 0u : CF_OBS_UNLIT));
      o->image[i] = (uint32_t)k;
      o->pixel[2 * i] = (float)(x + 0.5);
      o->pixel[2 * i + 1] = (float)(y + 0.5);
      ++o->count;
      ++info->observations;
      info->clipped += clipped != 0;
    }
  }
  return CF_OK;
}
