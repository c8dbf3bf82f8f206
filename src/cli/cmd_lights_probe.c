/* clayfit lights --probe: a light probe from one HDR photo of a chrome ball,
 * or from exposure brackets of it, unwrapped into the equirectangular map a
 * capture's `environment` light reads (src/capture/include/capture/light_probe.h,
 * docs/lights.md "Light probe"). cmd_lights.c hands over when it sees
 * --probe. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "args.h"
#include "capture/chrome_ball.h"
#include "capture/light_probe.h"
#include "cli.h"
#include "json_out.h"

#define MAX_PHOTOS 64
#define MAX_PIXELS (1L << 28) /* 268 megapixels: more than any camera's photo */
#define COMMAND "lights --probe"

static void probe_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit lights --probe PHOTO [PHOTO...] [--exposures T...]\n"
          "                      [--mask MASK | --circle CX CY R] -o PROBE.exr [options]\n\n"
          "A light probe: the photo of a chrome (mirror) ball unwrapped into an\n"
          "equirectangular environment map (RGBA OpenEXR) that a capture's light\n"
          "{\"type\": \"environment\", \"file\": \"PROBE.exr\"} reads. The camera is taken as\n"
          "orthographic, looking down -z (x right, y up, z toward the camera); the map is\n"
          "in that frame. Directions behind the ball (around -z) are not seen: alpha 0\n"
          "and RGB 0 there, the share of the sphere reported.\n\n"
          "  --probe PHOTO...   one HDR photo (OpenEXR, Radiance .hdr, PFM: linear), or\n"
          "                     2 to 64 exposure brackets of one scene (8- or 16-bit,\n"
          "                     shortest exposure first), merged to radiance by\n"
          "                     Debevec & Malik's (1997) weighted mean of decoded value /\n"
          "                     exposure with their hat weight on the stored code;\n"
          "                     clipped and dark codes get no weight\n"
          "  --exposures T...   one exposure per photo (seconds or any relative unit, as\n"
          "                     numbers or fractions like 1/60), strictly increasing,\n"
          "                     each in [1e-9, 1e9]; default: the photos' EXIF\n"
          "                     ExposureTime (1 for one photo)\n"
          "  --encoding E       the brackets' tone curve: srgb (default for 8/16-bit\n"
          "                     photos), linear (default for float ones) or gamma\n"
          "  --gamma G          for --encoding gamma, in [0.1, 10] (default 2.2)\n"
          "  --clip X           stored value (0..1) at or above which a code is clipped\n"
          "                     (default: the top code, 1 - 0.5/(2^bits - 1))\n"
          "  --mask MASK        the ball's pixels (non-zero); its outline gives the circle,\n"
          "                     and only pixels on it are read\n"
          "  --circle CX CY R   the ball's outline in pixels (pixel centres at +0.5);\n"
          "                     --mask or --circle is required\n"
          "  --margin PX        the band inside the outline left out (default 2)\n"
          "  --reflectance R    chrome's reflectance, one constant in [0.01, 1] (default 1:\n"
          "                     the map is the reflection as photographed; Fresnel\n"
          "                     ignored)\n"
          "  --width W          the map's width, even (default 512; height W/2)\n"
          "  -o PROBE.exr       the map (written atomically)\n"
          "  --max-image-memory GB  the most decoded image data the photos and mask may\n"
          "                     hold, all together (default 32; checked from the files'\n"
          "                     headers before decoding)\n"
          "  --json             print the summary as JSON\n"
          "  -h, --help         this help\n\n"
          "Exit status: 0 done, 1 failure while running, 2 bad command line or input\n"
          "(a bracket missing or of another size, exposures not increasing, a map\n"
          "that is no usable light: a texel not finite, or all black); nothing is\n"
          "written then.\n");
}

typedef struct probe_args {
  const char *photos[MAX_PHOTOS];
  int num_photos;
  double exposures[MAX_PHOTOS];
  int num_exposures;
  const char *mask, *output, *encoding;
  double circle[3];
  int has_circle, width, json;
  double gamma, clip, margin, reflectance;
  unsigned long long max_image_bytes; /* --max-image-memory, 0: the default */
} probe_args;

