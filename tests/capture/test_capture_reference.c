/* A reference target of known albedo sets the scale of a capture with
 * relative radiometry (capture file: "reference").
 *
 * A noise-free EXR synth capture with a grey card (albedo 0.5) whose
 * capture file gives the flash's intensity wrong by 0.37: loading finds the
 * scale 1/0.37 to 1e-6 and makes the observations' irradiance equal, to
 * 1e-6, that of the same scene written with absolute radiometry; the
 * capture then counts as absolute. A wrong albedo colour gives a warning.
 * Then every kind of bad reference block is refused, naming the file and
 * its JSON path. The bad capture files stay in DIR for the CLI tests
 * (tests/fit/reference.cmake: exit status 2 through `clayfit inspect`).
 * usage: test_capture_reference DIR */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/synth.h"
#include "core/file.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PI 3.14159265358979323846

static char ref_dir[4096], abs_dir[4096];
static int region[4]; /* the card's region in image 0, from the synth's capture.json */

static cf_status synth(const char *dir, double reference_albedo, cf_error *err) {
  cf_synth_options o;
  cf_synth_default_options(&o);
  o.model = CF_MODEL_DIELECTRIC;
  cf_model_default_params(o.model, o.params);
  const double params[6] = {0.6, 0.4, 0.3, 0.3, 0.3, 0.05}; /* albedo, σ, roughness, f0 */
  memcpy(o.params, params, sizeof params);
  o.images = 8;
  o.width = 200;
  o.height = 150;
  o.focal_px = 240.0;
  o.format = CF_SYNTH_EXR;
  o.supersample = 1;
  o.read_noise = o.shot_noise = 0.0;
  o.reference_albedo = reference_albedo;
  return cf_synth_write(dir, &o, err);
}

/* The region the synth wrote into capture.json. */
static int read_region(void) {
  char path[4200], *text = NULL;
  size_t size = 0;
  cf_error err = {0};
  snprintf(path, sizeof path, "%s/capture.json", ref_dir);
  if (cf_read_file(path, 1 << 20, &text, &size, &err) != CF_OK) return 0;
  const char *at = strstr(text, "\"region\"");
  int ok = at && sscanf(at, "\"region\" : [ %d , %d , %d , %d", &region[0], &region[1], &region[2],
                        &region[3]) == 4;
  free(text);
  return ok;
}

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  if (!f) {
    CHECK(0, "cannot write %s", path);
    return;
  }
  fputs(text, f);
  fclose(f);
}

/* A capture file over the synth's images, named ref_dir/<name>.json:
 * `camera_geometry`, `colour`, `radiometry` and `lights` as JSON members'
 * text, `reference` the reference object's members (NULL: no block). */
typedef struct capture_text {
  const char *camera_geometry, *colour, *radiometry, *lights, *reference;
} capture_text;

static void write_case(const char *name, const capture_text *t, char *path, size_t size) {
  static const char *const colmap =
      "\"camera\": {\"type\": \"colmap\", \"model\": \"sparse/0\"}, \"geometry\": {\"type\": "
      "\"sphere\", \"center\": [0, 0, 0], \"radius\": 1}";
  char flash[256], reference[1024] = "", text[4096];
  double intensity = CF_SYNTH_REFERENCE_FACTOR * 0.5 * PI * 25.0; /* as synth writes it */
  snprintf(flash, sizeof flash,
           "{\"type\": \"flash\", \"offset\": [0.3, -0.3, 0], \"intensity\": [%.17g, %.17g, "
           "%.17g]}",
           intensity, intensity, intensity);
  if (t->reference) snprintf(reference, sizeof reference, ", \"reference\": {%s}", t->reference);
  snprintf(text, sizeof text,
           "{\"clayfit_capture\": 1, %s, \"images\": {\"directory\": \"images\", \"files\": "
           "[\"000.exr\", \"001.exr\", \"002.exr\", \"003.exr\", \"004.exr\", \"005.exr\", "
           "\"006.exr\", \"007.exr\"]}, \"colour\": {\"encoding\": \"linear\"%s}, \"radiometry\": "
           "\"%s\", \"lights\": [%s]%s}\n",
           t->camera_geometry ? t->camera_geometry : colmap, t->colour ? t->colour : "",
           t->radiometry ? t->radiometry : "relative", t->lights ? t->lights : flash, reference);
  snprintf(path, size, "%s/%s.json", ref_dir, name);
  write_text(path, text);
}

