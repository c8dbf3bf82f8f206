/* The sphere's surface in a capture: which pixels see it, where, with which
 * normal and from which direction. Four cases:
 *   COLMAP cameras + a given sphere: ray-sphere intersection per pixel;
 *   COLMAP cameras + sphere_from_silhouettes: the sphere triangulated from
 *     every image's silhouette first, then as above;
 *   orthographic camera + sphere_from_silhouettes: a circle fitted in the
 *     image (or its mask), normals of a sphere seen orthographically;
 *   orthographic camera + normal_map: the map's normals.
 * Pixels within geometry.margin_px of the silhouette are left out: they mix
 * sphere and background. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/vec.h"

enum { MAX_BOUNDARY_POINTS = 4096 };

/* d_world = Rᵀ d_camera */
static void camera_to_world(const double r[9], const double d[3], double out[3]) {
  for (int k = 0; k < 3; ++k)
    out[k] = r[0 * 3 + k] * d[0] + r[1 * 3 + k] * d[1] + r[2 * 3 + k] * d[2];
}

/* d_camera = R d_world */
static void world_to_camera(const double r[9], const double d[3], double out[3]) {
  for (int k = 0; k < 3; ++k) out[k] = r[3 * k] * d[0] + r[3 * k + 1] * d[1] + r[3 * k + 2] * d[2];
}

/* ---- COLMAP cameras + sphere from silhouettes ---- */

/* Stored values to an sRGB rendition in place, whatever the file's
 * encoding: the silhouette is looked for where a person would see it. In
 * linear radiance the edge between a dark limb and the sphere's own shadow
 * on the background all but vanishes, and the shadow's bright outer edge
 * would be taken for the sphere's. */
static void perceptual_in_place(const cf_capture_spec *spec, cf_image *image) {
  cf_decode decode = {spec->transfer, spec->gamma, 0.0, INFINITY, 1.0};
  size_t n = (size_t)image->width * (size_t)image->height;
  for (size_t i = 0; i < n; ++i) {
    float *p = image->pixels + i * (size_t)image->channels;
    double rgb[3];
    cf_decode_pixel(&decode, p, image->channels, rgb);
    for (int c = 0; c < image->channels && c < 3; ++c)
      p[c] = (float)cf_linear_to_srgb(fmax(0.0, rgb[c]));
  }
}

/* One image's silhouette, as world rays from its camera centre. */
static cf_status silhouette_view(cf_capture *capture, size_t k, double *rays, size_t *count,
                                 cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  cf_image image = {0}, mask = {0};
  cf_status s = cf_image_read(spec->image_paths[k], &image, NULL, err);
  if (s == CF_OK) perceptual_in_place(spec, &image);
  if (s == CF_OK) s = capture_check_size(capture, k, &image, err);
  if (s == CF_OK && spec->mask_paths) s = cf_image_read(spec->mask_paths[k], &mask, NULL, err);
  if (s != CF_OK) {
    cf_image_free(&image);
    cf_image_free(&mask);
    return s;
  }
  cf_silhouette_hint hint = {mask.pixels ? &mask : NULL, {0.0, 0.0}, 0.0};
  cf_ellipse ellipse;
  double boundary[2 * MAX_BOUNDARY_POINTS];
  size_t points = 0;
  s = cf_detect_sphere_silhouette(&image, &hint, spec->image_paths[k], &ellipse, boundary,
                                  MAX_BOUNDARY_POINTS, &points, err);
  cf_image_free(&image);
  cf_image_free(&mask);
  if (s != CF_OK) return s;
  const capture_view *view = &capture->views[k];
  *count = 0;
  for (size_t i = 0; i < points; ++i) {
    double ray_camera[3];
    if (!cf_camera_unproject(view->camera, boundary + 2 * i, ray_camera)) continue;
    camera_to_world(view->r, ray_camera, rays + 3 * *count);
    ++*count;
  }
  return CF_OK;
}

