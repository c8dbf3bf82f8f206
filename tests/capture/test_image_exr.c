/* The OpenEXR codec (image_exr.cpp) against OpenImageIO 2.4 (image_oiio_read
 * and image_oiio_write), bit for bit: the real HDRIs of ../shared/data/hdri
 * (skipped when absent), files image_oiio_write writes, and files made with
 * OpenEXR's API (exr_fixtures.cpp: tiles, MIP maps, two parts, channel
 * names and types of every kind, data windows, compressions, exposure
 * attributes of every type); the writer's files decode to the pixels of
 * image_oiio_write's, half's limits included; damaged and hostile files
 * fail naming the file. Prints the read and write times (not asserted).
 * Usage: test_image_exr [shared-data-dir] */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "capture/image_codec.h"
#include "capture/image_exr_check.h"
#include "codec_support.h"
#include "core/file.h"
#include "exr_fixtures.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static char folder[256];

static void clear_header(cf_image_header *header) {
  memset(header, 0, sizeof *header);
  codec_info_clear(&header->info);
}

/* The lead's dispatcher, for OpenEXR: the file's size, the header walk
 * (image_exr_check.c), then the reader. check = 0 skips the walk. */
static cf_status exr_read(const char *path, int check, int width, int height,
                          cf_image_header *header, cf_image *image, cf_error *err) {
  clear_header(header);
  if (image) memset(image, 0, sizeof *image);
  FILE *file;
  long long size;
  cf_status s = cf_open_regular_file(path, &file, &size, err);
  if (s != CF_OK) return s;
  s = check ? cf_exr_check_headers(path, file, size, err) : CF_OK;
  if (s == CF_OK) {
    rewind(file);
    s = image_exr_read(path, file, size, width, height, header, image, err);
  }
  fclose(file);
  return s;
}

static cf_status oiio_read(const char *path, int width, int height, cf_image_header *header,
                           cf_image *image, cf_error *err) {
  clear_header(header);
  if (image) memset(image, 0, sizeof *image);
  return image_oiio_read(path, width, height, header, image, err);
}

static int same_double(double a, double b) {
  return (isnan(a) && isnan(b)) || a == b;
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
  size_t n = (size_t)a->width * a->height * a->channels;
  return a->pixels && b->pixels && a->width == b->width && a->height == b->height &&
         a->channels == b->channels && memcmp(a->pixels, b->pixels, n * sizeof(float)) == 0;
}

static int compared = 0;

/* One file through both readers: the same status; when read, the same
 * header and the same bits; a refusal's message alike. Prints a row. */
static void compare_file(const char *path, const char *label) {
  cf_image_header ho, hm;
  cf_image io, im;
  cf_error eo = {0}, em = {0};
  cf_status so = oiio_read(path, 0, 0, &ho, &io, &eo);
  cf_status sm = exr_read(path, 1, 0, 0, &hm, &im, &em);
  int pixels = so == CF_OK && sm == CF_OK && same_pixels(&io, &im);
  int header = so == CF_OK && sm == CF_OK && same_header(&ho, &hm);
  /* OpenImageIO fails to open a subsampled file (CF_EIO); ours says
   * CF_EUNSUPPORTED */
  int subsampled = so == CF_EIO && sm == CF_EUNSUPPORTED && strstr(em.message, "subsampled");
  CHECK(so == sm || subsampled, "%s: OpenImageIO %s (%s), ours %s (%s)", label, cf_status_name(so),
        eo.message, cf_status_name(sm), em.message);
  if (so == CF_OK && sm == CF_OK) {
    CHECK(pixels, "%s: the pixels differ", label);
    if (!pixels)
      for (size_t k = 0; k < (size_t)hm.width * hm.height * hm.channels; ++k)
        if (memcmp(&io.pixels[k], &im.pixels[k], sizeof(float)) != 0) {
          printf("  value %zu: %.9g against ours %.9g\n", k, io.pixels[k], im.pixels[k]);
          break;
        }
    CHECK(header,
          "%s: the header differs: %dx%dx%d %d-bit float %d (%g %g %g) against ours "
          "%dx%dx%d %d-bit float %d (%g %g %g)",
          label, ho.width, ho.height, ho.channels, ho.info.bits_per_sample, ho.info.is_float,
          ho.info.exposure_time, ho.info.f_number, ho.info.iso, hm.width, hm.height, hm.channels,
          hm.info.bits_per_sample, hm.info.is_float, hm.info.exposure_time, hm.info.f_number,
          hm.info.iso);
    printf("  %-34s %5dx%-5d %d ch %2d-bit %-5s t=%-8g f=%-5g iso=%-5g  %s\n", label, hm.width,
           hm.height, hm.channels, hm.info.bits_per_sample, hm.info.is_float ? "float" : "uint",
           hm.info.exposure_time, hm.info.f_number, hm.info.iso,
           pixels && header ? "equal" : "DIFFERENT");
  } else {
    if (so == sm && so == CF_EUNSUPPORTED && strstr(eo.message, "data window"))
      CHECK(strcmp(eo.message, em.message) == 0, "%s: '%s' against '%s'", label, eo.message,
            em.message);
    CHECK(sm == CF_OK || (im.pixels == NULL && strstr(em.message, path)), "%s: %s", label,
          em.message);
    printf("  %-34s refused: %s / %s  (ours: %s)\n", label, cf_status_name(so), cf_status_name(sm),
           em.message + strlen(folder));
  }
  ++compared;
  cf_image_free(&io);
  cf_image_free(&im);
}

