/* The PNG codec (src/capture/image_png.c) against OpenImageIO 2.4, its
 * reference (image_oiio_read / image_oiio_write): bit-for-bit equal
 * pixels and header on every PNG in ../shared/data (DiLiGenT, uw_chrome),
 * on PNGs made here with libpng (palette, 1/2/4-bit grey, tRNS, Adam7,
 * colour chunks, EXIF) and with image_oiio_write (8/16 bits x 1-4
 * channels); files written by both writers decoded both ways; the
 * quantisation of floats to 8/16 bits; damaged files; and a printed (not
 * asserted) speed comparison. Usage: test_image_png [shared-data-dir] */
#include <dirent.h>
#include <math.h>
#include <png.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

#include "capture/image_codec.h"
#include "codec_support.h"
#include "support/check.h"
#include "test_image_png_make.h"

CHECK_MAIN_STATE;

/* AddressSanitizer keeps freed blocks (its quarantine, 256 MB): the peak
 * memory says nothing about what libpng held there. */
#if defined(__SANITIZE_ADDRESS__)
#define PEAK_MEANINGFUL 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PEAK_MEANINGFUL 0
#endif
#endif
#ifndef PEAK_MEANINGFUL
#define PEAK_MEANINGFUL 1
#endif

static char folder[256];
static int exif_available; /* image_exif_read reads EXIF (image_exif.c merged) */

/* A path in the temporary folder: one buffer per name, kept. */
static const char *temp_path(const char *name) {
  static char paths[32][320];
  static int count = 0;
  char path[320];
  snprintf(path, sizeof path, "%s/%s", folder, name);
  for (int i = 0; i < count; ++i)
    if (strcmp(paths[i], path) == 0) return paths[i];
  if (count == 32) abort();
  memcpy(paths[count], path, sizeof path);
  return paths[count++];
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static cf_status oiio_read(const char *path, cf_image_header *header, cf_image *image,
                           cf_error *err) {
  memset(header, 0, sizeof *header);
  codec_info_clear(&header->info);
  return image_oiio_read(path, 0, 0, header, image, err);
}

static int same_number(double a, double b) {
  return (isnan(a) && isnan(b)) || a == b;
}

/* Both readers on path: equal status, header, info and pixels (memcmp). */
static int compare_readers(const char *path, const char *label) {
  cf_image_header a, b;
  cf_image ia = {0}, ib = {0};
  cf_error ea = {0}, eb = {0};
  cf_status sa = codec_read(image_png_read, path, 0, 0, &a, &ia, &ea);
  cf_status sb = oiio_read(path, &b, &ib, &eb);
  CHECK(sa == CF_OK && sb == CF_OK, "%s: png %d (%s), oiio %d (%s)", label, sa, ea.message, sb,
        eb.message);
  int equal = 0;
  if (sa == CF_OK && sb == CF_OK) {
    int header_equal = a.width == b.width && a.height == b.height && a.channels == b.channels &&
                       strcmp(a.info.format, b.info.format) == 0 &&
                       a.info.bits_per_sample == b.info.bits_per_sample &&
                       a.info.is_float == b.info.is_float;
    int exif_equal = same_number(a.info.exposure_time, b.info.exposure_time) &&
                     same_number(a.info.f_number, b.info.f_number) &&
                     same_number(a.info.iso, b.info.iso);
    size_t n = (size_t)a.width * (size_t)a.height * (size_t)a.channels;
    int pixels_equal = header_equal && memcmp(ia.pixels, ib.pixels, n * sizeof(float)) == 0;
    CHECK(header_equal, "%s: header %dx%dx%d %s %d bits vs %dx%dx%d %s %d bits", label, a.width,
          a.height, a.channels, a.info.format, a.info.bits_per_sample, b.width, b.height,
          b.channels, b.info.format, b.info.bits_per_sample);
    CHECK(pixels_equal, "%s: pixels differ", label);
    CHECK(exif_equal || !exif_available, "%s: EXIF %g %g %g vs %g %g %g", label,
          a.info.exposure_time, a.info.f_number, a.info.iso, b.info.exposure_time, b.info.f_number,
          b.info.iso);
    equal = header_equal && pixels_equal && (exif_equal || !exif_available);
    printf("  %-34s %4d x %-4d x %d %2d bits  exposure %-8.4g %s\n", label, a.width, a.height,
           a.channels, a.info.bits_per_sample, b.info.exposure_time, equal ? "equal" : "DIFFERENT");
  }
  cf_image_free(&ia);
  cf_image_free(&ib);
  return equal;
}

/* ---- the real files ---- */

static int compare_folder(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  int count = 0;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    size_t n = strlen(e->d_name);
    if (n < 5 || strcmp(e->d_name + n - 4, ".png") != 0) continue;
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    count += compare_readers(path, e->d_name);
  }
  closedir(d);
  return count;
}

