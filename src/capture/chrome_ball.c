/* Light directions from photos of a chrome ball (chrome_ball.h).
 *
 * A mirror sphere shows a distant light where its normal n halves the angle
 * between the view and the light: the light is the view ray reflected,
 * l = d − 2 (d·n) n, d the ray from the camera. Orthographic: d = (0, 0, −1)
 * and n from the pixel's place on the disc. Perspective: the outline's
 * back-projection is the cone of rays tangent to the ball; the ball is put
 * at distance 1 on its axis with radius sin(half-angle) (a mirror ball's
 * directions do not depend on its scale), and the pixel's ray meets it. */
#include "capture/chrome_ball.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/order_statistics.h"
#include "core/vec.h"
#define CONE_SAMPLES 72 /* points of the outline back-projected */
#define DIFF_STEP 0.01  /* px, central differences */
#define BORDER_PX 1.0   /* an outline closer to the border is clipped */
#define RIM_PX 1.5      /* a blob closer to the outline grazes */
#define RIM_RHO 0.95    /* a centroid farther out grazes: light > 143° off the view */
#define EXTENDED_FRACTION 0.02
/* The ball's background level is this quantile of its grey: a highlight
 * covering up to 1 − it of the ball does not raise it (the median of
 * uw_chrome's balls is 0). */
#define BACKGROUND_QUANTILE 0.9

const char *cf_chrome_warning_text(unsigned bit) {
  switch (bit) {
    case CF_CHROME_GRAZING:
      return "the highlight is at the ball's rim (grazing): the light is behind the ball and its "
             "direction unreliable (see its 1-px sensitivity)";
    case CF_CHROME_EXTENDED:
      return "the highlight covers more than 2% of the ball: an extended source, not a distant "
             "point light; its direction is the area's centre";
    case CF_CHROME_UNSATURATED:
      return "no pixel of the highlight is clipped: it may be a reflection of something other "
             "than the light";
    default:
      return "";
  }
}

void cf_chrome_default_options(cf_chrome_options *o) {
  o->lights = 1;
  o->threshold = 0.5;
  o->min_contrast = 8.0;
  o->speck = 0.01;
  o->clip_level = 0.99;
}

/* ---- small vectors ---- */

/* v reflected about the unit normal n. */
static void reflect(const double v[3], const double n[3], double out[3]) {
  double vn = cf_dot3(v, n);
  for (int k = 0; k < 3; ++k) out[k] = v[k] - 2.0 * vn * n[k];
}


/* ---- the ball as seen ---- */

/* Orthographic: the circle. Perspective: the camera and the unit ball's
 * centre `axis` (distance 1) and radius sin_half. */
typedef struct ball {
  const cf_camera *camera;
  double cx, cy, r;         /* orthographic */
  double axis[3], sin_half; /* perspective */
  double cos_half, half;
} ball;

/* A point of the ellipse at parameter t, pixels. */
static void ellipse_point(const cf_ellipse *e, double t, double p[2]) {
  double c = cos(e->angle), s = sin(e->angle), u = e->a * cos(t), v = e->b * sin(t);
  p[0] = e->cx + c * u - s * v;
  p[1] = e->cy + s * u + c * v;
}

/* Solve the symmetric 3 × 3 system A x = b by Cramer's rule; 0 if singular. */
static int solve3(const double A[9], const double b[3], double x[3]) {
  double det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
               A[2] * (A[3] * A[7] - A[4] * A[6]);
  double scale = fabs(A[0] * A[4] * A[8]) + 1e-300;
  if (!(fabs(det) > 1e-14 * scale)) return 0;
  for (int k = 0; k < 3; ++k) {
    double M[9];
    memcpy(M, A, sizeof M);
    for (int i = 0; i < 3; ++i) M[3 * i + k] = b[i];
    x[k] = (M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
            M[2] * (M[3] * M[7] - M[4] * M[6])) /
           det;
  }
  return 1;
}

/* The cone tangent to the ball: every outline ray r satisfies a·r = cos α,
 * so w = a / cos α solves w·r = 1 in least squares (linear, like Kasa's
 * circle); a = w/|w|, cos α = 1/|w|. */
