/* clayfit inspect: load a capture, summarise it, and draw the pixels it
 * uses (data_schema/inspect.schema.json with --json). */
#include <getopt.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/capture.h"
#include "cli.h"
#include "core/file.h"
#include "core/vec.h"
#include "json_out.h"
#include "out_path.h"

static void inspect_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit inspect CAPTURE [-o DIR] [--json]\n\n"
          "Loads a capture file (data_schema/capture.schema.json) and everything it names\n"
          "and prints a summary (images, cameras, lights, sphere, observation counts,\n"
          "clipped fraction, pixels per image). Writes nothing unless asked:\n\n"
          "  -o DIR   write one overlay PNG per image into DIR (created if missing): the\n"
          "           photo with the pixels used green and the clipped ones red\n"
          "  --json   print the summary as JSON (data_schema/inspect.schema.json)\n"
          CLI_IMAGE_MEMORY_USAGE);
}

typedef struct totals {
  size_t clipped, unlit;
} totals;

static totals count_flags(const cf_observations *o) {
  totals t = {0, 0};
  for (size_t i = 0; i < o->count; ++i) {
    t.clipped += (o->flags[i] & CF_OBS_CLIPPED) != 0;
    t.unlit += (o->flags[i] & CF_OBS_UNLIT) != 0;
  }
  return t;
}

/* "absolute", "relative", or "from_reference" (relative lights scaled by
 * a reference target of known albedo). */
static const char *radiometry_name(const cf_capture_summary *sum) {
  return sum->radiometry_from_reference ? "from_reference"
         : sum->radiometry_relative     ? "relative"
                                        : "absolute";
}

/* The sphere: world centre and radius with COLMAP cameras (null with the
 * orthographic camera, which has no world positions); with silhouettes
 * seen orthographically, the outline fitted in pixels instead. */
static json_t *sphere_json(const cf_capture_summary *sum) {
  int world = strcmp(sum->camera, "orthographic") != 0;
  json_t *sphere = json_pack("{s:o, s:o, s:f, s:f}", "center",
                             world ? json_doubles(sum->sphere_center, 3) : json_null(), "radius",
                             world ? json_real(sum->sphere_radius) : json_null(), "rms_px",
                             sum->sphere_rms_px, "silhouette_kept", sum->silhouette_kept);
  if (sum->has_circle)
    json_object_set_new(
        sphere, "circle",
        json_pack("{s:o, s:f, s:o, s:f, s:s}", "center_px", json_doubles(sum->circle_center_px, 2),
                  "radius_px", 0.5 * (sum->circle_axes_px[0] + sum->circle_axes_px[1]),
                  "semi_axes_px", json_doubles(sum->circle_axes_px, 2), "angle_deg",
                  sum->circle_angle * CF_DEGREES, "fitted_to", sum->circle_source));
  return sphere;
}

static json_t *summary_json(const cf_capture *capture, const cf_capture_summary *sum,
                            json_t *overlays) {
  const cf_observations *o = cf_capture_observations(capture);
  totals t = count_flags(o);
  json_t *images = json_array();
  for (size_t k = 0; k < cf_capture_image_count(capture); ++k) {
    const cf_capture_image *im = cf_capture_image_at(capture, k);
    json_array_append_new(
        images, json_pack("{s:s, s:i, s:i, s:f, s:I, s:I, s:I, s:I, s:i}", "name", im->name,
                          "width", im->width, "height", im->height, "exposure", im->exposure,
                          "sphere_pixels", (json_int_t)im->sphere_pixels, "observations",
                          (json_int_t)im->observations, "clipped", (json_int_t)im->clipped,
                          "not_radiance", (json_int_t)im->not_radiance, "lights", im->lights));
  }
  json_t *warnings = json_array();
  for (size_t i = 0; i < sum->warnings; ++i)
    json_array_append_new(warnings, json_string(cf_capture_warning(capture, i)));
  json_t *doc = json_pack(
      "{s:s, s:s, s:s, s:o, s:s, s:s, s:I, s:i, s:I, s:I, s:o, s:o}", "name", sum->name, "camera",
      sum->camera, "geometry", sum->geometry, "sphere", sphere_json(sum), "radiometry",
      radiometry_name(sum), "tone_curve", sum->tone_curve_unknown ? "unknown" : "known",
      "observations", (json_int_t)o->count, "lights_per_observation", o->lights, "clipped",
      (json_int_t)t.clipped, "unlit", (json_int_t)t.unlit, "images", images, "warnings", warnings);
  if (sum->has_noise)
    json_object_set_new(doc, "noise",
                        json_pack("{s:f, s:f}", "read", sum->noise_read, "shot", sum->noise_shot));
  if (sum->radiometry_from_reference)
    json_object_set_new(doc, "reference",
                        json_pack("{s:f, s:f, s:o, s:I}", "scale", sum->reference_scale, "spread",
                                  sum->reference_spread, "channel_scales",
                                  json_doubles(sum->reference_channel_scales, 3), "pixels",
                                  (json_int_t)sum->reference_pixels));
  if (overlays) json_object_set_new(doc, "overlays", overlays);
  return doc;
}

