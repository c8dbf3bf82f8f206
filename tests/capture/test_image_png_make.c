/* PNG files for test_image_png (test_image_png_make.h). */
#include "test_image_png_make.h"

#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static void put16(unsigned char *p, unsigned v) {
  p[0] = (unsigned char)v;
  p[1] = (unsigned char)(v >> 8);
}
static void put32(unsigned char *p, uint32_t v) {
  put16(p, v & 0xffff);
  put16(p + 2, v >> 16);
}
static void put32_be(unsigned char *p, uint32_t v) {
  p[0] = (unsigned char)(v >> 24);
  p[1] = (unsigned char)(v >> 16);
  p[2] = (unsigned char)(v >> 8);
  p[3] = (unsigned char)v;
}
static void entry(unsigned char *p, unsigned tag, unsigned type, uint32_t count, uint32_t value) {
  put16(p, tag);
  put16(p + 2, type);
  put32(p + 4, count);
  put32(p + 8, value);
}

size_t exif_block_make(unsigned char out[84], uint32_t denominator) {
  memset(out, 0, 84);
  memcpy(out, "II*\0", 4);
  put32(out + 4, 8);
  put16(out + 8, 1);                  /* IFD0: one entry */
  entry(out + 10, 0x8769, 4, 1, 26);  /* the Exif IFD at 26 */
  put16(out + 26, 3);                 /* Exif IFD: three entries */
  entry(out + 28, 0x829A, 5, 1, 68);  /* ExposureTime, RATIONAL at 68 */
  entry(out + 40, 0x829D, 5, 1, 76);  /* FNumber, RATIONAL at 76 */
  entry(out + 52, 0x8827, 3, 1, 200); /* PhotographicSensitivity 200 */
  put32(out + 68, 1);
  put32(out + 72, denominator);
  put32(out + 76, 28);
  put32(out + 80, 10);
  return 84;
}

/* ImageMagick's text form of an EXIF profile: "\nexif\n  <size>\n" and
 * hex lines of 72 digits, of "Exif\0\0" and the block. */
static char *exif_text(uint32_t denominator) {
  unsigned char bytes[90];
  memcpy(bytes, "Exif\0\0", 6);
  exif_block_make(bytes + 6, denominator);
  char *text = malloc(64 + 3 * sizeof bytes);
  int n = sprintf(text, "\nexif\n      %zu\n", sizeof bytes);
  for (size_t i = 0; i < sizeof bytes; ++i) {
    n += sprintf(text + n, "%02x", bytes[i]);
    if (i % 36 == 35) text[n++] = '\n';
  }
  text[n++] = '\n';
  text[n] = '\0';
  return text;
}

/* A sample pattern: pseudo-random bytes, the tRNS colour every 3rd pixel. */
static void fill_rows(unsigned char *rows, size_t row_bytes, int height, int bytes_per_pixel,
                      const unsigned char *trns_pixel) {
  uint32_t state = 12345u;
  for (size_t i = 0; i < row_bytes * (size_t)height; ++i) {
    state = state * 1664525u + 1013904223u;
    rows[i] = (unsigned char)(state >> 24);
  }
  if (!trns_pixel || bytes_per_pixel == 0) return;
  for (int y = 0; y < height; ++y)
    for (size_t x = 0; (x + 1) * (size_t)bytes_per_pixel <= row_bytes; x += 3)
      memcpy(rows + (size_t)y * row_bytes + x * (size_t)bytes_per_pixel, trns_pixel,
             (size_t)bytes_per_pixel);
}

static void set_chunks(png_structp png, png_infop info, const png_made *m, char **text) {
  if (m->flags & MADE_COLOUR_CHUNKS) {
    png_set_gAMA(png, info, 1.0 / 2.2);
    png_set_cHRM(png, info, 0.3127, 0.329, 0.64, 0.33, 0.3, 0.6, 0.15, 0.06);
    png_color_8 sig = {5, 6, 5, 5, 0};
    png_set_sBIT(png, info, &sig);
    png_set_pHYs(png, info, 2835, 2835, PNG_RESOLUTION_METER);
  }
  if (m->flags & MADE_SRGB) png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  if (m->flags & MADE_OFFS_ZERO) png_set_oFFs(png, info, 0, 0, PNG_OFFSET_PIXEL);
  if (m->flags & MADE_OFFS) png_set_oFFs(png, info, 5, 7, PNG_OFFSET_PIXEL);
  png_text t[2];
  int n = 0;
  memset(t, 0, sizeof t);
  if (m->flags & MADE_COLOUR_CHUNKS) {
    t[n].compression = PNG_TEXT_COMPRESSION_NONE;
    t[n].key = (char *)"Comment";
    t[n++].text = (char *)"made by test_image_png";
  }
  if (m->flags & MADE_EXIF_TEXT) {
    *text = exif_text(80);
    t[n].compression = PNG_TEXT_COMPRESSION_zTXt;
    t[n].key = (char *)"Raw profile type exif";
    t[n++].text = *text;
  }
  if (n) png_set_text(png, info, t, n);
  if (m->flags & MADE_EXIF_CHUNK) {
    static unsigned char block[84];
    exif_block_make(block, 125);
    png_set_eXIf_1(png, info, sizeof block, block);
  }
}

/* The palette (and its tRNS alphas) or the tRNS colour of `m`; the bytes
 * of one transparent pixel (NULL where the pattern has it anyway). */