static int fit_cone(const cf_ellipse *e, const cf_camera *camera, ball *b) {
  double A[9] = {0}, rhs[3] = {0}, w[3];
  int used = 0;
  for (int k = 0; k < CONE_SAMPLES; ++k) {
    double p[2], ray[3];
    ellipse_point(e, 2.0 * CF_PI * k / CONE_SAMPLES, p);
    if (!cf_camera_unproject(camera, p, ray) || !cf_normalize3(ray)) continue;
    for (int i = 0; i < 3; ++i) {
      rhs[i] += ray[i];
      for (int j = 0; j < 3; ++j) A[3 * i + j] += ray[i] * ray[j];
    }
    ++used;
  }
  if (used < CONE_SAMPLES / 2 || !solve3(A, rhs, w)) return 0;
  double length = sqrt(cf_dot3(w, w));
  if (!(length > 1.0) || !isfinite(length)) return 0;
  for (int k = 0; k < 3; ++k) b->axis[k] = w[k] / length;
  b->cos_half = 1.0 / length;
  b->sin_half = sqrt(1.0 - b->cos_half * b->cos_half);
  b->half = acos(b->cos_half);
  return b->axis[2] > 0.0;
}

static int make_ball(const cf_ellipse *e, const cf_camera *camera, ball *b) {
  memset(b, 0, sizeof *b);
  b->camera = camera;
  if (!e || !isfinite(e->cx) || !isfinite(e->cy) || !(e->b > 0.0) || !isfinite(e->a)) return 0;
  b->cx = e->cx;
  b->cy = e->cy;
  b->r = 0.5 * (e->a + e->b);
  if (!camera) return 1;
  return fit_cone(e, camera, b);
}

/* The direction toward the light seen at (x, y), and rho (the pixel's
 * place from the centre, 0, to the rim, 1). 0 if off the ball. */
static int ball_direction(const ball *b, double x, double y, double l[3], double *rho) {
  if (!b->camera) {
    cf_ellipse circle = {b->cx, b->cy, b->r, b->r, 0.0};
    double n[3];
    if (!cf_sphere_normal_orthographic(&circle, x, y, n)) return 0;
    static const double down[3] = {0.0, 0.0, -1.0}; /* the view ray, toward the scene */
    reflect(down, n, l);
    if (rho) *rho = sqrt(n[0] * n[0] + n[1] * n[1]);
    return 1;
  }
  double uv[2] = {x, y}, u[3];
  if (!cf_camera_unproject(b->camera, uv, u) || !cf_normalize3(u)) return 0;
  double along = cf_dot3(u, b->axis);
  double disc = along * along - b->cos_half * b->cos_half; /* |c|² − R² = cos² α */
  if (!(disc >= 0.0) || along <= 0.0) return 0;
  double t = along - sqrt(disc), n[3];
  for (int k = 0; k < 3; ++k) n[k] = (t * u[k] - b->axis[k]) / b->sin_half;
  if (!cf_normalize3(n)) return 0;
  reflect(u, n, l);
  if (rho) *rho = b->half > 0.0 ? cf_angle3(u, b->axis) / b->half : 0.0;
  return 1;
}

int cf_chrome_direction(const cf_ellipse *outline, const cf_camera *camera, double x, double y,
                        double l[3]) {
  ball b;
  return make_ball(outline, camera, &b) && ball_direction(&b, x, y, l, NULL);
}

/* ---- sensitivities: central differences of the same computation ---- */

/* The largest angle (radians per px) that a unit move in the plane of two
 * derivatives (3-vectors) gives: the spectral norm of [d1 d2]. */
static double worst_rate(const double d1[3], const double d2[3]) {
  double a = cf_dot3(d1, d1), b = cf_dot3(d1, d2), c = cf_dot3(d2, d2);
  double mean = 0.5 * (a + c), gap = sqrt(0.25 * (a - c) * (a - c) + b * b);
  return sqrt(mean + gap);
}

/* The derivative of the direction at (x, y) when the highlight (which = 0,
 * 1: x, y), the outline's centre (2, 3) or its radius (4) moves. 0 if a
 * step leaves the ball. */