static cf_status triangulate_sphere(cf_capture *capture, const cf_capture_options *options,
                                    cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  size_t n = spec->num_images;
  double *rays = malloc(n * 3 * MAX_BOUNDARY_POINTS * sizeof(double));
  cf_silhouette_view *views = calloc(n, sizeof *views);
  if (!rays || !views) {
    free(rays);
    free(views);
    return cf_error_set(err, CF_ENOMEM, "out of memory for the silhouettes");
  }
  size_t used = 0;
  cf_status s = CF_OK;
  for (size_t k = 0; k < n; ++k) {
    if (options && options->progress)
      options->progress(options->progress_user, "finding the sphere's silhouettes", k, n);
    double *own = rays + used * 3 * MAX_BOUNDARY_POINTS;
    size_t count = 0;
    cf_error detect = {0};
    s = silhouette_view(capture, k, own, &count, &detect);
    if (s == CF_ENOTFOUND) { /* this image shows no sphere: go on without it */
      capture_warn(capture, "%s", detect.message);
      s = CF_OK;
      continue;
    }
    if (s != CF_OK) {
      if (err) *err = detect;
      break;
    }
    if (count < 5) { /* too few of its points unproject: go on without it */
      capture_warn(capture,
                   "%s: only %zu silhouette points could be turned into rays; image "
                   "not used for the sphere",
                   spec->image_paths[k], count);
      continue;
    }
    cf_silhouette_view *view = &views[used++];
    memcpy(view->origin, capture->views[k].c, sizeof view->origin);
    view->rays = own;
    view->count = count;
    view->focal_px = capture->views[k].focal_px;
  }
  cf_sphere_fit fit;
  if (s == CF_OK && used < 2)
    s = cf_error_set(err, CF_ENOTFOUND,
                     "%s: the sphere's silhouette was found in %zu of %zu images; "
                     "triangulating it needs 2",
                     spec->path, used, n);
  /* outline points more than a pixel off (the sphere's shadow on the
   * background next to a dark limb, clutter) are left out */
  double kept = 1.0;
  if (s == CF_OK) s = cf_sphere_from_silhouettes_robust(views, used, 1.0, &fit, &kept, err);
  if (s == CF_OK) {
    memcpy(capture->center, fit.center, sizeof fit.center);
    capture->radius = fit.radius;
    capture->rms_px = fit.rms_px;
    capture->silhouette_kept = kept;
  }
  free(rays);
  free(views);
  return s;
}

/* ---- orthographic camera ---- */

static cf_status orthographic_circle(cf_capture *capture, cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  if (fabs(spec->view[2] - 1.0) > 1e-12)
    return cf_error_set(err, CF_EINVAL,
                        "%s: geometry \"sphere_from_silhouettes\" with an orthographic camera "
                        "needs camera.view [0, 0, 1] (normals are in the camera's frame)",
                        spec->path);
  const char *source = spec->mask_paths ? spec->mask_paths[0] : spec->image_paths[0];
  capture->circle_source = source;
  cf_image image = {0};
  cf_status s = cf_image_read(source, &image, NULL, err);
  if (s != CF_OK) return s;
  cf_silhouette_hint hint = {spec->mask_paths ? &image : NULL, {0.0, 0.0}, 0.0};
  double boundary[2 * MAX_BOUNDARY_POINTS];
  size_t points = 0;
  s = cf_detect_sphere_silhouette(&image, &hint, source, &capture->circle, boundary,
                                  MAX_BOUNDARY_POINTS, &points, err);
  cf_image_free(&image);
  return s;
}

/* A unit normal from the map at pixel (x, y), or 0 where there is none
 * (zero or too short: outside the object). */
static int map_normal(const cf_image *map, int x, int y, double n[3]) {
  if (x < 0 || y < 0 || x >= map->width || y >= map->height) return 0;
  const float *p =
      map->pixels + ((size_t)y * (size_t)map->width + (size_t)x) * (size_t)map->channels;
  double length = sqrt((double)p[0] * p[0] + (double)p[1] * p[1] + (double)p[2] * p[2]);
  if (!(length > 0.5)) return 0;
  for (int k = 0; k < 3; ++k) n[k] = p[k] / length;
  return 1;
}

/* Classify the map's pixels once: no normal (miss), a normal but a pixel
 * without one within margin_px (margin), or clear of the edge (hit). */