/* ---- PNGs made with libpng: every colour type, depth and chunk ---- */

static void libpng_cases(void) {
  static const png_made cases[] = {
      {"palette 8-bit", 29, 17, 8, PNG_COLOR_TYPE_PALETTE, 0, 0, 0},
      {"palette 4-bit", 29, 17, 4, PNG_COLOR_TYPE_PALETTE, 0, 0, 0},
      {"palette 2-bit", 29, 17, 2, PNG_COLOR_TYPE_PALETTE, 0, 0, 0},
      {"palette 1-bit", 29, 17, 1, PNG_COLOR_TYPE_PALETTE, 0, 0, 0},
      {"palette 8-bit + tRNS", 29, 17, 8, PNG_COLOR_TYPE_PALETTE, 0, 1, 0},
      {"palette 2-bit + tRNS", 29, 17, 2, PNG_COLOR_TYPE_PALETTE, 0, 1, 0},
      {"grey 1-bit", 29, 17, 1, PNG_COLOR_TYPE_GRAY, 0, 0, 0},
      {"grey 2-bit", 29, 17, 2, PNG_COLOR_TYPE_GRAY, 0, 0, 0},
      {"grey 4-bit", 29, 17, 4, PNG_COLOR_TYPE_GRAY, 0, 0, 0},
      {"grey 8-bit", 29, 17, 8, PNG_COLOR_TYPE_GRAY, 0, 0, 0},
      {"grey 16-bit", 29, 17, 16, PNG_COLOR_TYPE_GRAY, 0, 0, 0},
      {"grey 2-bit + tRNS", 29, 17, 2, PNG_COLOR_TYPE_GRAY, 0, 1, 0},
      {"grey 8-bit + tRNS", 29, 17, 8, PNG_COLOR_TYPE_GRAY, 0, 1, 0},
      {"grey 16-bit + tRNS", 29, 17, 16, PNG_COLOR_TYPE_GRAY, 0, 1, 0},
      {"grey+alpha 8-bit", 29, 17, 8, PNG_COLOR_TYPE_GRAY_ALPHA, 0, 0, 0},
      {"grey+alpha 16-bit", 29, 17, 16, PNG_COLOR_TYPE_GRAY_ALPHA, 0, 0, 0},
      {"RGB 8-bit + tRNS", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 1, 0},
      {"RGB 16-bit + tRNS", 29, 17, 16, PNG_COLOR_TYPE_RGB, 0, 1, 0},
      {"RGBA 16-bit", 29, 17, 16, PNG_COLOR_TYPE_RGB_ALPHA, 0, 0, 0},
      {"RGB 8-bit, gAMA cHRM sBIT pHYs tEXt", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0,
       MADE_COLOUR_CHUNKS},
      {"RGB 16-bit, sRGB", 29, 17, 16, PNG_COLOR_TYPE_RGB, 0, 0, MADE_SRGB},
      {"Adam7 RGB 8-bit", 29, 17, 8, PNG_COLOR_TYPE_RGB, 1, 0, 0},
      {"Adam7 RGBA 16-bit", 29, 17, 16, PNG_COLOR_TYPE_RGB_ALPHA, 1, 0, 0},
      {"Adam7 grey 1-bit", 29, 17, 1, PNG_COLOR_TYPE_GRAY, 1, 0, 0},
      {"Adam7 palette 4-bit + tRNS", 29, 17, 4, PNG_COLOR_TYPE_PALETTE, 1, 1, 0},
      {"Adam7 grey 16-bit, 3 x 2", 3, 2, 16, PNG_COLOR_TYPE_GRAY, 1, 0, 0},
      {"oFFs 0 0 (as OpenImageIO writes)", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0, MADE_OFFS_ZERO},
      {"eXIf chunk", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0, MADE_EXIF_CHUNK},
      {"zTXt Raw profile type exif", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0, MADE_EXIF_TEXT},
      {"both EXIF (the text wins)", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0,
       MADE_EXIF_TEXT | MADE_EXIF_CHUNK},
  };
  printf("PNGs made with libpng:\n");
  int equal = 0, total = (int)(sizeof cases / sizeof cases[0]);
  for (int i = 0; i < total; ++i) {
    const char *path = temp_path("made.png");
    CHECK(png_make(path, &cases[i]) == 0, "%s: could not make it", cases[i].label);
    equal += compare_readers(path, cases[i].label);
  }
  printf("  %d of %d equal\n", equal, total);
}

