/* The PFM codec (src/capture/image_pfm.c) against OpenImageIO 2.4's PNM
 * reader (image_oiio_read): bit-for-bit equal pixels and header on
 * DiLiGenT's Normal_gt.pfm and on PFMs made here (both byte orders, a
 * scale other than 1, 1 and 3 channels, comments, NaN and infinities,
 * trailing bytes), image_pfm_write read back, and damaged headers and
 * data refused. Usage: test_image_pfm [shared-data-dir] */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "capture/image_codec.h"
#include "codec_support.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static char folder[256];

/* Both readers: equal header and pixels. */
static void compare_readers(const char *path, const char *label) {
  cf_image_header a, b;
  cf_image ia = {0}, ib = {0};
  cf_error ea = {0}, eb = {0};
  cf_status sa = codec_read(image_pfm_read, path, 0, 0, &a, &ia, &ea);
  memset(&b, 0, sizeof b);
  codec_info_clear(&b.info);
  cf_status sb = image_oiio_read(path, 0, 0, &b, &ib, &eb);
  CHECK(sa == CF_OK && sb == CF_OK, "%s: pfm %d (%s), oiio %d (%s)", label, sa, ea.message, sb,
        eb.message);
  if (sa == CF_OK && sb == CF_OK) {
    int header_equal = a.width == b.width && a.height == b.height && a.channels == b.channels &&
                       strcmp(a.info.format, b.info.format) == 0 &&
                       a.info.bits_per_sample == b.info.bits_per_sample &&
                       a.info.is_float == b.info.is_float && isnan(b.info.exposure_time);
    size_t n = (size_t)a.width * (size_t)a.height * (size_t)a.channels;
    int equal = header_equal && memcmp(ia.pixels, ib.pixels, n * sizeof(float)) == 0;
    CHECK(header_equal, "%s: header %dx%dx%d %s vs %dx%dx%d %s", label, a.width, a.height,
          a.channels, a.info.format, b.width, b.height, b.channels, b.info.format);
    CHECK(equal, "%s: pixels differ", label);
    printf("  %-36s %4d x %-4d x %d  %s %d bits float %d  %s\n", label, a.width, a.height,
           a.channels, a.info.format, a.info.bits_per_sample, a.info.is_float,
           equal ? "equal" : "DIFFERENT");
  }
  cf_image_free(&ia);
  cf_image_free(&ib);
}

/* A PFM of width x height x channels with `header` text before the data,
 * samples v(i) in the byte order asked, rows as stored (the file's first
 * row is the image's bottom one), and `extra` bytes after them. */
static const char *make_pfm(const char *name, const char *header, int width, int height,
                            int channels, int big_endian, size_t extra) {
  static char path[320];
  snprintf(path, sizeof path, "%s/%s", folder, name);
  FILE *f = fopen(path, "wb");
  fputs(header, f);
  size_t n = (size_t)width * height * channels;
  for (size_t i = 0; i < n; ++i) {
    float v = i % 11 == 5 ? NAN : i % 13 == 7 ? -INFINITY : (float)i * 0.37f - 3.0f;
    if (i == 4) v = -0.0f;
    unsigned char b[4];
    uint32_t bits;
    memcpy(&bits, &v, 4);
    for (int k = 0; k < 4; ++k) b[big_endian ? 3 - k : k] = (unsigned char)(bits >> (8 * k));
    fwrite(b, 1, 4, f);
  }
  for (size_t i = 0; i < extra; ++i) fputc('\n', f);
  fclose(f);
  return path;
}

static void made_cases(void) {
  printf("PFMs made here:\n");
  compare_readers(make_pfm("a.pfm", "PF\n7 5\n-1.0\n", 7, 5, 3, 0, 0), "PF little-endian");
  compare_readers(make_pfm("b.pfm", "Pf\n7 5\n-1.0\n", 7, 5, 1, 0, 0), "Pf little-endian");
  compare_readers(make_pfm("c.pfm", "PF\n7 5\n1.0\n", 7, 5, 3, 1, 0), "PF big-endian");
  compare_readers(make_pfm("d.pfm", "PF 7 5 -2.5\n", 7, 5, 3, 0, 0), "PF scale -2.5, one line");
  compare_readers(make_pfm("e.pfm", "Pf\n7 5\n0.125\n", 7, 5, 1, 1, 0),
                  "Pf big-endian scale 0.125");
  compare_readers(make_pfm("f.pfm", "PF\n# made\n7\t5 # here\n-1\r", 7, 5, 3, 0, 0),
                  "comments, tab, CR before the data");
  compare_readers(make_pfm("g.pfm", "PF\n7 5\n-1.0\n", 7, 5, 3, 0, 3), "3 bytes after the rows");

  cf_image image = {0}, back = {0};
  cf_error err = {0};
  cf_image_alloc(&image, 9, 4, 3, &err);
  for (int i = 0; i < 9 * 4 * 3; ++i) image.pixels[i] = i == 7 ? NAN : (float)i / 3.0f - 1.0f;
  char path[320];
  snprintf(path, sizeof path, "%s/written.pfm", folder);
  CHECK(image_pfm_write(path, &image, &err) == CF_OK, "%s", err.message);
  compare_readers(path, "image_pfm_write, 3 channels");
  cf_image_header header;
  CHECK(codec_read(image_pfm_read, path, 9, 4, &header, &back, &err) == CF_OK && back.pixels &&
            memcmp(back.pixels, image.pixels, sizeof(float) * 9 * 4 * 3) == 0,
        "image_pfm_write: read back other values");
  cf_image_free(&back);
  cf_image_free(&image);
  CHECK(image_pfm_write("/dev/full", &(cf_image){1, 1, 1, (float[]){0.5f}}, &err) == CF_EIO,
        "a PFM written to /dev/full");
}