static cf_status classify_normal_map(cf_capture *capture, cf_error *err) {
  const cf_image *map = &capture->normal_map;
  size_t n = (size_t)map->width * (size_t)map->height;
  uint8_t *has = malloc(n), *class = malloc(n);
  if (!has || !class) {
    free(has);
    free(class);
    return cf_error_set(err, CF_ENOMEM, "out of memory for the normal map");
  }
  double normal[3], margin = capture->spec.margin_px;
  int r = (int)ceil(margin);
  for (int y = 0; y < map->height; ++y)
    for (int x = 0; x < map->width; ++x)
      has[(size_t)y * (size_t)map->width + (size_t)x] = (uint8_t)map_normal(map, x, y, normal);
  for (int y = 0; y < map->height; ++y) {
    for (int x = 0; x < map->width; ++x) {
      size_t i = (size_t)y * (size_t)map->width + (size_t)x;
      class[i] = has[i] ? SURFACE_HIT : SURFACE_MISS;
      for (int dy = -r; has[i] && class[i] == SURFACE_HIT && dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          int u = x + dx, v = y + dy;
          if (dx * dx + dy * dy > margin * margin) continue;
          if (u < 0 || v < 0 || u >= map->width || v >= map->height ||
              !has[(size_t)v * (size_t)map->width + (size_t)u]) {
            class[i] = SURFACE_MARGIN;
            break;
          }
        }
    }
  }
  free(has);
  capture->map_class = class;
  int *box = capture->map_box;
  box[0] = map->width, box[1] = map->height, box[2] = 0, box[3] = 0;
  for (int y = 0; y < map->height; ++y)
    for (int x = 0; x < map->width; ++x) {
      if (class[(size_t)y * (size_t)map->width + (size_t)x] == SURFACE_MISS) continue;
      box[0] = x < box[0] ? x : box[0], box[1] = y < box[1] ? y : box[1];
      box[2] = x + 1 > box[2] ? x + 1 : box[2], box[3] = y + 1 > box[3] ? y + 1 : box[3];
    }
  if (box[2] <= box[0]) box[0] = box[1] = box[2] = box[3] = 0; /* no surface at all */
  return CF_OK;
}

static cf_status read_normal_map(cf_capture *capture, cf_error *err) {
  const char *path = capture->spec.normal_map;
  /* the size its header declared (capture_read_headers) */
  const int width = capture->normal_map.width, height = capture->normal_map.height;
  cf_status s = cf_image_read_sized(path, width, height, &capture->normal_map, NULL, err);
  if (s == CF_OK && capture->normal_map.channels < 3)
    s = cf_error_set(err, CF_EINVAL, "%s: a normal map needs 3 channels, it has %d", path,
                     capture->normal_map.channels);
  if (s == CF_OK) s = cf_image_check_finite(&capture->normal_map, path, err);
  if (s == CF_OK) s = classify_normal_map(capture, err);
  return s;
}

cf_status capture_load_surface(cf_capture *capture, const cf_capture_options *options,
                               cf_error *err) {
  const cf_capture_spec *spec = &capture->spec;
  switch (spec->geometry) {
    case CF_GEOMETRY_SPHERE:
      memcpy(capture->center, spec->center, sizeof capture->center);
      capture->radius = spec->radius;
      return CF_OK;
    case CF_GEOMETRY_SPHERE_FROM_SILHOUETTES:
      return spec->camera == CF_CAMERA_KIND_COLMAP ? triangulate_sphere(capture, options, err)
                                                   : orthographic_circle(capture, err);
    case CF_GEOMETRY_NORMAL_MAP:
      return read_normal_map(capture, err);
  }
  return CF_EINVAL;
}

/* ---- per pixel ---- */

/* The map's normal at continuous pixel coordinates (u, v): bilinear
 * between the four nearest pixel centres where all four have a normal,
 * else the normal of the pixel (u, v) falls in. */
