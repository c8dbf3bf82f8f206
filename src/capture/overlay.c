/* A picture of which pixels of an image became observations
 * (cf_capture_write_overlay). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture_internal.h"
#include "core/order_statistics.h"

/* The 99.5th percentile of the decoded values: the overlay's white. */
static double white_point(const cf_image *image, const cf_decode *decode) {
  size_t n = (size_t)image->width * (size_t)image->height;
  double *values = malloc(n * sizeof *values);
  if (!values) return 1.0;
  for (size_t i = 0; i < n; ++i) {
    double rgb[3];
    cf_decode_pixel(decode, image->pixels + i * (size_t)image->channels, image->channels, rgb);
    values[i] = fmax(rgb[0], fmax(rgb[1], rgb[2]));
  }
  double white = order_kth_smallest(values, n, (size_t)(0.995 * (double)(n - 1)));
  free(values);
  return white > 0.0 ? white : 1.0;
}

cf_status cf_capture_write_overlay(const cf_capture *capture, size_t index, const char *path,
                                   cf_error *err) {
  if (index >= capture->spec.num_images)
    return cf_error_set(err, CF_EINVAL, "image %zu of %zu", index, capture->spec.num_images);
  cf_image image = {0}, picture = {0};
  cf_status s = cf_image_read(capture->spec.image_paths[index], &image, NULL, err);
  if (s == CF_OK) s = cf_image_alloc(&picture, image.width, image.height, 3, err);
  if (s != CF_OK) {
    cf_image_free(&image);
    return s;
  }
  cf_decode decode = {capture->spec.transfer, capture->spec.gamma, capture->spec.black_level,
                      INFINITY, 1.0};
  double white = white_point(&image, &decode);
  size_t n = (size_t)image.width * (size_t)image.height;
  for (size_t i = 0; i < n; ++i) {
    double rgb[3];
    cf_decode_pixel(&decode, image.pixels + i * (size_t)image.channels, image.channels, rgb);
    for (int c = 0; c < 3; ++c)
      picture.pixels[3 * i + c] = (float)fmin(1.0, fmax(0.0, rgb[c] / white));
  }
  /* tint the pixels used: green, or red where a channel is clipped */
  const cf_observations *o = &capture->obs;
  for (size_t i = 0; i < o->count; ++i) {
    if (o->image[i] != index) continue;
    size_t p = (size_t)o->pixel[2 * i + 1] * (size_t)image.width + (size_t)o->pixel[2 * i];
    const float tint[3] = {(o->flags[i] & CF_OBS_CLIPPED) ? 1.0f : 0.0f,
                           (o->flags[i] & CF_OBS_CLIPPED) ? 0.0f : 1.0f, 0.0f};
    for (int c = 0; c < 3; ++c)
      picture.pixels[3 * p + c] = 0.6f * picture.pixels[3 * p + c] + 0.4f * tint[c];
  }
  for (size_t i = 0; i < 3 * n; ++i)
    picture.pixels[i] = (float)cf_linear_to_srgb(picture.pixels[i]);
  s = cf_image_write(path, &picture, 8, err);
  cf_image_free(&image);
  cf_image_free(&picture);
  return s;
}