/* A damaged file: refused with `want`, naming it, nothing allocated. */
static void refused(const char *header, int width, int height, int channels, size_t cut,
                    cf_status want, const char *label) {
  const char *path = make_pfm("bad.pfm", header, width, height, channels, 0, 0);
  if (cut) {
    struct stat st;
    stat(path, &st);
    if (truncate(path, st.st_size - (off_t)cut) != 0) perror("truncate");
  }
  cf_image_header h;
  cf_image image = {0};
  cf_error err = {0};
  cf_status s = codec_read(image_pfm_read, path, 0, 0, &h, &image, &err);
  CHECK(s == want, "%s: status %s, not %s (%s)", label, cf_status_name(s), cf_status_name(want),
        err.message);
  CHECK(image.pixels == NULL && strstr(err.message, path), "%s: %s", label, err.message);
  printf("  %-36s %-8s %s\n", label, cf_status_name(s), err.message);
}

static void error_cases(void) {
  printf("damaged PFMs:\n");
  refused("PF\n7 5\n-1.0\n", 7, 5, 3, 1, CF_EIO, "one byte short");
  refused("PF\n7 5\n-1.0\n", 0, 0, 3, 0, CF_EIO, "no rows at all");
  refused("PF\n7 5\n-1.0", 0, 0, 3, 0, CF_EPARSE, "no blank after the scale");
  refused("PX\n7 5\n-1.0\n", 7, 5, 3, 0, CF_EPARSE, "magic PX");
  refused("PF7 5\n-1.0\n", 7, 5, 3, 0, CF_EPARSE, "no blank after the magic");
  refused("PF\n7x 5\n-1.0\n", 7, 5, 3, 0, CF_EPARSE, "width 7x");
  refused("PF\n-7 5\n-1.0\n", 7, 5, 3, 0, CF_EPARSE, "width -7");
  refused("PF\n7 99999999999\n-1.0\n", 7, 5, 3, 0, CF_EPARSE, "height past 2^31");
  refused("PF\n7 5\n0\n", 7, 5, 3, 0, CF_EPARSE, "scale 0");
  refused("PF\n7 5\nnan\n", 7, 5, 3, 0, CF_EPARSE, "scale nan");
  refused("PF\n7 5\n-1.0x\n", 7, 5, 3, 0, CF_EPARSE, "scale -1.0x");
  refused("PF\n0 5\n-1.0\n", 0, 5, 3, 0, CF_EPARSE, "width 0");
  refused("PF\n100000 100000\n-1.0\n", 1, 1, 3, 0, CF_ERANGE, "100000 x 100000 declared");
  const char *path = make_pfm("sized.pfm", "PF\n7 5\n-1.0\n", 7, 5, 3, 0, 0);
  cf_image_header h;
  cf_image image = {0};
  cf_error err = {0};
  CHECK(codec_read(image_pfm_read, path, 5, 7, &h, &image, &err) == CF_EINVAL && !image.pixels,
        "5 x 7 expected: %s", err.message);
  printf("  %-36s %-8s %s\n", "5 x 7 expected", "EINVAL", err.message);
}

int main(int argc, char **argv) {
  snprintf(folder, sizeof folder, "/tmp/test_image_pfm.XXXXXX");
  if (!mkdtemp(folder)) {
    perror("mkdtemp");
    return 1;
  }
  made_cases();
  error_cases();
  char path[1024];
  snprintf(path, sizeof path, "%s/diligent_ball/Normal_gt.pfm", argc > 1 ? argv[1] : "");
  struct stat st;
  if (argc < 2 || stat(path, &st) != 0) {
    printf("shared data absent: DiLiGenT's Normal_gt.pfm skipped\n");
  } else {
    printf("the real PFM:\n");
    compare_readers(path, "DiLiGenT Normal_gt.pfm");
  }
  char command[400];
  snprintf(command, sizeof command, "rm -rf '%s'", folder);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", folder);
  return check_finish("test_image_pfm");
}