static void fixture(const char *name, exr_fixture f) {
  const char *path = codec_path(folder, name);
  char why[256];
  if (exr_fixture_write(path, &f, why, sizeof why) != 0) {
    CHECK(0, "%s: %s", name, why);
    return;
  }
  compare_file(path, name);
}

/* ---- reading ---- */

static void test_fixtures(void) {
  printf("files made with OpenEXR's API (random bit patterns of each type):\n");
  static const char *const sets[][2] = {
      {"rgb.exr", "R:h G:h B:h"},
      {"abgr.exr", "A:h B:h G:h R:h"},
      {"y.exr", "Y:h"},
      {"ya.exr", "A:h Y:h"},
      {"z.exr", "Z:f"},
      {"foo.exr", "foo:h"},
      {"yrYbY.exr", "Y:h RY:h BY:h"},
      {"xyz.exr", "Z:f Y:f X:f"},
      {"xYA.exr", "x:h Y:h A:h"},
      {"diffuse.exr", "diffuse.B:h diffuse.R:h diffuse.G:h"},
      {"normal.exr", "N.Z:f N.X:f N.Y:f"},
      {"layers.exr", "b.G:h a.R:h R:h"},
      {"lower.exr", "r:h a:h g:h b:h"},
      {"names.exr", "Alpha:h Blue:h Green:h Red:h"},
      {"red_r.exr", "Red:h R:h"},
      {"rgbz.exr", "Z:f B:h G:h R:h"},
      {"mixed.exr", "R:h G:f B:h"},
      {"mixed_a.exr", "R:f G:f B:f A:h"},
      {"uint.exr", "Y:u"},
      {"uint_mixed.exr", "R:h G:u B:f"},
      {"uint_rgb.exr", "R:u G:u B:u"},
      {"depth.exr", "Depth:f A:h Zback:f"},
  };
  for (size_t k = 0; k < sizeof sets / sizeof sets[0]; ++k)
    fixture(sets[k][0], (exr_fixture){.width = 13,
                                      .height = 7,
                                      .channels = sets[k][1],
                                      .compression = 3,
                                      .seed = 11u + (unsigned)k});
  const char *rgba = "R:h G:h B:h A:h";
  fixture("tiled.exr", (exr_fixture){37, 21, rgba, .tile = 16, .compression = 3, .seed = 5});
  fixture("mipmap.exr",
          (exr_fixture){37, 21, "Y:f", .tile = 8, .mipmap = 1, .compression = 4, .seed = 6});
  fixture("two_parts.exr", (exr_fixture){19, 9, rgba, .compression = 3, .parts = 2, .seed = 7});
  fixture("two_parts_tiled.exr",
          (exr_fixture){19, 9, "Y:h", .tile = 4, .compression = 3, .parts = 2, .seed = 8});
  fixture("origin.exr", (exr_fixture){12, 10, rgba, .x = -3, .y = 5, .compression = 3, .seed = 9});
  fixture("window.exr", (exr_fixture){12, 10, rgba, .x = 2, .display_shift = 4, .seed = 10});
  fixture("deep.exr", (exr_fixture){8, 4, "Z:f", .deep = 1});
  fixture("subsampled.exr", (exr_fixture){8, 4, "Y:h RY:h", .subsampled = 1, .seed = 12});
  static const char *const compressions[10] = {"none",  "rle", "zips", "zip",  "piz",
                                               "pxr24", "b44", "b44a", "dwaa", "dwab"};
  for (int c = 0; c < 10; ++c) {
    char name[40];
    snprintf(name, sizeof name, "compression_%s.exr", compressions[c]);
    fixture(name, (exr_fixture){70, 40, "R:h G:h B:f", .compression = c, .seed = 20u + c});
  }
}

