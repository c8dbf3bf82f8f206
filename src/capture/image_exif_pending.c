/* TEMPORARY (branch codec-png only): a stand-in for image_exif_read until
 * image_exif.c (written on another branch) is merged; the merge deletes
 * this file and its line in image.cmake. It reads nothing. */
#include "image_codec.h"

void image_exif_read(const unsigned char *tiff, size_t size, cf_image_info *info) {
  (void)tiff;
  (void)size;
  (void)info;
}