static int derivative(const cf_ellipse *outline, const ball *base, double x, double y, int which,
                      double d[3]) {
  double lp[3], lm[3];
  int ok = 1;
  for (int side = 0; side < 2 && ok; ++side) {
    double h = side == 0 ? DIFF_STEP : -DIFF_STEP;
    cf_ellipse e = *outline;
    double px = x, py = y;
    if (which == 0) px += h;
    if (which == 1) py += h;
    if (which == 2) e.cx += h;
    if (which == 3) e.cy += h;
    if (which == 4) e.a += h, e.b += h;
    ball b = *base;
    if (which >= 2) ok = make_ball(&e, base->camera, &b);
    ok = ok && ball_direction(&b, px, py, side == 0 ? lp : lm, NULL);
  }
  for (int k = 0; ok && k < 3; ++k) d[k] = (lp[k] - lm[k]) / (2.0 * DIFF_STEP);
  return ok;
}

static void sensitivities(const cf_ellipse *outline, const ball *b, cf_chrome_light *light) {
  double d[5][3];
  int ok[5];
  for (int k = 0; k < 5; ++k)
    ok[k] = derivative(outline, b, light->pixel[0], light->pixel[1], k, d[k]);
  light->per_px_highlight_deg = ok[0] && ok[1] ? CF_DEGREES * worst_rate(d[0], d[1]) : INFINITY;
  light->per_px_center_deg = ok[2] && ok[3] ? CF_DEGREES * worst_rate(d[2], d[3]) : INFINITY;
  light->per_px_radius_deg = ok[4] ? CF_DEGREES * cf_norm3(d[4]) : INFINITY;
}

/* ---- the outline ---- */

static cf_status check_mask_border(const cf_image *mask, const char *name, cf_error *err) {
  for (int y = 0; y < mask->height; ++y)
    for (int x = 0; x < mask->width; ++x) {
      if (y != 0 && y != mask->height - 1 && x != 0 && x != mask->width - 1) continue;
      float v =
          mask->pixels[((size_t)y * (size_t)mask->width + (size_t)x) * (size_t)mask->channels];
      if (isfinite(v) && v != 0.0f)
        return cf_error_set(err, CF_EINVAL,
                            "%s: the ball's mask touches the image border at pixel (%d, %d): the "
                            "ball is clipped and its outline cannot be measured",
                            name, x, y);
    }
  return CF_OK;
}

static cf_status check_outline_border(const cf_ellipse *e, int width, int height, const char *name,
                                      cf_error *err) {
  double c = cos(e->angle), s = sin(e->angle);
  double hx = sqrt(e->a * e->a * c * c + e->b * e->b * s * s);
  double hy = sqrt(e->a * e->a * s * s + e->b * e->b * c * c);
  if (e->cx - hx < BORDER_PX || e->cx + hx > width - BORDER_PX || e->cy - hy < BORDER_PX ||
      e->cy + hy > height - BORDER_PX)
    return cf_error_set(err, CF_EINVAL,
                        "%s: the ball's outline (centre %.1f, %.1f, radius %.1f px) reaches the "
                        "image border (%d x %d): a clipped ball's outline cannot be measured",
                        name, e->cx, e->cy, 0.5 * (e->a + e->b), width, height);
  return CF_OK;
}

/* The per-pixel median of the photos' grey (mean of the first three
 * channels) into a one-channel image. */
static cf_status median_image(const cf_image *photos, size_t count, const char *name, cf_image *out,
                              cf_error *err) {
  cf_status s = cf_image_alloc(out, photos[0].width, photos[0].height, 1, err);
  double *values = s == CF_OK ? malloc(count * sizeof *values) : NULL;
  if (s == CF_OK && !values) s = cf_error_set(err, CF_ENOMEM, "%s: out of memory", name);
  for (size_t i = 0; s == CF_OK && i < count; ++i)
    if (photos[i].width != out->width || photos[i].height != out->height)
      s = cf_error_set(err, CF_EINVAL, "%s: photo %zu is %d x %d, photo 1 is %d x %d", name, i + 1,
                       photos[i].width, photos[i].height, out->width, out->height);
  for (size_t k = 0; s == CF_OK && k < (size_t)out->width * (size_t)out->height; ++k) {
    for (size_t i = 0; i < count; ++i) {
      const cf_image *p = &photos[i];
      int used = p->channels >= 3 ? 3 : 1;
      double sum = 0.0;
      for (int c = 0; c < used; ++c) sum += p->pixels[k * (size_t)p->channels + (size_t)c];
      values[i] = isfinite(sum) ? sum / used : 0.0;
    }
    out->pixels[k] = (float)order_median(values, count);
  }
  free(values);
  return s;
}

