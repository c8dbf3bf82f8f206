/* JPEG's coding error, modelled by coding the prediction (fit_jpeg.h).
 *
 * A JPEG's codec moves a photo's values by a few tenths of a code, in the
 * same way in every image (colour conversion, the DCT's rounding, dropped
 * frequencies, averaged chroma): a bias, which no estimate of the noise
 * sees. It depends on the image, so it is measured on the image the fit
 * predicts: the photo with its sphere replaced by the prediction, coded as
 * the camera coded the photo. The codec's rounding depends on the noise it
 * codes (noise dithers it), so the prediction is coded with draws of the
 * noise model added. On synthetic M2 JPEGs (320 × 240, quality 90, 4:2:0)
 * the noise-free prediction's coding left the green albedo 4 sd low; with
 * the noise drawn, every value is within 2 sd (docs/model.md §6.2). */
#include "fit_jpeg.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/image.h"
#include "core/rng.h"
#include "fit_plan.h"
#include "fit_sample.h"
#include "core/parallel.h"

int fit_jpeg_modelled(const cf_capture *capture) {
  for (size_t k = 0; k < cf_capture_image_count(capture); ++k)
    if (cf_capture_image_at(capture, k)->jpeg_quality > 0) return 1;
  return 0;
}

/* The problem over image k's observations at p's current values, σ as
 * p's (its noise model at the prediction, or its one σ), at the pixels'
 * centres: integrating the footprints as the fit does cost as much as the
 * rest of the codec's model and moved no value by more than 0.06 sd
 * (a 16-image M4 capture with a film roughness of 0.15). */
static cf_status problem_of_image(const fit_problem *p, const cf_capture *capture, size_t k,
                                  int threads, fit_problem **q, uint32_t **index, cf_error *err) {
  *q = NULL;
  unsigned char *use = calloc(fit_problem_images(p), 1);
  if (!use) return cf_error_set(err, CF_ENOMEM, "out of memory");
  use[k] = 1;
  fit_population population;
  cf_status s = fit_population_of_images(capture, use, &population, index, err);
  free(use);
  if (s == CF_OK)
    s = fit_problem_new(q, capture, fit_problem_model(p), population.index, population.count,
                        threads, err);
  if (s != CF_OK) return s;
  fit_problem_copy_values(*q, p);
  fit_problem_clear_unknowns(*q);
  s = fit_problem_finish(*q, err);
  if (s == CF_OK) fit_problem_set_sigma(*q, fit_problem_sigma(p));
  if (s == CF_OK) s = fit_problem_reweight(*q, err); /* σ at the prediction */
  if (s != CF_OK) {
    fit_problem_free(*q);
    *q = NULL;
  }
  return s;
}

/* Observation i's pixel in an image of `width` × `height`: its offset in
 * pixels, or SIZE_MAX outside. */
static size_t pixel_of(const cf_observations *obs, size_t i, int width, int height) {
  double x = floor(obs->pixel[2 * i]), y = floor(obs->pixel[2 * i + 1]);
  if (!(x >= 0.0 && y >= 0.0 && x < width && y < height)) return SIZE_MAX;
  return (size_t)y * (size_t)width + (size_t)x;
}

/* What one image's coding needs: the photo as stored, the prediction and
 * σ of each observed channel, and the codec's mean change of the
 * prediction there (in the measurements' units). With a fitted response
 * curve R the noise is the sensor's, before R: the linear value x =
 * R⁻¹(prediction) and σ there (σ / R'(x)), for draws R(x + σ g). */
typedef struct image_coding {
  cf_image stored, noisy;
  cf_decode decode;
  const double *response; /* R's slopes, or NULL: no curve */
  size_t *at;             /* count: the observation's pixel offset */
  double *prediction;     /* 3 × count */
  double *linear;         /* 3 × count: x (with a curve), else the prediction */
  double *spread;         /* 3 × count: σ of x */
  double *before;         /* 3 × count: a draw's value before the codec */
  double *bias;           /* 3 × count */
  /* the 8-bit codes decoded (the clip level aside), and the values where
   * rounding to a code steps from one code to the next: code k holds the
   * values in [edge[k − 1], edge[k]) (the transfer curve's pow once per
   * code, not per value and draw: 4 times faster on 1.2 M observations) */
  double code_value[256], code_edge[255];
} image_coding;

/* The code tables of c->decode, without its clip level. */
static void code_tables(image_coding *c) {
  cf_decode unclipped = c->decode;
  unclipped.clip_level = INFINITY;
  for (int k = 0; k < 256; ++k) {
    const float at[2] = {(float)k / 255.0f, (float)(k + 0.5) / 255.0f};
    double value[3];
    for (int e = 0; e < 2 && k + e < 256; ++e) {
      const float px[3] = {at[e], at[e], at[e]};
      cf_decode_pixel(&unclipped, px, 3, value);
      if (e == 0)
        c->code_value[k] = value[0];
      else if (k < 255)
        c->code_edge[k] = value[0];
    }
  }
}