static int usage_error(const char *format, ...) __attribute__((format(printf, 1, 2)));

/* Report a command-line error; CLI_EXIT_USAGE. */
static int usage_error(const char *format, ...) {
  char message[1200];
  va_list ap;
  va_start(ap, format);
  vsnprintf(message, sizeof message, format, ap);
  va_end(ap);
  cli_report(COMMAND, message);
  return CLI_EXIT_USAGE;
}

/* "1/60" or a number. */
static cf_status parse_exposure(const char *text, double *out, cf_error *err) {
  const char *slash = strchr(text, '/');
  if (!slash) return cli_parse_number(text, "--exposures", out, err);
  char numerator[64];
  size_t n = (size_t)(slash - text);
  if (n == 0 || n >= sizeof numerator)
    return cf_error_set(err, CF_EINVAL, "--exposures: '%s' is not a number or a fraction", text);
  memcpy(numerator, text, n);
  numerator[n] = '\0';
  double a, b;
  cf_status s = cli_parse_number(numerator, "--exposures", &a, err);
  if (s == CF_OK) s = cli_parse_number(slash + 1, "--exposures", &b, err);
  if (s == CF_OK && !(b != 0.0))
    return cf_error_set(err, CF_EINVAL, "--exposures: '%s' divides by 0", text);
  if (s == CF_OK) *out = a / b;
  return s;
}

/* An exposure (--exposures or EXIF, `from`) inside the merge's range. */
static cf_status check_exposure(double t, const char *from, cf_error *err) {
  if (t >= CF_BRACKET_MIN_EXPOSURE && t <= CF_BRACKET_MAX_EXPOSURE) return CF_OK;
  return cf_error_set(err, CF_EINVAL, "%s: exposure %g is outside [%g, %g]", from, t,
                      CF_BRACKET_MIN_EXPOSURE, CF_BRACKET_MAX_EXPOSURE);
}

/* The values after a multi-valued option, up to the next option. */
static int values_after(int argc, char **argv, int i) {
  int n = 0;
  while (i + 1 + n < argc && strncmp(argv[i + 1 + n], "--", 2) != 0 &&
         strcmp(argv[i + 1 + n], "-o") != 0 && strcmp(argv[i + 1 + n], "-h") != 0)
    ++n;
  return n;
}

/* One option with its values at argv[*i]; advances *i past them. */
static int parse_option(int argc, char **argv, int *i, probe_args *a, cf_error *err) {
  const char *opt = argv[*i];
  const int n = values_after(argc, argv, *i);
  cf_status s = CF_OK;
  long width = 0;
  if (!strcmp(opt, "--probe")) {
    if (n < 1 || n > MAX_PHOTOS) return usage_error("--probe takes 1 to 64 photos");
    for (int k = 0; k < n; ++k) a->photos[k] = argv[*i + 1 + k];
    a->num_photos = n;
  } else if (!strcmp(opt, "--exposures")) {
    if (n < 1 || n > MAX_PHOTOS) return usage_error("--exposures takes 1 to 64 values");
    for (int k = 0; s == CF_OK && k < n; ++k) {
      s = parse_exposure(argv[*i + 1 + k], &a->exposures[k], err);
      if (s == CF_OK) s = check_exposure(a->exposures[k], "--exposures", err);
    }
    a->num_exposures = n;
  } else if (!strcmp(opt, "--circle")) {
    if (n != 3) return usage_error("--circle takes 3 numbers: CX CY R");
    for (int k = 0; s == CF_OK && k < 3; ++k)
      s = cli_parse_number(argv[*i + 1 + k], "--circle", &a->circle[k], err);
    a->has_circle = 1;
  } else if (!strcmp(opt, "--json")) {
    if (n) return usage_error("--json takes no value, got '%s'", argv[*i + 1]);
    a->json = 1;
  } else {
    if (n != 1)
      return usage_error(
          "unknown option or missing value in '%s' (see clayfit lights --probe --help)", opt);
    const char *v = argv[*i + 1];
    if (!strcmp(opt, "--mask"))
      a->mask = v;
    else if (!strcmp(opt, "-o") || !strcmp(opt, "--output"))
      a->output = v;
    else if (!strcmp(opt, "--encoding"))
      a->encoding = v;
    else if (!strcmp(opt, "--gamma"))
      s = cli_parse_number(v, "--gamma", &a->gamma, err);
    else if (!strcmp(opt, "--clip"))
      s = cli_parse_number(v, "--clip", &a->clip, err);
    else if (!strcmp(opt, "--margin"))
      s = cli_parse_number(v, "--margin", &a->margin, err);
    else if (!strcmp(opt, "--reflectance"))
      s = cli_parse_number(v, "--reflectance", &a->reflectance, err);
    else if (!strcmp(opt, "--max-image-memory"))
      s = cli_parse_image_memory(v, &a->max_image_bytes, err);
    else if (!strcmp(opt, "--width")) {
      s = cli_parse_count(v, "--width", 8, 16384, &width, err);
      a->width = (int)width;
    } else
      return usage_error(
          "unknown option or missing value in '%s' (see clayfit lights --probe --help)", opt);
  }
  if (s != CF_OK) return usage_error("%s", err->message);
  *i += n + 1;
  return CLI_EXIT_OK;
}

