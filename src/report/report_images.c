/* Each image's photo, its re-rendering with the fitted parameters and the
 * signed residual heat map, cropped around the sphere (report_internal.h). */
#include <math.h>
#include <pthread.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/image.h"
#include "core/order_statistics.h"
#include "core/parallel.h"
#include "report_internal.h"

enum { CROP_MARGIN = 8 };

/* The residual colour scale, in linear RGB: blue at −1, white at 0, red at
 * +1 (of CF_REPORT_SIGMA_RANGE σ); the marks' colours. */
static const float cold[3] = {0.05f, 0.15f, 0.75f}, hot[3] = {0.75f, 0.02f, 0.03f};
static const float censored_colour[3] = {1.0f, 0.0f, 1.0f},
                   rejected_colour[3] = {0.0f, 0.45f, 0.0f};
static const float background[3] = {0.12f, 0.12f, 0.12f};

void report_residual_colour(double r, float rgb[3]) {
  double t = r / CF_REPORT_SIGMA_RANGE;
  t = t < -1.0 ? -1.0 : t > 1.0 ? 1.0 : t; /* the scale's ends (display only) */
  const float *end = t < 0.0 ? cold : hot;
  double a = fabs(t);
  for (int c = 0; c < 3; ++c) rgb[c] = (float)((1.0 - a) * 1.0 + a * end[c]);
}

/* The display's white: the 99.5th percentile of the image's measured
 * values (over its observations and channels). */
static double white_point(const report_data *d, size_t k) {
  size_t n = 3 * d->observations[k], m = 0;
  double *values = n ? malloc(n * sizeof *values) : NULL;
  if (!values) return 1.0;
  for (size_t i = d->first[k]; i < d->last[k]; ++i)
    if (d->obs->image[i] == k)
      for (int c = 0; c < 3; ++c) values[m++] = (float)d->obs->rgb[3 * i + c];
  double white = m ? order_kth_smallest(values, m, (size_t)(0.995 * (double)(m - 1))) : 1.0;
  free(values);
  return white > 0.0 ? white : 1.0;
}

/* ---- the 8-bit sRGB encoding ----
 * The PNG writer stores a value v as round(255 v) (clamped; image.h), so
 * a linear value x becomes the code q(x) = round(255 srgb(x)), x clamped to
 * [0, 1]: a non-decreasing step function of x, found once at its 255 steps
 * (a bisection over the floats, 32 steps each) and then read per pixel
 * from the table, without pow: every float in [0, 1] gives the code
 * cf_linear_to_srgb gives (checked over all of them once, and at every
 * step by test_report_srgb). */

/* The code the writer stores for linear value x (the direct way). */
static int srgb_code(float x) {
  const float v = (float)cf_linear_to_srgb(fmin(1.0, fmax(0.0, x)));
  const float scaled = v * 255.0f;
  return !(scaled > 0.0f) ? 0 : scaled >= 255.0f ? 255 : (int)roundf(scaled);
}

static float float_of(uint32_t bits) {
  float x;
  memcpy(&x, &bits, sizeof x);
  return x;
}

void report_srgb_init(report_srgb *t) {
  uint32_t one;
  const float unit = 1.0f;
  memcpy(&one, &unit, sizeof one);
  t->threshold[0] = 0.0f;
  for (int q = 1; q < 256; ++q) { /* the least x in (0, 1] with code q or above */
    uint32_t lo = 0, hi = one;      /* code(lo) < q <= code(hi) */
    while (hi - lo > 1) {
      uint32_t mid = lo + (hi - lo) / 2;
      if (srgb_code(float_of(mid)) >= q)
        hi = mid;
      else
        lo = mid;
    }
    t->threshold[q] = float_of(hi);
  }
  int q = 0;
  for (int b = 0; b <= REPORT_SRGB_BINS; ++b) {
    const float x = (float)b / (float)REPORT_SRGB_BINS;
    while (q < 255 && t->threshold[q + 1] <= x) ++q;
    t->start[b] = (uint8_t)q;
  }
}

int report_srgb_encode(const report_srgb *t, float x) {
  if (!(x > 0.0f)) return 0; /* NaN too, as fmax(0, NaN) gives */
  if (x >= 1.0f) return 255;
  int q = t->start[(int)(x * (float)REPORT_SRGB_BINS)];
  while (q < 255 && t->threshold[q + 1] <= x) ++q; /* at most a step or two past the bin's */
  return q;
}

static cf_status write_srgb(const report_data *d, const char *dir, const char *name,
                            cf_image *picture, cf_error *err) {
  size_t n = 3 * (size_t)picture->width * (size_t)picture->height;
  for (size_t i = 0; i < n; ++i)
    picture->pixels[i] = (float)report_srgb_encode(&d->srgb, picture->pixels[i]) / 255.0f;
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  return cf_image_write(path, picture, 8, err);
}

