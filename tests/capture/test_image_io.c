/* The OpenImageIO adapter: every format written and read back (values,
 * orientation, what the file says about itself), EXIF exposure data,
 * errors that name the file, non-finite values, and — when ../shared/data
 * is there — the real DiLiGenT files (Shi et al., CVPR 2016): a 16-bit
 * linear PNG and the ground-truth normals as PFM (rows stored bottom to
 * top) against their PNG picture. Usage: test_image_io [shared-data-dir] */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clayfit/image.h"
#include "support/check.h"

/* OpenImageIO 2.4's PNG reader leaks one std::string (about 30 bytes)
 * on a truncated file: its read callback builds the message, then libpng
 * longjmps past the destructor. LeakSanitizer is told to look away for
 * that one read. */
#if defined(__SANITIZE_ADDRESS__)
#define HAVE_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HAVE_LSAN 1
#endif
#endif
#ifdef HAVE_LSAN
#include <sanitizer/lsan_interface.h>
#define OIIO_LEAK_BEGIN() __lsan_disable()
#define OIIO_LEAK_END() __lsan_enable()
#else
#define OIIO_LEAK_BEGIN() ((void)0)
#define OIIO_LEAK_END() ((void)0)
#endif

CHECK_MAIN_STATE;

enum { W = 32, H = 24, MARK_X = 3, MARK_Y = 1 };

static char folder[256];
static char made[64][320];
static int made_count = 0;

/* A path in the temporary folder, remembered for the clean-up. */
static const char *temp_path(const char *name) {
  if (made_count == 64) {
    fprintf(stderr, "too many temporary files\n");
    exit(1);
  }
  char *out = made[made_count++];
  snprintf(out, sizeof made[0], "%s/%s", folder, name);
  return out;
}

/* A smooth gradient in [0.05, 0.95] per channel, with a marker pixel
 * (1, 0, 1) at (MARK_X, MARK_Y) that no other pixel matches. */
static float base_value(int x, int y, int c, int channels) {
  if (x == MARK_X && y == MARK_Y) return c == 1 ? 0.0f : 1.0f;
  if (c == 3) return 0.25f + 0.5f * (float)x / (W - 1); /* alpha, partly transparent */
  if (channels == 1 || c == 0) return 0.05f + 0.9f * (float)x / (W - 1);
  if (c == 1) return 0.05f + 0.9f * (float)y / (H - 1);
  return 0.05f + 0.9f * (float)(x + y) / (W + H - 2);
}

/* The gradient, scaled and offset (float formats hold more than [0, 1]). */
static void make_gradient(cf_image *image, int channels, float scale, float offset) {
  cf_error err = {0};
  if (cf_image_alloc(image, W, H, channels, &err) != CF_OK) {
    fprintf(stderr, "%s\n", err.message);
    exit(1);
  }
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int c = 0; c < channels; ++c)
        image->pixels[(y * W + x) * channels + c] = scale * base_value(x, y, c, channels) + offset;
}

typedef enum precision { EXACT, HALF, RGBE, QUANTISED, LOSSY } precision;

typedef struct format_case {
  const char *name;
  int bits, channels;
  precision precision;
  float scale, offset;
  const char *format; /* OpenImageIO's name */
  int is_float, bits_read;
} format_case;

/* Error of b against a under the format's precision: absolute for EXACT,
 * QUANTISED and LOSSY, relative for HALF, relative to the pixel's largest
 * channel for RGBE (one shared exponent). */
static double value_error(precision p, const float *a, const float *b, int channels, int c) {
  double d = fabs((double)a[c] - (double)b[c]);
  if (p == HALF) return d / fmax(fabs((double)a[c]), 6.2e-5); /* half's smallest normal */
  if (p == RGBE) {
    double m = 0.0;
    for (int k = 0; k < channels; ++k) m = fmax(m, fabs((double)a[k]));
    return m > 0.0 ? d / m : d;
  }
  return d;
}

