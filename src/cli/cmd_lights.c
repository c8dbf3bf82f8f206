/* clayfit lights: light directions from photos of a chrome (mirror) ball,
 * written as a capture's directional_per_image files (docs/lights.md).
 * With --probe, a light probe instead (cmd_lights_probe.c). */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "args.h"
#include "capture/chrome_ball.h"
#include "clayfit/capture.h"
#include "cli.h"
#include "core/file.h"
#include "core/json_reader.h"
#include "core/vec.h"
#include "json_out.h"
#include "out_path.h"

#define COMMAND "lights"
#define MAX_PHOTOS 4096

static void lights_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit lights PHOTO... (--mask MASK... | --silhouette) -o DIR\n"
          "                      [--colmap MODEL [--image NAME...]] [--lights N]\n"
          "                      [--threshold F] [--contrast C] [--max-image-memory GB]\n"
          "       clayfit lights --probe ...   (a light probe: clayfit lights --probe --help)\n\n"
          "Finds the highlight of each light in photos of a chrome (mirror) ball taken\n"
          "with the camera and lights of a capture, and the direction toward each light:\n"
          "the view ray reflected about the ball's normal there. Writes into DIR:\n"
          "  directions.txt  one row 'x y z' per photo, the unit direction toward its\n"
          "                  light: a capture's directional_per_image file (with --lights\n"
          "                  N > 1, directions_1.txt ... directions_N.txt, the highlights\n"
          "                  of each photo ordered by their brightness times area)\n"
          "  lights.json     per photo: each highlight's pixel, direction and how far a\n"
          "                  1-px error in the highlight or the ball's outline moves it\n"
          "                  (degrees), warnings; and the capture's light entry\n\n"
          "  --mask MASK      the ball's pixels (non-zero): one for every photo, or one per\n"
          "                   photo in order; its outline gives the ball's circle\n"
          "  --silhouette     the outline found in the photos instead: the per-pixel\n"
          "                   median of the photos (the highlights move, the ball does\n"
          "                   not), needs one camera pose for all photos\n"
          "  --colmap MODEL   a COLMAP sparse model with the photos registered in it:\n"
          "                   their camera models and poses; directions in its world\n"
          "                   frame. Default: orthographic, view (0, 0, 1), directions in\n"
          "                   DiLiGenT's frame (x right, y up, z toward the camera)\n"
          "  --image NAME     the photo's name in the COLMAP model, once per photo in\n"
          "                   order (default: each photo's file name)\n"
          "  --lights N       lights (highlights) in each photo (default 1); a photo with\n"
          "                   another number is an error\n"
          "  --threshold F    a highlight's pixels are at least F times the ball's\n"
          "                   brightest value (default 0.5)\n"
          "  --contrast C     the brightest value must be C times the ball's background\n"
          "                   (its 90th percentile), or the photo has no highlight\n"
          "                   (default 8)\n"
          "  --max-image-memory GB  the most decoded image data the photos and masks\n"
          "                   may hold, all together (default 32; checked from the\n"
          "                   files' headers before decoding)\n"
          "  -o DIR           the output folder (created if missing)\n"
          "  -h, --help       this help\n\n"
          "A photo without a highlight, with more or fewer than N, a ball clipped by the\n"
          "image border, or a photo that does not match its mask or camera (checked from\n"
          "the headers before any pixel is decoded) is an error (exit 2) and nothing is\n"
          "written. A highlight at the ball's rim (the light\n"
          "behind the ball) is a warning, in lights.json and on stderr.\n");
}

typedef struct lights_args {
  const char *out, *colmap;
  const char *photos[MAX_PHOTOS], *masks[MAX_PHOTOS], *names[MAX_PHOTOS];
  int photo_count, mask_count, name_count, silhouette;
  unsigned long long max_image_bytes; /* --max-image-memory, 0: the default */
  cf_chrome_options options;
} lights_args;

