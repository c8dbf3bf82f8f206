/* The sphere's silhouette in one image (cf_detect_sphere_silhouette), on
 * images rendered here: a shaded sphere (Lambert plus ambient) seen
 * orthographically or through a pinhole, on a flat or a textured
 * background, antialiased by 8 × 8 supersampling; with and without a
 * mask. Positions are COLMAP's: pixel (x, y) covers [x, x+1) × [y, y+1). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture/sphere_silhouette.h"
#include "core/rng.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define SS 8 /* supersampling per axis */
#define W 640
#define H 480
#define MAX_POINTS 4096

/* What is rendered: an orthographic disc (focal = 0) or a pinhole view of
 * a sphere centred at `center` (camera frame, x right, y down, z forward). */
typedef struct sphere_view {
  double focal, cx, cy;     /* pinhole; focal 0: orthographic */
  double center[3], radius; /* pinhole: world units; orthographic: center[0..1] and radius in px */
} sphere_view;

static const double kLight[3] = {-0.3, -0.5, 0.8}; /* camera frame, normalised below */

/* Radiance of the sphere at continuous pixel (u, v), or -1 if the ray
 * misses it. */
static double shade(const sphere_view *s, double u, double v) {
  double n[3];
  if (s->focal == 0.0) {
    double dx = (u - s->center[0]) / s->radius, dy = (v - s->center[1]) / s->radius;
    double q = dx * dx + dy * dy;
    if (q >= 1.0) return -1.0;
    n[0] = dx;
    n[1] = dy;
    n[2] = -sqrt(1.0 - q); /* toward the camera (z forward) */
  } else {
    double d[3] = {(u - s->cx) / s->focal, (v - s->cy) / s->focal, 1.0};
    double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double dc = d[0] * s->center[0] + d[1] * s->center[1] + d[2] * s->center[2];
    double cc =
        s->center[0] * s->center[0] + s->center[1] * s->center[1] + s->center[2] * s->center[2];
    double disc = dc * dc - dd * (cc - s->radius * s->radius);
    if (disc <= 0.0) return -1.0;
    double t = (dc - sqrt(disc)) / dd;
    for (int k = 0; k < 3; ++k) n[k] = (t * d[k] - s->center[k]) / s->radius;
  }
  double ln = sqrt(kLight[0] * kLight[0] + kLight[1] * kLight[1] + kLight[2] * kLight[2]);
  /* light toward the camera side: l = −kLight in the z-forward frame */
  double cosine = -(n[0] * kLight[0] + n[1] * kLight[1] + n[2] * kLight[2]) / ln;
  return 0.6 * (0.25 + (cosine > 0.0 ? cosine : 0.0));
}

/* Background radiance at (u, v): flat (checker 0) or random checker
 * squares of `checker` px with values in [0.05, 0.6]. */
typedef struct background {
  int checker;
  double flat;
  double cells[64][64];
} background;

static double background_at(const background *b, double u, double v) {
  if (b->checker == 0) return b->flat;
  int i = (int)floor(u / b->checker) & 63, j = (int)floor(v / b->checker) & 63;
  return b->cells[j][i];
}

static float *render(const sphere_view *s, const background *b, double noise, double gain,
                     cf_rng *rng) {
  float *pixels = malloc(sizeof(float) * W * H * 3);
  if (!pixels) return NULL;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      double sum = 0.0;
      for (int j = 0; j < SS; ++j)
        for (int i = 0; i < SS; ++i) {
          double u = x + (i + 0.5) / SS, v = y + (j + 0.5) / SS;
          double value = shade(s, u, v);
          sum += value >= 0.0 ? value : background_at(b, u, v);
        }
      double value = sum / (SS * SS);
      if (noise > 0.0) value += noise * (cf_rng_uniform(rng) - 0.5) * 2.0;
      float *p = pixels + 3 * (y * W + x);
      p[0] = (float)(gain * value * 1.1);
      p[1] = (float)(gain * value);
      p[2] = (float)(gain * value * 0.8);
    }
  return pixels;
}