static int map_normal_at(const cf_image *map, double u, double v, double n[3]) {
  double fx = u - 0.5, fy = v - 0.5;
  int x0 = (int)floor(fx), y0 = (int)floor(fy);
  double tx = fx - x0, ty = fy - y0, corner[4][3], sum[3] = {0.0, 0.0, 0.0};
  int all = map_normal(map, x0, y0, corner[0]) && map_normal(map, x0 + 1, y0, corner[1]) &&
            map_normal(map, x0, y0 + 1, corner[2]) && map_normal(map, x0 + 1, y0 + 1, corner[3]);
  if (!all) return map_normal(map, (int)floor(u), (int)floor(v), n);
  double w[4] = {(1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), (1.0 - tx) * ty, tx * ty};
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 3; ++k) sum[k] += w[c] * corner[c][k];
  double length = cf_norm3(sum);
  if (!(length > 0.0)) return 0;
  for (int k = 0; k < 3; ++k) n[k] = sum[k] / length;
  return 1;
}

static surface_hit orthographic_at(const cf_capture *capture, double u, double v,
                                   surface_point *point) {
  const cf_capture_spec *spec = &capture->spec;
  memset(point->position, 0, sizeof point->position);
  memcpy(point->view, spec->view, sizeof point->view);
  if (spec->geometry == CF_GEOMETRY_NORMAL_MAP) {
    const cf_image *map = &capture->normal_map;
    int x = (int)floor(u), y = (int)floor(v);
    if (x < 0 || y < 0 || x >= map->width || y >= map->height) return SURFACE_MISS;
    surface_hit hit = (surface_hit)capture->map_class[(size_t)y * (size_t)map->width + (size_t)x];
    int centre = fabs(u - (x + 0.5)) == 0.0 && fabs(v - (y + 0.5)) == 0.0;
    if (hit != SURFACE_MISS &&
        !(centre ? map_normal(map, x, y, point->normal) : map_normal_at(map, u, v, point->normal)))
      return SURFACE_MISS;
    return hit;
  }
  const cf_ellipse *circle = &capture->circle;
  if (!cf_sphere_normal_orthographic(circle, u, v, point->normal)) return SURFACE_MISS;
  double r = 0.5 * (circle->a + circle->b);
  double distance = hypot(u - circle->cx, v - circle->cy);
  return r - distance >= spec->margin_px ? SURFACE_HIT : SURFACE_MARGIN;
}

/* COLMAP camera: the first intersection of the ray through pixel
 * coordinates (u, v) with the sphere; the margin measured as the angle
 * between the ray and the sphere's tangent cone, times the focal length. */
static surface_hit perspective_at(const cf_capture *capture, size_t k, double u, double v,
                                  surface_point *point) {
  const capture_view *view = &capture->views[k];
  double uv[2] = {u, v}, ray_camera[3], d[3];
  if (!cf_camera_unproject(view->camera, uv, ray_camera)) return SURFACE_MISS;
  camera_to_world(view->r, ray_camera, d);
  double oc[3] = {view->c[0] - capture->center[0], view->c[1] - capture->center[1],
                  view->c[2] - capture->center[2]};
  double b = cf_dot3(d, oc), distance2 = cf_dot3(oc, oc);
  double r2 = capture->radius * capture->radius;
  double discriminant = b * b - (distance2 - r2);
  if (discriminant < 0.0 || distance2 <= r2) return SURFACE_MISS;
  double t = -b - sqrt(discriminant);
  if (!(t > 0.0)) return SURFACE_MISS;
  for (int c = 0; c < 3; ++c) {
    point->position[c] = view->c[c] + t * d[c];
    point->normal[c] = (point->position[c] - capture->center[c]) / capture->radius;
    point->view[c] = -d[c];
  }
  /* angle of the ray from the direction to the centre, and of the cone */
  double distance = sqrt(distance2);
  double cos_ray = -b / distance;
  double ray_angle = acos(cos_ray > 1.0 ? 1.0 : cos_ray);
  double cone_angle = asin(capture->radius / distance);
  return (cone_angle - ray_angle) * view->focal_px >= capture->spec.margin_px ? SURFACE_HIT
                                                                              : SURFACE_MARGIN;
}

