/* synth --response and --format jpg (include/clayfit/synth.h):
 *  - each response curve: decoding the 8-bit codes synth writes through the
 *    curve's inverse gives the linear render (the same scene as a float EXR,
 *    no noise) within the code's quantisation;
 *  - png8 without a response is byte for byte png8 with "srgb";
 *  - truth.json names the curve; the capture's colour block stays "srgb";
 *  - jpg with EXIF exposures: readable JPEGs whose exposure time, ISO and
 *    f-number vary per image, the photos scaled by those exposures, and
 *    the capture loader's exposures equal truth.json's. */
#define _POSIX_C_SOURCE 200809L
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/image.h"
#include "clayfit/synth.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { IMAGES = 2 };

static void small_scene(cf_synth_options *o) {
  cf_synth_default_options(o);
  o->images = IMAGES;
  o->width = 96;
  o->height = 72;
  o->focal_px = 115.2;
  o->supersample = 1;
  o->read_noise = o->shot_noise = 0.0;
}

static int render(const char *dir, const cf_synth_options *o) {
  cf_error err = {0};
  cf_status s = cf_synth_write(dir, o, &err);
  CHECK(s == CF_OK, "synth into %s: %s", dir, err.message);
  return s == CF_OK;
}

static int read_image(const char *dir, const char *name, cf_image *image, cf_image_info *info) {
  char path[4096];
  snprintf(path, sizeof path, "%s/images/%s", dir, name);
  cf_error err = {0};
  cf_status s = cf_image_read(path, image, info, &err);
  CHECK(s == CF_OK, "read %s: %s", path, err.message);
  return s == CF_OK;
}

static json_t *read_json(const char *dir, const char *name) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  json_error_t error;
  json_t *doc = json_load_file(path, 0, &error);
  CHECK(doc != NULL, "%s: %s", path, error.text);
  return doc;
}

/* The codes of `dir` (8-bit through `response`) against the float render
 * of `linear_dir`: the linear value (clipped to [0, 1]) lies between the
 * decoded code ± half a step, i.e. the code is the rounded curve. Returns
 * the worst distance from the code in steps (0.5 at most). */
static double compare_codes(const char *dir, const char *linear_dir, cf_response response) {
  double worst = 0.0;
  size_t used = 0;
  for (int k = 0; k < IMAGES; ++k) {
    char png[32], exr[32];
    snprintf(png, sizeof png, "%03d.png", k);
    snprintf(exr, sizeof exr, "%03d.exr", k);
    cf_image coded = {0}, linear = {0};
    if (read_image(dir, png, &coded, NULL) && read_image(linear_dir, exr, &linear, NULL)) {
      size_t n = (size_t)coded.width * (size_t)coded.height * 3;
      for (size_t i = 0; i < n; ++i) {
        double code = coded.pixels[i], truth = fmin(1.0, fmax(0.0, linear.pixels[i]));
        double low = cf_response_decode(response, code - 0.5 / 255);
        double high = cf_response_decode(response, code + 0.5 / 255);
        double slack = 1e-6 * (high - low); /* float32 codes */
        if (truth < low - slack || truth > high + slack)
          worst = fmax(worst, 1.0); /* outside its code's interval */
        else
          worst = fmax(worst, 255.0 * fabs(cf_response_encode(response, truth) - code));
        used += truth > 0.02;
      }
    }
    cf_image_free(&coded);
    cf_image_free(&linear);
  }
  CHECK(used > 1000, "%zu values above 0.02 compared", used);
  return worst;
}

static void check_declared(const char *dir, cf_response response) {
  json_t *truth = read_json(dir, "truth.json"), *capture = read_json(dir, "capture.json");
  const char *name = json_string_value(json_object_get(truth, "response"));
  CHECK(name && strcmp(name, cf_response_name(response)) == 0, "truth.json: response %s, not %s",
        name ? name : "(none)", cf_response_name(response));
  const char *encoding =
      json_string_value(json_object_get(json_object_get(capture, "colour"), "encoding"));
  CHECK(encoding && strcmp(encoding, "srgb") == 0, "the capture declares srgb, not %s",
        encoding ? encoding : "(none)");
  json_decref(truth);
  json_decref(capture);
}