cf_status cf_chrome_outline(const cf_image *photos, size_t count, const cf_image *mask,
                            const char *name, cf_ellipse *outline, cf_error *err) {
  if (!mask && (!photos || count == 0))
    return cf_error_set(err, CF_EINVAL, "%s: no photo and no mask for the ball's outline", name);
  cf_status s;
  if (mask) {
    cf_silhouette_hint hint = {mask, {0.0, 0.0}, 0.0};
    if ((s = check_mask_border(mask, name, err)) != CF_OK) return s;
    s = cf_detect_sphere_silhouette(NULL, &hint, name, outline, NULL, 0, NULL, err);
    if (s == CF_OK) s = check_outline_border(outline, mask->width, mask->height, name, err);
    return s;
  }
  cf_image median = {0};
  s = median_image(photos, count, name, &median, err);
  if (s == CF_OK) s = cf_detect_sphere_silhouette(&median, NULL, name, outline, NULL, 0, NULL, err);
  if (s == CF_OK) s = check_outline_border(outline, median.width, median.height, name, err);
  cf_image_free(&median);
  return s;
}

/* ---- highlights ---- */

static double grey_at(const cf_image *p, size_t k) {
  if (p->channels < 3) return p->pixels[k * (size_t)p->channels];
  const float *v = p->pixels + k * (size_t)p->channels;
  return ((double)v[0] + v[1] + v[2]) / 3.0;
}

/* The ball's pixels (-1 off it, else 0) and their grey's peak and
 * background level (BACKGROUND_QUANTILE). */
static cf_status ball_pixels(const cf_image *photo, const ball *b, const char *name, int *label,
                             cf_chrome_result *result, cf_error *err) {
  size_t n = (size_t)photo->width * (size_t)photo->height, on = 0;
  double *values = malloc(n * sizeof *values);
  if (!values) return cf_error_set(err, CF_ENOMEM, "%s: out of memory", name);
  result->peak = 0.0;
  for (size_t k = 0; k < n; ++k) {
    double l[3], x = (double)(k % (size_t)photo->width) + 0.5,
                 y = (double)(k / (size_t)photo->width) + 0.5;
    label[k] = ball_direction(b, x, y, l, NULL) ? 0 : -1;
    if (label[k] < 0) continue;
    double g = grey_at(photo, k);
    if (!isfinite(g)) g = 0.0;
    values[on++] = g;
    if (g > result->peak) result->peak = g;
  }
  result->ball_pixels = on;
  result->background =
      on ? order_kth_smallest(values, on, (size_t)(BACKGROUND_QUANTILE * (double)(on - 1))) : 0.0;
  free(values);
  if (on < 20)
    return cf_error_set(err, CF_EINVAL, "%s: the ball covers %zu pixels of the photo", name, on);
  return CF_OK;
}

typedef struct blob {
  double weight, sx, sy, peak, rho_max;
  size_t area, clipped;
} blob;

/* Label the 8-connected blobs of ball pixels at or above `threshold`
 * (label 1, 2, ...) and sum each one's weight and moments. */
static cf_status find_blobs(const cf_image *photo, const ball *b, double threshold, double clip,
                            int *label, size_t *stack, blob *blobs, size_t max_blobs, size_t *count,
                            const char *name, cf_error *err) {
  const int w = photo->width, h = photo->height;
  *count = 0;
  for (size_t seed = 0; seed < (size_t)w * (size_t)h; ++seed) {
    if (label[seed] != 0 || !(grey_at(photo, seed) >= threshold)) continue; /* NaN too */
    if (*count == max_blobs)
      return cf_error_set(err, CF_EINVAL, "%s: more than %zu bright blobs on the ball", name,
                          max_blobs);
    blob *B = &blobs[(*count)++];
    memset(B, 0, sizeof *B);
    size_t top = 0;
    stack[top++] = seed;
    label[seed] = (int)*count;
    while (top > 0) {
      size_t k = stack[--top];
      int x = (int)(k % (size_t)w), y = (int)(k / (size_t)w);
      /* value − threshold, and a little more so that a blob all at the
       * threshold still has a centre */
      double g = grey_at(photo, k), weight = g - threshold + 1e-3 * threshold, rho = 0.0, l[3];
      ball_direction(b, x + 0.5, y + 0.5, l, &rho);
      B->weight += weight;
      B->sx += weight * (x + 0.5);
      B->sy += weight * (y + 0.5);
      B->area++;
      B->clipped += g >= clip;
      if (g > B->peak) B->peak = g;
      if (rho > B->rho_max) B->rho_max = rho;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
          size_t j = (size_t)yy * (size_t)w + (size_t)xx;
          if (label[j] != 0 || !(grey_at(photo, j) >= threshold)) continue;
          label[j] = (int)*count;
          stack[top++] = j;
        }
    }
  }
  return CF_OK;
}

