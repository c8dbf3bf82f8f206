/* What the codec tests (test_image_png, _jpeg, _exr, _pfm) share: a
 * reader called as the dispatcher (src/capture/image_io.c) calls it, and
 * paths in the test's temporary folder. */
#ifndef CLAYFIT_TESTS_CODEC_SUPPORT_H
#define CLAYFIT_TESTS_CODEC_SUPPORT_H

#include "capture/image_codec.h"

/* An image's information with nothing known: zero, the EXIF fields NaN. */
void codec_info_clear(cf_image_info *info);

/* `reader` on `path` as the dispatcher calls it: the file opened
 * (cf_open_regular_file), its size, the header zero (codec_info_clear). */
cf_status codec_read(image_reader reader, const char *path, int width, int height,
                     cf_image_header *header, cf_image *image, cf_error *err);

/* folder/name, in one of 8 buffers used in turn (valid for 8 calls). */
const char *codec_path(const char *folder, const char *name);

#endif /* CLAYFIT_TESTS_CODEC_SUPPORT_H */
