/* An OpenEXR file's headers checked before OpenEXR reads them
 * (image_exr_check.c). Private to the image component. */
#ifndef CLAYFIT_IMAGE_EXR_CHECK_H
#define CLAYFIT_IMAGE_EXR_CHECK_H

#include <stdio.h>

#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* `file` (of file_size bytes, path for messages) starts with OpenEXR's
 * magic number. CF_OK when every header attribute fits in the file and has
 * its type's size, and the data window's offset table fits too; else
 * CF_EPARSE naming the attribute and its byte. */
cf_status cf_exr_check_headers(const char *path, FILE *file, long long file_size, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_IMAGE_EXR_CHECK_H */
