/* PNG through libpng 1.6 (image_codec.h): the reader gives, sample for
 * sample, what OpenImageIO 2.4's PNG reader gives (src/png.imageio,
 * png_pvt.h read_info and read_into_buffer), and the writer writes what
 * its PNG writer writes, pixel for pixel.
 *
 * Reading: the same libpng transforms as OpenImageIO's read_info:
 * png_set_expand (palette to RGB, or RGBA where a tRNS chunk gives
 * transparency; grey of 1, 2 or 4 bits to 8 bits; a tRNS colour to an
 * alpha channel) and 16-bit samples in host order; no gamma, sRGB, iCCP
 * or sBIT transform (libpng applies none unless asked). The channel count
 * is png_get_channels after those transforms. EXIF comes, as in
 * OpenImageIO 2.4, from "Raw profile type exif" text chunks (hex, the way
 * ImageMagick and exiftool store it) over an eXIf chunk, both before
 * the image data. An oFFs chunk (a position on a page) is
 * ignored: OpenImageIO 2.4 makes a non-zero one the data window's origin,
 * which image_oiio_read refuses as a partial image, but the file holds
 * the whole image (test_image_png: "oFFs 5 7").
 *
 * Hostile files: libpng's own limits stay as Debian builds them (an
 * ancillary chunk of more than 8,000,000 bytes is an error, as it is for
 * OpenImageIO), at most 32 text chunks are kept (OpenImageIO: 1000), and
 * everything libpng allocates for one file is capped at 64 MiB
 * (png_create_read_struct_2's allocator), so that compressed text chunks
 * cannot inflate to gigabytes. libpng's warnings are dropped; its errors
 * longjmp here and become a CF_EIO naming the file. */
#include <png.h>

#include <errno.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "image_codec.h"

enum {
  /* all that libpng may hold for one file: 8 of its largest chunks */
  LIBPNG_BUDGET = 64 << 20,
  /* text chunks kept (libpng's default is 1000, each up to 8 MB inflated:
   * 100 zTXt chunks of 4 MB took 3.0 s to read with 64, 1.5 s with 32) */
  TEXT_CHUNKS_KEPT = 32,
  /* zlib's level for the files written. Measured on DiLiGenT's 001.png
   * (noisy 16-bit), a smooth 16-bit render of a sphere, and both as 8-bit
   * sRGB, against OpenImageIO 2.4 (level 6, libpng's adaptive filters):
   * level 4 with no filter at 8 bits gives 0.91-1.04 x its size in
   * 0.10-0.24 x its time; at 16 bits adaptive filters keep a smooth
   * render at 1.02 x (1.50 x unfiltered), 1.05 x on DiLiGenT, in
   * 0.19-0.92 x its time. */
  WRITE_LEVEL = 4
};

/* One file's decoding state, shared with libpng's callbacks. */
typedef struct png_session {
  size_t allocated;  /* bytes libpng holds now */
  int over_budget;   /* an allocation was refused */
  char message[160]; /* libpng's last error */
} png_session;

/* ---- libpng callbacks ---- */

static void on_error(png_structp png, png_const_charp message) {
  png_session *session = (png_session *)png_get_error_ptr(png);
  if (session) snprintf(session->message, sizeof session->message, "%s", message);
  png_longjmp(png, 1);
}

static void on_warning(png_structp png, png_const_charp message) {
  (void)png;
  (void)message; /* libpng's warnings are never printed */
}

/* An allocation header keeps the size for the budget (16 bytes: malloc's
 * alignment). */
typedef union block_header {
  size_t size;
  max_align_t align;
} block_header;

static png_voidp budget_malloc(png_structp png, png_alloc_size_t size) {
  png_session *session = (png_session *)png_get_mem_ptr(png);
  if (size > LIBPNG_BUDGET - session->allocated) {
    session->over_budget = 1;
    return NULL;
  }
  block_header *block = malloc(sizeof(block_header) + size);
  if (!block) return NULL;
  block->size = size;
  session->allocated += size;
  return block + 1;
}