/* The good reference block's members, with the card's region. */
static void good_reference(char *out, size_t size, const char *albedo) {
  snprintf(out, size,
           "\"image\": \"000.exr\", \"region\": [%d, %d, %d, %d], \"albedo\": %s, \"normal\": "
           "[0, 0, 1], \"point\": [0, 0, -1]",
           region[0], region[1], region[2], region[3], albedo);
}

/* Loading must fail with a message naming the file and containing
 * `expected`. */
static void refused(const char *name, const capture_text *t, const char *expected) {
  char path[4200];
  write_case(name, t, path, sizeof path);
  cf_capture *capture = NULL;
  cf_error err = {0};
  cf_status s = cf_capture_load(path, NULL, &capture, &err);
  char file[256];
  snprintf(file, sizeof file, "%s.json", name);
  CHECK(s != CF_OK && s != CF_ENOMEM, "%s: loaded (status %s)", name, cf_status_name(s));
  CHECK(strstr(err.message, file) && strstr(err.message, expected), "%s: message '%s' lacks '%s'",
        name, err.message, expected);
  printf("%-22s -> %s\n", name,
         strstr(err.message, file) ? strstr(err.message, file) : err.message);
  cf_capture_free(capture);
}

static cf_capture *load(const char *path) {
  cf_capture *capture = NULL;
  cf_error err = {0};
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_OK, "load %s: %s", path, err.message);
  return capture;
}

/* The synth's own capture: the scale, and the observations against the
 * same scene with absolute radiometry. */
static void check_scale(void) {
  char path[4200];
  snprintf(path, sizeof path, "%s/capture.json", ref_dir);
  cf_capture *with = load(path);
  snprintf(path, sizeof path, "%s/capture.json", abs_dir);
  cf_capture *truth = load(path);
  if (!with || !truth) {
    cf_capture_free(with);
    cf_capture_free(truth);
    return;
  }
  cf_capture_summary sum;
  cf_capture_summarize(with, &sum);
  double expected = 1.0 / CF_SYNTH_REFERENCE_FACTOR;
  double error = fabs(sum.reference_scale / expected - 1.0);
  printf(
      "reference: scale %.12g (1/%.2f = %.12g, relative error %.2g), spread %.2g, %zu pixels, "
      "channels %.12g %.12g %.12g\n",
      sum.reference_scale, CF_SYNTH_REFERENCE_FACTOR, expected, error, sum.reference_spread,
      sum.reference_pixels, sum.reference_channel_scales[0], sum.reference_channel_scales[1],
      sum.reference_channel_scales[2]);
  CHECK(sum.radiometry_from_reference && !sum.radiometry_relative,
        "the radiometry counts as absolute, from the reference");
  CHECK(error < 1e-6, "the scale %.12g is 1/0.37 to %.2g, not 1e-6", sum.reference_scale, error);
  CHECK(sum.reference_spread < 1e-6, "spread %.3g", sum.reference_spread);
  size_t card = (size_t)(region[2] - region[0]) * (size_t)(region[3] - region[1]);
  CHECK(sum.reference_pixels == card, "%zu pixels used of the region's %zu", sum.reference_pixels,
        card);
  for (int c = 0; c < 3; ++c)
    CHECK(fabs(sum.reference_channel_scales[c] / expected - 1.0) < 1e-6, "channel %d scale %.12g",
          c, sum.reference_channel_scales[c]);
  CHECK(sum.warnings == 0, "no warning (%zu)", sum.warnings);

  const cf_observations *a = cf_capture_observations(with), *b = cf_capture_observations(truth);
  CHECK(a->count == b->count && a->count > 10000, "%zu and %zu observations", a->count, b->count);
  double worst = 0.0;
  size_t n = a->count < b->count ? a->count : b->count;
  for (size_t i = 0; i < 3 * n * (size_t)a->lights; ++i)
    worst = fmax(worst, fabs(a->irradiance[i] - b->irradiance[i]) / fmax(b->irradiance[i], 1e-12));
  for (size_t i = 0; i < 3 * n; ++i)
    worst = fmax(worst, fabs(a->rgb[i] - b->rgb[i]) / fmax(fabs(b->rgb[i]), 1e-12));
  printf("observations against absolute radiometry: worst relative difference %.2g\n", worst);
  CHECK(worst < 1e-6, "irradiance and RGB equal the absolute capture's to %.3g", worst);
  cf_capture_free(with);
  cf_capture_free(truth);
}

