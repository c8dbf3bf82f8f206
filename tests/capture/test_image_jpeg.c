/* The JPEG codec (src/capture/image_jpeg.c) and the EXIF block
 * (image_exif.c) against OpenImageIO 2.4 (image_oiio_*), bit for bit:
 * decoding files OpenImageIO wrote (qualities x chroma x channels, odd
 * sizes) and files libjpeg wrote (progressive, CMYK, YCCK); encoding
 * (both writers' files decoded); the in-memory round trip the fit uses;
 * EXIF both ways, OpenImageIO reading ours, malformed blocks; hostile
 * files (truncated, corrupt, huge, too many scans). Prints the speeds on
 * a 612 x 512 image (a DiLiGenT photo when the data is there).
 * Usage: test_image_jpeg [shared-data-dir] */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <jpeglib.h>

#include "capture/image_codec.h"
#include "codec_support.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static char folder[256];

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static const char *chroma_name(cf_chroma c) {
  return c == CF_CHROMA_420 ? "4:2:0" : c == CF_CHROMA_422 ? "4:2:2" : "4:4:4";
}

/* A picture with edges, gradients and noise (all of a codec's cases). */
static cf_image picture(int width, int height, int channels, unsigned seed) {
  cf_image image = {0};
  cf_error err;
  CHECK(cf_image_alloc(&image, width, height, channels, &err) == CF_OK, "%s", err.message);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c) {
        seed = seed * 1664525u + 1013904223u;
        double v = 0.5 + 0.35 * sin(0.13 * x * (c + 1) + 0.09 * y) + ((x / 9 + y / 7) % 2) * 0.1;
        image.pixels[((size_t)y * width + x) * channels + c] =
            (float)(v + 0.08 * ((seed >> 8) / 16777216.0 - 0.5));
      }
  return image;
}