static void budget_free(png_structp png, png_voidp pointer) {
  if (!pointer) return;
  png_session *session = (png_session *)png_get_mem_ptr(png);
  block_header *block = (block_header *)pointer - 1;
  session->allocated -= block->size;
  free(block);
}

/* ---- EXIF (OpenImageIO 2.4: png_pvt.h read_info, exif.cpp decode_exif) ---- */

/* decode_exif: a block may start with "Exif\0\0"; the TIFF structure
 * follows. */
static void exif_block(const unsigned char *bytes, size_t size, cf_image_info *info) {
  if (size >= 6 && memcmp(bytes, "Exif\0\0", 6) == 0) {
    bytes += 6;
    size -= 6;
  }
  image_exif_read(bytes, size, info);
}

static int is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

static int hex_digit_value(char c) { /* png_pvt.h hex2int, even for a non-digit */
  return c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10;
}

static int is_hex_digit(char c) {
  return (c >= '0' && c <= '9') || ((c | 0x20) >= 'a' && (c | 0x20) <= 'f');
}

/* png_pvt.h decode_png_text_exif: blanks, "exif", a non-zero length,
 * blanks, then hex pairs (other characters skipped one at a time); the
 * bytes are EXIF when they start with "Exif" (any case). The length is
 * not used, as there. */
static void exif_from_text(const char *text, size_t length, cf_image_info *info) {
  const char *p = text, *end = text + length;
  while (p < end && is_blank(*p)) ++p;
  if (end - p < 4 || memcmp(p, "exif", 4) != 0) return;
  p += 4;
  char *after;
  if ((int)strtol(p, &after, 10) == 0 || after == p) return; /* Strutil::parse_int */
  p = after;
  while (p < end && is_blank(*p)) ++p;
  unsigned char *bytes = malloc((size_t)(end - p) / 2 + 1);
  if (!bytes) return;
  size_t count = 0;
  while (end - p >= 2) {
    if (!is_hex_digit(*p)) {
      ++p;
      continue;
    }
    bytes[count++] = (unsigned char)((hex_digit_value(p[0]) << 4) | hex_digit_value(p[1]));
    p += 2;
  }
  if (count >= 4 && (bytes[0] | 0x20) == 'e' && (bytes[1] | 0x20) == 'x' &&
      (bytes[2] | 0x20) == 'i' && (bytes[3] | 0x20) == 'f')
    exif_block(bytes, count, info);
  free(bytes);
}

static int key_is(const char *key, const char *name) { /* Strutil::iequals */
  for (; *key && *name; ++key, ++name)
    if ((*key | 0x20) != (*name | 0x20)) return 0;
  return *key == *name;
}

/* What the chunks before the image data say of the exposure: the eXIf
 * chunk, then the text chunks in file order, each over the last (the
 * order OpenImageIO 2.4.7 gives them, measured: test_image_png "both
 * EXIF"). */
static void exif_read(png_structp png, png_infop info_png, cf_image_info *info) {
  png_uint_32 size = 0;
  png_bytep exif = NULL;
  if (png_get_eXIf_1(png, info_png, &size, &exif) && exif) exif_block(exif, size, info);
  png_textp text = NULL;
  int count = png_get_text(png, info_png, &text, NULL);
  for (int i = 0; i < count; ++i)
    if (text[i].key && text[i].text && key_is(text[i].key, "Raw profile type exif"))
      exif_from_text(text[i].text,
                     text[i].compression >= PNG_ITXT_COMPRESSION_NONE ? text[i].itxt_length
                                                                      : text[i].text_length,
                     info);
}

/* ---- reading ---- */

/* The header and the transforms (read_info's): width, height, channels
 * and bits per sample after them. 0 or libpng's longjmp. */