static const unsigned char *set_palette_trns(png_structp png, png_infop info, const png_made *m,
                                             unsigned char pixel[8]) {
  if (m->colour == PNG_COLOR_TYPE_PALETTE) {
    png_color palette[256];
    png_byte alpha[256];
    for (int i = 0; i < 256; ++i) {
      palette[i].red = (png_byte)(i * 7);
      palette[i].green = (png_byte)(255 - i);
      palette[i].blue = (png_byte)(i * 13);
      alpha[i] = (png_byte)(i * 37);
    }
    png_set_PLTE(png, info, palette, 1 << m->bit_depth);
    if (m->trns) png_set_tRNS(png, info, alpha, (1 << m->bit_depth) - 1, NULL);
    return NULL;
  }
  if (!m->trns) return NULL;
  const int wide = m->bit_depth == 16;
  png_color_16 colour = {0, 0x12, 0x56, 0x88, 77};
  if (wide) colour = (png_color_16){0, 0x1234, 0x0456, 0x7788, 0x9abc};
  if (m->bit_depth < 8) colour.gray = 2;
  png_set_tRNS(png, info, NULL, 0, &colour);
  if (m->bit_depth < 8) return NULL; /* grey 2 occurs in the pattern */
  if (m->colour == PNG_COLOR_TYPE_GRAY) {
    put32_be(pixel, (uint32_t)colour.gray << (wide ? 16 : 24));
    return pixel;
  }
  const png_uint_16 rgb[3] = {colour.red, colour.green, colour.blue};
  for (int c = 0; c < 3; ++c) {
    if (wide) {
      pixel[2 * c] = (unsigned char)(rgb[c] >> 8);
      pixel[2 * c + 1] = (unsigned char)rgb[c];
    } else {
      pixel[c] = (unsigned char)rgb[c];
    }
  }
  return pixel;
}

int png_make(const char *path, const png_made *m) {
  FILE *file = fopen(path, "wb");
  if (!file) return -1;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
  png_infop info = png_create_info_struct(png);
  unsigned char *rows = NULL;
  png_bytep *pointers = NULL;
  char *text = NULL;
  int result = -1;
  if (setjmp(png_jmpbuf(png))) goto done;
  png_init_io(png, file);
  png_set_IHDR(png, info, (png_uint_32)m->width, (png_uint_32)m->height, m->bit_depth, m->colour,
               m->interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  unsigned char pixel[8];
  const unsigned char *trns_pixel = set_palette_trns(png, info, m, pixel);
  set_chunks(png, info, m, &text);
  png_write_info(png, info);
  size_t row_bytes = png_get_rowbytes(png, info);
  int bytes_per_pixel = m->bit_depth < 8 ? 0 : png_get_channels(png, info) * m->bit_depth / 8;
  rows = malloc(row_bytes * (size_t)m->height);
  pointers = malloc(sizeof(png_bytep) * (size_t)m->height);
  fill_rows(rows, row_bytes, m->height, bytes_per_pixel, trns_pixel);
  for (int y = 0; y < m->height; ++y) pointers[y] = rows + (size_t)y * row_bytes;
  png_write_image(png, pointers);
  png_write_end(png, NULL);
  result = 0;
done:
  png_destroy_write_struct(&png, &info);
  free(rows);
  free(pointers);
  free(text);
  if (fclose(file) != 0) result = -1;
  return result;
}

unsigned char *file_load(const char *path, size_t *size) {
  FILE *file = fopen(path, "rb");
  if (!file) return NULL;
  fseek(file, 0, SEEK_END);
  long n = ftell(file);
  fseek(file, 0, SEEK_SET);
  unsigned char *bytes = malloc((size_t)n + 1);
  if (bytes && fread(bytes, 1, (size_t)n, file) != (size_t)n) {
    free(bytes);
    bytes = NULL;
  }
  fclose(file);
  *size = (size_t)n;
  return bytes;
}

int file_save(const char *path, const unsigned char *bytes, size_t size) {
  FILE *file = fopen(path, "wb");
  if (!file) return -1;
  int ok = fwrite(bytes, 1, size, file) == size;
  return (fclose(file) == 0 && ok) ? 0 : -1;
}

static uint32_t get32_be(const unsigned char *p) {
  return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

long chunk_find(const unsigned char *bytes, size_t size, const char type[4]) {
  for (size_t at = 8; at + 12 <= size;) {
    uint32_t length = get32_be(bytes + at);
    if (memcmp(bytes + at + 4, type, 4) == 0) return (long)at;
    at += 12 + (size_t)length;
  }
  return -1;
}

void chunk_fix_crc(unsigned char *bytes, long chunk) {
  uint32_t length = get32_be(bytes + chunk);
  uLong crc = crc32(0L, bytes + chunk + 4, 4 + length);
  put32_be(bytes + chunk + 8 + length, (uint32_t)crc);
}

int png_add_text_bombs(const char *path, int count, size_t inflated) {
  size_t size;
  unsigned char *bytes = file_load(path, &size);
  unsigned char *plain = malloc(inflated);
  uLongf packed_size = compressBound(inflated);
  unsigned char *packed = malloc(packed_size);
  int result = -1;
  if (plain) memset(plain, 'a', inflated);
  if (bytes && plain && packed && compress2(packed, &packed_size, plain, inflated, 9) == Z_OK) {
    const size_t data = 9 + packed_size, chunk = 12 + data; /* "Comment\0", method 0 */
    unsigned char *out = malloc(size + (size_t)count * chunk);
    memcpy(out, bytes, 33); /* signature and IHDR */
    size_t at = 33;
    for (int i = 0; i < count; ++i, at += chunk) {
      put32_be(out + at, (uint32_t)data);
      memcpy(out + at + 4, "zTXtComment\0\0", 13);
      memcpy(out + at + 17, packed, packed_size);
      chunk_fix_crc(out, (long)at);
    }
    memcpy(out + at, bytes + 33, size - 33);
    result = file_save(path, out, at + size - 33);
    free(out);
  }
  free(bytes);
  free(plain);
  free(packed);
  return result;
}
