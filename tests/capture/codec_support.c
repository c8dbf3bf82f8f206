/* What the codec tests share (codec_support.h). */
#include "codec_support.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/file.h"

void codec_info_clear(cf_image_info *info) {
  memset(info, 0, sizeof *info);
  info->exposure_time = info->f_number = info->iso = NAN;
}

cf_status codec_read(image_reader reader, const char *path, int width, int height,
                     cf_image_header *header, cf_image *image, cf_error *err) {
  memset(header, 0, sizeof *header);
  codec_info_clear(&header->info);
  FILE *file;
  long long size;
  cf_status s = cf_open_regular_file(path, &file, &size, err);
  if (s != CF_OK) return s;
  s = reader(path, file, size, width, height, header, image, err);
  fclose(file);
  return s;
}

const char *codec_path(const char *folder, const char *name) {
  static char paths[8][320];
  static int next = 0;
  char *out = paths[next++ % 8];
  snprintf(out, sizeof paths[0], "%s/%s", folder, name);
  return out;
}
