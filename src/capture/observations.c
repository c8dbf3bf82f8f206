/* The pixel loop of a capture: for every pixel of image k that sees the
 * sphere clear of its silhouette (and is inside the mask, if any), decode
 * the photo's value to linear radiance and record the observation: normal,
 * view, every light's direction and irradiance, RGB, flags; and the arrays
 * that hold them (the screen that follows: capture_screen.c). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/memory.h"
#include "image_codec.h"

/* The arrays of n observations (o->lights set) as they are: `field`,
 * its values per observation. */
#define EACH_ARRAY(o, slots, DO) \
  DO(normal, 3);                 \
  DO(view, 3);                   \
  DO(light_dir, 3 * (slots));    \
  DO(irradiance, 3 * (slots));   \
  DO(rgb, 3);                    \
  DO(flags, 1);                  \
  DO(image, 1);                  \
  DO(pixel, 2)

static size_t slots_of(const cf_observations *o) {
  return (size_t)(o->lights > 0 ? o->lights : 1);
}

cf_status capture_allocate_observations(cf_observations *o, size_t n, cf_error *err) {
  const size_t slots = slots_of(o), room = n ? n : 1;
#define ALLOCATE(field, per)                                                   \
  if (!(o->field = cf_malloc_large(room * (per) * sizeof *o->field)))          \
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu observations", n)
  EACH_ARRAY(o, slots, ALLOCATE);
#undef ALLOCATE
  return CF_OK;
}

void capture_shrink_observations(cf_observations *o) {
  const size_t slots = slots_of(o), room = o->count ? o->count : 1;
  void *shrunk;
#define SHRINK(field, per)                                         \
  if ((shrunk = realloc(o->field, room * (per) * sizeof *o->field))) \
  o->field = shrunk /* (on failure the larger block stays) */
  EACH_ARRAY(o, slots, SHRINK);
#undef SHRINK
}

void capture_free_observations(cf_observations *o) {
  const size_t slots = slots_of(o);
#define FREE(field, per) \
  free(o->field);        \
  o->field = NULL
  EACH_ARRAY(o, slots, FREE);
#undef FREE
  (void)slots;
}

void capture_move_observations(cf_observations *to, size_t at, const cf_observations *from,
                               size_t first, size_t count) {
  if ((to == from && at == first) || count == 0) return;
  const size_t slots = slots_of(to);
#define MOVE(field, per) \
  memmove(to->field + (per) * at, from->field + (per) * first, (per) * count * sizeof *to->field)
  EACH_ARRAY(to, slots, MOVE);
#undef MOVE
}

/* An 8-bit image's 256 values (image_scale_u8's) decoded once each by
 * cf_decode_pixel: a look-up instead of a pow per channel, bit-identical;
 * a value that is not one of them is decoded directly. (Loading the demo:
 * user time 0.92 of that without the table, 5 alternating runs.) */
typedef struct code_table {
  int used;
  uint32_t key[256]; /* each code's float's bits */
  double radiance[256];
  uint8_t clipped[256];
} code_table;

static void code_table_init(code_table *t, const cf_decode *decode, int eight_bit) {
  t->used = eight_bit;
  if (!eight_bit) return;
  uint8_t codes[256];
  float values[256];
  for (int c = 0; c < 256; ++c) codes[c] = (uint8_t)c;
  image_scale_u8(codes, 256, values);
  for (int c = 0; c < 256; ++c) {
    double rgb[3];
    t->clipped[c] = (uint8_t)(cf_decode_pixel(decode, &values[c], 1, rgb) & 1u);
    t->radiance[c] = rgb[0];
    memcpy(&t->key[c], &values[c], sizeof t->key[c]);
  }
}

/* cf_decode_pixel, through the table where it holds every channel. */
static unsigned decode_stored(const code_table *t, const cf_decode *decode, const float *stored,
                              int channels, double radiance[3]) {
  const int grey = channels < 3;
  if (t->used) {
    unsigned clipped = 0;
    int c = 0;
    for (; c < 3; ++c) {
      const float value = stored[grey ? 0 : c], scaled = value * 255.0f;
      if (!(scaled >= 0.0f && scaled <= 255.0f)) break;
      const int code = (int)(scaled + 0.5f);
      uint32_t bits;
      memcpy(&bits, &value, sizeof bits);
      if (bits != t->key[code]) break;
      radiance[c] = t->radiance[code];
      clipped |= (unsigned)t->clipped[code] << c;
    }
    if (c == 3) return clipped;
  }
  return cf_decode_pixel(decode, stored, channels, radiance);
}

/* Is pixel (x, y) inside the mask (first channel > 0.5)? */
static int in_mask(const cf_image *mask, int x, int y) {
  if (!mask || !mask->pixels) return 1;
  return capture_mask_usable(
      mask->pixels[((size_t)y * (size_t)mask->width + (size_t)x) * (size_t)mask->channels]);
}

/* Every light slot's direction and irradiance at a surface point seen in
 * image k (zero for the slots the image does not use); 1 if some light
 * reaches it (n·l > 0 and some irradiance). */
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
    lit |= l[0] * point->normal[0] + l[1] * point->normal[1] + l[2] * point->normal[2] > 0.0 &&
           e[0] + e[1] + e[2] > 0.0;
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

void capture_add_observations(const cf_capture *capture, size_t k, const cf_image *image,
                              const cf_image *mask, const cf_decode *decode, int eight_bit,
                              cf_observations *o, image_observations *out) {
  const size_t slots = (size_t)o->lights;
  int bounds[4];
  capture_surface_bounds(capture, k, image->width, image->height, bounds);
  code_table table;
  code_table_init(&table, decode, eight_bit);
  size_t i = o->count;
  memset(out, 0, sizeof *out);
  for (int y = bounds[1]; y < bounds[3]; ++y) {
    for (int x = bounds[0]; x < bounds[2]; ++x) {
      surface_point point;
      surface_hit hit = capture_surface_at(capture, k, x, y, &point);
      if (hit == SURFACE_MISS) continue;
      ++out->sphere_pixels;
      if (hit == SURFACE_MARGIN || !in_mask(mask, x, y)) continue;

      const float *stored =
          image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
      unsigned clipped = decode_stored(&table, decode, stored, image->channels, o->rgb + 3 * i);
      int lit = lights_at(capture, k, &point, o->light_dir + 3 * slots * i,
                          o->irradiance + 3 * slots * i);
      memcpy(o->normal + 3 * i, point.normal, sizeof point.normal);
      memcpy(o->view + 3 * i, point.view, sizeof point.view);
      o->flags[i] = (uint8_t)(clipped | (lit ? 0u : CF_OBS_UNLIT));
      o->image[i] = (uint32_t)k;
      o->pixel[2 * i] = (float)(x + 0.5);
      o->pixel[2 * i + 1] = (float)(y + 0.5);
      ++i;
      out->clipped += clipped != 0;
    }
  }
  out->observations = i - o->count;
  o->count = i;
}

