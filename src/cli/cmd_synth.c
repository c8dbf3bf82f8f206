/* clayfit synth: a synthetic capture with known parameters. */
#include <getopt.h>
#include <stdio.h>
#include <string.h>

#include "args.h"
#include "clayfit/capture.h"
#include "clayfit/image.h"
#include "clayfit/synth.h"
#include "cli.h"
#include "core/file.h"
#include "out_path.h"

static void synth_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit synth -o DIR [--model M] [--param name=value ...] [--images N]\n"
          "                     [--size WxH] [--format png8|png16|exr|jpg] [--quality Q]\n"
          "                     [--response NAME] [--exif-exposures] [--supersample S]\n"
          "                     [--read-noise SIGMA] [--shot-noise K] [--no-noise]\n"
          "                     [--flash-intensity I] [--flash-offset x,y,z] [--silhouettes]\n"
          "                     [--masks] [--seed N]\n"
          "                     [--reference ALBEDO]\n"
          "                     [--environment MAP [--environment-lights K]\n"
          "                      [--environment-rotation r00,r01,...,r22]]\n\n"
          "Renders a clay sphere (radius 1, centre at the origin, z up) on a textured\n"
          "ground inside a textured backdrop, seen by an orbit of N cameras (two rings,\n"
          "20 and 35 degrees up, distance 5), each lit by its flash, with clayfit's image\n"
          "formation and S x S samples per pixel near and on the sphere. Writes DIR/images/,\n"
          "the true COLMAP model DIR/sparse/0/ (text), DIR/capture.json and DIR/truth.json.\n\n"
          "  --model M          material model (default clay), --param as in clayfit eval\n"
          "  --images N         cameras (default 16)        --size WxH (default 640x480)\n"
          "  --format F         png8: 8-bit sRGB (default); png16: 16-bit linear; exr: float;\n"
          "                     jpg: 8-bit sRGB JPEG, 4:2:0 chroma\n"
          "  --quality Q        JPEG quality 1..100 (default 90)\n"
          "  --response NAME    code the photos with this camera curve: linear, srgb,\n"
          "                     gamma2.2 or filmic (Hable's; default: the format's own,\n"
          "                     srgb for png8 and jpg, linear for png16). The capture file\n"
          "                     still declares the format's own; truth.json has the curve\n"
          "  --exif-exposures   (jpg) per-image exposure time, ISO and f-number in EXIF,\n"
          "                     the photos scaled to match; the capture says exposure exif\n"
          "  --supersample S    samples per pixel side (default 3)\n"
          "  --read-noise SIGMA read noise, radiance units (default 0.002)\n"
          "  --shot-noise K     photon-noise variance per unit radiance (default 0.0005)\n"
          "  --no-noise         neither\n"
          "  --flash-intensity I  radiant intensity (default: a white Lambert surface\n"
          "                     facing the flash at distance 5 has radiance 0.5)\n"
          "  --flash-offset x,y,z  the flash in camera coordinates (x right, y down, z\n"
          "                     forward; default 0.3,-0.3,0)\n"
          "  --silhouettes      the capture file asks for the sphere from its silhouettes\n"
          "  --masks            also write DIR/masks/ (the sphere's pixels)\n"
          "  --seed N           textures and noise (default 1)\n"
          "  --reference ALBEDO a grey card of this albedo on the ground in front of the\n"
          "                     sphere in image 0; the capture file says \"radiometry\":\n"
          "                     \"relative\", gives the flash intensity times 0.37 (wrong\n"
          "                     on purpose) and names the card as its reference\n"
          "  --environment MAP  light every image with an equirectangular map (linear RGB\n"
          "                     radiance, e.g. OpenEXR; the capture format's environment\n"
          "                     convention, docs/captures.md) instead of the flash: its K\n"
          "                     median-cut directional lights, L = sum_k f E_k (n.l_k)+,\n"
          "                     the fit's image formation. The sphere is not shadowed by\n"
          "                     the ground (neither is the fit's); the ground and\n"
          "                     backdrop are, by the sphere. capture.json declares the\n"
          "                     map as its environment light (path relative to DIR);\n"
          "                     not with --flash-offset, --flash-intensity, --reference\n"
          "  --environment-lights K  median-cut lights, 1..65536 (default 1024); the\n"
          "                     capture file declares at most 4096 (the fit keeps every\n"
          "                     light of every observation), truth.json the K rendered\n"
          "  --environment-rotation r00,...,r22  map frame (y up) to world (z up),\n"
          "                     row-major, orthonormal (default 1,0,0,0,0,-1,0,1,0:\n"
          "                     d_world = (x, -z, y) of d_map, the map's up to +z)\n");
}

enum { MAX_PARAMS = 64 };