static cf_status parse_value(int c, const char *arg, lights_args *a, cf_error *err) {
  long count = 0;
  cf_status s = CF_OK;
  switch (c) {
    case 'n':
      s = cli_parse_count(arg, "--lights", 1, CF_CHROME_MAX_LIGHTS, &count, err);
      a->options.lights = (int)count;
      return s;
    case 't':
      s = cli_parse_number(arg, "--threshold", &a->options.threshold, err);
      if (s == CF_OK && !(a->options.threshold > 0.0 && a->options.threshold < 1.0))
        s = cf_error_set(err, CF_EINVAL, "--threshold: %g is outside (0, 1)", a->options.threshold);
      return s;
    case 'C':
      s = cli_parse_number(arg, "--contrast", &a->options.min_contrast, err);
      if (s == CF_OK && !(a->options.min_contrast >= 1.0))
        s = cf_error_set(err, CF_EINVAL, "--contrast: %g is below 1", a->options.min_contrast);
      return s;
    case 'm':
      if (a->mask_count == MAX_PHOTOS) return cf_error_set(err, CF_EINVAL, "too many --mask");
      a->masks[a->mask_count++] = arg;
      return CF_OK;
    case 'G':
      return cli_parse_image_memory(arg, &a->max_image_bytes, err);
    case 'i':
      if (a->name_count == MAX_PHOTOS) return cf_error_set(err, CF_EINVAL, "too many --image");
      a->names[a->name_count++] = arg;
      return CF_OK;
  }
  return cf_error_set(err, CF_EINVAL, "unknown option");
}

/* The options' combinations. */
static cf_status check_args(lights_args *a, int argc, char **argv, cf_error *err) {
  for (int k = optind; k < argc; ++k) {
    if (a->photo_count == MAX_PHOTOS)
      return cf_error_set(err, CF_EINVAL, "more than %d photos", MAX_PHOTOS);
    a->photos[a->photo_count++] = argv[k];
  }
  if (a->photo_count == 0) return cf_error_set(err, CF_EINVAL, "no photo given");
  if (!a->out) return cf_error_set(err, CF_EINVAL, "-o DIR is required");
  if ((a->mask_count > 0) == a->silhouette)
    return cf_error_set(err, CF_EINVAL, "give the ball's outline: --mask MASK or --silhouette");
  if (a->mask_count > 1 && a->mask_count != a->photo_count)
    return cf_error_set(err, CF_EINVAL, "%d masks for %d photos: give one, or one per photo",
                        a->mask_count, a->photo_count);
  if (a->name_count && !a->colmap)
    return cf_error_set(err, CF_EINVAL, "--image names a photo in a COLMAP model: give --colmap");
  if (a->name_count && a->name_count != a->photo_count)
    return cf_error_set(err, CF_EINVAL, "%d --image names for %d photos", a->name_count,
                        a->photo_count);
  return CF_OK;
}

/* Returns -1 to go on, else the exit status; errors in *s and err. */
static int parse_lights_args(int argc, char **argv, lights_args *a, cf_status *s, cf_error *err) {
  static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                          {"mask", required_argument, NULL, 'm'},
                                          {"silhouette", no_argument, NULL, 'S'},
                                          {"colmap", required_argument, NULL, 'c'},
                                          {"image", required_argument, NULL, 'i'},
                                          {"lights", required_argument, NULL, 'n'},
                                          {"threshold", required_argument, NULL, 't'},
                                          {"contrast", required_argument, NULL, 'C'},
                                          {"max-image-memory", required_argument, NULL, 'G'},
                                          {"help", no_argument, NULL, 'h'},
                                          {0}};
  memset(a, 0, sizeof *a);
  cf_chrome_default_options(&a->options);
  optind = 1;
  opterr = 0;
  for (int c; *s == CF_OK && (c = getopt_long(argc, argv, "o:h", options, NULL)) != -1;) {
    if (c == 'o') {
      a->out = optarg;
    } else if (c == 'S') {
      a->silhouette = 1;
    } else if (c == 'c') {
      a->colmap = optarg;
    } else if (c == 'h') {
      lights_usage(stdout);
      return CLI_EXIT_OK;
    } else if (c == '?' || c == ':') {
      return cli_bad_option(COMMAND, argv);
    } else {
      *s = parse_value(c, optarg, a, err);
    }
  }
  if (*s == CF_OK) *s = check_args(a, argc, argv, err);
  return -1;
}

/* ---- the photos, the outlines, the cameras ---- */

typedef struct lights_run {
  cf_image_header *headers; /* per photo */
  cf_image *photos, *masks;
  cf_ellipse *outlines; /* one per photo */
  cf_colmap_model model;
  const cf_camera **cameras; /* per photo, NULL: orthographic */
  double (*rotations)[9];    /* per photo, world-to-camera (COLMAP) */
  cf_chrome_result *results;
} lights_run;