/* The command line, checked for what needs no file. */
static int parse_args(int argc, char **argv, probe_args *a, int *help) {
  cf_error err = {0};
  /* margin 2 px: with a bright background and the outline 1 px too large,
   * 0 px gave 8.15 % SH-2 irradiance error on sunset.exr, 2 px 0.46 %
   * (test_light_probe) */
  *a = (probe_args){.width = 512, .gamma = 2.2, .clip = NAN, .margin = 2.0, .reflectance = 1.0};
  *help = 0;
  for (int i = 1; i < argc; ++i) *help |= !strcmp(argv[i], "--help") || !strcmp(argv[i], "-h");
  if (*help) return CLI_EXIT_OK;
  for (int i = 1; i < argc;) {
    if (strncmp(argv[i], "-", 1) != 0)
      return usage_error("'%s' belongs to no option (photos follow --probe)", argv[i]);
    int rc = parse_option(argc, argv, &i, a, &err);
    if (rc != CLI_EXIT_OK) return rc;
  }
  if (!a->num_photos) return usage_error("--probe needs at least one photo");
  if (!a->output) return usage_error("-o PROBE.exr is required");
  const char *dot = strrchr(a->output, '.');
  if (!dot || strcasecmp(dot, ".exr") != 0)
    return usage_error("-o '%s': the probe is written as OpenEXR; name it *.exr", a->output);
  if (a->width % 2) return usage_error("--width must be even");
  if (a->mask && a->has_circle) return usage_error("give --mask or --circle, not both");
  /* the outline found in the photo alone misses by 5 % of the radius on a
   * ball rendered in studio.exr (reflected edges inside it): not guessed */
  if (!a->mask && !a->has_circle)
    return usage_error("the ball's outline is needed: give --mask MASK or --circle CX CY R");
  if (a->num_exposures && a->num_exposures != a->num_photos) {
    char counts[160];
    snprintf(counts, sizeof counts, "%d photos but %d exposures", a->num_photos, a->num_exposures);
    return usage_error("--probe and --exposures: %s; a bracket is missing or an exposure is extra",
                       counts);
  }
  if (a->encoding && strcmp(a->encoding, "srgb") && strcmp(a->encoding, "linear") &&
      strcmp(a->encoding, "gamma"))
    return usage_error("--encoding '%s': expected srgb, linear or gamma", a->encoding);
  /* cameras' and displays' tone curves are gamma 1.8 to 2.6 */
  if (!(a->gamma >= 0.1 && a->gamma <= 10.0))
    return usage_error("--gamma: %g is outside [0.1, 10]", a->gamma);
  if (!(a->reflectance >= CF_PROBE_MIN_REFLECTANCE && a->reflectance <= 1.0))
    return usage_error(
        "--reflectance: %g is outside [%g, 1] (black glass reflects 0.04, chrome "
        "about 0.6)",
        a->reflectance, CF_PROBE_MIN_REFLECTANCE);
  if (!isnan(a->clip) && !(a->clip > 0.0 && a->clip <= 1.0))
    return usage_error("--clip must be in (0, 1]");
  return CLI_EXIT_OK;
}