/* oFFs 5 7: OpenImageIO 2.4 makes it the data window's origin, which
 * image_oiio_read refuses as a partial image; image_png_read reads the
 * whole image, the pixels of the same file without the chunk. */
static void offset_case(void) {
  const png_made with = {"oFFs 5 7", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0, MADE_OFFS};
  const png_made without = {"no oFFs", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0, 0};
  const char *a = temp_path("offset.png"), *b = temp_path("no_offset.png");
  png_make(a, &with);
  png_make(b, &without);
  cf_image_header h1, h2;
  cf_image ia = {0}, ib = {0};
  cf_error err = {0};
  CHECK(codec_read(image_png_read, a, 0, 0, &h1, &ia, &err) == CF_OK, "oFFs 5 7: %s", err.message);
  CHECK(oiio_read(b, &h2, &ib, &err) == CF_OK, "%s", err.message);
  int equal =
      ia.pixels && ib.pixels && memcmp(ia.pixels, ib.pixels, sizeof(float) * 29 * 17 * 3) == 0;
  CHECK(equal, "oFFs 5 7: other pixels than the file without it");
  cf_image_header h3;
  cf_status theirs = oiio_read(a, &h3, NULL, &err);
  printf("  %-34s read whole here (%s); image_oiio_read: %s\n", "oFFs 5 7",
         equal ? "equal" : "DIFFERENT", theirs == CF_OK ? "read" : cf_status_name(theirs));
  cf_image_free(&ia);
  cf_image_free(&ib);
}

/* An image with every kind of value: a gradient, out of range, not
 * finite (OpenImageIO's quantisation of 0x1.0101p-9 depends on the
 * value's place, see quantisation_sweep: left out here). */
static void fill_test_image(cf_image *image) {
  static const float special[] = {
      -0.5f, -0.0f, 1.5f, 1e30f, NAN, INFINITY, -INFINITY, 0.5f / 65535.0f, 254.5f / 255.0f, 1.0f};
  size_t n = (size_t)image->width * image->height * image->channels;
  for (size_t i = 0; i < n; ++i)
    image->pixels[i] =
        i % 7 == 3 ? special[(i / 7) % 10] : (float)((i * 2654435761u) % 100003) / 100002.0f;
}

/* PNGs from image_oiio_write, and ours against it. */
static void writer_cases(void) {
  printf("PNGs written by OpenImageIO and by image_png_write, read both ways:\n");
  for (int bits = 8; bits <= 16; bits += 8)
    for (int channels = 1; channels <= 4; ++channels) {
      cf_image image = {0};
      cf_error err = {0};
      cf_image_alloc(&image, 37, 23, channels, &err);
      fill_test_image(&image);
      const char *theirs = temp_path("theirs.png"), *ours = temp_path("ours.png");
      char label[64];
      snprintf(label, sizeof label, "OIIO-written %d-bit x %d", bits, channels);
      CHECK(image_oiio_write(theirs, &image, bits, NULL, 0, CF_CHROMA_444, &err) == CF_OK, "%s",
            err.message);
      compare_readers(theirs, label);
      CHECK(image_png_write(ours, &image, bits, NULL, &err) == CF_OK, "%s", err.message);
      snprintf(label, sizeof label, "ours %d-bit x %d", bits, channels);
      compare_readers(ours, label);
      cf_image_header h1, h2;
      cf_image a = {0}, b = {0};
      CHECK(codec_read(image_png_read, ours, 0, 0, &h1, &a, &err) == CF_OK &&
                codec_read(image_png_read, theirs, 0, 0, &h2, &b, &err) == CF_OK,
            "%s", err.message);
      CHECK(a.pixels && b.pixels &&
                memcmp(a.pixels, b.pixels, sizeof(float) * 37 * 23 * (size_t)channels) == 0,
            "%s: our file decodes to other pixels than OpenImageIO's", label);
      cf_image_free(&a);
      cf_image_free(&b);
      cf_image_free(&image);
    }
}