/* The 8-bit code a value is stored as (rounded, clipped to 0 .. 255). */
static int code_of(const image_coding *c, double value) {
  int lo = 0, hi = 255; /* the first edge above the value */
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (c->code_edge[mid] > value)
      hi = mid;
    else
      lo = mid + 1;
  }
  return lo;
}

static void coding_free(image_coding *c) {
  cf_image_free(&c->stored);
  cf_image_free(&c->noisy);
  free(c->at), free(c->prediction), free(c->linear), free(c->spread), free(c->before);
  free(c->bias);
}

/* The part of the photo the codec's model codes: the observed pixels'
 * bounding box grown by CROP_MARGIN pixels, its corner on the codec's
 * 16 × 16 grid (its blocks, and the chroma they average, are the photo's;
 * the chroma upsampling reads one block beyond, inside the margin). On
 * 640 × 480 photos this codes a third of the pixels. */
#define CROP_MARGIN 16
static cf_status crop_to_sphere(size_t n, image_coding *c, cf_error *err) {
  int width = c->stored.width, height = c->stored.height;
  int x0 = width, y0 = height, x1 = 0, y1 = 0;
  for (size_t i = 0; i < n; ++i) {
    if (c->at[i] == SIZE_MAX) continue;
    int x = (int)(c->at[i] % (size_t)width), y = (int)(c->at[i] / (size_t)width);
    x0 = x < x0 ? x : x0, y0 = y < y0 ? y : y0, x1 = x > x1 ? x : x1, y1 = y > y1 ? y : y1;
  }
  if (x0 > x1) return CF_OK; /* nothing observed */
  x0 = (x0 - CROP_MARGIN > 0 ? x0 - CROP_MARGIN : 0) / 16 * 16;
  y0 = (y0 - CROP_MARGIN > 0 ? y0 - CROP_MARGIN : 0) / 16 * 16;
  x1 = x1 + CROP_MARGIN + 1 < width ? x1 + CROP_MARGIN + 1 : width;
  y1 = y1 + CROP_MARGIN + 1 < height ? y1 + CROP_MARGIN + 1 : height;
  cf_image crop;
  cf_status s = cf_image_alloc(&crop, x1 - x0, y1 - y0, 3, err);
  if (s != CF_OK) return s;
  for (int y = y0; y < y1; ++y)
    memcpy(crop.pixels + 3 * (size_t)(y - y0) * (size_t)crop.width,
           c->stored.pixels + 3 * ((size_t)y * (size_t)width + (size_t)x0),
           3 * (size_t)crop.width * sizeof *crop.pixels);
  for (size_t i = 0; i < n; ++i)
    if (c->at[i] != SIZE_MAX)
      c->at[i] = (c->at[i] / (size_t)width - (size_t)y0) * (size_t)crop.width +
                 (c->at[i] % (size_t)width - (size_t)x0);
  cf_image_free(&c->stored);
  c->stored = crop;
  return CF_OK;
}

/* The prediction, σ and pixel of every observation of q. */
static cf_status predict(const fit_problem *q, const uint32_t *index, image_coding *c,
                         cf_error *err) {
  size_t n = fit_problem_count(q), m = n ? n : 1;
  const cf_observations *obs = cf_capture_observations(fit_problem_capture(q));
  const double *inv_sigma = fit_problem_inv_sigma(q);
  double *measured = malloc(3 * m * sizeof *measured);
  c->at = malloc(m * sizeof *c->at);
  c->prediction = malloc(3 * m * sizeof *c->prediction);
  c->linear = malloc(3 * m * sizeof *c->linear);
  c->before = malloc(3 * m * sizeof *c->before);
  c->spread = malloc(3 * m * sizeof *c->spread);
  c->bias = calloc(3 * m, sizeof *c->bias);
  cf_status s = measured && c->at && c->prediction && c->linear && c->spread && c->before && c->bias
                    ? fit_problem_predict(q, c->prediction, measured, err)
                    : cf_error_set(err, CF_ENOMEM, "out of memory");
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    c->at[i] = pixel_of(obs, index[i], c->stored.width, c->stored.height);
    for (int ch = 0; ch < 3; ++ch) {
      size_t v = 3 * i + (size_t)ch;
      c->linear[v] = c->prediction[v];
      c->spread[v] = 1.0 / inv_sigma[v];
      if (!c->response) continue;
      c->linear[v] = c->prediction[v] > 0.0
                         ? cf_response_model_inverse(c->response, NULL, c->prediction[v], NULL)
                         : 0.0;
      c->spread[v] /= fit_problem_curve_slope(q, c->prediction[v]); /* R'(x) */
    }
  }
  free(measured);
  return s == CF_OK ? crop_to_sphere(n, c, err) : s;
}