static int read_header(png_structp png, png_infop info, png_uint_32 *width, png_uint_32 *height,
                       int *channels, int *bits) {
  if (setjmp(png_jmpbuf(png))) return -1;
  png_read_info(png, info);
  png_set_expand(png);
  const uint16_t probe = 1;
  if (*(const unsigned char *)&probe == 1) png_set_swap(png); /* samples in host order */
  png_set_interlace_handling(png);                            /* png_read_image's passes */
  png_read_update_info(png, info);
  int colour, interlace;
  png_get_IHDR(png, info, width, height, bits, &colour, &interlace, NULL, NULL);
  *channels = png_get_channels(png, info);
  return 0;
}

/* Every row into `rows`, then the chunks after the image data (their
 * CRCs checked; their contents dropped). 0 or libpng's longjmp. */
static int read_rows(png_structp png, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return -1;
  png_read_image(png, rows);
  png_read_end(png, NULL);
  return 0;
}

/* The stored samples of a checked header, scaled into image. */
static cf_status read_pixels(const char *path, png_structp png, png_infop info,
                             png_session *session, int bits, cf_image *image, cf_error *err) {
  const size_t row_values = (size_t)image->width * (size_t)image->channels;
  const size_t row_bytes = row_values * (size_t)(bits / 8);
  if (png_get_rowbytes(png, info) != row_bytes)
    return cf_error_set(err, CF_EIO, "%s: libpng's rows are %zu bytes, not the %zu expected", path,
                        (size_t)png_get_rowbytes(png, info), row_bytes);
  unsigned char *stored = malloc(row_bytes * (size_t)image->height);
  png_bytepp rows = malloc(sizeof(png_bytep) * (size_t)image->height);
  if (!stored || !rows) {
    free(stored);
    free(rows);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while decoding it", path);
  }
  for (int y = 0; y < image->height; ++y) rows[y] = stored + (size_t)y * row_bytes;
  cf_status status = CF_OK;
  if (read_rows(png, rows) != 0)
    status =
        cf_error_set(err, CF_EIO, "%s: a corrupt or truncated PNG: %s%s", path, session->message,
                     session->over_budget ? " (over clayfit's 64 MiB for libpng)" : "");
  else if (bits == 16)
    image_scale_u16((const uint16_t *)(const void *)stored, row_values * (size_t)image->height,
                    image->pixels);
  else
    image_scale_u8(stored, row_values * (size_t)image->height, image->pixels);
  free(rows);
  free(stored);
  return status;
}

/* image_png_read's body, with libpng's structures made. */
static cf_status read_png(const char *path, png_structp png, png_infop info, png_session *session,
                          int width, int height, cf_image_header *header, cf_image *image,
                          cf_error *err) {
  png_uint_32 w = 0, h = 0;
  int channels = 0, bits = 0;
  if (read_header(png, info, &w, &h, &channels, &bits) != 0)
    return cf_error_set(err, CF_EIO, "%s: a corrupt PNG header: %s", path, session->message);
  if (w > INT32_MAX || h > INT32_MAX) /* libpng refuses them already (PNG_USER_WIDTH_MAX) */
    return cf_error_set(err, CF_EPARSE, "%s: a PNG of %lu x %lu pixels", path, (unsigned long)w,
                        (unsigned long)h);
  cf_status status = image_header_accept(path, (int)w, (int)h, channels, width, height, err);
  if (status != CF_OK) return status;
  header->width = (int)w;
  header->height = (int)h;
  header->channels = channels;
  snprintf(header->info.format, sizeof header->info.format, "png");
  header->info.bits_per_sample = bits;
  header->info.is_float = 0;
  exif_read(png, info, &header->info);
  if (!image) return CF_OK;
  status = cf_image_alloc(image, (int)w, (int)h, channels, err);
  if (status != CF_OK) return cf_error_prefix(err, "%s", path), status;
  status = read_pixels(path, png, info, session, bits, image, err);
  if (status != CF_OK) cf_image_free(image);
  return status;
}