/* ---- quantisation ---- */

static size_t sweep_values(int bits, float *out) {
  const double max = bits == 8 ? 255.0 : 65535.0;
  size_t n = 0;
  for (int k = 0; k <= (int)max; ++k) {
    const float exact = (float)(k / max), half = (float)((k + 0.5) / max);
    const float list[6] = {exact, nextafterf(exact, -1.0f), nextafterf(exact, 2.0f),
                           half,  nextafterf(half, -1.0f),  nextafterf(half, 2.0f)};
    for (int i = 0; i < 6; ++i) out[n++] = list[i];
  }
  static const float special[] = {-0.0f,        -1e-9f,         -0.5f, -1.0f, 1.0000001f, 1.5f,
                                  1e30f,        -1e30f,         NAN,   -NAN,  INFINITY,   -INFINITY,
                                  0x1.0101p-9f, 0x1.0000fep-17f};
  for (size_t i = 0; i < sizeof special / sizeof special[0]; ++i) out[n++] = special[i];
  return n;
}

/* image_quantize_u8/_u16 against what image_oiio_write stores, on every
 * k/max, (k + 0.5)/max and their float neighbours, in two layouts (one
 * value per row; 612 x 3 per row). The one float whose product with 255
 * is 0.5 - 2^-25 (0x1.0101p-9, the float nearest 0.5/255) is stored by
 * OpenImageIO 2.4 as 0 in its SIMD loop (roundf) and as 1 in its scalar
 * tail (+0.5 then truncation), whose place in a row depends on the
 * thread count (OPENIMAGEIO_THREADS): clayfit stores 0 (it is below
 * 0.5/255); no float times 65535 lands there. */
static void quantisation_sweep(void) {
  printf("quantisation sweep (image_quantize_u8/_u16 vs OpenImageIO's stored values):\n");
  float *values = malloc(sizeof(float) * 6 * 65536 + 256);
  for (int bits = 8; bits <= 16; bits += 8) {
    size_t n = sweep_values(bits, values);
    const int widths[2][2] = {{1, 1}, {612, 3}};
    for (int layout = 0; layout < 2; ++layout) {
      int w = widths[layout][0], c = widths[layout][1];
      int per_row = w * c, h = (int)((n + (size_t)per_row - 1) / (size_t)per_row);
      cf_image image = {0}, back = {0};
      cf_image_header header;
      cf_error err = {0};
      cf_image_alloc(&image, w, h, c, &err);
      memcpy(image.pixels, values, n * sizeof(float));
      const char *path = temp_path("sweep.png");
      CHECK(image_oiio_write(path, &image, bits, NULL, 0, CF_CHROMA_444, &err) == CF_OK, "%s",
            err.message);
      CHECK(oiio_read(path, &header, &back, &err) == CF_OK, "%s", err.message);
      size_t differ = 0, ambiguous = 0;
      for (size_t i = 0; back.pixels && i < n; ++i) {
        float ours;
        if (bits == 8) {
          uint8_t q = image_quantize_u8(values[i]);
          image_scale_u8(&q, 1, &ours);
        } else {
          uint16_t q = image_quantize_u16(values[i]);
          image_scale_u16(&q, 1, &ours);
        }
        if (memcmp(&ours, &back.pixels[i], sizeof ours) == 0) continue;
        if (bits == 8 && values[i] == 0x1.0101p-9f && back.pixels[i] == 1.0f / 255.0f) {
          ++ambiguous;
          continue;
        }
        ++differ;
        CHECK(0, "%d bits: %a stored as %.9g by OpenImageIO, %.9g here", bits, values[i],
              back.pixels[i] * (bits == 8 ? 255.0 : 65535.0), ours * (bits == 8 ? 255.0 : 65535.0));
      }
      printf(
          "  %2d bits, %4d x %d per row: %zu values, %zu differ, %zu of 0x1.0101p-9 stored "
          "as 1 by OpenImageIO (0 here)\n",
          bits, w, c, n, differ, ambiguous);
      cf_image_free(&image);
      cf_image_free(&back);
    }
  }
  /* no float near 0.5/65535 has 0.5 - 2^-25 (the float below 0.5) as its product */
  float v = 0.5f / 65535.0f;
  for (int i = 0; i < 1000; ++i) v = nextafterf(v, 0.0f);
  for (int i = 0; i < 2000; ++i, v = nextafterf(v, 1.0f)) {
    const float p = v * 65535.0f;
    CHECK(p != 0x1.fffffep-2f, "%a x 65535 = %a", v, p);
  }
  free(values);
}