static int heavier(const void *a, const void *b) {
  double wa = ((const blob *)a)->weight, wb = ((const blob *)b)->weight;
  return (wa < wb) - (wa > wb);
}

/* Blobs to lights: specks dropped, the count checked, each direction and
 * its sensitivities and warnings. */
static cf_status blobs_to_lights(blob *blobs, size_t count, const cf_ellipse *outline,
                                 const ball *b, const cf_chrome_options *o, const char *name,
                                 cf_chrome_result *result, cf_error *err) {
  qsort(blobs, count, sizeof *blobs, heavier);
  size_t kept = 0;
  while (kept < count && blobs[kept].weight >= o->speck * blobs[0].weight) ++kept;
  result->specks = count - kept;
  if (kept != (size_t)o->lights) {
    char where[256] = "";
    for (size_t k = 0, used = 0; k < kept && k < 4 && used < sizeof where - 40; ++k)
      used += (size_t)snprintf(where + used, sizeof where - used, "%s(%.1f, %.1f)", k ? ", " : "",
                               blobs[k].sx / blobs[k].weight, blobs[k].sy / blobs[k].weight);
    return cf_error_set(err, CF_EINVAL,
                        "%s: %zu highlights on the ball (%s%s) where %d %s expected: a photo must "
                        "show exactly the lights declared",
                        name, kept, where, kept > 4 ? ", ..." : "", o->lights,
                        o->lights == 1 ? "was" : "were");
  }
  result->count = kept;
  double r_px = 0.5 * (outline->a + outline->b);
  for (size_t k = 0; k < kept; ++k) {
    cf_chrome_light *L = &result->lights[k];
    const blob *B = &blobs[k];
    memset(L, 0, sizeof *L);
    L->pixel[0] = B->sx / B->weight;
    L->pixel[1] = B->sy / B->weight;
    L->area = B->area;
    L->clipped = B->clipped;
    L->peak = B->peak;
    if (!ball_direction(b, L->pixel[0], L->pixel[1], L->direction, &L->rho))
      return cf_error_set(err, CF_EINVAL, "%s: highlight %zu's centre (%.2f, %.2f) is off the ball",
                          name, k + 1, L->pixel[0], L->pixel[1]);
    double view[3] = {0.0, 0.0, b->camera ? -1.0 : 1.0}; /* toward the camera */
    if (b->camera) {
      double uv[2] = {L->pixel[0], L->pixel[1]};
      if (cf_camera_unproject(b->camera, uv, view) && cf_normalize3(view))
        for (int c = 0; c < 3; ++c) view[c] = -view[c];
    }
    L->view_angle_deg = CF_DEGREES * cf_angle3(L->direction, view);
    sensitivities(outline, b, L);
    if ((1.0 - B->rho_max) * r_px < RIM_PX || L->rho > RIM_RHO) L->warnings |= CF_CHROME_GRAZING;
    if ((double)B->area > EXTENDED_FRACTION * (double)result->ball_pixels)
      L->warnings |= CF_CHROME_EXTENDED;
    if (B->clipped == 0) L->warnings |= CF_CHROME_UNSATURATED;
  }
  return CF_OK;
}

/* The error for a ball whose brightest value is not min_contrast times its
 * background. When the pixels a highlight would take (threshold × the
 * brightest value) cover more of the ball than a highlight can without
 * raising the background, that is what is wrong: the ball is bright
 * over too much of it. */