static int same_file(const char *a, const char *b) {
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  int same = fa && fb;
  for (int ca = 0, cb = 0; same && ca != EOF;) {
    ca = fgetc(fa), cb = fgetc(fb);
    same = ca == cb;
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return same;
}

static void check_responses(const char *root) {
  char linear_dir[4096], dir[4096];
  snprintf(linear_dir, sizeof linear_dir, "%s/exr", root);
  cf_synth_options o;
  small_scene(&o);
  o.format = CF_SYNTH_EXR;
  if (!render(linear_dir, &o)) return;
  for (int r = 0; r < CF_RESPONSE_COUNT; ++r) {
    snprintf(dir, sizeof dir, "%s/%s", root, cf_response_name((cf_response)r));
    small_scene(&o);
    o.response = r;
    if (!render(dir, &o)) continue;
    double worst = compare_codes(dir, linear_dir, (cf_response)r);
    printf("%-9s worst |code - encode(linear)| %.4f code steps\n", cf_response_name(r), worst);
    /* half a step, and float32 rounding of the stored code */
    CHECK(worst <= 0.5 + 1e-4, "%s: decoded codes within half a step (worst %.4f)",
          cf_response_name(r), worst);
    check_declared(dir, (cf_response)r);
  }
  /* png8 without --response is png8 through sRGB, byte for byte */
  snprintf(dir, sizeof dir, "%s/default", root);
  small_scene(&o);
  if (!render(dir, &o)) return;
  for (int k = 0; k < IMAGES; ++k) {
    char a[4200], b[4200];
    snprintf(a, sizeof a, "%s/default/images/%03d.png", root, k);
    snprintf(b, sizeof b, "%s/srgb/images/%03d.png", root, k);
    CHECK(same_file(a, b), "%s and %s are the same bytes", a, b);
  }
}

/* JPEG with EXIF: the fields vary per image, the photos are scaled by the
 * exposure, and the capture loader agrees with truth.json. */
static void check_jpeg(const char *root) {
  char dir[4096], png_dir[4096];
  snprintf(dir, sizeof dir, "%s/jpg", root);
  snprintf(png_dir, sizeof png_dir, "%s/default", root);
  cf_synth_options o;
  small_scene(&o);
  o.format = CF_SYNTH_JPEG;
  o.exif_exposures = 1;
  if (!render(dir, &o)) return;
  json_t *truth = read_json(dir, "truth.json");
  json_t *exposures = json_object_get(truth, "exposures");
  CHECK(json_array_size(exposures) == IMAGES, "truth.json has %d exposures", IMAGES);
  CHECK(json_integer_value(json_object_get(json_object_get(truth, "jpeg"), "quality")) ==
            CF_SYNTH_JPEG_QUALITY,
        "truth.json: the JPEG quality");
  double first = NAN, log_sum = 0.0;
  for (int k = 0; k < IMAGES; ++k) {
    char name[32], png[32];
    snprintf(name, sizeof name, "%03d.jpg", k);
    snprintf(png, sizeof png, "%03d.png", k);
    cf_image jpeg = {0}, reference = {0};
    cf_image_info info;
    if (!read_image(dir, name, &jpeg, &info) || !read_image(png_dir, png, &reference, NULL)) {
      cf_image_free(&jpeg);
      continue;
    }
    CHECK(strcmp(info.format, "jpeg") == 0 && info.bits_per_sample == 8, "%s: 8-bit JPEG (%s)",
          name, info.format);
    CHECK(isfinite(info.exposure_time) && isfinite(info.iso) && isfinite(info.f_number),
          "%s: EXIF exposure time %g, ISO %g, f-number %g", name, info.exposure_time, info.iso,
          info.f_number);
    double raw = info.exposure_time * info.iso / (info.f_number * info.f_number);
    if (k == 0) first = raw;
    if (k == 1) CHECK(fabs(raw / first - 1.0) > 0.1, "the exposures vary (%g, %g)", first, raw);
    log_sum += log(raw);
    /* the sphere's mean linear value over the PNG's (exposure 1): e_k */
    double e = json_real_value(json_array_get(exposures, (size_t)k)), sum_j = 0.0, sum_p = 0.0;
    size_t n = (size_t)jpeg.width * (size_t)jpeg.height * 3;
    for (size_t i = 0; i < n; ++i) {
      double p = cf_srgb_to_linear(reference.pixels[i]);
      if (p < 0.05 || p * e > 0.9) continue;
      sum_p += p;
      sum_j += cf_srgb_to_linear(jpeg.pixels[i]);
    }
    CHECK(fabs(sum_j / sum_p / e - 1.0) < 0.02, "%s: photo scaled by its exposure %g (ratio %g)",
          name, e, sum_j / sum_p);
    cf_image_free(&jpeg);
    cf_image_free(&reference);
  }
  char path[4200];
  snprintf(path, sizeof path, "%s/capture.json", dir);
  cf_capture *capture = NULL;
  cf_error err = {0};
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_OK, "load %s: %s", path, err.message);
  for (size_t k = 0; capture && k < cf_capture_image_count(capture); ++k) {
    double loaded = cf_capture_image_at(capture, k)->exposure;
    double expected = json_real_value(json_array_get(exposures, k));
    CHECK(fabs(loaded / expected - 1.0) < 1e-5, "image %zu: exposure %.9g from EXIF, truth %.9g", k,
          loaded, expected);
  }
  cf_capture_free(capture);
  json_decref(truth);
}

