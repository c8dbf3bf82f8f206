/* How a JPEG file was coded, from its markers (ITU-T T.81 §B.1–B.2): its
 * quality, matched against libjpeg's scaled standard tables, and its
 * chroma subsampling. A stream parser over bytes plus a thin path wrapper,
 * every length checked against what is left. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "clayfit/image.h"
#include "core/file.h"

/* The markers come before the first scan; 1 MiB holds them in any camera's
 * file (EXIF segments are at most 64 KiB each). */
#define JPEG_HEADER_MOST (1u << 20)

/* T.81 Annex K, Table K.1: the luminance quantisation table at libjpeg's
 * quality 50, in natural (row-major) order. */
static const int kStandardLuminance[64] = {
    16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
    14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
    18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};

/* T.81 Figure A.6: the zigzag position k of a DQT's k-th value, in natural order. */
static const int kNaturalOrder[64] = {
    0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,  12, 19, 26, 33, 40, 48,
    41, 34, 27, 20, 13, 6,  7,  14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23,
    30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

/* libjpeg's jpeg_quality_scaling and jpeg_add_quant_table (baseline). */
static int scaled_entry(int base, int quality) {
  int scale = quality < 50 ? 5000 / quality : 200 - 2 * quality;
  long value = ((long)base * scale + 50) / 100;
  return value < 1 ? 1 : value > 255 ? 255 : (int)value;
}

/* The quality whose table is nearest `table` in log ratio (exact if equal). */
static void match_quality(const int table[64], cf_jpeg_coding *coding) {
  double best = HUGE_VAL;
  for (int q = 1; q <= 100; ++q) {
    double distance = 0.0;
    for (int k = 0; k < 64; ++k) {
      double r = log((double)table[k] / scaled_entry(kStandardLuminance[k], q));
      distance += r * r;
    }
    if (distance < best) best = distance, coding->quality = q, coding->exact = distance == 0.0;
  }
}

typedef struct jpeg_header {
  int table[4][64]; /* natural order */
  int has_table[4];
  int components, luma_table;
  int h[3], v[3]; /* sampling factors */
  int has_frame;
} jpeg_header;

static cf_status bad(cf_error *err, const char *what, size_t at, const char *why) {
  return cf_error_set(err, CF_EINVAL, "%s: not a JPEG clayfit can model (byte %zu): %s", what, at,
                      why);
}

/* A DQT segment (T.81 §B.2.4.1): tables of 64 values of 8 or 16 bits. */
static cf_status read_dqt(const unsigned char *b, size_t n, size_t at, const char *what,
                          jpeg_header *h, cf_error *err) {
  size_t i = 0;
  while (i < n) {
    int precision = b[i] >> 4, id = b[i] & 15, bytes = precision ? 2 : 1;
    if (precision > 1 || id > 3) return bad(err, what, at + i, "a DQT table's precision or id");
    if (n - i - 1 < (size_t)(64 * bytes)) return bad(err, what, at + i, "a DQT table is cut");
    for (int k = 0; k < 64; ++k) {
      const unsigned char *e = b + i + 1 + (size_t)(k * bytes);
      int value = bytes == 2 ? e[0] << 8 | e[1] : e[0];
      if (value < 1) return bad(err, what, at + i, "a DQT value of 0");
      h->table[id][kNaturalOrder[k]] = value;
    }
    h->has_table[id] = 1;
    i += 1 + (size_t)(64 * bytes);
  }
  return CF_OK;
}

/* A frame header (T.81 §B.2.2): 8-bit samples, 1 or 3 components. */
static cf_status read_sof(const unsigned char *b, size_t n, size_t at, const char *what,
                          jpeg_header *h, cf_error *err) {
  if (n < 6) return bad(err, what, at, "a frame header is cut");
  if (b[0] != 8) return bad(err, what, at, "samples of other than 8 bits");
  int components = b[5];
  if (components != 1 && components != 3)
    return bad(err, what, at, "a frame of other than 1 or 3 components");
  if (n < 6 + 3 * (size_t)components) return bad(err, what, at, "a frame header is cut");
  for (int c = 0; c < components; ++c) {
    const unsigned char *e = b + 6 + 3 * c;
    h->h[c] = e[1] >> 4, h->v[c] = e[1] & 15;
    if (h->h[c] < 1 || h->v[c] < 1 || h->h[c] > 4 || h->v[c] > 4 || e[2] > 3)
      return bad(err, what, at, "a component's sampling factors or table");
    if (c == 0) h->luma_table = e[2];
  }
  h->components = components, h->has_frame = 1;
  return CF_OK;
}

/* The subsampling from the sampling factors: the chroma components 1 × 1. */
static cf_status chroma_of(const jpeg_header *h, const char *what, cf_jpeg_coding *coding,
                           cf_error *err) {
  if (h->components == 1 || (h->h[0] == h->h[1] && h->v[0] == h->v[1])) {
    coding->chroma = CF_CHROMA_444;
    return CF_OK;
  }
  for (int c = 1; c < 3; ++c)
    if (h->h[c] != 1 || h->v[c] != 1)
      return bad(err, what, 0, "chroma sampling other than 4:4:4, 4:2:2 or 4:2:0");
  if (h->h[0] == 2 && h->v[0] == 2)
    coding->chroma = CF_CHROMA_420;
  else if (h->h[0] == 2 && h->v[0] == 1)
    coding->chroma = CF_CHROMA_422;
  else
    return bad(err, what, 0, "chroma sampling other than 4:4:4, 4:2:2 or 4:2:0");
  return CF_OK;
}

/* The markers from SOI to the first SOS (T.81 §B.1.1.2–B.1.1.4). */
static cf_status walk_markers(const unsigned char *b, size_t size, const char *what, jpeg_header *h,
                              cf_error *err) {
  if (size < 4 || b[0] != 0xFF || b[1] != 0xD8) return bad(err, what, 0, "no SOI marker");
  size_t i = 2;
  for (;;) {
    if (i >= size || b[i] != 0xFF) return bad(err, what, i, "a marker was expected");
    while (i < size && b[i] == 0xFF) ++i; /* fill bytes */
    if (i >= size) return bad(err, what, i, "the file ends inside a marker");
    int marker = b[i++];
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue; /* no length */
    if (marker == 0xD9) return bad(err, what, i, "the image ends before its first scan");
    if (size - i < 2) return bad(err, what, i, "a segment's length is cut");
    size_t length = (size_t)b[i] << 8 | b[i + 1];
    if (length < 2 || length > size - i) return bad(err, what, i, "a segment's length");
    const unsigned char *body = b + i + 2;
    size_t n = length - 2;
    cf_status s = CF_OK;
    if (marker == 0xDA) return CF_OK; /* SOS: the header is over */
    if (marker == 0xDB) s = read_dqt(body, n, i + 2, what, h, err);
    if (marker == 0xC0 || marker == 0xC1 || marker == 0xC2)
      s = read_sof(body, n, i + 2, what, h, err);
    if (marker == 0xC3 || (marker >= 0xC5 && marker <= 0xCF && marker != 0xC8 && marker != 0xCC))
      return bad(err, what, i, "a lossless, hierarchical or arithmetic-coded frame");
    if (s != CF_OK) return s;
    i += length;
  }
}

cf_status cf_jpeg_coding_parse(const unsigned char *bytes, size_t size, const char *what,
                               cf_jpeg_coding *coding, cf_error *err) {
  jpeg_header h = {0};
  cf_status s = walk_markers(bytes, size, what, &h, err);
  if (s != CF_OK) return s;
  if (!h.has_frame) return bad(err, what, 0, "no frame header before the first scan");
  if (!h.has_table[h.luma_table]) return bad(err, what, 0, "the luminance table is missing");
  s = chroma_of(&h, what, coding, err);
  if (s == CF_OK) match_quality(h.table[h.luma_table], coding);
  return s;
}

cf_status cf_jpeg_coding_read(const char *path, cf_jpeg_coding *coding, cf_error *err) {
  FILE *file;
  long long file_size;
  cf_status opened = cf_open_regular_file(path, &file, &file_size, err);
  if (opened != CF_OK) return opened;
  unsigned char *bytes = malloc(JPEG_HEADER_MOST);
  size_t size = bytes ? fread(bytes, 1, JPEG_HEADER_MOST, file) : 0;
  int failed = ferror(file);
  fclose(file);
  cf_status s = !bytes   ? cf_error_set(err, CF_ENOMEM, "%s: out of memory", path)
                : failed ? cf_error_set(err, CF_EIO, "%s: could not read it", path)
                         : cf_jpeg_coding_parse(bytes, size, path, coding, err);
  free(bytes);
  return s;
}