static void print_summary(const cf_capture *capture, const cf_capture_summary *sum) {
  const cf_observations *o = cf_capture_observations(capture);
  totals t = count_flags(o);
  size_t n = cf_capture_image_count(capture);
  printf("capture: %s\n", sum->name[0] ? sum->name : "(unnamed)");
  printf("camera: %s; %zu images; lights per image: %d\n", sum->camera, n, o->lights);
  if (sum->has_circle)
    printf(
        "sphere (%s, orthographic): outline fitted to %s, used for every image: centre "
        "%.6g %.6g px, radius %.6g px (ellipse semi-axes %.6g, %.6g px at %.3g deg); no world "
        "position or size",
        sum->geometry, sum->circle_source, sum->circle_center_px[0], sum->circle_center_px[1],
        0.5 * (sum->circle_axes_px[0] + sum->circle_axes_px[1]), sum->circle_axes_px[0],
        sum->circle_axes_px[1], sum->circle_angle * CF_DEGREES);
  else if (sum->sphere_radius > 0.0)
    printf("sphere (%s): centre %.6g %.6g %.6g, radius %.6g world units", sum->geometry,
           sum->sphere_center[0], sum->sphere_center[1], sum->sphere_center[2], sum->sphere_radius);
  else
    printf("geometry: %s", sum->geometry);
  if (sum->sphere_rms_px > 0.0)
    printf(" (silhouettes: RMS %.3g px over the %.3g %% of their points that fit)",
           sum->sphere_rms_px, 100.0 * sum->silhouette_kept);
  printf("\nradiometry: %s", radiometry_name(sum));
  if (sum->radiometry_from_reference)
    printf(
        " (lights scaled by %.6g from %zu pixels of the reference, spread %.3g %%; channels "
        "%.6g %.6g %.6g)",
        sum->reference_scale, sum->reference_pixels, 100.0 * sum->reference_spread,
        sum->reference_channel_scales[0], sum->reference_channel_scales[1],
        sum->reference_channel_scales[2]);
  printf("; tone curve: %s", sum->tone_curve_unknown ? "unknown" : "known");
  if (sum->has_noise) printf("; noise: read %g, shot %g", sum->noise_read, sum->noise_shot);
  printf("\nobservations: %zu (%.3g %% with a clipped channel, %.3g %% unlit)\n", o->count,
         o->count ? 100.0 * (double)t.clipped / (double)o->count : 0.0,
         o->count ? 100.0 * (double)t.unlit / (double)o->count : 0.0);
  printf("%-24s %11s %9s %12s %12s %9s %12s\n", "image", "size", "exposure", "sphere px", "used",
         "clipped", "not radiance");
  for (size_t k = 0; k < n; ++k) {
    const cf_capture_image *im = cf_capture_image_at(capture, k);
    char size[32];
    snprintf(size, sizeof size, "%dx%d", im->width, im->height);
    printf("%-24s %11s %9.4g %12zu %12zu %9zu %12zu\n", im->name, size, im->exposure,
           im->sphere_pixels, im->observations, im->clipped, im->not_radiance);
  }
  for (size_t i = 0; i < sum->warnings; ++i)
    printf("warning: %s\n", cf_capture_warning(capture, i));
}