/* The exposure attributes under every type OpenEXR has and every name
 * OpenImageIO keeps them under (ImageSpec matches names ignoring case). */
static void test_attributes(void) {
  static const char *const lists[] = {
      "expTime:float=0.008;aperture:float=5.6;Exif:PhotographicSensitivity:int=200",
      "expTime:double=0.1;aperture:double=2.8",
      "expTime:rational=1/125;aperture:rational=28/10",
      "expTime:rational=3/4294967294;aperture:rational=1/0",
      "expTime:string=0.25;aperture:string= 4;Exif:ISOSpeedRatings:string=400 ",
      "expTime:string=;aperture:string=f/2",
      "expTime:v2f=1,2;aperture:stringvector=5.6;Exif:PhotographicSensitivity:float=100",
      "expTime:chromaticities=0.5;aperture:floatvector=8;Exif:ISOSpeedRatings:timecode=1600",
      "ExposureTime:int=2;expTime:float=0.5",
      "exposuretime:int=3;expTime:double=0.1",
      "EXPOSURETIME:float=3;expTime:float=0.02",
      "FNumber:float=11;aperture:float=2",
      "fnumber:float=11;aperture:float=2",
      "exif:photographicsensitivity:int=50;Exif:PhotographicSensitivity:int=100",
      "Exif:PhotographicSensitivity:int=0;Exif:ISOSpeedRatings:int=640",
      "isoSpeed:float=100;expTime:float=-1;aperture:float=0",
  };
  printf("exposure attributes:\n");
  for (size_t k = 0; k < sizeof lists / sizeof lists[0]; ++k) {
    char name[32];
    snprintf(name, sizeof name, "attributes_%zu.exr", k);
    printf("  [%zu] %s\n", k, lists[k]);
    fixture(name, (exr_fixture){4, 3, "R:h G:h B:h", .compression = 3, .attributes = lists[k],
                                .seed = 40u + (unsigned)k});
  }
}