/* ---- damaged files, hostile chunks ---- */

/* stderr sent to a file while the codec runs: libpng must print nothing. */
static int saved_stderr = -1;
static void quiet_begin(void) {
  fflush(stderr);
  saved_stderr = dup(2);
  FILE *f = freopen(temp_path("stderr.txt"), "w", stderr);
  (void)f;
}
static long quiet_end(void) {
  fflush(stderr);
  dup2(saved_stderr, 2);
  close(saved_stderr);
  struct stat st;
  return stat(temp_path("stderr.txt"), &st) == 0 ? (long)st.st_size : -1;
}

/* A damaged copy of `source`: `edit` applied to its bytes; the status
 * image_png_read gives it, with the error checked to name the file. */
typedef void (*damage)(unsigned char *bytes, size_t *size);
static cf_status read_damaged(const char *source, damage edit, const char *label) {
  size_t size;
  unsigned char *bytes = file_load(source, &size);
  const char *path = temp_path("damaged.png");
  edit(bytes, &size);
  file_save(path, bytes, size);
  free(bytes);
  cf_image_header header;
  cf_image image = {0};
  cf_error err = {0};
  quiet_begin();
  cf_status s = codec_read(image_png_read, path, 0, 0, &header, &image, &err);
  long printed = quiet_end();
  CHECK(printed == 0, "%s: %ld bytes printed on stderr", label, printed);
  CHECK(s == CF_OK || strstr(err.message, path) != NULL, "%s: error without the file: %s", label,
        err.message);
  CHECK(s == CF_OK || image.pixels == NULL, "%s: pixels left after an error", label);
  printf("  %-34s %-8s %s\n", label, cf_status_name(s), s == CF_OK ? "" : err.message);
  cf_image_free(&image);
  return s;
}

static void cut_after_ihdr(unsigned char *bytes, size_t *size) {
  (void)bytes;
  *size = 33;
}
static void idat_crc(unsigned char *bytes, size_t *size) {
  long at = chunk_find(bytes, *size, "IDAT");
  bytes[at + 8 + ((uint32_t)bytes[at + 2] << 8 | bytes[at + 3])] ^= 0x55;
}
static void text_crc(unsigned char *bytes, size_t *size) {
  long at = chunk_find(bytes, *size, "tEXt");
  bytes[at + 8 + bytes[at + 3]] ^= 0x55; /* a short chunk: its length is its last byte */
}
static void idat_block_type(unsigned char *bytes, size_t *size) {
  long at = chunk_find(bytes, *size, "IDAT");
  bytes[at + 10] = 0xff; /* the first deflate block: type 3, invalid */
  chunk_fix_crc(bytes, at);
}
static void zlib_header(unsigned char *bytes, size_t *size) {
  long at = chunk_find(bytes, *size, "IDAT");
  bytes[at + 8] = 0x00;
  chunk_fix_crc(bytes, at);
}
static void ihdr_huge(unsigned char *bytes, size_t *size) {
  (void)size;
  static const unsigned char huge[8] = {0, 1, 0x86, 0xa0, 0, 1, 0x86, 0xa0}; /* 100000 */
  memcpy(bytes + 16, huge, 8);
  chunk_fix_crc(bytes, 8);
}

