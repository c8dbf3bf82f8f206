/* A JPEG's coding read from its markers (cf_jpeg_coding_read: quality from
 * its luminance table, chroma from its sampling factors), the in-memory
 * round trip (cf_image_jpeg_roundtrip: the same pixels as a file written
 * and read back), and the parser's refusals of damaged headers, each
 * naming the file and the byte. cf_encode_value inverts cf_decode_pixel. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "clayfit/image.h"
#include "support/check.h"

CHECK_MAIN_STATE;

/* A smooth test picture with some colour. */
static void picture(cf_image *image) {
  cf_error err;
  CHECK(cf_image_alloc(image, 67, 45, 3, &err) == CF_OK, "%s", err.message);
  for (int y = 0; y < image->height; ++y)
    for (int x = 0; x < image->width; ++x)
      for (int c = 0; c < 3; ++c)
        image->pixels[3 * (y * image->width + x) + c] =
            (float)(0.5 + 0.4 * sin(0.11 * x * (c + 1) + 0.07 * y));
}

static const char *chroma_name(cf_chroma c) {
  return c == CF_CHROMA_420 ? "4:2:0" : c == CF_CHROMA_422 ? "4:2:2" : "4:4:4";
}

/* Written at each quality and chroma, read back: the same coding, exact. */
static void test_qualities(const char *dir, const cf_image *image) {
  static const int qualities[] = {10, 50, 75, 90, 95, 100};
  static const cf_chroma chromas[] = {CF_CHROMA_420, CF_CHROMA_422, CF_CHROMA_444};
  char path[512];
  snprintf(path, sizeof path, "%s/q.jpg", dir);
  for (size_t i = 0; i < sizeof qualities / sizeof *qualities; ++i)
    for (size_t j = 0; j < 3; ++j) {
      cf_error err = {0};
      cf_jpeg_coding coding = {0};
      cf_status s = cf_image_write_jpeg(path, image, qualities[i], chromas[j], NULL, &err);
      if (s == CF_OK) s = cf_jpeg_coding_read(path, &coding, &err);
      CHECK(s == CF_OK && coding.quality == qualities[i] && coding.exact &&
                coding.chroma == chromas[j],
            "quality %d %s: read %d (exact %d) %s: %s", qualities[i], chroma_name(chromas[j]),
            coding.quality, coding.exact, chroma_name(coding.chroma), err.message);
    }
}

/* The round trip in memory gives the pixels of a file written and read. */
static void test_roundtrip(const char *dir, const cf_image *image) {
  char path[512];
  snprintf(path, sizeof path, "%s/r.jpg", dir);
  cf_error err = {0};
  cf_image file = {0}, memory = {0};
  cf_status s = cf_image_write_jpeg(path, image, 85, CF_CHROMA_420, NULL, &err);
  if (s == CF_OK) s = cf_image_read(path, &file, NULL, &err);
  if (s == CF_OK) s = cf_image_jpeg_roundtrip(image, 85, CF_CHROMA_420, &memory, &err);
  CHECK(s == CF_OK, "%s", err.message);
  size_t n = 3 * (size_t)image->width * (size_t)image->height, differ = 0;
  double worst = 0.0;
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    differ += file.pixels[i] != memory.pixels[i];
    worst = fmax(worst, fabs(memory.pixels[i] - image->pixels[i]));
  }
  printf(
      "round trip at quality 85, 4:2:0: %zu of %zu values differ from the file's; the "
      "codec moved values by up to %.1f codes\n",
      differ, n, 255.0 * worst);
  CHECK(s == CF_OK && differ == 0, "%zu values differ from the file's", differ);
  CHECK(worst > 0.5 / 255.0, "the round trip changed nothing: not a JPEG coding");
  cf_image_free(&memory);
  cf_image bad = *image;
  bad.channels = 1;
  CHECK(cf_image_jpeg_roundtrip(&bad, 85, CF_CHROMA_420, &memory, &err) == CF_EINVAL,
        "a 1-channel image is refused");
  CHECK(cf_image_jpeg_roundtrip(image, 0, CF_CHROMA_420, &memory, &err) == CF_EINVAL,
        "quality 0 is refused");
  cf_image_free(&file);
}

/* One damaged header: refused with CF_EINVAL naming the byte. */
static void refused(const unsigned char *bytes, size_t size, const char *what, const char *why) {
  cf_error err = {0};
  cf_jpeg_coding coding;
  cf_status s = cf_jpeg_coding_parse(bytes, size, what, &coding, &err);
  printf("%s: %s\n", what, err.message);
  CHECK(s == CF_EINVAL && strstr(err.message, what) && strstr(err.message, why),
        "%s: status %d, '%s' (expected '%s')", what, s, err.message, why);
}