static cf_status parse_size(const char *text, cf_synth_options *o, cf_error *err) {
  int w = 0, h = 0;
  char tail;
  cf_status s = CF_OK;
  if (sscanf(text, "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 16384 || h > 16384)
    s = cf_error_set(err, CF_EINVAL, "--size: '%s' is not WIDTHxHEIGHT with each in [16, 16384]",
                     text);
  o->width = w, o->height = h;
  o->focal_px = 1.2 * w;
  return s;
}

static cf_status parse_format(const char *text, cf_synth_format *format, cf_error *err) {
  if (strcmp(text, "png8") == 0)
    *format = CF_SYNTH_PNG8;
  else if (strcmp(text, "png16") == 0)
    *format = CF_SYNTH_PNG16;
  else if (strcmp(text, "exr") == 0)
    *format = CF_SYNTH_EXR;
  else if (strcmp(text, "jpg") == 0)
    *format = CF_SYNTH_JPEG;
  else
    return cf_error_set(err, CF_EINVAL, "--format: '%s' is not png8, png16, exr or jpg", text);
  return CF_OK;
}

/* One option with a value into the options. */
static cf_status parse_setting(int c, const char *arg, cf_synth_options *o, cf_error *err) {
  long count = 0;
  cf_status s = CF_OK;
  switch (c) {
    case 'n':
      s = cli_parse_count(arg, "--images", 1, 10000, &count, err);
      o->images = (int)count;
      return s;
    case 's':
      return parse_size(arg, o, err);
    case 'f':
      return parse_format(arg, &o->format, err);
    case 'q':
      s = cli_parse_count(arg, "--quality", 1, 100, &count, err);
      o->jpeg_quality = (int)count;
      return s;
    case 'c': {
      cf_response response = CF_RESPONSE_LINEAR;
      cf_error why = {0};
      if (cf_response_find(arg, &response, &why) != CF_OK)
        return cf_error_set(err, CF_EINVAL, "--response: %s", why.message);
      o->response = (int)response;
      return CF_OK;
    }
    case 'S':
      s = cli_parse_count(arg, "--supersample", 1, 16, &count, err);
      o->supersample = (int)count;
      return s;
    case 'r':
      return cli_parse_number(arg, "--read-noise", &o->read_noise, err);
    case 'k':
      return cli_parse_number(arg, "--shot-noise", &o->shot_noise, err);
    case 'I':
      return cli_parse_number(arg, "--flash-intensity", &o->flash_intensity, err);
    case 'F':
      return cli_parse_list(arg, "--flash-offset", 3, o->flash_offset, err);
    case 'e':
      s = cli_parse_count(arg, "--seed", 0, 2147483647, &count, err);
      o->seed = (uint64_t)count;
      return s;
    case 'E':
      o->environment = arg;
      return CF_OK;
    case 'K':
      s = cli_parse_count(arg, "--environment-lights", 1, CF_ENVMAP_MAX_LIGHTS, &count, err);
      o->environment_lights = (int)count;
      return s;
    case 'T':
      return cli_parse_list(arg, "--environment-rotation", 9, o->environment_rotation, err);
    case 'R':
      s = cli_parse_number(arg, "--reference", &o->reference_albedo, err);
      if (s == CF_OK && !(o->reference_albedo > 0.0 && o->reference_albedo <= 1.0))
        s = cf_error_set(err, CF_EINVAL, "--reference: the albedo %g is outside (0, 1]",
                         o->reference_albedo);
      return s;
  }
  return cf_error_set(err, CF_EINVAL, "unknown option");
}

typedef struct synth_args {
  const char *dir, *model_text;
  int flash_given; /* the letter of the last --flash-offset, --flash-intensity or --reference */
  const char *assignments[MAX_PARAMS];
  int assignment_count;
} synth_args;

/* --environment: the map exists, and the flash's options are not given
 * (the map replaces the flash). */
static cf_status check_environment(const synth_args *a, const cf_synth_options *o, cf_error *err) {
  if (!o->environment) return CF_OK;
  if (a->flash_given)
    return cf_error_set(err, CF_EINVAL, "--environment replaces the flash: not with %s",
                        a->flash_given == 'F'   ? "--flash-offset"
                        : a->flash_given == 'I' ? "--flash-intensity"
                                                : "--reference");
  if (!cf_path_exists(o->environment))
    return cf_error_set(err, CF_ENOTFOUND, "--environment: no file '%s'", o->environment);
  return CF_OK;
}

/* The command line into a and o. Returns -1 to go on, else the exit status
 * (--help, a bad option, too many --param); other errors are left in *s
 * and err. */
static int parse_synth_args(int argc, char **argv, synth_args *a, cf_synth_options *o, cf_status *s,
                            cf_error *err) {
  static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                          {"model", required_argument, NULL, 'm'},
                                          {"param", required_argument, NULL, 'p'},
                                          {"images", required_argument, NULL, 'n'},
                                          {"size", required_argument, NULL, 's'},
                                          {"format", required_argument, NULL, 'f'},
                                          {"quality", required_argument, NULL, 'q'},
                                          {"response", required_argument, NULL, 'c'},
                                          {"exif-exposures", no_argument, NULL, 'x'},
                                          {"supersample", required_argument, NULL, 'S'},
                                          {"read-noise", required_argument, NULL, 'r'},
                                          {"shot-noise", required_argument, NULL, 'k'},
                                          {"no-noise", no_argument, NULL, 'N'},
                                          {"flash-intensity", required_argument, NULL, 'I'},
                                          {"flash-offset", required_argument, NULL, 'F'},
                                          {"silhouettes", no_argument, NULL, 'g'},
                                          {"masks", no_argument, NULL, 'M'},
                                          {"seed", required_argument, NULL, 'e'},
                                          {"reference", required_argument, NULL, 'R'},
                                          {"environment", required_argument, NULL, 'E'},
                                          {"environment-lights", required_argument, NULL, 'K'},
                                          {"environment-rotation", required_argument, NULL, 'T'},
                                          {"help", no_argument, NULL, 'h'},
                                          {0}};
  memset(a, 0, sizeof *a);
  a->model_text = "clay";
  optind = 1;
  opterr = 0;
  for (int c; *s == CF_OK && (c = getopt_long(argc, argv, "o:", options, NULL)) != -1;) {
    if (c == 'o') {
      a->dir = optarg;
    } else if (c == 'm') {
      a->model_text = optarg;
    } else if (c == 'p') {
      if (a->assignment_count == MAX_PARAMS) {
        cli_report("synth", "too many --param options");
        return CLI_EXIT_USAGE;
      }
      a->assignments[a->assignment_count++] = optarg;
    } else if (c == 'N') {
      o->read_noise = o->shot_noise = 0.0;
    } else if (c == 'g') {
      o->silhouette_geometry = 1;
    } else if (c == 'M') {
      o->write_masks = 1;
    } else if (c == 'x') {
      o->exif_exposures = 1;
    } else if (c == 'h') {
      synth_usage(stdout);
      return CLI_EXIT_OK;
    } else if (c == '?' || c == ':') {
      return cli_bad_option("synth", argv);
    } else {
      if (c == 'F' || c == 'I' || c == 'R') a->flash_given = c;
      *s = parse_setting(c, optarg, o, err);
    }
  }
  if (*s == CF_OK && optind < argc)
    *s = cf_error_set(err, CF_EINVAL, "unexpected argument '%s'", argv[optind]);
  if (*s == CF_OK && !a->dir) *s = cf_error_set(err, CF_EINVAL, "-o DIR is required");
  if (*s == CF_OK) *s = check_environment(a, o, err);
  return -1;
}

/* The model and its parameters: the defaults, then --param. */
static cf_status synth_params(const synth_args *a, cf_synth_options *o, cf_error *err) {
  cf_status s = cf_model_find(a->model_text, &o->model, err);
  if (s == CF_OK) {
    int given[CF_MAX_DIM] = {0};
    cf_model_default_params(o->model, o->params);
    for (int k = 0; s == CF_OK && k < a->assignment_count; ++k)
      s = cli_apply_param(o->model, "--param", a->assignments[k], o->params, given, err);
  }
  if (s == CF_OK) s = cf_params_check(o->model, o->params, err);
  return s;
}

int cmd_synth(int argc, char **argv, cli_context *ctx) {
  cf_synth_options o;
  cf_synth_default_options(&o);
  synth_args a;
  cf_error err = {0};
  cf_status s = CF_OK;
  int exit_status = parse_synth_args(argc, argv, &a, &o, &s, &err);
  if (exit_status >= 0) return exit_status;
  if (s == CF_OK) s = synth_params(&a, &o, &err);
  if (s == CF_OK) s = cli_check_output("-o", a.dir, CLI_OUT_FOLDER, &err);
  if (s != CF_OK) {
    cli_report("synth", err.message);
    return CLI_EXIT_USAGE;
  }
  if (!ctx->quiet) {
    o.progress = cli_progress;
    o.progress_user = "synth";
  }
  s = cf_synth_write(a.dir, &o, &err);
  if (s != CF_OK) {
    cli_report("synth", err.message);
    return s == CF_ERANGE || s == CF_EINVAL ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE;
  }
  if (o.environment && o.environment_lights > CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS)
    fprintf(stderr,
            "clayfit synth: note: the photos were lit by %d median-cut lights; capture.json "
            "declares %d, a capture file's limit (truth.json has %d)\n",
            o.environment_lights, CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS, o.environment_lights);
  if (!ctx->quiet) fprintf(stderr, "clayfit synth: wrote %s/capture.json\n", a.dir);
  return CLI_EXIT_OK;
}
