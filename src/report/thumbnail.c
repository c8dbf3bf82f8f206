/* The fitted sphere under the standard light (include/clayfit/thumbnail.h):
 * a linear render through the evaluator, and its 8-bit sRGB PNG. */
#include "clayfit/thumbnail.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/vec.h"

/* The standard light (thumbnail.h): the key (−4, 4, 7)/9 at 0.8π, so that
 * an albedo-1 Lambertian surface facing it gives (1/π)(0.8π) = 0.8; the
 * fill (6, −2, 3)/7 at a quarter of that. */
static const cf_sphere_light standard_lights[CF_SPHERE_LIGHT_COUNT] = {
    {{-4.0 / 9.0, 4.0 / 9.0, 7.0 / 9.0}, 0.8 * CF_PI},
    {{6.0 / 7.0, -2.0 / 7.0, 3.0 / 7.0}, 0.2 * CF_PI},
};

static const double view_dir[3] = {0.0, 0.0, 1.0};

const cf_sphere_light *cf_sphere_lights(void) {
  return standard_lights;
}

void cf_sphere_view_default(cf_sphere_view *view) {
  view->size = 256;
  view->radius = 0.92;
  for (int c = 0; c < 3; ++c) view->background[c] = 0.18;
  view->edge_samples = 3;
  view->footprint_tolerance = 2e-3;
  view->footprint_max = 8;
  view->light_count = 0;
  view->light_direction = view->light_irradiance = NULL;
}

double cf_sphere_tone(double linear) {
  if (!(linear > 0.0)) return 0.0;
  if (linear <= CF_SPHERE_KNEE) return linear;
  double room = 1.0 - CF_SPHERE_KNEE;
  return CF_SPHERE_KNEE + room * (1.0 - exp(-(linear - CF_SPHERE_KNEE) / room));
}

static cf_status check_view(const cf_sphere_view *v, cf_error *err) {
  if (v->size < 1 || v->size > CF_SPHERE_MAX_SIZE)
    return cf_error_set(err, CF_EINVAL, "sphere view: size %d is outside 1..%d", v->size,
                        CF_SPHERE_MAX_SIZE);
  if (!(v->radius > 0.0 && v->radius <= 1.0))
    return cf_error_set(err, CF_EINVAL, "sphere view: radius %g is outside (0, 1]", v->radius);
  for (int c = 0; c < 3; ++c)
    if (!isfinite(v->background[c]))
      return cf_error_set(err, CF_EINVAL, "sphere view: background[%d] is not finite", c);
  if (v->edge_samples < 1 || v->edge_samples > CF_SPHERE_MAX_SAMPLES || v->footprint_max < 1 ||
      v->footprint_max > CF_SPHERE_MAX_SAMPLES)
    return cf_error_set(err, CF_EINVAL,
                        "sphere view: edge_samples %d and footprint_max %d must be in 1..%d",
                        v->edge_samples, v->footprint_max, CF_SPHERE_MAX_SAMPLES);
  if (!(v->footprint_tolerance >= 0.0) || !isfinite(v->footprint_tolerance))
    return cf_error_set(err, CF_EINVAL, "sphere view: footprint_tolerance %g is not >= 0",
                        v->footprint_tolerance);
  if (v->light_count < 0 || v->light_count > CF_SPHERE_MAX_LIGHTS ||
      (v->light_count > 0 && (!v->light_direction || !v->light_irradiance)))
    return cf_error_set(err, CF_EINVAL,
                        "sphere view: light_count %d is outside 0..%d, or no lights",
                        v->light_count, CF_SPHERE_MAX_LIGHTS);
  for (int k = 0; k < 3 * v->light_count; ++k)
    if (!isfinite(v->light_direction[k]) || !(v->light_irradiance[k] >= 0.0) ||
        !isfinite(v->light_irradiance[k]))
      return cf_error_set(err, CF_EINVAL, "sphere view: light %d is not finite or negative", k / 3);
  return CF_OK;
}

/* The view's lights (its own, or the standard light), directions unit. */
typedef struct sphere_lights {
  int count;
  double direction[CF_SPHERE_MAX_LIGHTS][3], irradiance[CF_SPHERE_MAX_LIGHTS][3];
} sphere_lights;

static void view_lights(const cf_sphere_view *v, sphere_lights *out) {
  out->count = v->light_count ? v->light_count : CF_SPHERE_LIGHT_COUNT;
  for (int k = 0; k < out->count; ++k) {
    const double *d = v->light_count ? v->light_direction + 3 * k : standard_lights[k].direction;
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; ++c) {
      out->direction[k][c] = len > 0.0 ? d[c] / len : 0.0;
      out->irradiance[k][c] = len > 0.0 ? (v->light_count ? v->light_irradiance[3 * k + c]
                                                          : standard_lights[k].irradiance)
                                        : 0.0;
    }
  }
}

/* ---- the render: samples of a row batched through cf_eval_batch ---- */