surface_hit capture_surface_at_uv(const cf_capture *capture, size_t k, double u, double v,
                                  surface_point *point) {
  if (capture->spec.camera == CF_CAMERA_KIND_ORTHOGRAPHIC)
    return orthographic_at(capture, u, v, point);
  return perspective_at(capture, k, u, v, point);
}

surface_hit capture_surface_at(const cf_capture *capture, size_t k, int x, int y,
                               surface_point *point) {
  return capture_surface_at_uv(capture, k, x + 0.5, y + 0.5, point);
}

void capture_surface_bounds(const cf_capture *capture, size_t k, int width, int height,
                            int bounds[4]) {
  bounds[0] = 0, bounds[1] = 0, bounds[2] = width, bounds[3] = height;
  if (capture->spec.camera == CF_CAMERA_KIND_ORTHOGRAPHIC) {
    double box[4]; /* the normal map's surface, or the circle's box padded by 2 pixels */
    if (capture->spec.geometry == CF_GEOMETRY_NORMAL_MAP) {
      for (int i = 0; i < 4; ++i) box[i] = capture->map_box[i];
    } else {
      const cf_ellipse *e = &capture->circle;
      double r = fmax(e->a, e->b) + 2.0;
      box[0] = floor(e->cx - r), box[1] = floor(e->cy - r);
      box[2] = ceil(e->cx + r), box[3] = ceil(e->cy + r);
    }
    if (!(box[0] <= box[2] && box[1] <= box[3])) return; /* NaN: keep everything */
    bounds[0] = (int)fmax(0.0, fmin(box[0], width));
    bounds[1] = (int)fmax(0.0, fmin(box[1], height));
    bounds[2] = (int)fmax(bounds[0], fmin(box[2], width));
    bounds[3] = (int)fmax(bounds[1], fmin(box[3], height));
    return;
  }
  if (capture->spec.camera != CF_CAMERA_KIND_COLMAP) return;
  /* project 64 points of the tangent cone's circle; pad by 2 pixels */
  const capture_view *view = &capture->views[k];
  double to_center[3], axis[3];
  for (int c = 0; c < 3; ++c) to_center[c] = capture->center[c] - view->c[c];
  world_to_camera(view->r, to_center, axis);
  double distance = cf_norm3(axis);
  if (!(distance > capture->radius)) return; /* inside the sphere: keep everything */
  double sin_cone = capture->radius / distance, cos_cone = sqrt(1.0 - sin_cone * sin_cone);
  double a[3] = {axis[0] / distance, axis[1] / distance, axis[2] / distance};
  double e1[3] = {fabs(a[0]) < 0.9 ? 1.0 : 0.0, fabs(a[0]) < 0.9 ? 0.0 : 1.0, 0.0};
  double da = cf_dot3(e1, a);
  for (int c = 0; c < 3; ++c) e1[c] -= da * a[c];
  double l1 = cf_norm3(e1);
  for (int c = 0; c < 3; ++c) e1[c] /= l1;
  double e2[3] = {a[1] * e1[2] - a[2] * e1[1], a[2] * e1[0] - a[0] * e1[2],
                  a[0] * e1[1] - a[1] * e1[0]};
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (int i = 0; i < 64; ++i) {
    double phi = 2.0 * CF_PI * i / 64.0;
    double ray[3], uv[2];
    for (int c = 0; c < 3; ++c)
      ray[c] = cos_cone * a[c] + sin_cone * (cos(phi) * e1[c] + sin(phi) * e2[c]);
    if (!cf_camera_project(view->camera, ray, uv)) return; /* behind: keep everything */
    for (int j = 0; j < 2; ++j) {
      lo[j] = fmin(lo[j], uv[j]);
      hi[j] = fmax(hi[j], uv[j]);
    }
  }
  double box[4] = {floor(lo[0]) - 2.0, floor(lo[1]) - 2.0, ceil(hi[0]) + 2.0, ceil(hi[1]) + 2.0};
  bounds[0] = (int)fmax(0.0, fmin(box[0], width));
  bounds[1] = (int)fmax(0.0, fmin(box[1], height));
  bounds[2] = (int)fmax(0.0, fmin(box[2], width));
  bounds[3] = (int)fmax(0.0, fmin(box[3], height));
}