static void run_free(lights_run *r, int photos, int masks) {
  for (int k = 0; r->photos && k < photos; ++k) cf_image_free(&r->photos[k]);
  for (int k = 0; r->masks && k < masks; ++k) cf_image_free(&r->masks[k]);
  free(r->headers);
  free(r->photos);
  free(r->masks);
  free(r->outlines);
  free(r->cameras);
  free(r->rotations);
  free(r->results);
  cf_colmap_model_free(&r->model);
}

cf_status cli_read_header(cli_headers *t, const char *path, cf_image_header *h, cf_error *err) {
  cf_status s = cf_image_read_header(path, h, err);
  if (s != CF_OK) return s;
  const unsigned long long cap = t->cap ? t->cap : CF_CAPTURE_MAX_IMAGE_BYTES;
  t->bytes += cf_image_header_bytes(h);
  if (t->bytes <= cap) return CF_OK;
  return cf_error_set(err, CF_ERANGE,
                      "%s (%d x %d x %d): the photos and masks up to it decode to %.3g GB of "
                      "32-bit floats, more than the cap of %.3g GB (checked from the headers, "
                      "before decoding; raise it with --max-image-memory GB)",
                      path, h->width, h->height, h->channels, (double)t->bytes / 1e9,
                      (double)cap / 1e9);
}

/* Every photo's and mask's header, before any pixel is decoded: each photo
 * the size of its mask (or of the first photo, for one outline), all within
 * the cap on decoded bytes. A 420 KB PNG declaring 12000 x 12000 took
 * 12.8 s and 2.2 GB to decode before its size was refused. */
static cf_status read_headers(const lights_args *a, lights_run *r, cf_error *err) {
  cli_headers t = {a->max_image_bytes, 0};
  cf_image_header mask;
  cf_status s = CF_OK;
  for (int k = 0; s == CF_OK && k < a->photo_count; ++k) {
    const cf_image_header *h = &r->headers[k], *first = &r->headers[0];
    s = cli_read_header(&t, a->photos[k], &r->headers[k], err);
    if (s == CF_OK && k < a->mask_count) s = cli_read_header(&t, a->masks[k], &mask, err);
    if (s != CF_OK) return s;
    if (a->mask_count && (h->width != mask.width || h->height != mask.height))
      s = cf_error_set(err, CF_EINVAL, "%s is %d x %d pixels but its mask %s is %d x %d",
                       a->photos[k], h->width, h->height, a->masks[a->mask_count == 1 ? 0 : k],
                       mask.width, mask.height);
    else if (a->silhouette && (h->width != first->width || h->height != first->height))
      s = cf_error_set(err, CF_EINVAL,
                       "%s is %d x %d, %s is %d x %d: one outline cannot serve both", a->photos[k],
                       h->width, h->height, a->photos[0], first->width, first->height);
    s = cf_image_header_refusal(s, err);
  }
  return s;
}

/* The photos and masks decoded, each of the size its header declared. */
static cf_status read_images(const lights_args *a, lights_run *r, cf_error *err) {
  cf_status s = CF_OK;
  for (int k = 0; s == CF_OK && k < a->photo_count; ++k) {
    const cf_image_header *h = &r->headers[k];
    s = cf_image_read_sized(a->photos[k], h->width, h->height, &r->photos[k], NULL, err);
    if (s == CF_OK) s = cf_image_check_finite(&r->photos[k], a->photos[k], err);
  }
  for (int k = 0; s == CF_OK && k < a->mask_count; ++k) {
    const cf_image *photo = &r->photos[k];
    s = cf_image_read_sized(a->masks[k], photo->width, photo->height, &r->masks[k], NULL, err);
  }
  return s;
}

static cf_status alloc_run(const lights_args *a, lights_run *r, cf_error *err) {
  size_t n = (size_t)a->photo_count;
  r->headers = calloc(n, sizeof *r->headers);
  r->photos = calloc(n, sizeof *r->photos);
  r->masks = calloc((size_t)a->mask_count + 1, sizeof *r->masks);
  r->outlines = calloc(n, sizeof *r->outlines);
  r->cameras = calloc(n, sizeof *r->cameras);
  r->rotations = calloc(n, sizeof *r->rotations);
  r->results = calloc(n, sizeof *r->results);
  if (!r->headers || !r->photos || !r->masks || !r->outlines || !r->cameras || !r->rotations ||
      !r->results)
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu photos", n);
  return CF_OK;
}