/* Geometries per evaluator call; a pixel needs at most
 * CF_SPHERE_MAX_SAMPLES² × CF_SPHERE_MAX_LIGHTS = 8192. */
enum { BATCH = 8192 };

typedef struct render {
  cf_model_id model;
  const double *params;
  const cf_sphere_view *view;
  sphere_lights lights;
  double centre, radius_px, lobe_width;
  cf_geometry *geometry; /* BATCH */
  double *f;             /* 3 × BATCH */
  int *pixel;            /* BATCH: the pixel of the row each geometry adds to */
  double *scale;         /* 3 × BATCH: E × the sample's weight */
  size_t count;
  double *row; /* 3 × size: the row's radiance */
} render;

/* Where sample j of n per side sits across a pixel, in pixels from its
 * centre: the footprint's Gauss-Legendre pairs for an even n (so that a
 * highlight is integrated as the fit does), the midpoints otherwise. */
static double sample_offset(int n, int j) {
  if (n > 1 && n % 2 == 0) return cf_footprint_offset(n, j);
  return (j + 0.5) / n - 0.5;
}

/* The outward normal seen at image position (px, py) (pixels, continuous);
 * 0 off the sphere. */
static int normal_at(const render *r, double px, double py, double n[3]) {
  double u = (px - r->centre) / r->radius_px, w = (r->centre - py) / r->radius_px;
  double z2 = 1.0 - u * u - w * w;
  if (!(z2 > 0.0)) return 0;
  n[0] = u;
  n[1] = w;
  n[2] = sqrt(z2);
  return 1;
}

/* Samples per side that integrate the narrowest lobe over pixel (px, py)
 * (its centre) to the view's tolerance, over every light that reaches it. */
static int footprint_samples(const render *r, double px, double py) {
  double n[3];
  if (r->view->footprint_tolerance <= 0.0 || !isfinite(r->lobe_width) || !normal_at(r, px, py, n))
    return 1;
  /* the normal turns fastest radially: 1/(R cos θ_o) radians per pixel */
  double delta = 1.0 / (r->radius_px * fmax(n[2], 1e-9));
  int most = 1;
  for (int k = 0; k < r->lights.count; ++k) {
    const double *l = r->lights.direction[k];
    if (n[0] * l[0] + n[1] * l[1] + n[2] * l[2] <= 0.0) continue;
    double h[3] = {l[0] + view_dir[0], l[1] + view_dir[1], l[2] + view_dir[2]};
    double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    double c = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / len;
    double theta_h = acos(fmin(1.0, fmax(-1.0, c)));
    int s = cf_footprint_samples(r->lobe_width, delta, theta_h, r->view->footprint_tolerance,
                                 r->view->footprint_max);
    if (s > most) most = s;
  }
  return most;
}

static cf_status flush(render *r) {
  if (r->count == 0) return CF_OK;
  cf_status s = cf_eval_batch(r->model, r->params, r->count, r->geometry, r->f, NULL);
  if (s != CF_OK) return s;
  for (size_t i = 0; i < r->count; ++i) {
    double weight = r->geometry[i].cos_i;
    for (int c = 0; c < 3; ++c)
      r->row[3 * (size_t)r->pixel[i] + c] += r->f[3 * i + c] * weight * r->scale[3 * i + c];
  }
  r->count = 0;
  return CF_OK;
}

/* One sample of pixel x at (px, py), of weight w: the background off the
 * sphere, else a geometry per light that reaches it. */
static cf_status add_sample(render *r, int x, double px, double py, double w) {
  double n[3];
  if (!normal_at(r, px, py, n)) {
    for (int c = 0; c < 3; ++c) r->row[3 * (size_t)x + c] += w * r->view->background[c];
    return CF_OK;
  }
  if (r->count + (size_t)r->lights.count > BATCH) {
    cf_status s = flush(r);
    if (s != CF_OK) return s;
  }
  for (int k = 0; k < r->lights.count; ++k) {
    cf_geometry g = cf_geometry_from_directions(n, r->lights.direction[k], view_dir);
    if (!cf_geometry_is_lit(&g)) continue;
    r->geometry[r->count] = g;
    r->pixel[r->count] = x;
    for (int c = 0; c < 3; ++c) r->scale[3 * r->count + c] = w * r->lights.irradiance[k][c];
    ++r->count;
  }
  return CF_OK;
}

/* Pixel (x, y): its samples per side (the silhouette's, the highlight's),
 * each sample added. A pixel wholly off the sphere is the background. */