cf_status report_image(const report_data *d, size_t k, const char *dir, char names[3][64],
                       cf_error *err) {
  const cf_observations *o = d->obs;
  const cf_capture_image *info = cf_capture_image_at(d->capture, k);
  int box[4] = {info->width, info->height, 0, 0};
  for (size_t i = d->first[k]; i < d->last[k]; ++i) {
    if (o->image[i] != k) continue;
    int x = (int)o->pixel[2 * i], y = (int)o->pixel[2 * i + 1];
    if (x < box[0]) box[0] = x;
    if (y < box[1]) box[1] = y;
    if (x + 1 > box[2]) box[2] = x + 1;
    if (y + 1 > box[3]) box[3] = y + 1;
  }
  if (box[2] <= box[0]) box[0] = box[1] = 0, box[2] = info->width, box[3] = info->height;
  box[0] = box[0] - CROP_MARGIN < 0 ? 0 : box[0] - CROP_MARGIN;
  box[1] = box[1] - CROP_MARGIN < 0 ? 0 : box[1] - CROP_MARGIN;
  box[2] = box[2] + CROP_MARGIN > info->width ? info->width : box[2] + CROP_MARGIN;
  box[3] = box[3] + CROP_MARGIN > info->height ? info->height : box[3] + CROP_MARGIN;
  int w = box[2] - box[0], h = box[3] - box[1];

  cf_image stored = {0}, picture[3] = {{0}};
  cf_decode decode;
  cf_status s = cf_capture_read_stored(d->capture, k, &stored, &decode, err);
  for (int p = 0; s == CF_OK && p < 3; ++p) s = cf_image_alloc(&picture[p], w, h, 3, err);
  if (s == CF_OK) {
    double white = white_point(d, k);
    for (int y = 0; y < h; ++y) /* the crop decoded (cf_capture_read_radiance's, per pixel) */
      for (int x = 0; x < w; ++x) {
        size_t at = 3 * ((size_t)y * (size_t)w + (size_t)x);
        size_t from = 3 * ((size_t)(y + box[1]) * (size_t)stored.width + (size_t)(x + box[0]));
        double rgb[3];
        cf_decode_pixel(&decode, stored.pixels + from, 3, rgb);
        for (int c = 0; c < 3; ++c) {
          picture[0].pixels[at + c] = picture[1].pixels[at + c] = (float)((float)rgb[c] / white);
          picture[2].pixels[at + c] = background[c];
        }
      }
    for (size_t i = d->first[k]; i < d->last[k]; ++i) {
      if (o->image[i] != k) continue;
      int x = (int)o->pixel[2 * i] - box[0], y = (int)o->pixel[2 * i + 1] - box[1];
      size_t at = 3 * ((size_t)y * (size_t)w + (size_t)x);
      for (int c = 0; c < 3; ++c)
        picture[1].pixels[at + c] = (float)(d->prediction[3 * i + c] / white);
      float rgb[3];
      if ((d->mark[i] & REPORT_CENSORED) || isnan(d->residual[i]))
        memcpy(rgb, censored_colour, sizeof rgb);
      else if (d->mark[i] & REPORT_REJECTED)
        memcpy(rgb, rejected_colour, sizeof rgb);
      else
        report_residual_colour(d->residual[i], rgb);
      memcpy(picture[2].pixels + at, rgb, sizeof rgb);
    }
    static const char *const kinds[3] = {"photo", "render", "residual"};
    for (int p = 0; s == CF_OK && p < 3; ++p) {
      snprintf(names[p], 64, "images/%03zu_%s.png", k, kinds[p]);
      s = write_srgb(d, dir, names[p], &picture[p], err);
    }
  }
  cf_image_free(&stored);
  for (int p = 0; p < 3; ++p) cf_image_free(&picture[p]);
  return s;
}

/* ---- every image's pictures, on the threads ---- */

typedef struct images_job {
  const report_data *d;
  const char *dir;
  char (*names)[3][64];
  cf_status *status; /* per image */
  cf_error *errors;  /* per image */
  cf_progress_fn progress;
  void *user;
  size_t done;
  pthread_mutex_t lock; /* done, and the progress callback: one at a time */
} images_job;

static void image_work(void *user, int k) {
  images_job *job = user;
  job->status[k] = report_image(job->d, (size_t)k, job->dir, job->names[k], &job->errors[k]);
  pthread_mutex_lock(&job->lock);
  ++job->done;
  if (job->progress) job->progress(job->user, "writing images", job->done, job->d->images);
  pthread_mutex_unlock(&job->lock);
}

cf_status report_images(const report_data *d, const char *dir, char (*names)[3][64],
                        cf_progress_fn progress, void *user, cf_error *err) {
  size_t n = d->images;
  cf_status *status = calloc(n ? n : 1, sizeof *status);
  cf_error *errors = calloc(n ? n : 1, sizeof *errors);
  if (!status || !errors || n > INT_MAX) {
    free(status);
    free(errors);
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu images", n);
  }
  if (progress) progress(user, "writing images", 0, n);
  images_job job = {d, dir, names, status, errors, progress, user, 0, PTHREAD_MUTEX_INITIALIZER};
  cf_parallel_for((int)n, d->threads, image_work, &job);
  pthread_mutex_destroy(&job.lock);
  cf_status s = CF_OK;
  for (size_t k = 0; s == CF_OK && k < n; ++k) /* the first image's failure, as one by one */
    if (status[k] != CF_OK) {
      s = status[k];
      if (err) *err = errors[k];
    }
  free(status);
  free(errors);
  return s;
}