static void test_round_trips(void) {
  static const format_case cases[] = {
      {"float.exr", 32, 3, EXACT, 40.0f, -2.0f, "openexr", 1, 32},
      {"half.exr", 16, 3, HALF, 40.0f, -2.0f, "openexr", 1, 16},
      {"rgba.exr", 32, 4, EXACT, 1.0f, 0.0f, "openexr", 1, 32},
      {"rgbe.hdr", 32, 3, RGBE, 40.0f, 0.0f, "hdr", 1, 32},
      {"float.pfm", 32, 3, EXACT, 40.0f, -2.0f, "pnm", 1, 32},
      {"grey.pfm", 32, 1, EXACT, 40.0f, -2.0f, "pnm", 1, 32},
      {"8.png", 8, 3, QUANTISED, 1.0f, 0.0f, "png", 0, 8},
      {"16.png", 16, 3, QUANTISED, 1.0f, 0.0f, "png", 0, 16},
      {"rgba16.png", 16, 4, QUANTISED, 1.0f, 0.0f, "png", 0, 16},
      {"grey16.png", 16, 1, QUANTISED, 1.0f, 0.0f, "png", 0, 16},
      {"8.tif", 8, 3, QUANTISED, 1.0f, 0.0f, "tiff", 0, 8},
      {"16.tiff", 16, 3, QUANTISED, 1.0f, 0.0f, "tiff", 0, 16},
      {"rgba8.tif", 8, 4, QUANTISED, 1.0f, 0.0f, "tiff", 0, 8},
      {"8.jpg", 8, 3, LOSSY, 1.0f, 0.0f, "jpeg", 0, 8},
  };
  printf("%-11s %-8s %5s %4s  %-12s %-12s %s\n", "file", "format", "bits", "ch", "max error",
         "tolerance", "marker (3, 1)");
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
    const format_case *t = &cases[i];
    const char *path = temp_path(t->name);
    cf_image written, read;
    cf_image_info info;
    cf_error err = {0};
    make_gradient(&written, t->channels, t->scale, t->offset);
    cf_status s = cf_image_write(path, &written, t->bits, &err);
    CHECK(s == CF_OK, "write %s: %s", path, err.message);
    s = cf_image_read(path, &read, &info, &err);
    CHECK(s == CF_OK, "read %s: %s", path, err.message);
    if (s != CF_OK) {
      cf_image_free(&written);
      continue;
    }
    CHECK(read.width == W && read.height == H && read.channels == t->channels, "%s: %d x %d x %d",
          t->name, read.width, read.height, read.channels);
    CHECK(strcmp(info.format, t->format) == 0, "%s: format '%s', expected '%s'", t->name,
          info.format, t->format);
    CHECK(info.bits_per_sample == t->bits_read && info.is_float == t->is_float,
          "%s: %d bits, float %d", t->name, info.bits_per_sample, info.is_float);
    CHECK(isnan(info.exposure_time) && isnan(info.f_number) && isnan(info.iso),
          "%s: no EXIF written, read %g %g %g", t->name, info.exposure_time, info.f_number,
          info.iso);
    double tolerance = 0.0, worst = 0.0, sum = 0.0, off_grid = 0.0;
    const double levels = t->bits == 8 ? 255.0 : 65535.0;
    switch (t->precision) {
      case EXACT:
        tolerance = 0.0;
        break;
      case HALF: /* 11 significant bits, rounded */
        tolerance = 1.0 / 2048.0;
        break;
      case RGBE: /* 8-bit mantissas and one shared exponent: under 1/128 of the largest */
        tolerance = 0.01;
        break;
      case QUANTISED:
        tolerance = 0.5 / levels + 1e-7;
        break;
      case LOSSY:
        tolerance = 0.06;
        break;
    }
    if (read.width == W && read.height == H && read.channels == t->channels) {
      const size_t n = (size_t)W * H * (size_t)t->channels;
      for (size_t k = 0; k < n; k += (size_t)t->channels)
        for (int c = 0; c < t->channels; ++c) {
          double e = value_error(t->precision, written.pixels + k, read.pixels + k, t->channels, c);
          worst = fmax(worst, e);
          sum += e;
          if (t->precision == QUANTISED) {
            double q = read.pixels[k + (size_t)c] * levels;
            off_grid = fmax(off_grid, fabs(q - round(q)));
          }
        }
      const float *mark = read.pixels + (size_t)(MARK_Y * W + MARK_X) * (size_t)t->channels;
      const float *mirror = read.pixels + (size_t)((H - 1 - MARK_Y) * W + MARK_X) * t->channels;
      const float hi = t->scale + t->offset, lo = t->offset;
      const double slack = t->precision == LOSSY ? 0.25 * t->scale : 0.02 * t->scale;
      printf("%-11s %-8s %5d %4d  %-12.3g %-12.3g (%g, %g, %g)\n", t->name, info.format,
             info.bits_per_sample, read.channels, worst, tolerance, mark[0],
             t->channels > 1 ? mark[1] : mark[0], t->channels > 2 ? mark[2] : mark[0]);
      CHECK(fabs(mark[0] - hi) <= slack, "%s: marker red %g, expected %g", t->name, mark[0], hi);
      if (t->channels >= 3)
        CHECK(fabs(mark[1] - lo) <= slack && fabs(mark[2] - hi) <= slack,
              "%s: marker (%g, %g, %g) at (3, 1)", t->name, mark[0], mark[1], mark[2]);
      CHECK(fabs(mirror[0] - hi) > slack || (t->channels >= 3 && fabs(mirror[1] - lo) > slack),
            "%s: the marker also at the mirrored row", t->name);
      if (t->precision == LOSSY) {
        double mean = sum / (double)n;
        printf("%-11s mean error %.4g\n", "", mean);
        CHECK(mean < 0.01, "%s: mean error %g", t->name, mean);
      }
      if (t->precision == QUANTISED)
        /* OpenImageIO scales in float: k/65535 is within ~0.004/65535 of k */
        CHECK(off_grid < 1e-2, "%s: values off the 1/%g grid by %g", t->name, levels, off_grid);
      CHECK(worst <= tolerance, "%s: error %g > %g", t->name, worst, tolerance);
    }
    cf_image_free(&written);
    cf_image_free(&read);
  }
}