static cf_status no_highlight(const cf_image *photo, const int *label, const cf_chrome_options *o,
                              const char *name, const cf_chrome_result *r, cf_error *err) {
  const size_t n = (size_t)photo->width * (size_t)photo->height;
  size_t bright = 0;
  for (size_t k = 0; k < n; ++k)
    bright += label[k] == 0 && grey_at(photo, k) >= o->threshold * r->peak;
  const double share = (double)bright / (double)r->ball_pixels, most = 1.0 - BACKGROUND_QUANTILE;
  if (r->peak > 0.0 && share > most)
    return cf_error_set(err, CF_EINVAL,
                        "%s: no highlight on the ball: its bright region (at least %g times its "
                        "brightest value %.3g) covers %.0f %% of the ball, more than the %.0f %% "
                        "a chrome ball's highlight can cover (an overexposed photo, or a ball "
                        "that is not a mirror?); take a shorter exposure, or photograph a "
                        "mirror ball",
                        name, o->threshold, r->peak, 100.0 * share, 100.0 * most);
  return cf_error_set(err, CF_EINVAL,
                      "%s: no highlight on the ball: its brightest value %.3g is not %g times its "
                      "background (%.0fth percentile) %.3g (is the light in the photo, and the "
                      "ball where the outline says?)",
                      name, r->peak, o->min_contrast, 100.0 * BACKGROUND_QUANTILE, r->background);
}

static cf_status check_options(const cf_chrome_options *o, const char *name, cf_error *err) {
  if (o->lights < 1 || o->lights > CF_CHROME_MAX_LIGHTS)
    return cf_error_set(err, CF_EINVAL, "%s: %d lights asked for; 1 to %d can be found", name,
                        o->lights, CF_CHROME_MAX_LIGHTS);
  if (!(o->threshold > 0.0 && o->threshold < 1.0) || !(o->min_contrast >= 1.0) ||
      !(o->speck >= 0.0 && o->speck < 1.0) || !(o->clip_level > 0.0))
    return cf_error_set(err, CF_EINVAL,
                        "%s: chrome-ball options out of range (threshold %g, contrast %g, speck "
                        "%g, clip level %g)",
                        name, o->threshold, o->min_contrast, o->speck, o->clip_level);
  return CF_OK;
}

cf_status cf_chrome_lights(const cf_image *photo, const cf_ellipse *outline,
                           const cf_camera *camera, const cf_chrome_options *options,
                           const char *name, cf_chrome_result *result, cf_error *err) {
  cf_chrome_options o;
  if (options)
    o = *options;
  else
    cf_chrome_default_options(&o);
  memset(result, 0, sizeof *result);
  name = name && *name ? name : "(unnamed photo)";
  cf_status s = check_options(&o, name, err);
  if (s != CF_OK) return s;
  if (!photo || !photo->pixels || photo->width <= 0 || photo->height <= 0)
    return cf_error_set(err, CF_EINVAL, "%s: no photo", name);
  ball b;
  if (!make_ball(outline, camera, &b))
    return cf_error_set(err, CF_EINVAL, "%s: the ball's outline cannot be used with this camera",
                        name);
  if ((s = check_outline_border(outline, photo->width, photo->height, name, err)) != CF_OK)
    return s;
  size_t n = (size_t)photo->width * (size_t)photo->height;
  enum { MAX_BLOBS = 4096 };
  int *label = malloc(n * sizeof *label);
  size_t *stack = malloc(n * sizeof *stack);
  blob *blobs = malloc(MAX_BLOBS * sizeof *blobs);
  size_t count = 0;
  s = label && stack && blobs ? CF_OK : cf_error_set(err, CF_ENOMEM, "%s: out of memory", name);
  if (s == CF_OK) s = ball_pixels(photo, &b, name, label, result, err);
  if (s == CF_OK && !(result->peak > 0.0 && result->peak >= o.min_contrast * result->background))
    s = no_highlight(photo, label, &o, name, result, err);
  if (s == CF_OK)
    s = find_blobs(photo, &b, o.threshold * result->peak, o.clip_level, label, stack, blobs,
                   MAX_BLOBS, &count, name, err);
  if (s == CF_OK) s = blobs_to_lights(blobs, count, outline, &b, &o, name, result, err);
  free(label);
  free(stack);
  free(blobs);
  return s;
}