/* An albedo whose colour is wrong: a warning naming the channels. */
static void check_channel_warning(void) {
  char members[512], path[4200];
  good_reference(members, sizeof members, "[0.5, 0.5, 0.55]");
  capture_text t = {.reference = members};
  write_case("wrong_colour", &t, path, sizeof path);
  cf_capture *capture = load(path);
  if (!capture) return;
  cf_capture_summary sum;
  cf_capture_summarize(capture, &sum);
  const char *warning = sum.warnings ? cf_capture_warning(capture, 0) : "";
  printf("wrong colour: scale %.6g, warning: %s\n", sum.reference_scale, warning);
  CHECK(sum.warnings == 1 && strstr(warning, "channels' scales disagree by 9.09 %"),
        "a warning about the channels: '%s'", warning);
  CHECK(fabs(sum.reference_scale * CF_SYNTH_REFERENCE_FACTOR - 1.0) < 1e-6,
        "the median over pixels and channels keeps the majority's scale: %.9g",
        sum.reference_scale);
  cf_capture_free(capture);
}

/* Directional lights need no point; one from below reaches no target. */
static void check_directional(void) {
  static const char *const from_above =
      "{\"type\": \"directional\", \"direction\": [0.3, 0, 1], \"irradiance\": [2, 2, 2]}";
  char members[512], path[4200];
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [%d, %d, %d, %d], \"albedo\": 0.5, \"normal\": "
           "[0, 0, 1]",
           region[0], region[1], region[2], region[3]);
  capture_text t = {.lights = from_above, .reference = members};
  write_case("directional", &t, path, sizeof path);
  cf_capture *capture = load(path);
  cf_capture_summary sum;
  if (capture) {
    cf_capture_summarize(capture, &sum);
    CHECK(sum.radiometry_from_reference && sum.reference_scale > 0.0,
          "directional lights, no point: scale %g", sum.reference_scale);
  }
  cf_capture_free(capture);
  t.lights = "{\"type\": \"directional\", \"direction\": [0, 0, -1], \"irradiance\": [2, 2, 2]}";
  refused("lit_from_below", &t, "reference: no light reaches the target at pixel");
}