static cf_status add_pixel(render *r, int x, int y) {
  double px = x + 0.5, py = y + 0.5;
  double d = hypot(px - r->centre, py - r->centre) - r->radius_px;
  const double half_diagonal = 0.7072; /* √2/2, rounded up */
  if (d >= half_diagonal) {
    for (int c = 0; c < 3; ++c) r->row[3 * (size_t)x + c] = r->view->background[c];
    return CF_OK;
  }
  int n = footprint_samples(r, px, py);
  if (d > -half_diagonal && r->view->edge_samples > n) n = r->view->edge_samples;
  double w = 1.0 / ((double)n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      cf_status s = add_sample(r, x, px + sample_offset(n, i), py + sample_offset(n, j), w);
      if (s != CF_OK) return s;
    }
  return CF_OK;
}

static cf_status render_rows(render *r, cf_image *out, cf_error *err) {
  int size = r->view->size;
  for (int y = 0; y < size; ++y) {
    memset(r->row, 0, 3 * (size_t)size * sizeof *r->row);
    cf_status s = CF_OK;
    for (int x = 0; x < size && s == CF_OK; ++x) s = add_pixel(r, x, y);
    if (s == CF_OK) s = flush(r);
    if (s != CF_OK) return cf_error_set(err, s, "sphere render: the evaluator failed");
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 3; ++c) {
        double v = r->row[3 * (size_t)x + c];
        if (!isfinite(v))
          return cf_error_set(err, CF_ENUMERIC,
                              "sphere render: pixel (%d, %d) channel %d is not finite", x, y, c);
        out->pixels[3 * ((size_t)y * (size_t)size + (size_t)x) + c] = (float)v;
      }
  }
  return CF_OK;
}

cf_status cf_sphere_render(cf_model_id model, const double *params, const cf_sphere_view *view,
                           cf_image *out, cf_error *err) {
  out->width = out->height = out->channels = 0;
  out->pixels = NULL;
  if (!cf_model_info_get(model))
    return cf_error_set(err, CF_EINVAL, "sphere render: unknown model %d", (int)model);
  if (!params || !view) return cf_error_set(err, CF_EINVAL, "sphere render: no parameters or view");
  cf_status s = check_view(view, err);
  if (s == CF_OK) s = cf_params_check(model, params, err);
  if (s != CF_OK) return s;

  render r = {.model = model, .params = params, .view = view};
  r.centre = 0.5 * view->size;
  r.radius_px = view->radius * r.centre;
  r.lobe_width = cf_model_lobe_width(model, params);
  r.geometry = malloc(BATCH * sizeof *r.geometry);
  r.f = malloc(3 * BATCH * sizeof *r.f);
  r.pixel = malloc(BATCH * sizeof *r.pixel);
  r.scale = malloc(3 * BATCH * sizeof *r.scale);
  view_lights(view, &r.lights);
  r.row = malloc(3 * (size_t)view->size * sizeof *r.row);
  if (!r.geometry || !r.f || !r.pixel || !r.scale || !r.row)
    s = cf_error_set(err, CF_ENOMEM, "sphere render: out of memory");
  if (s == CF_OK) s = cf_image_alloc(out, view->size, view->size, 3, err);
  if (s == CF_OK) s = render_rows(&r, out, err);
  if (s != CF_OK) cf_image_free(out);
  free(r.geometry);
  free(r.f);
  free(r.pixel);
  free(r.scale);
  free(r.row);
  return s;
}

cf_status cf_report_render_sphere(const cf_fit_result *result, const cf_sphere_view *view,
                                  cf_image *out, cf_error *err) {
  cf_sphere_view standard;
  if (!view) {
    cf_sphere_view_default(&standard);
    view = &standard;
  }
  if (!result) {
    out->width = out->height = out->channels = 0;
    out->pixels = NULL;
    return cf_error_set(err, CF_EINVAL, "sphere render: no fit result");
  }
  return cf_sphere_render(result->model, result->params, view, out, err);
}

/* ---- the PNG ---- */

cf_status cf_sphere_write_png(const cf_image *linear, const char *path, cf_error *err) {
  if (!linear || !linear->pixels || linear->channels != 3 || linear->width <= 0 ||
      linear->height <= 0)
    return cf_error_set(err, CF_EINVAL, "%s: nothing to write (not a 3-channel render)",
                        path ? path : "(no path)");
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty thumbnail path");
  cf_image display;
  cf_status s = cf_image_alloc(&display, linear->width, linear->height, 3, err);
  if (s != CF_OK) return s;
  size_t n = 3 * (size_t)linear->width * (size_t)linear->height;
  for (size_t i = 0; i < n; ++i)
    display.pixels[i] = (float)cf_linear_to_srgb(cf_sphere_tone(linear->pixels[i]));
  s = cf_image_write(path, &display, 8, err); /* whole or not at all */
  cf_image_free(&display);
  return s;
}

cf_status cf_report_write_thumbnail(const cf_fit_result *result, const cf_sphere_view *view,
                                    const char *path, cf_error *err) {
  cf_image linear;
  cf_status s = cf_report_render_sphere(result, view, &linear, err);
  if (s == CF_OK) s = cf_sphere_write_png(&linear, path, err);
  cf_image_free(&linear);
  return s;
}
