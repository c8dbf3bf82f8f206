/* Image k of a capture as the observations see it (cf_capture_read_radiance). */
#include <math.h>
#include <stdlib.h>

#include "capture_internal.h"

cf_status cf_capture_read_radiance(const cf_capture *capture, size_t index, cf_image *radiance,
                                   uint8_t *clipped, cf_error *err) {
  if (index >= capture->spec.num_images)
    return cf_error_set(err, CF_EINVAL, "image %zu of %zu", index, capture->spec.num_images);
  cf_image image = {0};
  cf_image_info info;
  cf_status s = cf_image_read(capture->spec.image_paths[index], &image, &info, err);
  if (s == CF_OK) s = cf_image_alloc(radiance, image.width, image.height, 3, err);
  if (s != CF_OK) {
    cf_image_free(&image);
    return s;
  }
  cf_decode decode = capture_image_decode(capture, &info, capture->images[index].exposure);
  size_t n = (size_t)image.width * (size_t)image.height;
  for (size_t i = 0; i < n; ++i) {
    double rgb[3];
    unsigned mask =
        cf_decode_pixel(&decode, image.pixels + i * (size_t)image.channels, image.channels, rgb);
    for (int c = 0; c < 3; ++c) radiance->pixels[3 * i + c] = (float)rgb[c];
    if (clipped) clipped[i] = (uint8_t)mask;
  }
  cf_image_free(&image);
  return CF_OK;
}