static void error_cases(void) {
  printf("damaged PNGs:\n");
  const png_made base = {"RGB 8-bit, tEXt",  61, 40, 8,
                         PNG_COLOR_TYPE_RGB, 0,  0,  MADE_COLOUR_CHUNKS};
  const char *source = temp_path("base.png");
  png_make(source, &base);
  CHECK(read_damaged(source, cut_after_ihdr, "truncated after the IHDR") == CF_EIO, "truncated");
  CHECK(read_damaged(source, idat_crc, "IDAT CRC") == CF_EIO, "IDAT CRC");
  CHECK(read_damaged(source, idat_block_type, "IDAT deflate block type") == CF_EIO, "deflate");
  CHECK(read_damaged(source, zlib_header, "IDAT zlib header") == CF_EIO, "zlib header");
  CHECK(read_damaged(source, ihdr_huge, "IHDR 100000 x 100000") == CF_ERANGE, "huge");
  /* an ancillary chunk's bad CRC: libpng drops the chunk, as for OpenImageIO */
  CHECK(read_damaged(source, text_crc, "tEXt CRC (dropped)") == CF_OK, "tEXt CRC");
  compare_readers(temp_path("damaged.png"), "tEXt CRC, both readers");

  cf_image_header header;
  cf_image image = {0};
  cf_error err = {0};
  CHECK(codec_read(image_png_read, source, 10, 10, &header, &image, &err) == CF_EINVAL &&
            !image.pixels,
        "the wrong size expected: %s", err.message);
  printf("  %-34s %-8s %s\n", "10 x 10 expected", "EINVAL", err.message);
  CHECK(codec_read(image_png_read, source, 61, 40, &header, NULL, &err) == CF_OK &&
            header.width == 61,
        "the header alone: %s", err.message);
  cf_image_alloc(&image, 61, 40, 3, &err);
  quiet_begin();
  cf_status s = image_png_write("/dev/full", &image, 8, NULL, &err);
  CHECK(quiet_end() == 0, "writing to /dev/full printed");
  CHECK(s == CF_EIO && strstr(err.message, "/dev/full"), "/dev/full: %d %s", s, err.message);
  printf("  %-34s %-8s %s\n", "written to /dev/full", cf_status_name(s), err.message);
  cf_image_free(&image);
}