/* ---- reading ---- */

typedef struct probe_inputs {
  cf_image photos[MAX_PHOTOS];
  cf_image_info info[MAX_PHOTOS];
  cf_image mask;
} probe_inputs;

static void free_inputs(probe_inputs *in, int count) {
  for (int k = 0; k < count; ++k) cf_image_free(&in->photos[k]);
  cf_image_free(&in->mask);
}

/* Every photo's and the mask's header, before any pixel is decoded: each
 * of the first photo's size, all within the cap on decoded bytes. */
static cf_status read_headers(const probe_args *a, cf_image_header *first, cf_error *err) {
  cli_headers t = {a->max_image_bytes, 0};
  cf_status s = cli_read_header(&t, a->photos[0], first, err);
  if (s == CF_OK && (long)first->width * first->height > MAX_PIXELS)
    s = cf_image_header_refusal(
        cf_error_set(err, CF_EINVAL, "%s: %d x %d pixels is more than a light probe needs",
                     a->photos[0], first->width, first->height),
        err);
  for (int k = 0; s == CF_OK && k <= a->num_photos; ++k) {
    const char *path = k < a->num_photos ? a->photos[k] : a->mask;
    cf_image_header h;
    if (k == 0 || !path) continue;
    s = cli_read_header(&t, path, &h, err);
    if (s == CF_OK && (h.width != first->width || h.height != first->height))
      s = cf_image_header_refusal(
          cf_error_set(err, CF_EINVAL, "%s is %d x %d pixels but %s is %d x %d: %s", path, h.width,
                       h.height, a->photos[0], first->width, first->height,
                       k < a->num_photos ? "brackets must be photos of one size"
                                         : "the mask must be the photo's size"),
          err);
  }
  return s;
}

/* Every photo (and the mask) of the first one's size, checked from the
 * headers before decoding; brackets of one kind (bits, float or not). */
static cf_status read_inputs(const probe_args *a, probe_inputs *in, cf_error *err) {
  cf_image_header first;
  cf_status s = read_headers(a, &first, err);
  if (s != CF_OK) return s;
  for (int k = 0; k < a->num_photos; ++k) {
    s = cf_image_read_sized(a->photos[k], first.width, first.height, &in->photos[k], &in->info[k],
                            err);
    if (s == CF_OK) s = cf_image_check_finite(&in->photos[k], a->photos[k], err);
    if (s != CF_OK) return s;
    if (in->info[k].is_float != in->info[0].is_float ||
        in->info[k].bits_per_sample != in->info[0].bits_per_sample)
      return cf_error_set(err, CF_EINVAL,
                          "%s is %d-bit%s but %s is %d-bit%s: brackets must come from one camera "
                          "setting",
                          a->photos[k], in->info[k].bits_per_sample,
                          in->info[k].is_float ? " float" : "", a->photos[0],
                          in->info[0].bits_per_sample, in->info[0].is_float ? " float" : "");
  }
  if (a->num_photos > 1 && in->info[0].is_float)
    return cf_error_set(err, CF_EINVAL,
                        "%d HDR (float) photos: give one; exposure brackets are 8- or 16-bit",
                        a->num_photos);
  if (a->mask) s = cf_image_read_sized(a->mask, first.width, first.height, &in->mask, NULL, err);
  return s;
}

/* The exposures: given, or EXIF, or 1 for a single photo. */
static cf_status exposures_of(const probe_args *a, const probe_inputs *in, double *t,
                              const char **source, cf_error *err) {
  *source = "--exposures";
  if (a->num_exposures) {
    memcpy(t, a->exposures, sizeof(double) * (size_t)a->num_photos);
    return CF_OK;
  }
  if (a->num_photos == 1 && !(in->info[0].exposure_time > 0.0)) {
    t[0] = 1.0;
    *source = "1 (none given)";
    return CF_OK;
  }
  *source = "EXIF";
  for (int k = 0; k < a->num_photos; ++k) {
    if (!(in->info[k].exposure_time > 0.0 && isfinite(in->info[k].exposure_time)))
      return cf_error_set(err, CF_EINVAL,
                          "%s has no EXIF exposure time: give every bracket's with --exposures",
                          a->photos[k]);
    t[k] = in->info[k].exposure_time;
    char from[4200];
    snprintf(from, sizeof from, "%.4000s (EXIF)", a->photos[k]);
    cf_status s = check_exposure(t[k], from, err);
    if (s != CF_OK) return s;
  }
  return CF_OK;
}