/* The curves themselves: endpoints, strictly increasing, inverse, and the
 * published formulas computed here independently. */
static void check_curves(void) {
  for (int r = 0; r < CF_RESPONSE_COUNT; ++r) {
    const cf_response c = (cf_response)r;
    double worst_round_trip = 0.0, previous = -1.0;
    int increasing = 1;
    for (int i = 0; i <= 4000; ++i) {
      double x = i / 4000.0, code = cf_response_encode(c, x);
      increasing &= code > previous;
      previous = code;
      worst_round_trip = fmax(worst_round_trip, fabs(cf_response_decode(c, code) - x));
    }
    CHECK(
        fabs(cf_response_encode(c, 0.0)) < 1e-15 && fabs(cf_response_encode(c, 1.0) - 1.0) < 1e-12,
        "%s: 0 -> 0 and 1 -> 1", cf_response_name(c));
    CHECK(increasing, "%s: strictly increasing on [0, 1]", cf_response_name(c));
    CHECK(worst_round_trip < 1e-12, "%s: decode(encode(x)) = x (worst %.3g)", cf_response_name(c),
          worst_round_trip);
    CHECK(cf_response_encode(c, -0.3) == -cf_response_encode(c, 0.3), "%s: odd",
          cf_response_name(c));
    cf_response found = CF_RESPONSE_COUNT;
    cf_error err = {0};
    CHECK(cf_response_find(cf_response_name(c), &found, &err) == CF_OK && found == c,
          "%s: found by name", cf_response_name(c));
  }
  cf_response found;
  cf_error err = {0};
  CHECK(cf_response_find("log", &found, &err) == CF_EINVAL && strstr(err.message, "filmic"),
        "an unknown curve names the known ones: %s", err.message);
  CHECK(fabs(cf_response_encode(CF_RESPONSE_GAMMA22, 0.18) - pow(0.18, 1 / 2.2)) < 1e-15,
        "gamma 2.2");
  CHECK(cf_response_encode(CF_RESPONSE_SRGB, 0.18) == cf_linear_to_srgb(0.18), "srgb");
  /* Hable's Uncharted 2 curve, white 11.2 */
  const double A = 0.15, B = 0.50, C = 0.10, D = 0.20, E = 0.02, F = 0.30, W = 11.2;
  for (double x = 0.05; x < 1.0; x += 0.1) {
    double h = W * x, hw = W;
    double fx = (h * (A * h + C * B) + D * E) / (h * (A * h + B) + D * F) - E / F;
    double fw = (hw * (A * hw + C * B) + D * E) / (hw * (A * hw + B) + D * F) - E / F;
    CHECK(fabs(cf_response_encode(CF_RESPONSE_FILMIC, x) - fx / fw) < 1e-14, "filmic at %g", x);
  }
  /* a toe and a shoulder: the slope at 0 below sRGB's, at 1 below 1 */
  double toe = cf_response_encode(CF_RESPONSE_FILMIC, 1e-6) / 1e-6;
  double shoulder = (1.0 - cf_response_encode(CF_RESPONSE_FILMIC, 1.0 - 1e-6)) / 1e-6;
  CHECK(toe > 4.0 && toe < 4.6 && shoulder > 0.2 && shoulder < 0.25,
        "filmic: slope %.3f at 0, %.3f at 1", toe, shoulder);
  CHECK(isinf(cf_response_decode(CF_RESPONSE_FILMIC, 1.3)), "filmic: no preimage above 1.287");
}

