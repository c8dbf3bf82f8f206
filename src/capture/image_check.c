/* Checks of an image and of a header (include/clayfit/image.h). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/image.h"

cf_status cf_image_check_finite(const cf_image *image, const char *path, cf_error *err) {
  const char *name = path && path[0] ? path : "image";
  if (!image || !image->pixels || image->width <= 0 || image->height <= 0 || image->channels <= 0)
    return cf_error_set(err, CF_EINVAL, "%s: an empty image", name);
  const size_t values = (size_t)image->width * (size_t)image->height * (size_t)image->channels;
  size_t count = 0, first = 0;
  for (size_t i = 0; i < values; ++i) {
    if (isfinite(image->pixels[i])) continue;
    if (count++ == 0) first = i;
  }
  if (count == 0) return CF_OK;
  const size_t pixel = first / (size_t)image->channels;
  const int channel = (int)(first % (size_t)image->channels);
  const int x = (int)(pixel % (size_t)image->width), y = (int)(pixel / (size_t)image->width);
  return cf_error_set(err, CF_EINVAL,
                      "%s: %zu non-finite value%s (NaN or infinity); the first is %s at pixel "
                      "(%d, %d), channel %d",
                      name, count, count == 1 ? "" : "s",
                      isnan(image->pixels[first]) ? "NaN" : "an infinity", x, y, channel);
}

unsigned long long cf_image_header_bytes(const cf_image_header *header) {
  return (unsigned long long)header->width * (unsigned long long)header->height *
         (unsigned long long)header->channels * sizeof(float);
}

cf_status cf_image_header_refusal(cf_status s, cf_error *err) {
  if (s != CF_OK && err) {
    size_t n = strlen(err->message);
    snprintf(err->message + n, sizeof err->message - n, " (from its header, before decoding)");
  }
  return s;
}