/* ---- the radiance photo ---- */

typedef struct probe_result {
  cf_image radiance;
  const char *exposure_source, *encoding;
  double exposures[MAX_PHOTOS];
  cf_bracket_report brackets;
  cf_probe_ball ball;
  const char *ball_source;
  double aspect; /* the outline's a/b */
  cf_probe_report unwrap;
} probe_result;

static cf_status merge_photos(const probe_args *a, probe_inputs *in, probe_result *r,
                              cf_error *err) {
  cf_status s = exposures_of(a, in, r->exposures, &r->exposure_source, err);
  if (s != CF_OK) return s;
  const int is_float = in->info[0].is_float;
  r->encoding = a->encoding ? a->encoding : is_float ? "linear" : "srgb";
  const double top = ldexp(1.0, in->info[0].bits_per_sample) - 1.0;
  cf_bracket_options o = {!strcmp(r->encoding, "srgb")     ? CF_TRANSFER_SRGB
                          : !strcmp(r->encoding, "linear") ? CF_TRANSFER_LINEAR
                                                           : CF_TRANSFER_GAMMA,
                          a->gamma, is_float ? 0.0 : 0.5 / top,
                          !isnan(a->clip) ? a->clip : 1.0 - 0.5 / top};
  if (is_float) { /* one HDR photo: values are radiance, nothing clips */
    s = cf_image_alloc(&r->radiance, in->photos[0].width, in->photos[0].height, 3, err);
    for (size_t i = 0; s == CF_OK && i < (size_t)r->radiance.width * r->radiance.height; ++i) {
      const cf_decode d = {o.transfer, o.gamma, 0.0, INFINITY, r->exposures[0]};
      double rgb[3];
      cf_decode_pixel(&d, in->photos[0].pixels + i * (size_t)in->photos[0].channels,
                      in->photos[0].channels, rgb);
      for (int c = 0; c < 3; ++c) r->radiance.pixels[3 * i + (size_t)c] = (float)rgb[c];
    }
    return s;
  }
  return cf_brackets_merge(in->photos, r->exposures, a->num_photos, a->photos, &o, &r->radiance,
                           &r->brackets, err);
}

/* The ball's outline: --circle, or the ellipse fitted to the mask. */
static cf_status find_ball(const probe_args *a, probe_inputs *in, probe_result *r, cf_error *err) {
  r->aspect = 1.0;
  if (a->has_circle) {
    r->ball = (cf_probe_ball){a->circle[0], a->circle[1], a->circle[2]};
    r->ball_source = "--circle";
    return CF_OK;
  }
  cf_ellipse outline;
  cf_status s = cf_chrome_outline(&r->radiance, 1, &in->mask, a->mask, &outline, err);
  if (s != CF_OK) return s;
  r->ball = (cf_probe_ball){outline.cx, outline.cy, 0.5 * (outline.a + outline.b)};
  r->ball_source = "the mask";
  r->aspect = outline.a / outline.b;
  return CF_OK;
}

/* ---- writing ---- */