/* The mask of the sphere: pixels whose centre it covers. */
static float *render_mask(const sphere_view *s) {
  float *pixels = malloc(sizeof(float) * W * H);
  if (!pixels) return NULL;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) pixels[y * W + x] = shade(s, x + 0.5, y + 0.5) >= 0.0 ? 1.0f : 0.0f;
  return pixels;
}

/* The exact silhouette as an ellipse: orthographic, the circle; pinhole,
 * the conic of rays d = (x, y, 1) tangent to the sphere,
 * (c·d)² − (|c|² − R²)|d|² = 0 (Hartley & Zisserman 2004, §8.3). */
static cf_ellipse true_outline(const sphere_view *s) {
  cf_ellipse e = {0, 0, 0, 0, 0};
  if (s->focal == 0.0) {
    e.cx = s->center[0];
    e.cy = s->center[1];
    e.a = e.b = s->radius;
    return e;
  }
  const double *c = s->center;
  double k = c[0] * c[0] + c[1] * c[1] + c[2] * c[2] - s->radius * s->radius;
  double m[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[i][j] = c[i] * c[j] - (i == j ? k : 0.0);
  /* centre: m2 x0 = −m[0..1][2] */
  double det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
  double x0 = (-m[0][2] * m[1][1] + m[1][2] * m[0][1]) / det;
  double y0 = (-m[1][2] * m[0][0] + m[0][2] * m[1][0]) / det;
  double f0 = m[0][0] * x0 * x0 + 2 * m[0][1] * x0 * y0 + m[1][1] * y0 * y0 + 2 * m[0][2] * x0 +
              2 * m[1][2] * y0 + m[2][2];
  /* (x − x0)ᵀ (−m2 / f0) (x − x0) = 1 */
  double p = -m[0][0] / f0, q = -m[0][1] / f0, r = -m[1][1] / f0;
  double mean = 0.5 * (p + r), diff = sqrt(0.25 * (p - r) * (p - r) + q * q);
  double lmin = mean - diff, lmax = mean + diff;
  e.cx = s->focal * x0 + s->cx;
  e.cy = s->focal * y0 + s->cy;
  e.a = s->focal / sqrt(lmin);
  e.b = s->focal / sqrt(lmax);
  /* eigenvector of lmin: (q, lmin − p) or (lmin − r, q) */
  double vx = q, vy = lmin - p;
  if (fabs(vx) + fabs(vy) < 1e-300) {
    vx = lmin - r;
    vy = q;
  }
  e.angle = atan(vy / vx);
  return e;
}

/* Distance from (x, y) to the ellipse, to first order in its eccentricity. */
static double outline_distance(const cf_ellipse *e, double x, double y) {
  double c = cos(e->angle), s = sin(e->angle);
  double dx = x - e->cx, dy = y - e->cy;
  double u = (c * dx + s * dy) / e->a, v = (-s * dx + c * dy) / e->b;
  double rho = sqrt(u * u + v * v);
  return fabs(hypot(dx, dy) * (1.0 - 1.0 / rho));
}

static double angle_difference(double a, double b) {
  double d = fmod(fabs(a - b), M_PI);
  return d > 0.5 * M_PI ? M_PI - d : d;
}

/* Detect, compare with the true outline, print. Tolerances in px. */
static void check_detection(const char *what, const cf_image *image, const cf_silhouette_hint *hint,
                            const sphere_view *s, double center_tol, double axis_tol,
                            double rms_tol) {
  static double boundary[2 * MAX_POINTS];
  cf_ellipse found;
  size_t count = 0;
  cf_error err = {0};
  cf_status st =
      cf_detect_sphere_silhouette(image, hint, what, &found, boundary, MAX_POINTS, &count, &err);
  CHECK(st == CF_OK, "%s: %s", what, err.message);
  if (st != CF_OK) return;
  cf_ellipse truth = true_outline(s);
  double dc = hypot(found.cx - truth.cx, found.cy - truth.cy);
  double da = fabs(found.a - truth.a), db = fabs(found.b - truth.b);
  double sum2 = 0.0, worst = 0.0;
  for (size_t k = 0; k < count; ++k) {
    double d = outline_distance(&truth, boundary[2 * k], boundary[2 * k + 1]);
    sum2 += d * d;
    if (d > worst) worst = d;
  }
  double rms = count ? sqrt(sum2 / (double)count) : INFINITY;
  printf(
      "%-44s centre (%.3f, %.3f) vs (%.3f, %.3f): error %.3f px; axes %.3f, %.3f vs %.3f, "
      "%.3f: errors %.3f, %.3f px; %zu points, RMS %.3f px (max %.3f) off the true outline\n",
      what, found.cx, found.cy, truth.cx, truth.cy, dc, found.a, found.b, truth.a, truth.b, da, db,
      count, rms, worst);
  CHECK(dc < center_tol, "%s: centre error %.3f px > %.3f", what, dc, center_tol);
  CHECK(da < axis_tol && db < axis_tol, "%s: axis errors %.3f, %.3f px > %.3f", what, da, db,
        axis_tol);
  CHECK(count >= 100, "%s: only %zu boundary points", what, count);
  CHECK(rms < rms_tol, "%s: boundary RMS %.3f px > %.3f", what, rms, rms_tol);
  CHECK(found.a >= found.b && found.b > 0, "%s: axes %g %g", what, found.a, found.b);
  if (truth.a - truth.b > 1.0) { /* a visibly elongated outline: its orientation */
    double dtheta = angle_difference(found.angle, truth.angle) * 180.0 / M_PI;
    printf("%-44s angle %.2f° vs %.2f°: error %.2f°\n", what, found.angle * 180.0 / M_PI,
           truth.angle * 180.0 / M_PI, dtheta);
    CHECK(dtheta < 3.0, "%s: angle error %.2f°", what, dtheta);
  }
}

static void init_checker(background *b, int size, cf_rng *rng) {
  b->checker = size;
  b->flat = 0.0;
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 64; ++i) b->cells[j][i] = cf_rng_range(rng, 0.05, 0.6);
}