/* The header of a real file, damaged in each way the parser checks. */
static void test_damaged(const char *dir, const cf_image *image) {
  char path[512];
  snprintf(path, sizeof path, "%s/d.jpg", dir);
  cf_error err;
  CHECK(cf_image_write_jpeg(path, image, 90, CF_CHROMA_420, NULL, &err) == CF_OK, "%s",
        err.message);
  FILE *f = fopen(path, "rb");
  static unsigned char good[1 << 16], b[1 << 16];
  size_t size = f ? fread(good, 1, sizeof good, f) : 0;
  if (f) fclose(f);
  CHECK(size > 200, "read %zu bytes", size);
  size_t dqt = 0, sof = 0;
  for (size_t i = 2; i + 1 < size && (!dqt || !sof); ++i) {
    if (good[i] == 0xFF && good[i + 1] == 0xDB && !dqt) dqt = i;
    if (good[i] == 0xFF && good[i + 1] == 0xC0 && !sof) sof = i;
  }
  CHECK(dqt && sof, "DQT at %zu, SOF0 at %zu", dqt, sof);
  refused(good, 1, "a single byte", "no SOI");
  refused(good, dqt + 3, "cut inside a segment length", "length");
  refused(good, sof, "cut before the frame", "marker was expected");
  memcpy(b, good, size), b[dqt + 5] = 0; /* the table's first value */
  refused(b, size, "a table value of 0", "DQT value of 0");
  memcpy(b, good, size), b[dqt + 4] = 0x70; /* precision 7 */
  refused(b, size, "a table of precision 7", "precision");
  memcpy(b, good, size), b[sof + 4] = 12; /* 12-bit samples */
  refused(b, size, "12-bit samples", "8 bits");
  memcpy(b, good, size), b[sof + 1] = 0xC3; /* lossless */
  refused(b, size, "a lossless frame", "lossless");
  memcpy(b, good, size), b[sof + 2] = 0xFF, b[sof + 3] = 0xFF; /* length beyond the file */
  refused(b, size, "a length beyond the file", "length");
  memcpy(b, good, size), b[sof + 11] = 0x41; /* luma sampled 4 x 1 */
  refused(b, size, "4:1:1 chroma", "chroma sampling");
  cf_jpeg_coding coding;
  CHECK(cf_jpeg_coding_parse(good, size, "good", &coding, &err) == CF_OK && coding.quality == 90,
        "the undamaged header reads: %s", err.message);
  CHECK(cf_jpeg_coding_read("/nonexistent/x.jpg", &coding, &err) == CF_ENOTFOUND,
        "a missing file is CF_ENOTFOUND");
}

/* cf_encode_value is decode's inverse, with its slope. */
static void test_encode(void) {
  cf_decode d = {CF_TRANSFER_SRGB, 2.2, 0.01, 0.93, 1.7};
  const cf_transfer transfers[] = {CF_TRANSFER_SRGB, CF_TRANSFER_GAMMA, CF_TRANSFER_LINEAR};
  double worst = 0.0, worst_slope = 0.0;
  for (int t = 0; t < 3; ++t)
    for (double v = 0.01; v < 0.5; v += 0.013) {
      d.transfer = transfers[t];
      double slope, stored = cf_encode_value(&d, v, &slope), back[3], up, down, s2;
      float px[3] = {(float)stored, (float)stored, (float)stored};
      cf_decode_pixel(&d, px, 3, back);
      up = cf_encode_value(&d, v + 1e-5, &s2), down = cf_encode_value(&d, v - 1e-5, &s2);
      worst = fmax(worst, fabs(back[0] - v) / v);
      worst_slope = fmax(worst_slope, fabs(slope / ((up - down) / 2e-5) - 1.0));
    }
  printf("encode then decode: worst relative error %.2g (float storage); slope %.2g\n", worst,
         worst_slope);
  CHECK(worst < 1e-6, "encode then decode differs by %g", worst);
  CHECK(worst_slope < 1e-5, "the slope differs from its difference quotient by %g", worst_slope);
}

int main(void) {
  char dir[] = "/tmp/clayfit_jpeg_coding_XXXXXX";
  if (!mkdtemp(dir)) return 1;
  cf_image image = {0};
  picture(&image);
  test_qualities(dir, &image);
  test_roundtrip(dir, &image);
  test_damaged(dir, &image);
  test_encode();
  cf_image_free(&image);
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_finish("test_jpeg_coding");
}