static cf_status find_outlines(const lights_args *a, lights_run *r, cf_error *err) {
  cf_status s = CF_OK;
  if (a->silhouette)
    s = cf_chrome_outline(r->photos, (size_t)a->photo_count, NULL, "the photos' median",
                          &r->outlines[0], err);
  for (int k = 0; s == CF_OK && k < a->mask_count; ++k)
    s = cf_chrome_outline(NULL, 0, &r->masks[k], a->masks[k], &r->outlines[k], err);
  int shared = a->silhouette || a->mask_count == 1;
  for (int k = 1; shared && k < a->photo_count; ++k) r->outlines[k] = r->outlines[0];
  return s;
}

static const char *base_name(const char *path) {
  const char *slash = strrchr(path, '/');
  return slash ? slash + 1 : path;
}

/* Each photo's COLMAP camera and rotation; with one outline for all photos
 * (--silhouette, one --mask) every photo must have the same pose. */
static cf_status find_cameras(const lights_args *a, lights_run *r, cf_error *err) {
  if (!a->colmap) return CF_OK;
  cf_status s = cf_colmap_read(a->colmap, 0, &r->model, err);
  const cf_colmap_image *first = NULL;
  for (int k = 0; s == CF_OK && k < a->photo_count; ++k) {
    const char *name = a->name_count ? a->names[k] : base_name(a->photos[k]);
    const cf_colmap_image *image = cf_colmap_find_image_by_name(&r->model, name);
    if (!image)
      return cf_error_set(err, CF_EINVAL, "%s: no image '%s' in the COLMAP model %s%s",
                          a->photos[k], name, a->colmap,
                          a->name_count ? "" : " (give --image NAME)");
    const cf_camera *camera = cf_colmap_find_camera(&r->model, image->camera_id);
    const cf_image_header *h = &r->headers[k];
    if (!camera || camera->width != (uint64_t)h->width || camera->height != (uint64_t)h->height)
      return cf_image_header_refusal(
          cf_error_set(err, CF_EINVAL, "%s is %d x %d, its COLMAP camera %u is %llu x %llu",
                       a->photos[k], h->width, h->height, image->camera_id,
                       camera ? (unsigned long long)camera->width : 0ULL,
                       camera ? (unsigned long long)camera->height : 0ULL),
          err);
    r->cameras[k] = camera;
    cf_quaternion_to_matrix(image->qvec, r->rotations[k]);
    if (k == 0) first = image;
    int shared = a->silhouette || a->mask_count == 1;
    if (shared && (memcmp(image->qvec, first->qvec, sizeof image->qvec) != 0 ||
                   memcmp(image->tvec, first->tvec, sizeof image->tvec) != 0))
      return cf_error_set(err, CF_EINVAL,
                          "one outline (%s) serves photos of one camera pose, and %s's pose "
                          "differs from %s's: give one --mask per photo",
                          a->silhouette ? "--silhouette" : "one --mask", a->photos[k],
                          a->photos[0]);
  }
  return s;
}

/* The directions into the world frame of a COLMAP model: Rᵀ l. */
static void to_world(lights_run *r, int k) {
  if (!r->cameras[k]) return;
  const double *R = r->rotations[k];
  for (size_t j = 0; j < r->results[k].count; ++j) {
    double *l = r->results[k].lights[j].direction, w[3];
    for (int i = 0; i < 3; ++i) w[i] = R[i] * l[0] + R[3 + i] * l[1] + R[6 + i] * l[2];
    memcpy(l, w, sizeof w);
  }
}

static cf_status find_lights(const lights_args *a, lights_run *r, cli_context *ctx, cf_error *err) {
  cf_status s = CF_OK;
  for (int k = 0; s == CF_OK && k < a->photo_count; ++k) {
    s = cf_chrome_lights(&r->photos[k], &r->outlines[k], r->cameras[k], &a->options, a->photos[k],
                         &r->results[k], err);
    if (s == CF_OK) to_world(r, k);
    if (!ctx->quiet) cli_progress(COMMAND, "photos", (size_t)k + 1, (size_t)a->photo_count);
  }
  return s;
}

/* ---- the outputs ---- */