cf_status image_png_read(const char *path, FILE *file, long long size, int width, int height,
                         cf_image_header *header, cf_image *image, cf_error *err) {
  (void)size; /* the dispatcher walked the chunks against it */
  png_session session = {0};
  png_structp png = png_create_read_struct_2(PNG_LIBPNG_VER_STRING, &session, on_error, on_warning,
                                             &session, budget_malloc, budget_free);
  png_infop info = png ? png_create_info_struct(png) : NULL;
  if (!info) {
    png_destroy_read_struct(png ? &png : NULL, NULL, NULL);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory starting libpng", path);
  }
  png_set_chunk_malloc_max(png, PNG_USER_CHUNK_MALLOC_MAX); /* libpng's own: as OpenImageIO */
  png_set_chunk_cache_max(png, TEXT_CHUNKS_KEPT);
  png_init_io(png, file);
  cf_status status = read_png(path, png, info, &session, width, height, header, image, err);
  png_destroy_read_struct(&png, &info, NULL);
  return status;
}

/* ---- writing ---- */

/* One row of values as stored: 8 bits, or 16 bits big-endian. */
static void quantise_row(const float *values, size_t count, int bits, unsigned char *out) {
  if (bits == 8) {
    for (size_t i = 0; i < count; ++i) out[i] = image_quantize_u8(values[i]);
    return;
  }
  for (size_t i = 0; i < count; ++i) {
    const uint16_t v = image_quantize_u16(values[i]);
    out[2 * i] = (unsigned char)(v >> 8);
    out[2 * i + 1] = (unsigned char)(v & 0xff);
  }
}

/* The whole file through libpng into `file`; 0 or libpng's longjmp. */
static int write_rows(png_structp png, png_infop info, FILE *file, const cf_image *image, int bits,
                      unsigned char *row) {
  static const int colour[4] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                PNG_COLOR_TYPE_RGB_ALPHA};
  if (setjmp(png_jmpbuf(png))) return -1;
  png_init_io(png, file);
  png_set_compression_level(png, WRITE_LEVEL);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, bits == 8 ? PNG_FILTER_NONE : PNG_ALL_FILTERS);
  png_set_IHDR(png, info, (png_uint_32)image->width, (png_uint_32)image->height, bits,
               colour[image->channels - 1], PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  const size_t row_values = (size_t)image->width * (size_t)image->channels;
  for (int y = 0; y < image->height; ++y) {
    quantise_row(image->pixels + (size_t)y * row_values, row_values, bits, row);
    png_write_row(png, row);
  }
  png_write_end(png, NULL);
  return 0;
}

cf_status image_png_write(const char *path, const cf_image *image, int bits,
                          const cf_image_info *info, cf_error *err) {
  (void)info; /* OpenImageIO 2.4's PNG writer keeps no EXIF either */
  png_session session = {0};
  const size_t row_bytes = (size_t)image->width * (size_t)image->channels * (size_t)(bits / 8);
  unsigned char *row = malloc(row_bytes);
  png_structp png =
      row ? png_create_write_struct(PNG_LIBPNG_VER_STRING, &session, on_error, on_warning) : NULL;
  png_infop png_info = png ? png_create_info_struct(png) : NULL;
  if (!png_info) {
    png_destroy_write_struct(png ? &png : NULL, NULL);
    free(row);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory starting libpng", path);
  }
  cf_status status = CF_OK;
  FILE *file = fopen(path, "wb");
  if (!file) {
    status = cf_error_set(err, CF_EIO, "%s: cannot create the file: %s", path, strerror(errno));
  } else {
    const int failed = write_rows(png, png_info, file, image, bits, row);
    const int closed = fclose(file);
    if (failed || closed != 0)
      status = cf_error_set(err, CF_EIO, "%s: could not write the image%s%s", path,
                            failed ? ": " : " (closing it failed)", failed ? session.message : "");
  }
  png_destroy_write_struct(&png, &png_info);
  free(row);
  return status;
}