/* cf_image_write_jpeg: a red-and-blue pattern of single pixels keeps its
 * colours with 4:4:4 chroma and loses them with 4:2:0 (one colour per 2 x 2
 * pixels); a lower quality makes a smaller file. Returns the file's size. */
static long write_pattern(const char *root, const char *name, int quality, cf_chroma chroma,
                          double *worst) {
  cf_image image = {0}, back = {0};
  cf_error err = {0};
  char path[4200];
  snprintf(path, sizeof path, "%s/%s", root, name);
  long size = -1;
  *worst = NAN;
  if (cf_image_alloc(&image, 32, 32, 3, &err) != CF_OK) return -1;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      float *p = image.pixels + 3 * (y * 32 + x);
      int red = (x + y) % 2 == 0;
      p[0] = red ? 0.9f : 0.1f, p[1] = 0.2f, p[2] = red ? 0.1f : 0.9f;
    }
  cf_status s = cf_image_write_jpeg(path, &image, quality, chroma, NULL, &err);
  CHECK(s == CF_OK, "write %s: %s", path, err.message);
  if (s == CF_OK && cf_image_read(path, &back, NULL, &err) == CF_OK) {
    *worst = 0.0;
    for (size_t i = 0; i < 32 * 32 * 3; ++i)
      *worst = fmax(*worst, fabs(back.pixels[i] - image.pixels[i]));
    FILE *f = fopen(path, "rb");
    if (f && fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (f) fclose(f);
  }
  cf_image_free(&image);
  cf_image_free(&back);
  return size;
}

static void check_jpeg_writer(const char *root) {
  double full, sub, low;
  long full_size = write_pattern(root, "444.jpg", 100, CF_CHROMA_444, &full);
  write_pattern(root, "420.jpg", 100, CF_CHROMA_420, &sub);
  long low_size = write_pattern(root, "q30.jpg", 30, CF_CHROMA_444, &low);
  printf("JPEG: worst error 4:4:4 q100 %.3f, 4:2:0 q100 %.3f; %ld bytes at q100, %ld at q30\n",
         full, sub, full_size, low_size);
  CHECK(full < 0.05 && sub > 0.3, "4:2:0 loses single-pixel colour (%.3f), 4:4:4 keeps it (%.3f)",
        sub, full);
  CHECK(low_size > 0 && low_size < full_size, "quality 30 is smaller (%ld bytes) than 100 (%ld)",
        low_size, full_size);
  cf_image image = {0};
  cf_error err = {0};
  if (cf_image_alloc(&image, 16, 16, 3, &err) == CF_OK) {
    char path[4200];
    snprintf(path, sizeof path, "%s/bad.png", root);
    CHECK(cf_image_write_jpeg(path, &image, 90, CF_CHROMA_420, NULL, &err) == CF_EINVAL &&
              strstr(err.message, ".jpg"),
          "a JPEG needs its extension: %s", err.message);
    snprintf(path, sizeof path, "%s/bad.jpg", root);
    CHECK(cf_image_write_jpeg(path, &image, 0, CF_CHROMA_420, NULL, &err) == CF_EINVAL,
          "quality 0 is refused: %s", err.message);
  }
  cf_image_free(&image);
}

int main(void) {
  check_curves();
  char root[] = "/tmp/clayfit-synth-response-XXXXXX";
  if (!mkdtemp(root)) {
    perror("mkdtemp");
    return 1;
  }
  check_responses(root);
  check_jpeg(root);
  check_jpeg_writer(root);
  char command[4200];
  snprintf(command, sizeof command, "rm -rf '%s'", root);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", root);
  return check_finish("test_synth_response");
}