static long peak_kib(void) {
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

/* 100 zTXt chunks inflating to 4 MB each (OpenImageIO would hold 400 MB
 * of them): read within libpng's 64 MiB. */
static void hostile_text_chunks(void) {
  const png_made base = {"RGB 8-bit", 29, 17, 8, PNG_COLOR_TYPE_RGB, 0, 0, 0};
  const char *plain = temp_path("plain.png"), *bombed = temp_path("bombed.png");
  png_make(plain, &base);
  png_make(bombed, &base);
  CHECK(png_add_text_bombs(bombed, 100, 4000000) == 0, "could not make the text bombs");
  long before = peak_kib();
  double t = now();
  cf_image_header h1, h2;
  cf_image a = {0}, b = {0};
  cf_error err = {0};
  quiet_begin();
  cf_status s = codec_read(image_png_read, bombed, 0, 0, &h1, &a, &err);
  long printed = quiet_end();
  t = now() - t;
  long grown = peak_kib() - before;
  CHECK(s == CF_OK, "text bombs: %s", err.message);
  CHECK(printed == 0, "text bombs: %ld bytes on stderr", printed);
  CHECK(grown < 100 * 1024 || !PEAK_MEANINGFUL, "text bombs: the peak memory grew by %ld KiB",
        grown);
  CHECK(codec_read(image_png_read, plain, 0, 0, &h2, &b, &err) == CF_OK && a.pixels &&
            memcmp(a.pixels, b.pixels, sizeof(float) * 29 * 17 * 3) == 0,
        "text bombs: other pixels");
  printf("100 zTXt chunks of 4 MB inflated: read in %.2f s, peak memory +%ld KiB\n", t, grown);
  cf_image_free(&a);
  cf_image_free(&b);
}

/* ---- speed (printed, not asserted) ---- */

static void speed(const char *data) {
  double ours = 0.0, theirs = 0.0;
  int files = 0;
  cf_image first = {0};
  for (int i = 1; i <= 96; ++i) {
    char path[1024];
    snprintf(path, sizeof path, "%s/diligent_ball/%03d.png", data, i);
    cf_image_header header;
    cf_image image = {0};
    cf_error err = {0};
    double t = now();
    if (codec_read(image_png_read, path, 0, 0, &header, &image, &err) != CF_OK) continue;
    ours += now() - t;
    cf_image_free(&image);
    t = now();
    if (oiio_read(path, &header, i == 1 ? &first : &image, &err) != CF_OK) continue;
    theirs += now() - t;
    cf_image_free(&image);
    ++files;
  }
  printf("speed: %d DiLiGenT PNGs read in %.3f s (image_png_read), %.3f s (image_oiio_read)\n",
         files, ours, theirs);
  if (!first.pixels) return;
  size_t n = (size_t)first.width * first.height * 3;
  cf_image srgb = first;
  srgb.pixels = malloc(n * sizeof(float));
  for (size_t i = 0; i < n; ++i)
    srgb.pixels[i] = (float)cf_linear_to_srgb(fmin(1.0, 8.0 * first.pixels[i]));
  for (int bits = 8; bits <= 16; bits += 8) {
    const cf_image *image = bits == 8 ? &srgb : &first;
    const char *ours_path = temp_path("speed_ours.png"), *theirs_path = temp_path("speed_oiio.png");
    cf_error err = {0};
    double t = now();
    for (int r = 0; r < 3; ++r) image_png_write(ours_path, image, bits, NULL, &err);
    double t_ours = (now() - t) / 3;
    t = now();
    for (int r = 0; r < 3; ++r)
      image_oiio_write(theirs_path, image, bits, NULL, 0, CF_CHROMA_444, &err);
    double t_theirs = (now() - t) / 3;
    struct stat a, b;
    stat(ours_path, &a);
    stat(theirs_path, &b);
    printf(
        "speed: 612 x 512 RGB %2d-bit written in %.1f ms, %lld bytes (image_png_write); "
        "%.1f ms, %lld bytes (image_oiio_write)\n",
        bits, 1e3 * t_ours, (long long)a.st_size, 1e3 * t_theirs, (long long)b.st_size);
  }
  free(srgb.pixels);
  cf_image_free(&first);
}

int main(int argc, char **argv) {
  snprintf(folder, sizeof folder, "/tmp/test_image_png.XXXXXX");
  if (!mkdtemp(folder)) {
    perror("mkdtemp");
    return 1;
  }
  cf_image_info probe;
  codec_info_clear(&probe);
  unsigned char block[84];
  image_exif_read(block, exif_block_make(block, 125), &probe);
  exif_available = !isnan(probe.exposure_time);
  if (!exif_available)
    printf("EXIF: image_exif_read reads nothing yet; EXIF values not compared\n");

  hostile_text_chunks(); /* first: it measures the peak memory */
  libpng_cases();
  offset_case();
  writer_cases();
  quantisation_sweep();
  error_cases();

  const char *data = argc > 1 ? argv[1] : "";
  char dir[1024];
  snprintf(dir, sizeof dir, "%s/diligent_ball", data);
  struct stat st;
  if (!*data || stat(dir, &st) != 0) {
    printf("shared data absent (%s): the real PNGs skipped\n", *data ? dir : "no folder given");
  } else {
    printf("the real PNGs:\n");
    int equal = compare_folder(dir);
    snprintf(dir, sizeof dir, "%s/uw_chrome", data);
    equal += compare_folder(dir);
    printf("  %d real PNGs equal\n", equal);
    CHECK(equal >= 96, "only %d real PNGs compared equal", equal);
    speed(data);
  }
  char command[400];
  snprintf(command, sizeof command, "rm -rf '%s'", folder);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", folder);
  return check_finish("test_image_png");
}