/* One draw: the photo with every observed pixel replaced by the prediction
 * plus a draw of the noise, stored as the camera stores it (the noise is
 * the sensor's, before the encoding: its curvature moves the codes' mean,
 * which the codec's smoothing then keeps), and each value before the
 * codec, decoded, in c->before. */
static void draw_photo(size_t n, cf_rng *rng, double sign, image_coding *c) {
  memcpy(c->noisy.pixels, c->stored.pixels,
         3 * (size_t)c->stored.width * (size_t)c->stored.height * sizeof *c->noisy.pixels);
  for (size_t i = 0; i < n; ++i)
    for (int ch = 0; ch < 3 && c->at[i] != SIZE_MAX; ++ch) {
      size_t v = 3 * i + (size_t)ch;
      double value = c->linear[v] + sign * c->spread[v] * cf_rng_gaussian(rng);
      if (c->response) value = cf_response_model_value(c->response, value, NULL, NULL);
      int code = code_of(c, value);
      c->noisy.pixels[3 * c->at[i] + ch] = (float)code / 255.0f;
      c->before[v] = c->code_value[code];
    }
}

/* The codec's mean change of the photo at each observed pixel over
 * FIT_JPEG_DRAWS draws, decoded, into c->bias: from what the file would
 * hold without the codec (the noisy prediction clipped to the codes'
 * range) to what it holds. The draws come in
 * antithetic pairs (n, −n): what the codec passes of the noise cancels in
 * each pair, its bias does not (with independent draws the mean's own
 * noise was about 1 code; FIT_JPEG_DRAWS is even). */
static cf_status code_draws(const cf_capture_image *image, size_t k, size_t n, image_coding *c,
                            cf_error *err) {
  cf_image coded = {0};
  cf_status s = cf_image_alloc(&c->noisy, c->stored.width, c->stored.height, 3, err);
  cf_rng rng = cf_rng_seed(0x6a70656700000000ull + k); /* the same draws every run */
  cf_rng pair = rng;
  for (int d = 0; s == CF_OK && d < FIT_JPEG_DRAWS; ++d) {
    if (d % 2 == 0)
      pair = rng; /* the pair's second draw repeats the first's, negated */
    else
      rng = pair;
    draw_photo(n, &rng, d % 2 ? -1.0 : 1.0, c);
    s = cf_image_jpeg_roundtrip(&c->noisy, image->jpeg_quality, (cf_chroma)image->jpeg_chroma,
                                &coded, err);
    for (size_t i = 0; s == CF_OK && i < n; ++i) {
      if (c->at[i] == SIZE_MAX) continue;
      for (int ch = 0; ch < 3; ++ch) {
        long code = lrintf(255.0f * coded.pixels[3 * c->at[i] + (size_t)ch]);
        double decoded = c->code_value[code < 0 ? 0 : code > 255 ? 255 : code];
        c->bias[3 * i + ch] += (decoded - c->before[3 * i + ch]) / FIT_JPEG_DRAWS;
      }
    }
    cf_image_free(&coded);
  }
  return s;
}

/* Tallies of the correction's size in stored codes (1/255). */
typedef struct bias_tally {
  double sum_sq, sum[3];
  size_t count;
  int images;
} bias_tally;

/* Image k's measurements in `y` and flags in `flags` (3 × and 1 × the
 * capture's observations; only image k's written): the measurement less
 * the codec's mean change, an estimate of the value before the codec. A
 * channel clipped in the photo stays as it was; one whose estimate is at
 * the clip level or above was clipped before the codec (the codec's
 * ringing moved it below the level) and is clipped now: its value says
 * only "at least the clip level" (docs/model.md §6.3). */
static void corrected_values(const fit_problem *q, const uint32_t *index, const image_coding *c,
                             double *y, uint8_t *flags, bias_tally *tally) {
  const float top[3] = {(float)c->decode.clip_level, (float)c->decode.clip_level,
                        (float)c->decode.clip_level};
  double clip[3];
  cf_decode_pixel(&c->decode, top, 3, clip);
  for (size_t i = 0; i < fit_problem_count(q); ++i) {
    size_t o = index[i];
    if (c->at[i] == SIZE_MAX) continue;
    ++tally->count;
    for (int ch = 0; ch < 3; ++ch) {
      double slope, b = c->bias[3 * i + ch], *value = &y[3 * o + (size_t)ch];
      cf_encode_value(&c->decode, c->prediction[3 * i + ch], &slope);
      tally->sum_sq += (b * slope) * (b * slope), tally->sum[ch] += b * slope;
      if (flags[o] >> ch & 1u) continue;
      *value -= b;
      if (*value >= clip[ch]) *value = clip[ch], flags[o] |= (uint8_t)(1u << ch);
    }
  }
}