static void check_refusals(void) {
  char good[512], members[512];
  good_reference(good, sizeof good, "0.5");
  capture_text t = {.reference = good};
  t.radiometry = "absolute";
  refused("absolute", &t, "reference: a reference target sets the scale");
  t.radiometry = NULL;
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [190, 140, 210, 150], \"albedo\": 0.5, "
           "\"normal\": [0, 0, 1], \"point\": [0, 0, -1]");
  refused("region_outside", &(capture_text){.reference = members},
          "reference.region: [190, 140, 210, 150] reaches outside 000.exr, which is 200 x 150");
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [10, 10, 10, 20], \"albedo\": 0.5, \"normal\": "
           "[0, 0, 1], \"point\": [0, 0, -1]");
  refused("region_empty", &(capture_text){.reference = members},
          "reference.region: [10, 10, 10, 20] is empty");
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [10.5, 10, 20, 20], \"albedo\": 0.5, "
           "\"normal\": [0, 0, 1], \"point\": [0, 0, -1]");
  refused("region_fractional", &(capture_text){.reference = members},
          "reference.region[0]: expected an integer (pixels), got a fractional number");
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [95, 70, 105, 80], \"albedo\": 0.5, \"normal\": "
           "[0, 0, 1], \"point\": [0, 0, -1]");
  refused("region_on_sphere", &(capture_text){.reference = members},
          "reference.region: 100 of its pixels in 000.exr see the sphere");
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [%d, %d, %d, %d], \"albedo\": 0.5, \"normal\": "
           "[0, 0, 0], \"point\": [0, 0, -1]",
           region[0], region[1], region[2], region[3]);
  refused("zero_normal", &(capture_text){.reference = members},
          "reference.normal: a direction needs a finite, non-zero length");
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [%d, %d, %d, %d], \"albedo\": 0.5, \"normal\": "
           "[0, 0, -1], \"point\": [0, 0, -1]",
           region[0], region[1], region[2], region[3]);
  refused("normal_away", &(capture_text){.reference = members},
          "the camera sees the back of the target's plane");
  good_reference(members, sizeof members, "NaN");
  refused("albedo_nan", &(capture_text){.reference = members}, "albedo_nan.json:1:");
  good_reference(members, sizeof members, "\"nan\"");
  refused("albedo_nan_string", &(capture_text){.reference = members},
          "reference.albedo: expected a number or [r, g, b], got a string");
  good_reference(members, sizeof members, "1.5");
  refused("albedo_above_1", &(capture_text){.reference = members},
          "reference.albedo: 1.5 is outside (0, 1]");
  good_reference(members, sizeof members, "[0.5, 0, 0.5]");
  refused("albedo_zero_channel", &(capture_text){.reference = members},
          "reference.albedo[1]: 0 is outside (0, 1]");
  good_reference(members, sizeof members, "[0.5, 0.5]");
  refused("albedo_two_numbers", &(capture_text){.reference = members},
          "reference.albedo: expected 3 numbers, got 2");
  snprintf(members, sizeof members,
           "\"image\": \"100.exr\", \"region\": [1, 1, 20, 20], \"albedo\": 0.5, \"normal\": [0, "
           "0, 1], \"point\": [0, 0, -1]");
  refused("unknown_image", &(capture_text){.reference = members},
          "reference.image: '100.exr' is not one of the capture's 8 images (the first is "
          "'000.exr')");
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [%d, %d, %d, %d], \"albedo\": 0.5, \"normal\": "
           "[0, 0, 1]",
           region[0], region[1], region[2], region[3]);
  refused("flash_without_point", &(capture_text){.reference = members},
          "reference: the lights include a point light or a flash");
  refused("point_light_without_point",
          &(capture_text){.lights = "{\"type\": \"point\", \"position\": [4, 0, 3], "
                                    "\"intensity\": [30, 30, 30]}",
                          .reference = members},
          "reference: the lights include a point light or a flash");
  snprintf(members, sizeof members,
           "\"image\": \"000.exr\", \"region\": [%d, %d, %d, %d], \"albedo\": 0.5, \"normal\": "
           "[0, 0, 1], \"point\": [0, 0, -1], \"pointt\": [0, 0, 0]",
           region[0], region[1], region[2], region[3]);
  refused("unknown_key", &(capture_text){.reference = members}, "reference: unknown key 'pointt'");
  refused("orthographic_point",
          &(capture_text){.camera_geometry =
                              "\"camera\": {\"type\": \"orthographic\"}, \"geometry\": {\"type\": "
                              "\"sphere_from_silhouettes\"}",
                          .lights = "{\"type\": \"directional\", \"direction\": [0, 0, 1], "
                                    "\"irradiance\": [1, 1, 1]}",
                          .reference = good},
          "reference.point: an orthographic camera has no world positions");
  /* every pixel clipped: none usable */
  refused("no_usable_pixels",
          &(capture_text){.colour = ", \"clip_level\": 1e-9", .reference = good},
          "reference.region: only 0 of its");
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: test_capture_reference DIR\n");
    return 2;
  }
  snprintf(ref_dir, sizeof ref_dir, "%s/reference", argv[1]);
  snprintf(abs_dir, sizeof abs_dir, "%s/absolute", argv[1]);
  cf_error err = {0};
  if (synth(ref_dir, 0.5, &err) != CF_OK || synth(abs_dir, 0.0, &err) != CF_OK) {
    fprintf(stderr, "synth: %s\n", err.message);
    return 1;
  }
  CHECK(read_region(), "the region in %s/capture.json", ref_dir);
  printf("the card's region in image 0: [%d, %d, %d, %d]\n", region[0], region[1], region[2],
         region[3]);
  check_scale();
  check_channel_warning();
  check_directional();
  check_refusals();
  return check_finish("test_capture_reference");
}