static json_t *light_json(const cf_chrome_light *L) {
  json_t *warnings = json_array();
  for (unsigned bit = 1; bit <= CF_CHROME_UNSATURATED; bit <<= 1)
    if (L->warnings & bit)
      json_array_append_new(warnings, json_string(cf_chrome_warning_text(bit)));
  return json_pack("{s:o, s:I, s:I, s:f, s:f, s:o, s:f, s:{s:o, s:o, s:o}, s:o}", "pixel",
                   json_doubles(L->pixel, 2), "area", (json_int_t)L->area, "clipped",
                   (json_int_t)L->clipped, "peak", L->peak, "rho", L->rho, "direction",
                   json_doubles(L->direction, 3), "view_angle_deg", L->view_angle_deg, "per_px_deg",
                   "highlight", json_real_or_null(L->per_px_highlight_deg), "center",
                   json_real_or_null(L->per_px_center_deg), "radius",
                   json_real_or_null(L->per_px_radius_deg), "warnings", warnings);
}

static json_t *outline_json(const cf_ellipse *e, const char *fitted_to) {
  double center[2] = {e->cx, e->cy}, axes[2] = {e->a, e->b};
  return json_pack("{s:o, s:f, s:o, s:f, s:o}", "center_px", json_doubles(center, 2), "radius_px",
                   0.5 * (e->a + e->b), "semi_axes_px", json_doubles(axes, 2), "angle_deg",
                   e->angle * 180.0 / CF_PI, "fitted_to", json_text(fitted_to));
}

/* The capture's light entries for the files written. */
static json_t *capture_lights_json(const lights_args *a) {
  json_t *list = json_array();
  for (int j = 0; j < a->options.lights; ++j) {
    char file[32];
    if (a->options.lights == 1)
      snprintf(file, sizeof file, "directions.txt");
    else
      snprintf(file, sizeof file, "directions_%d.txt", j + 1);
    json_array_append_new(list, json_pack("{s:s, s:s, s:s}", "type", "directional_per_image",
                                          "directions", file, "intensities", "equal"));
  }
  return list;
}

static json_t *report_json(const lights_args *a, const lights_run *r) {
  json_t *images = json_array();
  for (int k = 0; k < a->photo_count; ++k) {
    json_t *lights = json_array();
    for (size_t j = 0; j < r->results[k].count; ++j)
      json_array_append_new(lights, light_json(&r->results[k].lights[j]));
    json_array_append_new(
        images,
        json_pack(
            "{s:o, s:o, s:o, s:I, s:f, s:f}", "file", json_text(a->photos[k]), "outline",
            outline_json(&r->outlines[k], a->silhouette ? "the photos' median"
                                                        : a->masks[a->mask_count == 1 ? 0 : k]),
            "lights", lights, "specks", (json_int_t)r->results[k].specks, "ball_peak",
            r->results[k].peak, "ball_background", r->results[k].background));
  }
  const char *frame =
      a->colmap ? "COLMAP world" : "orthographic: x right, y up, z toward the camera";
  return json_pack("{s:s, s:s, s:o, s:s, s:i, s:o, s:o}", "command", "clayfit lights", "camera",
                   a->colmap ? "colmap" : "orthographic", "colmap_model",
                   a->colmap ? json_text(a->colmap) : json_null(), "frame", frame,
                   "lights_per_photo", a->options.lights, "images", images, "capture_lights",
                   capture_lights_json(a));
}

/* directions.txt (or _1 ... _N): comments naming the frame and the photos,
 * then one row per photo. */
static cf_status write_directions(const lights_args *a, const lights_run *r, int j, cf_error *err) {
  size_t cap = 512 + (size_t)a->photo_count * 4200, used = 0;
  char *text = malloc(cap), file[32], path[4200];
  if (!text) return cf_error_set(err, CF_ENOMEM, "out of memory");
  used += (size_t)snprintf(text, cap,
                           "# clayfit lights: toward the light, one row 'x y z' per photo (%s)\n",
                           a->colmap ? "COLMAP world frame" : "x right, y up, z toward the camera");
  for (int k = 0; k < a->photo_count; ++k)
    used += (size_t)snprintf(text + used, cap - used, "# %d: %.4000s\n", k + 1, a->photos[k]);
  for (int k = 0; k < a->photo_count; ++k) {
    const double *l = r->results[k].lights[j].direction;
    used += (size_t)snprintf(text + used, cap - used, "%.12f %.12f %.12f\n", l[0], l[1], l[2]);
  }
  if (a->options.lights == 1)
    snprintf(file, sizeof file, "directions.txt");
  else
    snprintf(file, sizeof file, "directions_%d.txt", j + 1);
  cf_status s = cf_path_join(a->out, file, path, sizeof path, err);
  if (s == CF_OK) s = cf_write_file(path, text, used, err);
  free(text);
  return s;
}