/* What image_oiio_write writes, read back by both. */
static void test_oiio_files(void) {
  printf("files image_oiio_write writes:\n");
  const cf_image_info info = {"", 0, 0, 1.0 / 125.0, 5.6, 200.0};
  for (int bits = 16; bits <= 32; bits += 16)
    for (int channels = 1; channels <= 4; ++channels) {
      cf_image image;
      cf_error err = {0};
      cf_image_alloc(&image, 21, 13, channels, &err);
      uint32_t state = 99u + (unsigned)channels;
      for (size_t k = 0; k < (size_t)21 * 13 * channels; ++k) {
        state = state * 1664525u + 1013904223u;
        image.pixels[k] = (float)(state >> 8) / 16777216.0f * 40.0f - 2.0f;
      }
      char name[32];
      snprintf(name, sizeof name, "oiio_%d_%d.exr", bits, channels);
      const char *path = codec_path(folder, name);
      CHECK(image_oiio_write(path, &image, bits, &info, 0, CF_CHROMA_444, &err) == CF_OK, "%s",
            err.message);
      compare_file(path, name);
      cf_image_free(&image);
    }
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int by_value(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void test_hdris(const char *data) {
  static const char *const names[4] = {"city.exr", "forest.exr", "studio.exr", "sunset.exr"};
  char dir[512], paths[4][600];
  snprintf(dir, sizeof dir, "%s/hdri", data ? data : "");
  struct stat st;
  if (!data || stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
    printf("the HDRIs: skipped (no %s)\n", dir);
    return;
  }
  printf("the HDRIs of %s:\n", dir);
  for (int k = 0; k < 4; ++k) {
    snprintf(paths[k], sizeof paths[k], "%s/%s", dir, names[k]);
    compare_file(paths[k], names[k]);
  }
  /* the four read by each, alternately, 7 times: medians */
  enum { ROUNDS = 11 };
  double ours[ROUNDS], theirs[ROUNDS];
  for (int r = 0; r < ROUNDS; ++r)
    for (int who = 0; who < 2; ++who) {
      double start = now();
      for (int k = 0; k < 4; ++k) {
        cf_image_header header;
        cf_image image;
        cf_error err = {0};
        cf_status s = who ? oiio_read(paths[k], 0, 0, &header, &image, &err)
                          : exr_read(paths[k], 1, 0, 0, &header, &image, &err);
        CHECK(s == CF_OK, "%s", err.message);
        cf_image_free(&image);
      }
      (who ? theirs : ours)[r] = now() - start;
    }
  qsort(ours, ROUNDS, sizeof(double), by_value);
  qsort(theirs, ROUNDS, sizeof(double), by_value);
  printf("reading the 4 HDRIs (median of %d): image_exr_read %.1f ms, image_oiio_read %.1f ms\n",
         ROUNDS, 1e3 * ours[ROUNDS / 2], 1e3 * theirs[ROUNDS / 2]);
}

/* ---- writing ---- */

/* Floats half cannot hold, or holds only just: beyond 65504, its
 * rounding ties, denormals of both, NaNs with payloads, infinities. */
static const uint32_t special_bits[] = {
    0x00000000u,           0x80000000u,
    0x3f800000u,           0x477fe000u /* 65504 */,
    0x477fefffu,           0x477ff000u,
    0x49742400u /* 1e6 */, 0xc9742400u,
    0x7f800000u,           0xff800000u,
    0x7fc00000u,           0xffc00000u,
    0x7f800001u,           0x7fa00000u,
    0x7fc01234u,           0x00000001u,
    0x000fffffu,           0x33000000u /* 2^-25 */,
    0x33000001u,           0x33800000u,
    0x337fffffu,           0x387fc000u,
    0x38800000u,           0x3dcccccdu,
    0x3eaaaaabu,           0x45001000u /* 2049 */,
    0x45801000u,           0xc5801800u,
};

static void fill_special(cf_image *image, uint32_t seed) {
  const size_t n = sizeof special_bits / sizeof special_bits[0];
  const size_t count = (size_t)image->width * image->height * image->channels;
  for (size_t k = 0; k < count; ++k) {
    uint32_t bits = special_bits[k % n];
    if (k >= n) { /* then random floats of every exponent */
      seed ^= seed << 13;
      seed ^= seed >> 17;
      seed ^= seed << 5;
      bits = seed;
    }
    memcpy(&image->pixels[k], &bits, sizeof bits);
  }
}

static void test_writer(void) {
  printf("written by image_exr_write and image_oiio_write, read by both:\n");
  const cf_image_info infos[2] = {{"", 0, 0, 1.0 / 125.0, 5.6, 200.0}, {"", 0, 0, 0.5, NAN, NAN}};
  for (int bits = 16; bits <= 32; bits += 16)
    for (int channels = 1; channels <= 4; ++channels) {
      cf_image image;
      cf_error err = {0};
      cf_image_alloc(&image, 17, 9, channels, &err);
      fill_special(&image, 7u * (unsigned)(bits + channels));
      const cf_image_info *info = &infos[channels % 2];
      const char *theirs = codec_path(folder, "by_oiio.exr"),
                 *ours = codec_path(folder, "by_exr.exr");
      CHECK(image_oiio_write(theirs, &image, bits, info, 0, CF_CHROMA_444, &err) == CF_OK, "%s",
            err.message);
      CHECK(image_exr_write(ours, &image, bits, info, &err) == CF_OK, "%s", err.message);
      cf_image_header h[4];
      cf_image d[4];
      cf_status s[4] = {oiio_read(theirs, 0, 0, &h[0], &d[0], &err),
                        oiio_read(ours, 0, 0, &h[1], &d[1], &err),
                        exr_read(theirs, 1, 0, 0, &h[2], &d[2], &err),
                        exr_read(ours, 1, 0, 0, &h[3], &d[3], &err)};
      /* the same pixels four ways; each file's header the same through
       * both readers, and the two files' alike but for the ISO that
       * OpenImageIO 2.4 does not read from image_oiio_write's int */
      int equal = 1;
      for (int k = 0; k < 4; ++k) {
        CHECK(s[k] == CF_OK, "%s", err.message);
        equal &= s[k] == CF_OK && same_pixels(&d[0], &d[k]);
      }
      cf_image_header theirs_iso = h[0];
      theirs_iso.info.iso = h[1].info.iso;
      equal &= same_header(&h[0], &h[2]) && same_header(&h[1], &h[3]) &&
               same_header(&theirs_iso, &h[1]) && isnan(h[0].info.iso);
      CHECK(equal, "%d-bit %d channels: the four decodes differ", bits, channels);
      CHECK(same_double(h[3].info.exposure_time, (double)(float)info->exposure_time) &&
                same_double(h[3].info.f_number, (double)(float)info->f_number) &&
                same_double(h[3].info.iso, info->iso),
            "exposure read back: %g %g %g", h[3].info.exposure_time, h[3].info.f_number,
            h[3].info.iso);
      printf("  %2d-bit %d ch (%zu special values, then random): %s; t=%g f=%g iso=%g\n", bits,
             channels, sizeof special_bits / sizeof special_bits[0],
             equal ? "the four decodes equal" : "DIFFERENT", h[3].info.exposure_time,
             h[3].info.f_number, h[3].info.iso);
      for (int k = 0; k < 4; ++k) cf_image_free(&d[k]);
      cf_image_free(&image);
    }
}

static void test_write_time(void) {
  cf_image image;
  cf_error err = {0};
  cf_image_alloc(&image, 640, 480, 3, &err);
  for (size_t k = 0; k < (size_t)640 * 480 * 3; ++k)
    image.pixels[k] = 0.5f + 0.4f * sinf(0.001f * (float)k);
  enum { ROUNDS = 11 };
  double ours[ROUNDS], theirs[ROUNDS];
  const char *path = codec_path(folder, "timed.exr");
  for (int r = 0; r < ROUNDS; ++r) {
    double start = now();
    CHECK(image_exr_write(path, &image, 16, NULL, &err) == CF_OK, "%s", err.message);
    ours[r] = now() - start;
    start = now();
    CHECK(image_oiio_write(path, &image, 16, NULL, 0, CF_CHROMA_444, &err) == CF_OK, "%s",
          err.message);
    theirs[r] = now() - start;
  }
  qsort(ours, ROUNDS, sizeof(double), by_value);
  qsort(theirs, ROUNDS, sizeof(double), by_value);
  printf(
      "writing 640x480 RGB half (median of %d): image_exr_write %.1f ms, image_oiio_write "
      "%.1f ms\n",
      ROUNDS, 1e3 * ours[ROUNDS / 2], 1e3 * theirs[ROUNDS / 2]);
  cf_image_free(&image);
}

/* ---- errors ---- */

static long file_bytes(const char *path, unsigned char **bytes) {
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  rewind(f);
  *bytes = malloc((size_t)n + 1);
  n = (long)fread(*bytes, 1, (size_t)n, f);
  fclose(f);
  return n;
}

static void put_bytes(const char *path, const unsigned char *bytes, size_t n) {
  FILE *f = fopen(path, "wb");
  if (f) {
    fwrite(bytes, 1, n, f);
    fclose(f);
  }
}

/* Both with and without the header walk: `status` (or any failure when
 * status is CF_OK), an empty image, the file named. */
static void expect_failure(const char *path, const char *label, cf_status status, int width,
                           int height, cf_status unchecked) {
  for (int check = 1; check >= 0; --check) {
    cf_image_header header;
    cf_image image;
    cf_error err = {0};
    cf_status s = exr_read(path, check, width, height, &header, &image, &err);
    cf_status want = check ? status : unchecked;
    CHECK(s != CF_OK && (want == CF_OK || s == want) && image.pixels == NULL &&
              strstr(err.message, path),
          "%s (check %d): %s: %s", label, check, cf_status_name(s), err.message);
    printf("  %-28s %s: %s: %s\n", label, check ? "dispatched" : "reader alone", cf_status_name(s),
           err.message + strlen(folder));
  }
}

/* the dataWindow and displayWindow of an OpenEXR file's bytes set to
 * (0, 0) - (side - 1, side - 1) */
static int set_windows(unsigned char *bytes, long n, int32_t side) {
  int found = 0;
  for (long k = 0; k + 40 < n; ++k)
    if (memcmp(bytes + k, "dataWindow\0box2i\0", 17) == 0 ||
        memcmp(bytes + k, "displayWindow\0box2i\0", 20) == 0) {
      unsigned char *v = bytes + k + (bytes[k + 1] == 'a' ? 17 : 20) + 4;
      const int32_t box[4] = {0, 0, side - 1, side - 1};
      memcpy(v, box, sizeof box); /* little-endian, as OpenEXR */
      ++found;
    }
  return found;
}

static void test_errors(void) {
  printf("damaged and hostile files:\n");
  cf_image image;
  cf_error err = {0};
  cf_image_alloc(&image, 64, 64, 3, &err);
  fill_special(&image, 3u);
  for (size_t k = 0; k < (size_t)64 * 64 * 3; ++k) /* finite values, well compressed */
    image.pixels[k] = (float)(k % 97) / 8.0f;
  const char *good = codec_path(folder, "good.exr"), *bad = codec_path(folder, "bad.exr");
  CHECK(image_exr_write(good, &image, 16, NULL, &err) == CF_OK, "%s", err.message);
  cf_image_free(&image);
  unsigned char *bytes = NULL;
  long n = file_bytes(good, &bytes);
  CHECK(n > 1000, "good.exr has %ld bytes", n);
  if (n <= 1000) return;
  put_bytes(bad, bytes, (size_t)(n * 6 / 10));
  expect_failure(bad, "truncated in its chunks", CF_EIO, 0, 0, CF_EIO);
  put_bytes(bad, bytes, 60);
  expect_failure(bad, "truncated in its header", CF_EPARSE, 0, 0, CF_EPARSE);
  unsigned char *copy = malloc((size_t)n);
  memcpy(copy, bytes, (size_t)n);
  for (long k = n / 2; k < n / 2 + 16; ++k) copy[k] ^= 0x5a;
  put_bytes(bad, copy, (size_t)n);
  expect_failure(bad, "corrupt chunk data", CF_EIO, 0, 0, CF_EIO);
  expect_failure(good, "another size expected", CF_EINVAL, 32, 64, CF_EINVAL);
  /* 2^20 x 2^20 pixels declared, with an offset table that fits: the walk
   * refuses it, and so does the reader alone (2^40 values), before any
   * pixel is allocated */
  memcpy(copy, bytes, (size_t)n);
  CHECK(set_windows(copy, n, 1 << 20) == 2, "the windows of good.exr");
  const size_t table = (size_t)(1 << 20) / 16 * 8;
  unsigned char *huge = calloc((size_t)n + table, 1);
  memcpy(huge, copy, (size_t)n);
  put_bytes(bad, huge, (size_t)n + table);
  expect_failure(bad, "2^20 x 2^20 pixels", CF_EPARSE, 0, 0, CF_ERANGE);
  cf_image_header header;
  CHECK(exr_read(bad, 0, 0, 0, &header, NULL, &err) == CF_ERANGE && strstr(err.message, "2^31"),
        "its header alone: %s", err.message);
  free(huge);
  free(copy);
  free(bytes);
  /* the writer's errors name the file */
  cf_image_alloc(&image, 8, 8, 3, &err);
  const char *nowhere = "/nonexistent-folder/out.exr";
  CHECK(image_exr_write(nowhere, &image, 16, NULL, &err) == CF_EIO && strstr(err.message, nowhere),
        "%s", err.message);
  printf("  write to a missing folder: %s\n", err.message);
  if (access("/dev/full", W_OK) == 0) {
    CHECK(image_exr_write("/dev/full", &image, 32, NULL, &err) == CF_EIO &&
              strstr(err.message, "/dev/full"),
          "%s", err.message);
    printf("  write to a full device: %s\n", err.message);
  }
  cf_image_free(&image);
}

int main(int argc, char **argv) {
  const char *tmp = getenv("TMPDIR");
  snprintf(folder, sizeof folder, "%s/test_image_exr_XXXXXX", tmp && *tmp ? tmp : "/tmp");
  if (!mkdtemp(folder)) {
    perror("mkdtemp");
    return 1;
  }
  test_hdris(argc > 1 ? argv[1] : NULL);
  test_fixtures();
  test_attributes();
  test_oiio_files();
  test_writer();
  test_errors();
  test_write_time();
  printf("%d files compared with image_oiio_read\n", compared);
  char command[400];
  snprintf(command, sizeof command, "rm -rf '%s'", folder);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", folder);
  return check_finish("test_image_exr");
}
