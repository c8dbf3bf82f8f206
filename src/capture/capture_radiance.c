/* Image k of a capture as stored and as the observations see it
 * (cf_capture_read_stored, cf_capture_read_radiance). */
#include <math.h>
#include <stdlib.h>

#include "capture_internal.h"

cf_status cf_capture_read_radiance(const cf_capture *capture, size_t index, cf_image *radiance,
                                   uint8_t *clipped, cf_error *err) {
  cf_image stored;
  cf_decode decode;
  cf_status s = cf_capture_read_stored(capture, index, &stored, &decode, err);
  if (s == CF_OK) s = cf_image_alloc(radiance, stored.width, stored.height, 3, err);
  size_t n = s == CF_OK ? (size_t)stored.width * (size_t)stored.height : 0;
  for (size_t i = 0; i < n; ++i) {
    double rgb[3];
    unsigned mask = cf_decode_pixel(&decode, stored.pixels + 3 * i, 3, rgb);
    for (int c = 0; c < 3; ++c) radiance->pixels[3 * i + c] = (float)rgb[c];
    if (clipped) clipped[i] = (uint8_t)mask;
  }
  cf_image_free(&stored);
  return s;
}

cf_status cf_capture_read_stored(const cf_capture *capture, size_t index, cf_image *stored,
                                 cf_decode *decode, cf_error *err) {
  *stored = (cf_image){0};
  if (index >= capture->spec.num_images)
    return cf_error_set(err, CF_EINVAL, "image %zu of %zu", index, capture->spec.num_images);
  cf_image image = {0};
  cf_image_info info;
  const cf_capture_image *im = &capture->images[index];
  cf_status s = cf_image_read_sized(capture->spec.image_paths[index], im->width, im->height, &image,
                                    &info, err);
  if (s == CF_OK) s = cf_image_alloc(stored, image.width, image.height, 3, err);
  if (s == CF_OK) {
    *decode = capture_image_decode(capture, &info, im->exposure);
    size_t n = (size_t)image.width * (size_t)image.height;
    int grey = image.channels < 3;
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c)
        stored->pixels[3 * i + c] = image.pixels[i * (size_t)image.channels + (grey ? 0 : c)];
  }
  cf_image_free(&image);
  return s;
}
