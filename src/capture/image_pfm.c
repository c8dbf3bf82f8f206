/* PFM, Netpbm's float format (image_codec.h): "PF" (3 channels) or "Pf"
 * (1 channel), blank, width, blank, height, blank, a scale whose sign
 * gives the byte order (negative: little-endian), one blank byte, then
 * the rows of 32-bit floats from the bottom row to the top.
 *
 * The reader gives what OpenImageIO 2.4's PNM reader gives
 * (src/pnm.imageio/pnminput.cpp): every sample times |scale| in float,
 * rows returned top first, '#' comments allowed before each number as
 * there, bytes after the last row ignored as there. Stricter than it: a
 * blank must follow the magic and each number, the numbers are whole
 * (sizes: decimal digits; scale: finite, non-zero), and a file too short
 * for its rows is refused before anything is allocated. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "image_codec.h"

/* The longest header read: the magic, three numbers, comments. */
enum { HEADER_MOST = 4096, NUMBER_MOST = 64 };

/* What a PFM's header says. */
typedef struct pfm_header {
  int channels, width, height;
  float scale;
  long long data_offset; /* the first sample's byte */
} pfm_header;

/* A cursor over the header's bytes. */
typedef struct cursor {
  const char *at, *end;
} cursor;

static int is_blank(char c) { /* Strutil::isspace */
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

/* Blanks and '#' comments (to the end of their line) before a number, as
 * pnminput.cpp's skipComments. */
static void skip_blanks(cursor *c) {
  for (;;) {
    while (c->at < c->end && is_blank(*c->at)) ++c->at;
    if (c->at == c->end || *c->at != '#') return;
    while (c->at < c->end && *c->at != '\n') ++c->at;
  }
}

/* The next token (up to a blank) into buf; 0 when it is empty, too long
 * or not followed by a blank byte (the header ends at the last one). */
static int next_token(cursor *c, char buf[NUMBER_MOST]) {
  skip_blanks(c);
  size_t n = 0;
  while (c->at < c->end && !is_blank(*c->at)) {
    if (n + 1 == NUMBER_MOST) return 0;
    buf[n++] = *c->at++;
  }
  buf[n] = '\0';
  return n > 0 && c->at < c->end;
}

/* A size: decimal digits, 1 to INT32_MAX. */
static int parse_size(cursor *c, int *value) {
  char buf[NUMBER_MOST];
  if (!next_token(c, buf)) return 0;
  long long v = 0;
  for (const char *p = buf; *p; ++p) {
    if (*p < '0' || *p > '9') return 0;
    v = v * 10 + (*p - '0');
    if (v > INT32_MAX) return 0;
  }
  *value = (int)v;
  return 1;
}

/* The scale: a whole decimal number (strtof: the C locale a program has
 * unless it calls setlocale), finite and non-zero. */
static int parse_scale(cursor *c, float *value) {
  char buf[NUMBER_MOST];
  if (!next_token(c, buf)) return 0;
  char *end;
  errno = 0;
  const float v = strtof(buf, &end);
  if (*end != '\0' || errno == ERANGE || !isfinite(v) || v == 0.0f) return 0;
  *value = v;
  return 1;
}

/* The header from the file's first bytes. */
static cf_status parse_header(const char *path, const char *bytes, size_t count, pfm_header *header,
                              cf_error *err) {
  if (count < 3 || bytes[0] != 'P' || (bytes[1] != 'F' && bytes[1] != 'f') || !is_blank(bytes[2]))
    return cf_error_set(err, CF_EPARSE, "%s: not a PFM file (it starts with neither PF nor Pf)",
                        path);
  header->channels = bytes[1] == 'F' ? 3 : 1;
  cursor c = {bytes + 2, bytes + count};
  if (!parse_size(&c, &header->width) || !parse_size(&c, &header->height))
    return cf_error_set(err, CF_EPARSE, "%s: a PFM header whose width or height is not a number",
                        path);
  if (!parse_scale(&c, &header->scale))
    return cf_error_set(err, CF_EPARSE,
                        "%s: a PFM header whose scale is not a finite, non-zero number", path);
  header->data_offset = (long long)(c.at - bytes) + 1; /* the one blank byte */
  return CF_OK;
}

/* One row of the file, in its byte order, into `out` times |scale|
 * (pnminput.cpp unpack_floats). */
static void unpack_row(const unsigned char *in, size_t count, int little_endian, float scale,
                       float *out) {
  const float factor = fabsf(scale);
  for (size_t i = 0; i < count; ++i) {
    const unsigned char *b = in + 4 * i;
    const uint32_t bits =
        little_endian
            ? (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24
            : (uint32_t)b[3] | (uint32_t)b[2] << 8 | (uint32_t)b[1] << 16 | (uint32_t)b[0] << 24;
    float value;
    memcpy(&value, &bits, sizeof value);
    out[i] = factor * value;
  }
}

/* The rows, bottom first in the file, into image top first. */
static cf_status read_rows(const char *path, FILE *file, const pfm_header *header, cf_image *image,
                           cf_error *err) {
  const size_t row_values = (size_t)header->width * (size_t)header->channels;
  unsigned char *row = malloc(row_values * 4);
  if (!row) return cf_error_set(err, CF_ENOMEM, "%s: out of memory while decoding it", path);
  cf_status status = CF_OK;
  if (fseek(file, (long)header->data_offset, SEEK_SET) != 0)
    status = cf_error_set(err, CF_EIO, "%s: cannot seek to its samples", path);
  for (int y = header->height - 1; status == CF_OK && y >= 0; --y) {
    if (fread(row, 4, row_values, file) != row_values)
      status = cf_error_set(err, CF_EIO, "%s: reading its samples failed", path);
    else
      unpack_row(row, row_values, header->scale < 0.0f, header->scale,
                 image->pixels + (size_t)y * row_values);
  }
  free(row);
  return status;
}

cf_status image_pfm_read(const char *path, FILE *file, long long size, int width, int height,
                         cf_image_header *header, cf_image *image, cf_error *err) {
  char bytes[HEADER_MOST];
  const size_t count = fread(bytes, 1, sizeof bytes, file);
  pfm_header pfm = {0};
  cf_status status = parse_header(path, bytes, count, &pfm, err);
  if (status != CF_OK) return status;
  status = image_header_accept(path, pfm.width, pfm.height, pfm.channels, width, height, err);
  if (status != CF_OK) return status;
  const long long need = (long long)pfm.width * pfm.height * pfm.channels * 4;
  if (size - pfm.data_offset < need)
    return cf_error_set(err, CF_EIO,
                        "%s: a truncated PFM: %d x %d x %d floats need %lld bytes after the "
                        "header, the file has %lld",
                        path, pfm.width, pfm.height, pfm.channels, need, size - pfm.data_offset);
  header->width = pfm.width;
  header->height = pfm.height;
  header->channels = pfm.channels;
  snprintf(header->info.format, sizeof header->info.format, "pnm"); /* OpenImageIO's name */
  header->info.bits_per_sample = 32;
  header->info.is_float = 1;
  if (!image) return CF_OK;
  status = cf_image_alloc(image, pfm.width, pfm.height, pfm.channels, err);
  if (status != CF_OK) return cf_error_prefix(err, "%s", path), status;
  status = read_rows(path, file, &pfm, image, err);
  if (status != CF_OK) cf_image_free(image);
  return status;
}

/* Netpbm PFM: little-endian floats (negative scale) on a little-endian
 * host, rows bottom to top (1 or 3 channels: image_io.c checked). */
cf_status image_pfm_write(const char *path, const cf_image *image, cf_error *err) {
  const uint32_t probe = 1;
  unsigned char first;
  memcpy(&first, &probe, 1);
  const int little_endian = first == 1;
  FILE *file = fopen(path, "wb");
  if (!file) return cf_error_set(err, CF_EIO, "%s: %s", path, strerror(errno));
  int ok = fprintf(file, "%s\n%d %d\n%s\n", image->channels == 3 ? "PF" : "Pf", image->width,
                   image->height, little_endian ? "-1.0" : "1.0") > 0;
  const size_t row = (size_t)image->width * (size_t)image->channels;
  for (int y = image->height - 1; ok && y >= 0; --y)
    ok = fwrite(image->pixels + (size_t)y * row, sizeof(float), row, file) == row;
  ok = (fclose(file) == 0) && ok;
  if (!ok) return cf_error_set(err, CF_EIO, "%s: could not write the PFM file", path);
  return CF_OK;
}
