/* PNG files for test_image_png: made with libpng (every colour type and
 * depth, Adam7, colour chunks, EXIF) and damaged byte by byte. */
#ifndef CLAYFIT_TEST_IMAGE_PNG_MAKE_H
#define CLAYFIT_TEST_IMAGE_PNG_MAKE_H

#include <stddef.h>
#include <stdint.h>

enum {
  MADE_COLOUR_CHUNKS = 1, /* gAMA, cHRM, sBIT, pHYs, tEXt */
  MADE_SRGB = 2,          /* sRGB (with libpng's gAMA and cHRM) */
  MADE_OFFS_ZERO = 4,     /* oFFs 0 0, as OpenImageIO writes */
  MADE_EXIF_CHUNK = 8,    /* eXIf: exposure 1/125 s, f/2.8, ISO 200 */
  MADE_EXIF_TEXT = 16,    /* zTXt "Raw profile type exif": 1/80 s, f/2.8, ISO 200 */
  MADE_OFFS = 32          /* oFFs 5 7 */
};

typedef struct png_made {
  const char *label;
  int width, height, bit_depth, colour, interlace;
  int trns;  /* a tRNS chunk (palette alphas, or a grey/RGB colour that occurs) */
  int flags; /* MADE_* */
} png_made;

/* Pseudo-random samples in the layout `made` says; 0 or -1. */
int png_make(const char *path, const png_made *made);

/* An EXIF block (TIFF structure, little-endian): exposure 1 / denominator
 * s, f/2.8, ISO 200; its size (84 bytes). */
size_t exif_block_make(unsigned char out[84], uint32_t denominator);

/* A file's bytes (malloc'd), or NULL. */
unsigned char *file_load(const char *path, size_t *size);
int file_save(const char *path, const unsigned char *bytes, size_t size);

/* The byte where the first chunk of that type starts (its length field),
 * or -1; a chunk's CRC recomputed over its type and data. */
long chunk_find(const unsigned char *bytes, size_t size, const char type[4]);
void chunk_fix_crc(unsigned char *bytes, long chunk);

/* `count` zTXt chunks, each inflating to `inflated` bytes, inserted after
 * the IHDR of the PNG at path (in place); 0 or -1. */
int png_add_text_bombs(const char *path, int count, size_t inflated);

#endif