/* The PFM writer's file itself: Netpbm's header, little-endian floats
 * (negative scale), and rows from the bottom of the image up. */
static void test_pfm_layout(void) {
  cf_image image;
  cf_error err = {0};
  make_gradient(&image, 3, 40.0f, -2.0f);
  const char *path = temp_path("layout.pfm");
  CHECK(cf_image_write(path, &image, 32, &err) == CF_OK, "%s", err.message);
  static unsigned char bytes[64 + W * H * 3 * 4 + 64];
  FILE *f = fopen(path, "rb");
  size_t n = f ? fread(bytes, 1, sizeof bytes, f) : 0;
  if (f) fclose(f);
  char header[32];
  snprintf(header, sizeof header, "PF\n%d %d\n-1.0\n", W, H);
  const size_t h = strlen(header);
  CHECK(n == h + (size_t)W * H * 3 * 4, "layout.pfm has %zu bytes", n);
  CHECK(n >= h && memcmp(bytes, header, h) == 0, "PFM header '%.*s'", (int)h, (const char *)bytes);
  int bottom_first = n == h + (size_t)W * H * 3 * 4;
  for (int row = 0; bottom_first && row < H; ++row)
    for (int i = 0; i < W * 3; ++i) {
      const unsigned char *b = bytes + h + ((size_t)row * W * 3 + (size_t)i) * 4;
      uint32_t u =
          (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
      float v;
      memcpy(&v, &u, 4);
      if (v != image.pixels[(size_t)(H - 1 - row) * W * 3 + (size_t)i]) bottom_first = 0;
    }
  printf("layout.pfm: header as Netpbm's, little-endian rows bottom to top: %s\n",
         bottom_first ? "yes" : "no");
  CHECK(bottom_first, "the PFM file's rows are not the image's bottom to top");
  cf_image_free(&image);
}

static int exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

static int run(const char *command) {
  int status = system(command);
  return status;
}

static void test_exif(void) {
  cf_image image;
  cf_image_info info = {"", 0, 0, 1.0 / 125.0, 5.6, 400.0}, read_info;
  cf_error err = {0};
  make_gradient(&image, 3, 1.0f, 0.0f);
  const char *path = temp_path("exif.jpg");
  CHECK(cf_image_write_with_info(path, &image, 8, &info, &err) == CF_OK, "%s", err.message);
  cf_image back;
  CHECK(cf_image_read(path, &back, &read_info, &err) == CF_OK, "%s", err.message);
  printf("EXIF written by the adapter: exposure %.6g s, f/%.3g, ISO %g\n", read_info.exposure_time,
         read_info.f_number, read_info.iso);
  CHECK(fabs(read_info.exposure_time - 0.008) < 1e-3 * 0.008, "exposure time %g",
        read_info.exposure_time);
  CHECK(fabs(read_info.f_number - 5.6) < 1e-3 * 5.6, "f-number %g", read_info.f_number);
  CHECK(read_info.iso == 400.0, "ISO %g", read_info.iso);
  cf_image_free(&back);

  /* a file from another writer, with the older tag name ISOSpeedRatings */
  const char *png = temp_path("plain.png"), *jpg = temp_path("oiiotool.jpg");
  CHECK(cf_image_write(png, &image, 8, &err) == CF_OK, "%s", err.message);
  char command[1024];
  snprintf(command, sizeof command,
           "oiiotool '%s' --attrib ExposureTime 0.01 --attrib FNumber 2.8 "
           "--attrib Exif:ISOSpeedRatings 200 -o '%s' >/dev/null 2>&1",
           png, jpg);
  if (run(command) != 0) {
    printf("oiiotool is not available: skipping the EXIF file written by oiiotool\n");
  } else {
    CHECK(cf_image_read(jpg, &back, &read_info, &err) == CF_OK, "%s", err.message);
    printf("EXIF written by oiiotool: exposure %.6g s, f/%.3g, ISO %g\n", read_info.exposure_time,
           read_info.f_number, read_info.iso);
    CHECK(fabs(read_info.exposure_time - 0.01) < 1e-3 * 0.01, "exposure %g",
          read_info.exposure_time);
    CHECK(fabs(read_info.f_number - 2.8) < 1e-3 * 2.8, "f-number %g", read_info.f_number);
    CHECK(read_info.iso == 200.0, "ISO %g", read_info.iso);
    cf_image_free(&back);
  }
  /* absent metadata */
  CHECK(cf_image_read(png, &back, &read_info, &err) == CF_OK, "%s", err.message);
  CHECK(isnan(read_info.exposure_time) && isnan(read_info.f_number) && isnan(read_info.iso),
        "absent EXIF: %g %g %g", read_info.exposure_time, read_info.f_number, read_info.iso);
  cf_image_free(&back);
  cf_image_free(&image);
}

static uint32_t crc32_of(const unsigned char *data, size_t n) {
  uint32_t crc = 0xffffffffu;
  for (size_t i = 0; i < n; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xffffffffu;
}

static size_t put_chunk(unsigned char *out, const char *type, const unsigned char *data,
                        uint32_t n) {
  unsigned char *p = out;
  *p++ = (unsigned char)(n >> 24), *p++ = (unsigned char)(n >> 16);
  *p++ = (unsigned char)(n >> 8), *p++ = (unsigned char)n;
  memcpy(p, type, 4);
  if (n) memcpy(p + 4, data, n);
  uint32_t crc = crc32_of(p, 4 + (size_t)n);
  p += 4 + n;
  *p++ = (unsigned char)(crc >> 24), *p++ = (unsigned char)(crc >> 16);
  *p++ = (unsigned char)(crc >> 8), *p++ = (unsigned char)crc;
  return (size_t)(p - out);
}

static void write_bytes(const char *path, const void *data, size_t n) {
  FILE *f = fopen(path, "wb");
  if (!f || fwrite(data, 1, n, f) != n || fclose(f) != 0) {
    fprintf(stderr, "cannot write %s\n", path);
    exit(1);
  }
}

/* The read fails with `expected` and a message naming the file. */
static void expect_read_error(const char *path, cf_status expected, const char *also) {
  cf_image image;
  cf_image_info info;
  cf_error err = {0};
  cf_status s = cf_image_read(path, &image, &info, &err);
  printf("%s -> %s: %s\n", strrchr(path, '/') + 1, cf_status_name(s), err.message);
  CHECK(s == expected, "%s: status %s, expected %s", path, cf_status_name(s),
        cf_status_name(expected));
  CHECK(strstr(err.message, path) != NULL, "message does not name the file: %s", err.message);
  CHECK(!also || strstr(err.message, also), "message lacks '%s': %s", also, err.message);
  CHECK(image.pixels == NULL && image.width == 0, "an image left behind after an error");
  if (s == CF_OK) cf_image_free(&image);
}

static void test_errors(void) {
  cf_error err = {0};
  expect_read_error(temp_path("missing.png"), CF_ENOTFOUND, "no such file");

  /* a PNG cut short in its pixel data */
  const char *good = temp_path("noise.png"), *cut = temp_path("truncated.png");
  cf_image noise;
  cf_image_alloc(&noise, 128, 128, 3, &err);
  uint32_t state = 12345u;
  for (size_t i = 0; i < (size_t)128 * 128 * 3; ++i) {
    state = state * 1664525u + 1013904223u;
    noise.pixels[i] = (float)(state >> 8) / 16777216.0f;
  }
  CHECK(cf_image_write(good, &noise, 16, &err) == CF_OK, "%s", err.message);
  cf_image_free(&noise);
  FILE *f = fopen(good, "rb");
  static unsigned char bytes[1 << 18];
  size_t n = f ? fread(bytes, 1, sizeof bytes, f) : 0;
  if (f) fclose(f);
  CHECK(n > 1000, "noise.png has %zu bytes", n);
  write_bytes(cut, bytes, n / 2);
  OIIO_LEAK_BEGIN();
  expect_read_error(cut, CF_EIO, NULL);
  OIIO_LEAK_END();

  /* an empty file */
  const char *empty = temp_path("empty.png");
  write_bytes(empty, "", 0);
  expect_read_error(empty, CF_EIO, NULL);

  /* a text file named .exr */
  const char *text = temp_path("text.exr");
  const char *words = "This is not an image.\n";
  write_bytes(text, words, strlen(words));
  expect_read_error(text, CF_EIO, NULL);

  /* a PNG header claiming 50000 x 50000 RGB pixels: 7.5e9 values */
  unsigned char png[256];
  size_t at = 0;
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  memcpy(png, signature, 8);
  at = 8;
  const unsigned char ihdr[13] = {0, 0, 0xc3, 0x50, 0, 0, 0xc3, 0x50, 8, 2, 0, 0, 0};
  at += put_chunk(png + at, "IHDR", ihdr, 13);
  const unsigned char idat[8] = {0x78, 0x9c, 0x63, 0x60, 0x00, 0x00, 0x00, 0x04};
  at += put_chunk(png + at, "IDAT", idat, 8);
  at += put_chunk(png + at, "IEND", NULL, 0);
  const char *huge = temp_path("huge.png");
  write_bytes(huge, png, at);
  expect_read_error(huge, CF_ERANGE, "2^31");

  /* five channels */
  const char *five = temp_path("five.exr");
  char command[600];
  snprintf(command, sizeof command, "oiiotool --create 4x4 5 -d half -o '%s' >/dev/null 2>&1",
           five);
  if (run(command) == 0)
    expect_read_error(five, CF_EUNSUPPORTED, "5 channels");
  else
    printf("oiiotool is not available: skipping the five-channel file\n");

  /* cf_image_alloc and cf_image_write refuse what they cannot do */
  cf_image image;
  CHECK(cf_image_alloc(&image, 0, 4, 3, &err) == CF_EINVAL && image.pixels == NULL, "zero width");
  CHECK(cf_image_alloc(&image, 4, 4, 5, &err) == CF_EINVAL, "five channels");
  CHECK(cf_image_alloc(&image, 65536, 32768, 2, &err) == CF_EINVAL, "2^32 values");
  printf("alloc 65536 x 32768 x 2: %s\n", err.message);
  CHECK(strstr(err.message, "2^31") != NULL, "%s", err.message);
  make_gradient(&image, 3, 1.0f, 0.0f);
  const char *bmp = temp_path("gradient.bmp"), *png32 = temp_path("gradient32.png");
  CHECK(cf_image_write(bmp, &image, 8, &err) == CF_EINVAL && strstr(err.message, bmp),
        "unknown extension: %s", err.message);
  printf("write .bmp: %s\n", err.message);
  CHECK(cf_image_write(png32, &image, 32, &err) == CF_EINVAL && strstr(err.message, png32),
        "32-bit PNG: %s", err.message);
  printf("write 32-bit png: %s\n", err.message);
  CHECK(!exists(png32), "a refused write leaves no file");
  cf_image_free(&image);
  make_gradient(&image, 1, 1.0f, 0.0f);
  const char *grey_hdr = temp_path("grey.hdr");
  CHECK(cf_image_write(grey_hdr, &image, 32, &err) == CF_EINVAL, "one-channel HDR: %s",
        err.message);
  cf_image_free(&image);
}

static void test_non_finite(void) {
  cf_image image, back;
  cf_error err = {0};
  make_gradient(&image, 3, 1.0f, 0.0f);
  const char *clean = temp_path("clean.exr");
  CHECK(cf_image_check_finite(&image, clean, &err) == CF_OK, "clean image: %s", err.message);
  image.pixels[(2 * W + 5) * 3 + 1] = NAN;      /* (5, 2) green: the first */
  image.pixels[(7 * W + 1) * 3 + 0] = INFINITY; /* (1, 7) red */
  image.pixels[(9 * W + 9) * 3 + 2] = -INFINITY;
  const char *names[2] = {temp_path("nan_float.exr"), temp_path("nan_half.exr")};
  const int bits[2] = {32, 16};
  for (int i = 0; i < 2; ++i) {
    CHECK(cf_image_write(names[i], &image, bits[i], &err) == CF_OK, "%s", err.message);
    CHECK(cf_image_read(names[i], &back, NULL, &err) == CF_OK, "%s", err.message);
    if (!back.pixels) continue;
    cf_status s = cf_image_check_finite(&back, names[i], &err);
    printf("%s: %s\n", strrchr(names[i], '/') + 1, err.message);
    CHECK(s == CF_EINVAL, "status %s", cf_status_name(s));
    CHECK(strstr(err.message, names[i]) && strstr(err.message, "3 non-finite") &&
              strstr(err.message, "NaN at pixel (5, 2), channel 1"),
          "message: %s", err.message);
    CHECK(isinf(back.pixels[(7 * W + 1) * 3]) && back.pixels[(9 * W + 9) * 3 + 2] < 0.0f &&
              isinf(back.pixels[(9 * W + 9) * 3 + 2]),
          "infinities kept");
    cf_image_free(&back);
  }
  cf_image_free(&image);
}

/* ---- the real data ---- */

static int is_dir(const char *path) {
  struct stat st;
  return path && stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static const float *at(const cf_image *image, int x, int y) {
  return image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
}

static int test_diligent(const char *data) {
  char folder_ball[512], path[600];
  snprintf(folder_ball, sizeof folder_ball, "%s/diligent_ball", data ? data : "");
  if (!is_dir(folder_ball)) {
    printf("skipped: no DiLiGenT ball at %s\n",
           data ? folder_ball : "(no shared data folder given)");
    return 0;
  }
  cf_image image;
  cf_image_info info;
  cf_error err = {0};
  snprintf(path, sizeof path, "%s/001.png", folder_ball);
  CHECK(cf_image_read(path, &image, &info, &err) == CF_OK, "%s", err.message);
  if (image.pixels) {
    printf("001.png: %d x %d x %d, %s, %d bits, float %d\n", image.width, image.height,
           image.channels, info.format, info.bits_per_sample, info.is_float);
    CHECK(image.width == 612 && image.height == 512 && image.channels == 3, "size");
    CHECK(info.bits_per_sample == 16 && !info.is_float && strcmp(info.format, "png") == 0,
          "16-bit png");
    size_t clipped = 0, off_grid = 0;
    double max = 0.0;
    for (size_t i = 0; i < (size_t)612 * 512; ++i) {
      int any = 0;
      for (int c = 0; c < 3; ++c) {
        double v = image.pixels[i * 3 + (size_t)c];
        max = fmax(max, v);
        if (v == 1.0) any = 1;
        if (fabs(v * 65535.0 - round(v * 65535.0)) > 1e-2) ++off_grid;
      }
      clipped += (size_t)any;
    }
    printf(
        "001.png: max %.6f, %zu pixels at 65535 (README: 3 to 14), %zu values off the 1/65535 "
        "grid\n",
        max, clipped, off_grid);
    CHECK(clipped >= 3 && clipped <= 14, "clipped pixels %zu", clipped);
    CHECK(off_grid == 0, "values not k/65535: %zu", off_grid);
    cf_image_free(&image);
  }

  cf_image pfm, png;
  snprintf(path, sizeof path, "%s/Normal_gt.pfm", folder_ball);
  CHECK(cf_image_read(path, &pfm, &info, &err) == CF_OK, "%s", err.message);
  printf("Normal_gt.pfm: %d x %d x %d, %s, %d bits, float %d\n", pfm.width, pfm.height,
         pfm.channels, info.format, info.bits_per_sample, info.is_float);
  snprintf(path, sizeof path, "%s/Normal_gt.png", folder_ball);
  CHECK(cf_image_read(path, &png, NULL, &err) == CF_OK, "%s", err.message);
  if (!pfm.pixels || !png.pixels || pfm.width != 612 || pfm.height != 512 || pfm.channels != 3 ||
      png.width != 612 || png.height != 512 || png.channels < 3) {
    CHECK(0, "normal maps of unexpected size");
    cf_image_free(&pfm);
    cf_image_free(&png);
    return 1;
  }
  CHECK(info.is_float && info.bits_per_sample == 32, "float pfm");
  /* y is up: the ball's top (row 264 − 71 + 5) has n.y > 0, its bottom < 0;
   * x is right: its left edge has n.x < 0 */
  const float *top = at(&pfm, 308, 198), *bottom = at(&pfm, 308, 330);
  const float *left = at(&pfm, 240, 264), *right = at(&pfm, 376, 264);
  printf(
      "pfm normals: top (308, 198) %.3f %.3f %.3f; bottom (308, 330) %.3f %.3f %.3f; "
      "left (240, 264) %.3f %.3f %.3f\n",
      top[0], top[1], top[2], bottom[0], bottom[1], bottom[2], left[0], left[1], left[2]);
  CHECK(top[1] > 0.5f && bottom[1] < -0.5f, "top y %g, bottom y %g", top[1], bottom[1]);
  CHECK(left[0] < -0.5f && right[0] > 0.5f, "left x %g, right x %g", left[0], right[0]);
  /* the picture: png = (n + 1) / 2 in 8 bits; compare on the ball, as
   * stored and with one of them upside down */
  double sum = 0.0, sum_flipped = 0.0, worst = 0.0;
  size_t count = 0;
  for (int y = 0; y < 512; ++y)
    for (int x = 0; x < 612; ++x) {
      const float *n = at(&pfm, x, y);
      double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
      if (fabs(len - 1.0) > 1e-3) continue; /* background */
      const float *p = at(&png, x, y), *q = at(&png, x, 511 - y);
      double d = 0.0, e = 0.0;
      for (int c = 0; c < 3; ++c) {
        d = fmax(d, fabs(2.0 * p[c] - 1.0 - n[c]));
        e = fmax(e, fabs(2.0 * q[c] - 1.0 - n[c]));
      }
      sum += d;
      sum_flipped += e;
      worst = fmax(worst, d);
      ++count;
    }
  printf(
      "normals on the ball: %zu pixels; |2 png - 1 - pfm| mean %.4f max %.4f; with the png "
      "upside down mean %.4f\n",
      count, sum / (double)count, worst, sum_flipped / (double)count);
  CHECK(count > 15000 && count < 17000, "ball pixels %zu (mask: 15,791)", count);
  CHECK(sum / (double)count < 0.01 && worst < 0.02, "pfm and png disagree: mean %g, max %g",
        sum / (double)count, worst);
  CHECK(sum_flipped / (double)count > 0.1, "orientation not distinguished");
  cf_image_free(&pfm);
  cf_image_free(&png);
  return 1;
}

int main(int argc, char **argv) {
  const char *tmp = getenv("TMPDIR");
  snprintf(folder, sizeof folder, "%s/clayfit_image_XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
  if (!mkdtemp(folder)) {
    perror("mkdtemp");
    return 1;
  }
  test_round_trips();
  test_pfm_layout();
  test_exif();
  test_errors();
  test_non_finite();
  test_diligent(argc > 1 ? argv[1] : NULL);
  for (int i = 0; i < made_count; ++i) unlink(made[i]);
  if (rmdir(folder) != 0) printf("note: %s not empty\n", folder);
  return check_finish("test_image_io");
}