static void print_summary(const probe_args *a, const probe_result *r) {
  if (a->json) {
    json_t *doc = json_pack(
        "{s:s, s:i, s:i, s:{s:f, s:f, s:f, s:s}, s:i, s:s, s:o, s:s, s:I, s:I, s:f, s:f, s:i}",
        "output", a->output, "width", a->width, "height", a->width / 2, "ball", "cx", r->ball.cx,
        "cy", r->ball.cy, "radius", r->ball.radius, "from", r->ball_source, "photos", a->num_photos,
        "encoding", r->encoding, "exposures", json_doubles(r->exposures, a->num_photos),
        "exposures_from", r->exposure_source, "saturated_everywhere",
        (json_int_t)r->brackets.saturated_everywhere, "dark_everywhere",
        (json_int_t)r->brackets.dark_everywhere, "invalid_fraction", r->unwrap.invalid_fraction,
        "max_reflection_deg", r->unwrap.max_reflection_deg, "supersample", r->unwrap.supersample);
    if (a->num_photos > 1)
      json_object_set_new(doc, "measured_ratios",
                          json_doubles(r->brackets.measured_ratio, a->num_photos - 1));
    json_print(stdout, doc);
    return;
  }
  printf(
      "light probe %s: %d x %d RGBA, equirectangular (the capture frame: x right, y up, z "
      "toward the camera)\n",
      a->output, a->width, a->width / 2);
  printf("  ball: centre (%.2f, %.2f) px, radius %.2f px, from %s\n", r->ball.cx, r->ball.cy,
         r->ball.radius, r->ball_source);
  if (a->num_photos > 1) {
    printf("  %d brackets merged (Debevec & Malik hat weights, %s decoding), exposures from %s\n",
           a->num_photos, r->encoding, r->exposure_source);
    for (int k = 0; k + 1 < a->num_photos; ++k)
      printf("    %s / %s: %.4g declared, %.4g measured (%zu values)\n", a->photos[k + 1],
             a->photos[k], r->exposures[k + 1] / r->exposures[k], r->brackets.measured_ratio[k],
             r->brackets.ratio_samples[k]);
  }
  printf(
      "  observed: directions up to %.1f deg from the view; %.2f %% of the sphere (behind the "
      "ball) is not: alpha 0, RGB 0\n",
      r->unwrap.max_reflection_deg, 100.0 * r->unwrap.invalid_fraction);
  printf("  a capture reads it as {\"type\": \"environment\", \"file\": \"%s\"}\n", a->output);
}

static void warn(const probe_args *a, const probe_result *r) {
  char message[512];
  if (r->brackets.saturated_everywhere) {
    snprintf(message, sizeof message,
             "warning: %zu pixels are clipped in every bracket (even %s): their radiance is only "
             "a lower bound; add a shorter exposure",
             r->brackets.saturated_everywhere, a->photos[0]);
    cli_report(COMMAND, message);
  }
  if (r->aspect > 1.02) {
    snprintf(message, sizeof message,
             "warning: the ball's outline is an ellipse (axes %.3f : 1); the unwrap takes the "
             "camera as orthographic and uses the mean radius",
             r->aspect);
    cli_report(COMMAND, message);
  }
}

int cli_lights_probe(int argc, char **argv) {
  probe_args a;
  int help = 0;
  int rc = parse_args(argc, argv, &a, &help);
  if (help && rc == CLI_EXIT_OK) probe_usage(stdout);
  if (help || rc != CLI_EXIT_OK) return rc;
  probe_inputs in;
  memset(&in, 0, sizeof in);
  probe_result r;
  memset(&r, 0, sizeof r);
  cf_error err = {0};
  cf_status s = read_inputs(&a, &in, &err);
  if (s == CF_OK) s = merge_photos(&a, &in, &r, &err);
  if (s == CF_OK) s = find_ball(&a, &in, &r, &err);
  cf_image map = {0};
  const cf_probe_options o = {a.width, a.margin, a.reflectance, a.mask ? &in.mask : NULL};
  if (s == CF_OK) s = cf_probe_unwrap(&r.radiance, &r.ball, &o, &map, &r.unwrap, &err);
  free_inputs(&in, a.num_photos);
  cf_image_free(&r.radiance);
  if (s != CF_OK) {
    cli_report(COMMAND, err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  s = cf_image_write(a.output, &map, 32, &err); /* whole or not at all */
  cf_image_free(&map);
  if (s != CF_OK) {
    cli_report(COMMAND, err.message);
    return CLI_EXIT_FAILURE;
  }
  warn(&a, &r);
  print_summary(&a, &r);
  return CLI_EXIT_OK;
}