/* The images' work (cf_parallel_for): image[j] of `count`, each with its
 * own tally and error; the measurements and flags it writes are its own
 * image's. */
typedef struct coding_work {
  const fit_problem *p;
  const cf_capture *capture;
  const cf_fit_options *o;
  const size_t *image;
  int threads; /* each image's problem's */
  double *y;
  uint8_t *flags;
  bias_tally *tally;
  cf_status *status;
  cf_error *err;
} coding_work;

/* One image: its problem, prediction, draws and corrected measurements. */
static void correct_image(void *user, int j) {
  coding_work *w = user;
  size_t k = w->image[j];
  fit_problem *q;
  uint32_t *index = NULL;
  cf_error *err = &w->err[j];
  cf_status s = problem_of_image(w->p, w->capture, k, w->threads, &q, &index, err);
  if (s == CF_OK) {
    image_coding c = {0};
    c.response = fit_problem_response_on(q) ? fit_problem_read_values(q)->response : NULL;
    s = cf_capture_read_stored(w->capture, k, &c.stored, &c.decode, err);
    if (s == CF_OK) code_tables(&c);
    if (s == CF_OK) s = predict(q, index, &c, err);
    if (s == CF_OK)
      s = code_draws(cf_capture_image_at(w->capture, k), k, fit_problem_count(q), &c, err);
    if (s == CF_OK) corrected_values(q, index, &c, w->y, w->flags, &w->tally[j]);
    coding_free(&c);
    fit_problem_free(q);
  }
  free(index);
  w->status[j] = s;
}

/* The tallies into r, and the first failure's error into err. */
static cf_status gather(const coding_work *w, int count, cf_fit_result *r, cf_error *err) {
  bias_tally all = {0};
  for (int j = 0; j < count; ++j) {
    if (w->status[j] != CF_OK) {
      *err = w->err[j];
      return w->status[j];
    }
    all.sum_sq += w->tally[j].sum_sq, all.count += w->tally[j].count;
    for (int c = 0; c < 3; ++c) all.sum[c] += w->tally[j].sum[c];
  }
  r->jpeg_images = count;
  r->jpeg_bias_rms = all.count ? 255.0 * sqrt(all.sum_sq / (3.0 * (double)all.count)) : 0.0;
  for (int c = 0; c < 3; ++c)
    r->jpeg_bias_mean[c] = all.count ? 255.0 * all.sum[c] / (double)all.count : 0.0;
  return CF_OK;
}

cf_status fit_jpeg_correct(fit_problem *p, const cf_capture *capture, const cf_fit_options *o,
                           cf_fit_result *r, cf_error *err) {
  const cf_observations *obs = cf_capture_observations(capture);
  size_t images = cf_capture_image_count(capture), n = obs->count ? obs->count : 1;
  coding_work w = {p,         capture, o,    NULL, 1, malloc(3 * n * sizeof *w.y),
                   malloc(n), NULL,    NULL, NULL};
  size_t *image = malloc((images ? images : 1) * sizeof *image);
  w.tally = calloc(images ? images : 1, sizeof *w.tally);
  w.status = calloc(images ? images : 1, sizeof *w.status);
  w.err = calloc(images ? images : 1, sizeof *w.err);
  w.image = image;
  cf_status s = CF_OK;
  if (!w.y || !w.flags || !image || !w.tally || !w.status || !w.err)
    s = cf_error_set(err, CF_ENOMEM, "out of memory");
  int count = 0;
  for (size_t k = 0; s == CF_OK && k < images; ++k) { /* (an image may have no observation) */
    const cf_capture_image *at = cf_capture_image_at(capture, k);
    if (at->jpeg_quality > 0 && at->observations > 0) image[count++] = (size_t)k;
  }
  if (s == CF_OK) {
    memcpy(w.y, obs->rgb, 3 * obs->count * sizeof *w.y);
    memcpy(w.flags, obs->flags, obs->count);
    int threads = fit_threads(o);
    w.threads = count >= threads ? 1 : threads; /* the images side by side, or each on all */
    fit_progress(o, "modelling the JPEG coding", 0, 1);
    cf_parallel_for(count, count >= threads ? threads : 1, correct_image, &w);
    s = gather(&w, count, r, err);
  }
  if (s == CF_OK) fit_problem_set_measured(p, w.y, w.flags); /* the problem's rows */
  free(w.y), free(w.flags), free(image), free(w.tally), free(w.status), free(w.err);
  return s;
}