static cf_status write_outputs(const lights_args *a, const lights_run *r, cf_error *err) {
  char path[4200];
  cf_status s = cf_make_dirs(a->out, err);
  for (int j = 0; s == CF_OK && j < a->options.lights; ++j) s = write_directions(a, r, j, err);
  json_t *doc = s == CF_OK ? report_json(a, r) : NULL;
  if (s == CF_OK && !doc) s = cf_error_set(err, CF_ENOMEM, "out of memory");
  if (s == CF_OK) s = cf_path_join(a->out, "lights.json", path, sizeof path, err);
  if (s == CF_OK) s = json_write_file(doc, path, JSON_INDENT(2) | JSON_REAL_PRECISION(17), err);
  json_decref(doc);
  return s;
}

static void print_summary(const lights_args *a, const lights_run *r) {
  for (int k = 0; k < a->photo_count; ++k)
    for (size_t j = 0; j < r->results[k].count; ++j) {
      const cf_chrome_light *L = &r->results[k].lights[j];
      fprintf(stderr,
              "clayfit lights: %s: (%.4f, %.4f, %.4f), %.1f deg from the view; 1 px moves it "
              "%.2f deg (highlight), %.2f (centre), %.2f (radius)\n",
              a->photos[k], L->direction[0], L->direction[1], L->direction[2], L->view_angle_deg,
              L->per_px_highlight_deg, L->per_px_center_deg, L->per_px_radius_deg);
      for (unsigned bit = 1; bit <= CF_CHROME_UNSATURATED; bit <<= 1)
        if ((L->warnings & bit) && bit != CF_CHROME_UNSATURATED)
          fprintf(stderr, "clayfit lights: warning: %s: %s\n", a->photos[k],
                  cf_chrome_warning_text(bit));
    }
}

static int run_lights(int argc, char **argv, lights_args *a, cli_context *ctx) {
  cf_error err = {0};
  cf_status s = CF_OK;
  int exit_status = parse_lights_args(argc, argv, a, &s, &err);
  if (exit_status >= 0) return exit_status;
  if (s == CF_OK) s = cli_check_output("-o", a->out, CLI_OUT_FOLDER, &err);
  if (s != CF_OK) {
    cli_report(COMMAND, err.message);
    return CLI_EXIT_USAGE;
  }
  lights_run r;
  memset(&r, 0, sizeof r);
  s = alloc_run(a, &r, &err);
  if (s == CF_OK) s = read_headers(a, &r, &err);
  if (s == CF_OK) s = find_cameras(a, &r, &err);
  if (s == CF_OK) s = read_images(a, &r, &err);
  if (s == CF_OK) s = find_outlines(a, &r, &err);
  if (s == CF_OK) s = find_lights(a, &r, ctx, &err);
  int writing = s == CF_OK; /* the inputs were good: what fails now is a failure */
  if (s == CF_OK) s = write_outputs(a, &r, &err);
  if (s == CF_OK && !ctx->quiet) print_summary(a, &r);
  run_free(&r, a->photo_count, a->mask_count);
  if (s != CF_OK) {
    cli_report(COMMAND, err.message);
    return writing || s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  if (!ctx->quiet)
    fprintf(stderr, "clayfit lights: wrote %s/directions%s.txt and lights.json\n", a->out,
            a->options.lights == 1 ? "" : "_N");
  return CLI_EXIT_OK;
}

int cmd_lights(int argc, char **argv, cli_context *ctx) {
  for (int k = 1; k < argc; ++k)
    if (strcmp(argv[k], "--probe") == 0) return cli_lights_probe(argc, argv);
  lights_args *args = malloc(sizeof *args); /* large: the file lists */
  if (!args) {
    cli_report(COMMAND, "out of memory");
    return CLI_EXIT_FAILURE;
  }
  int exit_status = run_lights(argc, argv, args, ctx);
  free(args);
  return exit_status;
}