/* Overlays into dir, one per image, named after the image (slashes become
 * underscores, extension .png). */
static cf_status write_overlays(const cf_capture *capture, const char *dir, int quiet, json_t *list,
                                cf_error *err) {
  cf_status s = cf_make_dirs(dir, err);
  size_t n = cf_capture_image_count(capture);
  for (size_t k = 0; s == CF_OK && k < n; ++k) {
    char name[512], path[4096];
    snprintf(name, sizeof name, "%s", cf_capture_image_at(capture, k)->name);
    for (char *p = name; *p; ++p)
      if (*p == '/') *p = '_';
    char *dot = strrchr(name, '.');
    if (dot) *dot = '\0';
    strncat(name, ".png", sizeof name - strlen(name) - 1);
    s = cf_path_join(dir, name, path, sizeof path, err);
    if (s == CF_OK) s = cf_capture_write_overlay(capture, k, path, err);
    if (s == CF_OK) json_array_append_new(list, json_string(path));
    if (!quiet) cli_progress("inspect", "writing overlays", k + 1, n);
  }
  return s;
}

/* The summary on stdout, as text or JSON; overlays (the list of files
 * written, taken) only when they were written into out_dir. */
static int print_inspect(const cf_capture *capture, int as_json, const char *out_dir,
                         json_t *overlays) {
  cf_capture_summary sum;
  cf_capture_summarize(capture, &sum);
  if (as_json) {
    if (!out_dir) json_decref(overlays), overlays = NULL;
    return json_print(stdout, summary_json(capture, &sum, overlays)) ? CLI_EXIT_FAILURE
                                                                     : CLI_EXIT_OK;
  }
  print_summary(capture, &sum);
  if (out_dir) printf("overlays: %s/\n", out_dir);
  json_decref(overlays);
  return CLI_EXIT_OK;
}

int cmd_inspect(int argc, char **argv, cli_context *ctx) {
  static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                          {"json", no_argument, NULL, 'j'},
                                          {"no-overlays", no_argument, NULL, 'n'},
                                          {"max-image-memory", required_argument, NULL, 'G'},
                                          {"help", no_argument, NULL, 'h'},
                                          {0}};
  const char *out_dir = NULL;
  int as_json = 0, overlays = 1; /* --no-overlays: accepted for old scripts */
  unsigned long long max_image_bytes = 0;
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "o:", options, NULL)) != -1;) {
    if (c == 'o')
      out_dir = optarg;
    else if (c == 'j')
      as_json = 1;
    else if (c == 'n')
      overlays = 0;
    else if (c == 'G') {
      cf_error bad = {0};
      if (cli_parse_image_memory(optarg, &max_image_bytes, &bad) != CF_OK) {
        cli_report("inspect", bad.message);
        return CLI_EXIT_USAGE;
      }
    } else if (c == 'h') {
      inspect_usage(stdout);
      return CLI_EXIT_OK;
    } else
      return cli_bad_option("inspect", argv);
  }
  if (optind + 1 != argc) {
    cli_report("inspect", "expected one capture file (see clayfit inspect --help)");
    return CLI_EXIT_USAGE;
  }
  const char *path = argv[optind];
  overlays = overlays && out_dir;
  cf_error err = {0};
  cf_status s = overlays ? cli_check_output("-o", out_dir, CLI_OUT_FOLDER, &err) : CF_OK;
  if (s != CF_OK) {
    cli_report("inspect", err.message);
    return CLI_EXIT_USAGE;
  }
  cf_capture_options load_options = {ctx->quiet ? NULL : cli_progress, "inspect",
                                     max_image_bytes};
  cf_capture *capture = NULL;
  s = cf_capture_load(path, &load_options, &capture, &err);
  if (s != CF_OK) {
    cli_report("inspect", err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  json_t *list = json_array();
  if (overlays) s = write_overlays(capture, out_dir, ctx->quiet, list, &err);
  if (s != CF_OK) {
    json_decref(list);
    cf_capture_free(capture);
    cli_report("inspect", err.message);
    return s == CF_EINVAL ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE; /* EINVAL: not a file to replace */
  }
  int status = print_inspect(capture, as_json, overlays ? out_dir : NULL, list);
  cf_capture_free(capture);
  return status;
}
