/* Chrome balls rendered for the tests (chrome_render.h). */
#include "chrome_render.h"

#include <math.h>

#define SS 4
#define PI 3.14159265358979323846
#define SOURCE_RADIUS_DEG 1.0

static void unit(double v[3]) {
  double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int k = 0; k < 3; ++k) v[k] /= n;
}

void chrome_set_light(chrome_scene *s, int k, double x, double y, double z) {
  s->light[k][0] = x, s->light[k][1] = y, s->light[k][2] = z;
  unit(s->light[k]);
  if (k + 1 > s->sources) s->sources = k + 1;
}

double chrome_angle_deg(const double a[3], const double b[3]) {
  double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  return acos(fmin(1.0, fmax(-1.0, c))) * 180.0 / PI;
}

/* The reflected direction at continuous pixel (u, v); 0 off the ball. */
static int reflected(const chrome_scene *s, double u, double v, double out[3]) {
  double d[3], n[3];
  if (!s->camera) {
    double nx = (u - s->cx) / s->r, ny = -(v - s->cy) / s->r, q = nx * nx + ny * ny;
    if (q >= 1.0) return 0;
    n[0] = nx, n[1] = ny, n[2] = sqrt(1.0 - q);
    d[0] = 0, d[1] = 0, d[2] = -1;
  } else {
    const double *p = s->camera->params; /* PINHOLE fx fy cx cy */
    d[0] = (u - p[2]) / p[0], d[1] = (v - p[3]) / p[1], d[2] = 1.0;
    unit(d);
    double dc = d[0] * s->center[0] + d[1] * s->center[1] + d[2] * s->center[2];
    double cc =
        s->center[0] * s->center[0] + s->center[1] * s->center[1] + s->center[2] * s->center[2];
    double disc = dc * dc - (cc - s->radius * s->radius);
    if (disc <= 0.0) return 0;
    double t = dc - sqrt(disc);
    for (int k = 0; k < 3; ++k) n[k] = (t * d[k] - s->center[k]) / s->radius;
  }
  double dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
  for (int k = 0; k < 3; ++k) out[k] = d[k] - 2.0 * dn * n[k];
  return 1;
}

/* The mean of SS x SS samples of pixel (x, y). */
static double pixel_value(const chrome_scene *s, int x, int y, double cos_source) {
  double sum = 0.0, l[3];
  for (int j = 0; j < SS; ++j)
    for (int i = 0; i < SS; ++i) {
      if (!reflected(s, x + (i + 0.5) / SS, y + (j + 0.5) / SS, l)) {
        sum += 0.02;
        continue;
      }
      double value = s->sky * (1.2 + 0.5 * (s->camera ? -l[1] : l[1]));
      for (int k = 0; k < s->sources; ++k)
        if (l[0] * s->light[k][0] + l[1] * s->light[k][1] + l[2] * s->light[k][2] > cos_source)
          value += 4.0;
      sum += value;
    }
  return sum / (SS * SS);
}

int chrome_render(const chrome_scene *s, cf_image *photo, cf_image *mask) {
  if (cf_image_alloc(photo, s->width, s->height, 3, NULL) != CF_OK) return 0;
  if (cf_image_alloc(mask, s->width, s->height, 1, NULL) != CF_OK) return 0;
  double radius = s->source_radius_deg > 0.0 ? s->source_radius_deg : SOURCE_RADIUS_DEG;
  double cos_source = cos(radius * PI / 180.0), l[3];
  for (int y = 0; y < s->height; ++y)
    for (int x = 0; x < s->width; ++x) {
      double v = fmin(1.0, pixel_value(s, x, y, cos_source));
      v = floor(v * 255.0 + 0.5) / 255.0; /* 8-bit */
      size_t k = (size_t)y * (size_t)s->width + (size_t)x;
      for (int c = 0; c < 3; ++c) photo->pixels[3 * k + (size_t)c] = (float)v;
      mask->pixels[k] = (float)reflected(s, x + 0.5, y + 0.5, l);
    }
  return 1;
}