int main(void) {
  cf_rng rng = cf_rng_seed(77);
  static background flat = {0, 0.05, {{0}}}, textured;
  init_checker(&textured, 12, &rng);

  sphere_view disc = {0.0, 0.0, 0.0, {250.3, 218.7, 0.0}, 80.0};
  /* a sphere 25° off the axis of a pinhole camera: an ellipse */
  sphere_view off_axis = {500.0, 320.0, 240.0, {1.1, 0.55, 2.6}, 0.45};
  cf_ellipse truth = true_outline(&off_axis);
  printf("off-axis sphere: outline centre (%.3f, %.3f), axes %.3f, %.3f px, angle %.2f°\n",
         truth.cx, truth.cy, truth.a, truth.b, truth.angle * 180.0 / M_PI);
  CHECK(truth.a - truth.b > 5.0, "the off-axis outline should be visibly elongated");

  /* (a) flat background, with a little noise, without a hint */
  float *pixels = render(&disc, &flat, 0.005, 1.0, &rng);
  cf_image image = {W, H, 3, pixels};
  check_detection("disc, flat background:", &image, NULL, &disc, 0.5, 0.5, 0.3);
  free(pixels);

  /* the same, very dim and very bright: the percentile normalisation */
  for (int g = 0; g < 2; ++g) {
    cf_rng same = cf_rng_seed(5);
    pixels = render(&disc, &flat, 0.005, g ? 1000.0 : 1e-4, &same);
    image.pixels = pixels;
    check_detection(g ? "disc, flat background, gain 1000:" : "disc, flat background, gain 1e-4:",
                    &image, NULL, &disc, 0.5, 0.5, 0.3);
    free(pixels);
  }

  /* (b) textured background: random checker of contrast like the disc's */
  pixels = render(&disc, &textured, 0.01, 1.0, &rng);
  image.pixels = pixels;
  check_detection("disc, textured background:", &image, NULL, &disc, 1.5, 1.5, 1.0);
  cf_silhouette_hint hint = {NULL, {256.0, 210.0}, 70.0}; /* a rough hint */
  check_detection("disc, textured background, hint:", &image, &hint, &disc, 1.5, 1.5, 1.0);

  /* (c) with a mask: the image is not looked at */
  float *mask_pixels = render_mask(&disc);
  cf_image mask = {W, H, 1, mask_pixels};
  cf_silhouette_hint with_mask = {&mask, {0, 0}, 0};
  check_detection("disc, mask:", &image, &with_mask, &disc, 0.15, 0.15, 0.6);
  check_detection("disc, mask, no image:", NULL, &with_mask, &disc, 0.15, 0.15, 0.6);
  free(mask_pixels);
  free(pixels);

  /* the off-axis sphere: flat, textured, mask */
  pixels = render(&off_axis, &flat, 0.005, 1.0, &rng);
  image.pixels = pixels;
  check_detection("off-axis sphere, flat background:", &image, NULL, &off_axis, 0.5, 0.5, 0.3);
  free(pixels);
  pixels = render(&off_axis, &textured, 0.01, 1.0, &rng);
  image.pixels = pixels;
  check_detection("off-axis sphere, textured background:", &image, NULL, &off_axis, 1.5, 1.5, 1.0);
  mask_pixels = render_mask(&off_axis);
  mask.pixels = mask_pixels;
  check_detection("off-axis sphere, mask:", &image, &with_mask, &off_axis, 0.15, 0.15, 0.6);
  free(mask_pixels);
  free(pixels);

  /* the +0.5 convention: a disc centred on pixel (100, 80), i.e. at
   * continuous (100.5, 80.5), is found there, not at (100, 80) */
  sphere_view centred = {0.0, 0.0, 0.0, {100.5, 80.5, 0.0}, 30.0};
  pixels = render(&centred, &flat, 0.0, 1.0, &rng);
  image.pixels = pixels;
  mask_pixels = render_mask(&centred);
  mask.pixels = mask_pixels;
  const cf_silhouette_hint *hints[2] = {NULL, &with_mask};
  for (int k = 0; k < 2; ++k) {
    cf_ellipse found;
    size_t count = 0;
    double boundary[2 * 64];
    cf_error err = {0};
    cf_status st = cf_detect_sphere_silhouette(&image, hints[k], "centred", &found, boundary, 64,
                                               &count, &err);
    CHECK(st == CF_OK, "centred disc: %s", err.message);
    printf("disc at (100.5, 80.5) r 30, %s: found (%.4f, %.4f) r %.4f, %.4f; %zu points\n",
           k ? "mask" : "image", found.cx, found.cy, found.a, found.b, count);
    double tol = k ? 1e-3 : 0.1; /* the mask is symmetric about the pixel centre */
    CHECK(fabs(found.cx - 100.5) < tol && fabs(found.cy - 80.5) < tol,
          "centred disc (%s): (%.4f, %.4f), expected (100.5, 80.5)", k ? "mask" : "image", found.cx,
          found.cy);
    CHECK(count == 64, "max_points 64 gave %zu points", count);
    /* sorted by angle around the centre, spread around the outline */
    double previous = -INFINITY, largest_gap = 0.0, first = 0.0, mean_x = 0.0, mean_y = 0.0;
    int sorted = 1;
    for (size_t i = 0; i < count; ++i) {
      double angle = atan2(boundary[2 * i + 1] - found.cy, boundary[2 * i] - found.cx);
      if (i == 0) first = angle;
      if (angle < previous) sorted = 0;
      if (i > 0 && angle - previous > largest_gap) largest_gap = angle - previous;
      previous = angle;
      mean_x += boundary[2 * i] / (double)count;
      mean_y += boundary[2 * i + 1] / (double)count;
    }
    if (count > 0 && first + 2.0 * M_PI - previous > largest_gap)
      largest_gap = first + 2.0 * M_PI - previous;
    printf("  the %zu points: mean (%.3f, %.3f), largest angular gap %.1f°\n", count, mean_x,
           mean_y, largest_gap * 180.0 / M_PI);
    CHECK(sorted, "points not sorted by angle around the centre");
    CHECK(largest_gap < (k ? 0.2 : 2.0), "points spread around the outline: gap %.1f°",
          largest_gap * 180.0 / M_PI);
    if (k) /* the mask's points are symmetric about the centre */
      CHECK(fabs(mean_x - 100.5) < 0.05 && fabs(mean_y - 80.5) < 0.05, "mean (%.3f, %.3f)", mean_x,
            mean_y);
  }
  free(mask_pixels);

  /* bad arguments */
  {
    cf_ellipse found;
    size_t count = 0;
    cf_error err = {0};
    cf_image small_mask = {W / 2, H / 2, 1, pixels};
    cf_silhouette_hint bad = {&small_mask, {0, 0}, 0};
    CHECK(cf_detect_sphere_silhouette(&image, &bad, "sizes.png", &found, NULL, 0, &count, &err) ==
              CF_EINVAL,
          "mask of another size");
    printf("mask of another size: %s\n", err.message);
    CHECK(strstr(err.message, "sizes.png") && strstr(err.message, "mask"), "message: %s",
          err.message);
    cf_image no_pixels = {W, H, 3, NULL};
    CHECK(cf_detect_sphere_silhouette(&no_pixels, NULL, "empty.png", &found, NULL, 0, &count,
                                      &err) == CF_EINVAL,
          "no pixels");
    CHECK(strstr(err.message, "empty.png") != NULL, "message: %s", err.message);
    /* an empty mask */
    float *zeros = calloc((size_t)W * H, sizeof(float));
    cf_image empty_mask = {W, H, 1, zeros};
    cf_silhouette_hint empty = {&empty_mask, {0, 0}, 0};
    CHECK(zeros && cf_detect_sphere_silhouette(&image, &empty, "blank_mask.png", &found, NULL, 0,
                                               &count, &err) == CF_ENOTFOUND,
          "empty mask");
    printf("empty mask: %s\n", err.message);
    CHECK(strstr(err.message, "blank_mask.png") && strstr(err.message, "empty"), "message: %s",
          err.message);
    /* a black image */
    cf_image black = {W, H, 1, zeros};
    CHECK(cf_detect_sphere_silhouette(&black, NULL, "black.png", &found, NULL, 0, &count, &err) ==
              CF_ENOTFOUND,
          "black image");
    printf("black image: %s\n", err.message);
    CHECK(strstr(err.message, "black.png") != NULL, "message: %s", err.message);
    /* too small to hold a sphere */
    cf_image tiny = {4, 4, 1, zeros};
    CHECK(cf_detect_sphere_silhouette(&tiny, NULL, "tiny.png", &found, NULL, 0, &count, &err) ==
              CF_ENOTFOUND,
          "tiny image");
    printf("tiny image: %s\n", err.message);
    CHECK(strstr(err.message, "tiny.png") && strstr(err.message, "too small"), "message: %s",
          err.message);
    free(zeros);
  }

  free(pixels);

  /* non-finite pixels in the background count as 0 and do not disturb it */
  pixels = render(&disc, &flat, 0.005, 1.0, &rng);
  CHECK(pixels != NULL, "malloc");
  if (pixels) {
    for (int y = 20; y < 60; ++y)
      for (int x = 20; x < 60; ++x)
        pixels[3 * (y * W + x) + (x + y) % 3] = (x % 2) ? NAN : INFINITY;
    image.pixels = pixels;
    check_detection("disc, NaN and Inf in the background:", &image, NULL, &disc, 0.5, 0.5, 0.3);
    free(pixels);
  }

  /* no sphere: uniform noise, with and without a hint */
  pixels = malloc(sizeof(float) * W * H * 3);
  CHECK(pixels != NULL, "malloc");
  if (pixels) {
    for (int k = 0; k < W * H * 3; ++k) pixels[k] = (float)cf_rng_uniform(&rng);
    image.pixels = pixels;
    for (int k = 0; k < 2; ++k) {
      cf_ellipse found;
      size_t count = 7;
      cf_error err = {0};
      cf_silhouette_hint noise_hint = {NULL, {320.0, 240.0}, 80.0};
      cf_status st = cf_detect_sphere_silhouette(&image, k ? &noise_hint : NULL, "noise.exr",
                                                 &found, NULL, 0, &count, &err);
      printf("uniform noise%s: %s (%s)\n", k ? ", hint" : "", cf_status_name(st), err.message);
      CHECK(st == CF_ENOTFOUND, "noise%s: status %s", k ? " with hint" : "", cf_status_name(st));
      CHECK(strstr(err.message, "noise.exr") != NULL, "message names the image: %s", err.message);
      CHECK(count == 0, "no points on failure: %zu", count);
    }
    free(pixels);
  }
  return check_finish("test_sphere_detect");
}