static int same_double(double a, double b) {
  return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

static int same_header(const cf_image_header *a, const cf_image_header *b) {
  return a->width == b->width && a->height == b->height && a->channels == b->channels &&
         strcmp(a->info.format, b->info.format) == 0 &&
         a->info.bits_per_sample == b->info.bits_per_sample &&
         a->info.is_float == b->info.is_float &&
         same_double(a->info.exposure_time, b->info.exposure_time) &&
         same_double(a->info.f_number, b->info.f_number) && same_double(a->info.iso, b->info.iso);
}

static int same_pixels(const cf_image *a, const cf_image *b) {
  return a->pixels && b->pixels && a->width == b->width && a->height == b->height &&
         a->channels == b->channels &&
         memcmp(a->pixels, b->pixels,
                sizeof(float) * (size_t)a->width * (size_t)a->height * (size_t)a->channels) == 0;
}

static cf_status oiio_read(const char *path, int width, int height, cf_image_header *header,
                           cf_image *image, cf_error *err) {
  codec_info_clear(&header->info);
  return image_oiio_read(path, width, height, header, image, err);
}

/* Both readers on one file: 1 when header and pixels are the same. */
static int read_both_equal(const char *path, const char *label) {
  cf_image_header ha, hb;
  cf_image a = {0}, b = {0};
  cf_error ea = {0}, eb = {0};
  cf_status sa = oiio_read(path, 0, 0, &ha, &a, &ea),
            sb = codec_read(image_jpeg_read, path, 0, 0, &hb, &b, &eb);
  int equal = sa == CF_OK && sb == CF_OK && same_header(&ha, &hb) && same_pixels(&a, &b);
  CHECK(equal,
        "%s: OpenImageIO %d (%s), ours %d (%s): header %d (%.9g s f/%.9g ISO %g vs %.9g s "
        "f/%.9g ISO %g), pixels %d",
        label, sa, ea.message, sb, eb.message, sa == CF_OK && sb == CF_OK && same_header(&ha, &hb),
        ha.info.exposure_time, ha.info.f_number, ha.info.iso, hb.info.exposure_time,
        hb.info.f_number, hb.info.iso, same_pixels(&a, &b));
  cf_image_free(&a);
  cf_image_free(&b);
  return equal;
}

/* ---- files written with libjpeg itself ---- */

typedef struct libjpeg_file {
  int progressive;             /* jpeg_simple_progression */
  J_COLOR_SPACE in, stored;    /* JCS_CMYK with JCS_CMYK or JCS_YCCK */
  const jpeg_scan_info *scans; /* a scan script of its own */
  int scan_count;
  const unsigned char *app1; /* an APP1 segment's body */
  unsigned app1_size;
} libjpeg_file;

/* The 8-bit samples of image (components of them) written by libjpeg. */
static void libjpeg_write(const char *path, const cf_image *image, int components,
                          const libjpeg_file *how) {
  struct jpeg_compress_struct c;
  struct jpeg_error_mgr e;
  c.err = jpeg_std_error(&e);
  jpeg_create_compress(&c);
  FILE *file = fopen(path, "wb");
  jpeg_stdio_dest(&c, file);
  c.image_width = (JDIMENSION)image->width, c.image_height = (JDIMENSION)image->height;
  c.input_components = components;
  c.in_color_space = how->in ? how->in : components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(&c);
  jpeg_set_quality(&c, 90, TRUE);
  if (how->stored) jpeg_set_colorspace(&c, how->stored);
  if (how->progressive) jpeg_simple_progression(&c);
  if (how->scans) c.scan_info = how->scans, c.num_scans = how->scan_count;
  jpeg_start_compress(&c, TRUE);
  if (how->app1) jpeg_write_marker(&c, JPEG_APP0 + 1, how->app1, how->app1_size);
  unsigned char *row = malloc((size_t)image->width * (size_t)components);
  for (int y = 0; y < image->height; ++y) {
    for (int x = 0; x < image->width; ++x)
      for (int k = 0; k < components; ++k)
        row[x * components + k] = image_quantize_u8(
            image->pixels[((size_t)y * image->width + x) * image->channels + k % image->channels]);
    jpeg_write_scanlines(&c, &row, 1);
  }
  jpeg_finish_compress(&c);
  jpeg_destroy_compress(&c);
  fclose(file);
  free(row);
}

/* ---- decoding ---- */

static const int kQualities[] = {50, 85, 95, 100};
static const cf_chroma kChromas[] = {CF_CHROMA_444, CF_CHROMA_422, CF_CHROMA_420};

static void test_decoding(void) {
  static const int sizes[][2] = {{61, 37}, {64, 48}, {1, 1}, {17, 130}};
  int files = 0, equal = 0;
  for (size_t s = 0; s < 4; ++s)
    for (int channels = 1; channels <= 3; channels += 2)
      for (size_t q = 0; q < 4; ++q)
        for (size_t k = 0; k < 3; ++k) {
          if (channels == 1 && k > 0) continue; /* greyscale has no chroma */
          cf_image image = picture(sizes[s][0], sizes[s][1], channels, (unsigned)(q * 7 + k));
          const char *path = codec_path(folder, "decode.jpg");
          cf_error err = {0};
          CHECK(image_oiio_write(path, &image, 8, NULL, kQualities[q], kChromas[k], &err) == CF_OK,
                "%s", err.message);
          char label[96];
          snprintf(label, sizeof label, "%dx%dx%d q%d %s", sizes[s][0], sizes[s][1], channels,
                   kQualities[q], chroma_name(kChromas[k]));
          equal += read_both_equal(path, label), ++files;
          cf_image_free(&image);
        }
  printf("decoding, OpenImageIO's files: %d of %d identical (header and pixels)\n", equal, files);
  cf_image image = picture(61, 37, 3, 5);
  static const struct {
    const char *name;
    libjpeg_file how;
    int components;
  } kinds[] = {{"progressive RGB", {.progressive = 1}, 3},
               {"progressive grey", {.progressive = 1}, 1},
               {"CMYK", {.in = JCS_CMYK, .stored = JCS_CMYK}, 4},
               {"YCCK", {.in = JCS_CMYK, .stored = JCS_YCCK}, 4},
               {"progressive YCCK", {.in = JCS_CMYK, .stored = JCS_YCCK, .progressive = 1}, 4}};
  for (size_t i = 0; i < sizeof kinds / sizeof *kinds; ++i) {
    const char *path = codec_path(folder, "libjpeg.jpg");
    libjpeg_write(path, &image, kinds[i].components, &kinds[i].how);
    printf("decoding, libjpeg's %s file: %s\n", kinds[i].name,
           read_both_equal(path, kinds[i].name) ? "identical" : "DIFFERENT");
  }
  cf_image_free(&image);
}

/* ---- encoding and the round trip ---- */

/* image written by both writers, each file read by OpenImageIO (and ours
 * read by ours): 1 when all the pixels agree. */
static int write_both_equal(const cf_image *image, int quality, cf_chroma chroma) {
  const char *theirs = codec_path(folder, "oiio.jpg"), *ours = codec_path(folder, "ours.jpg");
  cf_error err = {0};
  cf_status s = image_oiio_write(theirs, image, 8, NULL, quality, chroma, &err);
  if (s == CF_OK) s = image_jpeg_write(ours, image, quality, chroma, NULL, &err);
  CHECK(s == CF_OK, "%s", err.message);
  cf_image_header h;
  cf_image a = {0}, b = {0}, c = {0};
  s = oiio_read(theirs, 0, 0, &h, &a, &err);
  if (s == CF_OK) s = oiio_read(ours, 0, 0, &h, &b, &err);
  if (s == CF_OK) s = codec_read(image_jpeg_read, ours, 0, 0, &h, &c, &err);
  int equal = s == CF_OK && same_pixels(&a, &b) && same_pixels(&b, &c);
  CHECK(equal, "encoding %dx%dx%d q%d %s: %s", image->width, image->height, image->channels,
        quality, chroma_name(chroma), s == CF_OK ? "pixels differ" : err.message);
  cf_image_free(&a), cf_image_free(&b), cf_image_free(&c);
  return equal;
}

static int roundtrip_equal(const cf_image *image, int quality, cf_chroma chroma) {
  cf_image a = {0}, b = {0};
  cf_error err = {0};
  cf_status s = image_oiio_jpeg_roundtrip(image, quality, chroma, &a, &err);
  if (s == CF_OK) s = image_jpeg_roundtrip(image, quality, chroma, &b, &err);
  int equal = s == CF_OK && same_pixels(&a, &b);
  CHECK(equal, "round trip %dx%d q%d %s: %s", image->width, image->height, quality,
        chroma_name(chroma), s == CF_OK ? "pixels differ" : err.message);
  cf_image_free(&a), cf_image_free(&b);
  return equal;
}

static void test_encoding(void) {
  int cases = 0, encoded = 0, round = 0;
  for (int channels = 1; channels <= 4; ++channels)
    for (size_t q = 0; q < 4; ++q)
      for (size_t k = 0; k < 3; ++k) {
        cf_image image = picture(61, 37, channels, (unsigned)(channels * 100 + q * 3 + k));
        for (size_t i = 0; i < 61 * 37 * (size_t)channels; i += 97) /* out of [0, 1], NaN */
          image.pixels[i] = i % 3 == 0 ? -0.25f : i % 3 == 1 ? 1.5f : NAN;
        encoded += write_both_equal(&image, kQualities[q], kChromas[k]), ++cases;
        if (channels == 3) round += roundtrip_equal(&image, kQualities[q], kChromas[k]);
        cf_image_free(&image);
      }
  for (int quality = 1; quality <= 100; quality += 9) {
    cf_image image = picture(45, 29, 3, (unsigned)quality);
    round += roundtrip_equal(&image, quality, kChromas[quality % 3]);
    cf_image_free(&image);
  }
  printf("encoding (1-4 channels x 4 qualities x 3 chromas, decoded): %d of %d identical\n",
         encoded, cases);
  printf("round trip in memory vs image_oiio_jpeg_roundtrip: %d of %d identical\n", round, 12 + 12);
}

/* ---- EXIF ---- */

/* image_exif_write then image_exif_read: each value comes back as the
 * float OpenImageIO reads (exact for 1/64 and 0.5, which OpenImageIO's own
 * writer turns into infinity). */
static void test_exif_values(void) {
  static const double times[] = {1.0 / 125, 1.0 / 64, 0.5,      1.0 / 50, 30.0,   1.0 / 8000,
                                 1.0 / 3,   2.5,      1.0 / 80, 1e-9,     4000.0, 1.0 / 3000};
  static const double fs[] = {5.6, 2.8, 1.4, 22.0, 4.0, 7.1};
  static const double isos[] = {100, 400, 12800, 50, 204800, 3};
  int checked = 0;
  for (int as_float = 0; as_float < 2; ++as_float)
    for (size_t i = 0; i < sizeof times / sizeof *times; ++i) {
      cf_image_info in, out;
      codec_info_clear(&in), codec_info_clear(&out);
      in.exposure_time = as_float ? (float)times[i] : times[i];
      in.f_number = as_float ? (float)fs[i % 6] : fs[i % 6];
      in.iso = isos[i % 6];
      unsigned char block[256];
      size_t size = image_exif_write(&in, block, sizeof block);
      image_exif_read(block, size, &out);
      CHECK(size > 0 && out.exposure_time == (float)in.exposure_time &&
                out.f_number == (float)in.f_number && out.iso == in.iso,
            "EXIF %.10g s f/%g ISO %g came back %.10g s f/%.10g ISO %g", in.exposure_time,
            in.f_number, in.iso, out.exposure_time, out.f_number, out.iso);
      ++checked;
    }
  cf_image_info none;
  codec_info_clear(&none);
  unsigned char block[256];
  CHECK(image_exif_write(&none, block, sizeof block) == 0, "no values, no block");
  printf("EXIF values written and read back as OpenImageIO's floats: %d settings\n", checked);
}

/* Our JPEG's EXIF as OpenImageIO reads it; and OpenImageIO's as ours does. */
static void test_exif_files(void) {
  static const double settings[][3] = {{1.0 / 125, 5.6, 100}, {1.0 / 64, 2.8, 400},
                                       {0.5, 8, 12800},       {1.0 / 50, 4, 200},
                                       {30, 11, 100},         {1.0 / 80, 4.5, 400}};
  cf_image image = picture(16, 8, 3, 1);
  printf("EXIF in a JPEG: written by ours / by OpenImageIO, read by OpenImageIO (s, f, ISO)\n");
  for (size_t i = 0; i < 6; ++i) {
    cf_image_info info;
    codec_info_clear(&info);
    info.exposure_time = settings[i][0], info.f_number = settings[i][1];
    info.iso = settings[i][2];
    const char *ours = codec_path(folder, "exif_ours.jpg"),
               *theirs = codec_path(folder, "exif_oiio.jpg");
    cf_error err = {0};
    cf_status s = image_jpeg_write(ours, &image, 90, CF_CHROMA_420, &info, &err);
    if (s == CF_OK) s = image_oiio_write(theirs, &image, 8, &info, 90, CF_CHROMA_420, &err);
    CHECK(s == CF_OK, "%s", err.message);
    cf_image_header a, b;
    CHECK(oiio_read(ours, 0, 0, &a, NULL, &err) == CF_OK, "%s", err.message);
    CHECK(a.info.exposure_time == (float)info.exposure_time &&
              a.info.f_number == (float)info.f_number && a.info.iso == info.iso,
          "OpenImageIO reads our %.6g s f/%g ISO %g as %.9g s f/%.9g ISO %g", info.exposure_time,
          info.f_number, info.iso, a.info.exposure_time, a.info.f_number, a.info.iso);
    printf("  %10.6g s f/%-4g ISO %-6g  ours: %.9g s f/%.9g ISO %g  OpenImageIO's: ",
           info.exposure_time, info.f_number, info.iso, a.info.exposure_time, a.info.f_number,
           a.info.iso);
    read_both_equal(ours, "our EXIF");
    read_both_equal(theirs, "OpenImageIO's EXIF");
    oiio_read(theirs, 0, 0, &b, NULL, &err);
    printf("%.9g s f/%.9g ISO %g\n", b.info.exposure_time, b.info.f_number, b.info.iso);
  }
  cf_image_free(&image);
}

/* A TIFF structure byte by byte: little (II) or big (MM) endian. */
typedef struct tiff_block {
  unsigned char b[160];
  int big;
} tiff_block;

static void put(tiff_block *t, size_t at, uint32_t v, int bytes) {
  for (int i = 0; i < bytes; ++i)
    t->b[at + (size_t)(t->big ? bytes - 1 - i : i)] = (unsigned char)(v >> (8 * i));
}

static void entry(tiff_block *t, size_t at, uint32_t tag, uint32_t type, uint32_t count,
                  uint32_t value) {
  put(t, at, tag, 2), put(t, at + 2, type, 2), put(t, at + 4, count, 4);
  put(t, at + 8, value, type == 3 && count <= 2 ? 2 : 4);
}

/* IFD0 at 8 with `n0` entries, the SubIFD at 40, rationals at 100+. */
static tiff_block block_base(int big) {
  tiff_block t;
  memset(&t, 0, sizeof t);
  t.big = big;
  memcpy(t.b, big ? "MM" : "II", 2);
  put(&t, 2, 42, 2), put(&t, 4, 8, 4);
  put(&t, 100, 1, 4), put(&t, 104, 250, 4); /* 1/250 */
  put(&t, 108, 71, 4), put(&t, 112, 10, 4); /* 7.1 */
  return t;
}

/* Blocks OpenImageIO reads too (compared, through a JPEG) and hostile ones
 * (ours only: OpenImageIO 2.4 reads outside some of them). */
static void test_exif_malformed(void) {
  cf_image image = picture(16, 8, 3, 2);
  for (int big = 0; big < 2; ++big)
    for (int variant = 0; variant < 6; ++variant) {
      tiff_block t = block_base(big);
      if (variant == 0) { /* the usual: IFD0 -> SubIFD */
        put(&t, 8, 1, 2), entry(&t, 10, 0x8769, 4, 1, 40);
        put(&t, 40, 3, 2), entry(&t, 42, 0x829A, 5, 1, 100), entry(&t, 54, 0x829D, 5, 1, 108);
        entry(&t, 66, 0x8827, 3, 1, 800);
      } else if (variant == 1) { /* the tags in IFD0, ISO as a LONG */
        put(&t, 8, 3, 2), entry(&t, 10, 0x829A, 5, 1, 100), entry(&t, 22, 0x829D, 5, 1, 108);
        entry(&t, 34, 0x8827, 4, 1, 1600);
      } else if (variant == 2) { /* ISO with 2 values, a zero denominator */
        put(&t, 8, 2, 2), entry(&t, 10, 0x8827, 3, 2, 640), entry(&t, 22, 0x829A, 5, 1, 116);
      } else if (variant == 3) { /* a zero time, an f-number as SHORT */
        put(&t, 120, 0, 4), put(&t, 124, 1, 4);
        put(&t, 8, 2, 2), entry(&t, 10, 0x829A, 5, 1, 120), entry(&t, 22, 0x829D, 3, 1, 8);
      } else if (variant == 4) { /* SRATIONAL time, LONG f-number, BYTE ISO */
        put(&t, 8, 3, 2), entry(&t, 10, 0x829A, 10, 1, 100), entry(&t, 22, 0x829D, 4, 1, 11);
        entry(&t, 34, 0x8827, 1, 1, 0), t.b[42] = 200;
      } else { /* 2 rationals, 3 ISO values */
        put(&t, 128, 3200, 2), put(&t, 130, 100, 2), put(&t, 132, 100, 2);
        put(&t, 8, 2, 2), entry(&t, 10, 0x829A, 5, 2, 100), entry(&t, 22, 0x8827, 3, 3, 128);
      }
      unsigned char app1[6 + sizeof t.b];
      memcpy(app1, "Exif\0\0", 6), memcpy(app1 + 6, t.b, sizeof t.b);
      const char *path = codec_path(folder, "exif_block.jpg");
      libjpeg_write(path, &image, 3, &(libjpeg_file){.app1 = app1, .app1_size = sizeof app1});
      char label[64];
      snprintf(label, sizeof label, "EXIF block %d (%s)", variant, big ? "MM" : "II");
      read_both_equal(path, label);
    }
  /* hostile: each read without a value and without reading outside */
  int hostile = 0;
  for (int variant = 0; variant < 7; ++variant) {
    tiff_block t = block_base(0);
    size_t size = sizeof t.b;
    if (variant == 0) put(&t, 4, 0xfffffff0u, 4); /* IFD0 far outside */
    if (variant == 1) put(&t, 8, 1, 2), entry(&t, 10, 0x829A, 5, 1, 0xfffffffcu);   /* value out */
    if (variant == 2) put(&t, 8, 1, 2), entry(&t, 10, 0x829A, 5, 0x40000000u, 100); /* huge count */
    if (variant == 3) { /* IFD0 and the SubIFD pointing at each other, and at themselves */
      put(&t, 8, 2, 2), entry(&t, 10, 0x8769, 4, 1, 40), entry(&t, 22, 0x8769, 4, 1, 8);
      put(&t, 40, 2, 2), entry(&t, 42, 0x8769, 4, 1, 8), entry(&t, 54, 0xA005, 4, 1, 40);
    }
    if (variant == 4) put(&t, 8, 0xffff, 2);                              /* 65535 entries */
    if (variant == 5) put(&t, 8, 1, 2), entry(&t, 10, 0x8769, 4, 1, 159); /* SubIFD at the end */
    if (variant == 6) size = 7; /* shorter than a header */
    cf_image_info info;
    codec_info_clear(&info);
    image_exif_read(t.b, size, &info);
    hostile += isnan(info.exposure_time) && isnan(info.f_number) && isnan(info.iso);
  }
  CHECK(hostile == 7, "%d of 7 hostile EXIF blocks gave no value", hostile);
  printf("EXIF: 12 odd blocks compared with OpenImageIO; %d of 7 hostile blocks read to nothing\n",
         hostile);
  cf_image_free(&image);
}

/* ---- hostile files ---- */

static unsigned char *file_bytes(const char *path, size_t *size) {
  FILE *f = fopen(path, "rb");
  fseek(f, 0, SEEK_END);
  *size = (size_t)ftell(f);
  rewind(f);
  unsigned char *bytes = malloc(*size);
  *size = fread(bytes, 1, *size, f);
  fclose(f);
  return bytes;
}

static void file_put(const char *path, const unsigned char *bytes, size_t size) {
  FILE *f = fopen(path, "wb");
  fwrite(bytes, 1, size, f);
  fclose(f);
}

/* The start of the first scan's data (after SOS's header). */
static size_t scan_start(const unsigned char *b, size_t size) {
  for (size_t i = 2; i + 4 < size; i += 2 + ((size_t)b[i + 2] << 8 | b[i + 3]))
    if (b[i] == 0xff && b[i + 1] == 0xda) return i + 2 + ((size_t)b[i + 2] << 8 | b[i + 3]);
  return 0;
}

/* Both readers on a damaged file: ours must fail (CF_EIO naming it). */
static void refused(const char *path, const char *what, cf_status want) {
  cf_image_header h;
  cf_image a = {0}, b = {0};
  cf_error ea = {0}, eb = {0};
  cf_status sa = oiio_read(path, 0, 0, &h, &a, &ea),
            sb = codec_read(image_jpeg_read, path, 0, 0, &h, &b, &eb);
  CHECK(sb == want && strstr(eb.message, path) && !b.pixels, "%s: ours gave %d (%s)", what, sb,
        eb.message);
  printf("  %-34s OpenImageIO: %s; ours: %s\n", what, sa == CF_OK ? "read it" : "refused",
         eb.message + strlen(path) + 2);
  cf_image_free(&a);
  cf_image_free(&b);
}

static void test_hostile(void) {
  cf_image image = picture(64, 48, 3, 9);
  const char *good = codec_path(folder, "good.jpg"), *bad = codec_path(folder, "bad.jpg");
  cf_error err = {0};
  CHECK(image_jpeg_write(good, &image, 90, CF_CHROMA_420, NULL, &err) == CF_OK, "%s", err.message);
  size_t size;
  unsigned char *bytes = file_bytes(good, &size), *copy = malloc(size + 64);
  const size_t scan = scan_start(bytes, size);
  CHECK(scan > 0, "no scan in our JPEG");
  printf("damaged files:\n");
  file_put(bad, bytes, scan + (size - scan) / 2);
  refused(bad, "truncated in its scan", CF_EIO);
  file_put(bad, bytes, size - 2);
  refused(bad, "without its EOI marker", CF_EIO);
  memcpy(copy, bytes, size);
  for (size_t i = scan + 40; i < scan + 60; i += 2) copy[i] = 0xff, copy[i + 1] = 0xd3;
  file_put(bad, copy, size);
  refused(bad, "corrupt entropy data (markers)", CF_EIO);
  memcpy(copy, bytes, size - 2);
  memcpy(copy + size - 2, "garbage!", 8), copy[size + 6] = 0xff, copy[size + 7] = 0xd9;
  file_put(bad, copy, size + 8);
  refused(bad, "extraneous bytes before EOI", CF_EIO);
  memcpy(copy, bytes, size);
  for (size_t i = 2; i + 8 < scan; i += 2 + ((size_t)copy[i + 2] << 8 | copy[i + 3]))
    if (copy[i] == 0xff && copy[i + 1] == 0xc0) /* SOF0: height, width at +5, +7 */
      copy[i + 5] = 0xff, copy[i + 6] = 0xdc, copy[i + 7] = 0xff, copy[i + 8] = 0xdc;
  file_put(bad, copy, size);
  double t0 = now();
  refused(bad, "SOF of 65500 x 65500", CF_ERANGE);
  printf("  (refused in %.1f ms)\n", 1e3 * (now() - t0));
  cf_image_header h;
  cf_image out = {0};
  CHECK(codec_read(image_jpeg_read, good, 63, 48, &h, &out, &err) == CF_EINVAL && !out.pixels,
        "another size expected: %s", err.message);
  CHECK(codec_read(image_jpeg_read, good, 64, 48, &h, &out, &err) == CF_OK && out.pixels, "%s",
        err.message);
  cf_image_free(&out);
  free(bytes), free(copy);
  cf_image_free(&image);
}

/* A greyscale file of 704 valid scans (each coefficient's 11 successive
 * approximation bits, one scan each): plain libjpeg's decoding time, and
 * ours refusing it. */
static void test_scans(void) {
  static jpeg_scan_info scans[704];
  int n = 0;
  for (int ah = 0; ah <= 10; ++ah) /* DC: first at bit 10, then refinements */
    scans[n++] = (jpeg_scan_info){1, {0}, 0, 0, ah == 0 ? 0 : 11 - ah, 10 - ah};
  for (int k = 1; k < 64; ++k)
    for (int ah = 0; ah <= 10; ++ah)
      scans[n++] = (jpeg_scan_info){1, {0}, k, k, ah == 0 ? 0 : 11 - ah, 10 - ah};
  cf_image image = picture(1024, 768, 1, 3);
  const char *path = codec_path(folder, "scans.jpg");
  libjpeg_write(path, &image, 1, &(libjpeg_file){.scans = scans, .scan_count = n});
  double t0 = now();
  struct jpeg_decompress_struct c;
  struct jpeg_error_mgr e;
  c.err = jpeg_std_error(&e);
  jpeg_create_decompress(&c);
  FILE *file = fopen(path, "rb");
  jpeg_stdio_src(&c, file);
  jpeg_read_header(&c, TRUE);
  jpeg_start_decompress(&c);
  unsigned char *row = malloc(c.output_width);
  while (c.output_scanline < c.output_height) jpeg_read_scanlines(&c, &row, 1);
  jpeg_finish_decompress(&c);
  jpeg_destroy_decompress(&c);
  fclose(file);
  free(row);
  double plain = now() - t0;
  t0 = now();
  cf_image_header h;
  cf_image out = {0};
  cf_error err = {0};
  cf_status s = codec_read(image_jpeg_read, path, 0, 0, &h, &out, &err);
  printf(
      "a 1024 x 768 file of %d scans: plain libjpeg decodes it in %.0f ms; ours: %s in %.0f "
      "ms\n",
      n, 1e3 * plain, err.message + strlen(path) + 2, 1e3 * (now() - t0));
  CHECK(s == CF_EIO && !out.pixels, "%d scans were decoded", n);
  cf_image_free(&image);
}

/* ---- speed ---- */

/* A 612 x 512 RGB picture: a DiLiGenT photo (16-bit linear) scaled and
 * sRGB-encoded-ish when the data is there, else a synthetic one. */
static cf_image speed_picture(const char *data) {
  char path[512];
  snprintf(path, sizeof path, "%s/diligent_ball/001.png", data ? data : "");
  cf_image image = {0};
  cf_image_header h;
  cf_error err;
  if (data && oiio_read(path, 0, 0, &h, &image, &err) == CF_OK && image.channels >= 3) {
    for (size_t i = 0; i < (size_t)image.width * image.height * image.channels; ++i)
      image.pixels[i] = powf(fminf(1.0f, 4.0f * image.pixels[i]), 1.0f / 2.2f);
    printf("speed on %s (612 x 512, brightened):\n", path);
    return image;
  }
  printf("speed on a synthetic 612 x 512 picture (no shared data):\n");
  return picture(612, 512, 3, 11);
}

static void test_speed(const char *data) {
  cf_image image = speed_picture(data);
  const char *path = codec_path(folder, "speed.jpg"),
             *theirs = codec_path(folder, "speed_oiio.jpg");
  enum { RUNS = 10 };
  double t[6] = {0};
  cf_error err;
  cf_image_header h;
  for (int r = 0; r < RUNS; ++r) {
    double t0 = now();
    image_oiio_write(theirs, &image, 8, NULL, 90, CF_CHROMA_420, &err);
    double t1 = now();
    image_jpeg_write(path, &image, 90, CF_CHROMA_420, NULL, &err);
    double t2 = now();
    cf_image a = {0}, b = {0}, c = {0}, d = {0};
    oiio_read(path, 0, 0, &h, &a, &err);
    double t3 = now();
    codec_read(image_jpeg_read, path, 0, 0, &h, &b, &err);
    double t4 = now();
    image_oiio_jpeg_roundtrip(&image, 90, CF_CHROMA_420, &c, &err);
    double t5 = now();
    image_jpeg_roundtrip(&image, 90, CF_CHROMA_420, &d, &err);
    double t6 = now();
    t[0] += t1 - t0, t[1] += t2 - t1, t[2] += t3 - t2, t[3] += t4 - t3, t[4] += t5 - t4,
        t[5] += t6 - t5;
    cf_image_free(&a), cf_image_free(&b), cf_image_free(&c), cf_image_free(&d);
  }
  printf("  %-12s %14s %10s %8s\n", "", "OpenImageIO", "ours", "ratio");
  static const char *rows[] = {"write", "read", "round trip"};
  for (int i = 0; i < 3; ++i)
    printf("  %-12s %11.2f ms %7.2f ms %7.2fx\n", rows[i], 1e3 * t[2 * i] / RUNS,
           1e3 * t[2 * i + 1] / RUNS, t[2 * i] / t[2 * i + 1]);
  cf_image_free(&image);
}

int main(int argc, char **argv) {
  snprintf(folder, sizeof folder, "/tmp/test_image_jpeg_XXXXXX");
  if (!mkdtemp(folder)) {
    perror("mkdtemp");
    return 1;
  }
  struct stat st;
  const char *data = argc > 1 && stat(argv[1], &st) == 0 ? argv[1] : NULL;
  test_decoding();
  test_encoding();
  test_exif_values();
  test_exif_files();
  test_exif_malformed();
  test_hostile();
  test_scans();
  test_speed(data);
  char command[320];
  snprintf(command, sizeof command, "rm -rf '%s'", folder);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", folder);
  return check_finish("test_image_jpeg");
}
