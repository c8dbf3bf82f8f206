/* What every codec shares (image_codec.h): images allocated and freed
 * (include/clayfit/image.h), the header checks, the data
 * window refusal, and the conversions between integer samples and float. */
#include "image_codec.h"

#include <math.h>
#include <stdlib.h>

/* 2^31: the most values clayfit reads or allocates in one image. */
#define MOST_VALUES ((int64_t)1 << 31)

cf_status cf_image_alloc(cf_image *image, int width, int height, int channels, cf_error *err) {
  image->width = image->height = image->channels = 0;
  image->pixels = NULL;
  if (width <= 0 || height <= 0 || channels < 1 || channels > 4)
    return cf_error_set(err, CF_EINVAL,
                        "cannot make an image of %d x %d pixels with %d channels (sizes must be "
                        "positive, channels 1 to 4)",
                        width, height, channels);
  const int64_t values = (int64_t)width * height * channels;
  if (values > MOST_VALUES)
    return cf_error_set(err, CF_EINVAL,
                        "an image of %d x %d pixels x %d channels has %lld values, more than 2^31",
                        width, height, channels, (long long)values);
  float *pixels = calloc((size_t)values, sizeof(float));
  if (!pixels)
    return cf_error_set(err, CF_ENOMEM, "out of memory for an image of %d x %d x %d floats", width,
                        height, channels);
  image->width = width;
  image->height = height;
  image->channels = channels;
  image->pixels = pixels;
  return CF_OK;
}

void cf_image_free(cf_image *image) {
  if (!image) return;
  free(image->pixels);
  image->pixels = NULL;
  image->width = image->height = image->channels = 0;
}

cf_status image_header_accept(const char *path, int width, int height, int channels,
                              int width_expected, int height_expected, cf_error *err) {
  if (width <= 0 || height <= 0 || channels <= 0)
    return cf_error_set(err, CF_EPARSE, "%s: zero size (%d x %d pixels, %d channels)", path,
                        width, height, channels);
  if (channels > 4)
    return cf_error_set(err, CF_EUNSUPPORTED,
                        "%s: %d channels; clayfit reads images of 1 to 4 channels", path,
                        channels);
  const int64_t values = (int64_t)width * height * channels;
  if (values > MOST_VALUES)
    return cf_error_set(err, CF_ERANGE,
                        "%s: %d x %d pixels x %d channels is %lld values, more than the 2^31 "
                        "clayfit reads",
                        path, width, height, channels, (long long)values);
  if (width_expected > 0 && height_expected > 0 &&
      (width != width_expected || height != height_expected))
    return cf_error_set(err, CF_EINVAL,
                        "%s: its header says %d x %d pixels, not the %d x %d expected; not decoded",
                        path, width, height, width_expected, height_expected);
  return CF_OK;
}

cf_status image_window_refuse(const char *path, int width, int height, int x, int y,
                              int full_width, int full_height, int full_x, int full_y,
                              cf_error *err) {
  return cf_error_set(err, CF_EUNSUPPORTED,
                      "%s: the data window (%d x %d at %d, %d) differs from the display window "
                      "(%d x %d at %d, %d); clayfit reads whole images only",
                      path, width, height, x, y, full_width, full_height, full_x, full_y);
}

void image_scale_u8(const uint8_t *in, size_t count, float *out) {
  const float scale = 1.0f / 255.0f;
  for (size_t i = 0; i < count; ++i) out[i] = (float)in[i] * scale;
}

void image_scale_u16(const uint16_t *in, size_t count, float *out) {
  const float scale = 1.0f / 65535.0f;
  for (size_t i = 0; i < count; ++i) out[i] = (float)in[i] * scale;
}

/* value × max rounded half away from zero, then clamped: OpenImageIO
 * 2.4's convert_type<float, uint8_t/uint16_t> (fmath.h: simd::round, which
 * is roundf on SSE2, then clamp); NaN gives 0 as there. */
static float quantized(float value, float max) {
  const float scaled = value * max;
  if (!(scaled > 0.0f)) return 0.0f;
  if (scaled >= max) return max;
  return roundf(scaled);
}

uint8_t image_quantize_u8(float value) {
  return (uint8_t)quantized(value, 255.0f);
}

uint16_t image_quantize_u16(float value) {
  return (uint16_t)quantized(value, 65535.0f);
}
