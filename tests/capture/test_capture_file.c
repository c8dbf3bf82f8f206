/* Capture files that are wrong, one mistake each: every one is refused with
 * a message naming the file and the JSON path (or line and column) and
 * what was expected; and a correct one reads with its defaults filled in. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/capture_spec.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static char dir[] = "/tmp/clayfit-capture-file-XXXXXX";

/* A valid COLMAP capture; each case replaces one piece of it. */
#define CAMERA "\"camera\": {\"type\": \"colmap\", \"model\": \"sparse/0\"}"
#define IMAGES "\"images\": {\"directory\": \"images\", \"files\": [\"a.png\", \"b.png\"]}"
#define COLOUR "\"colour\": {\"encoding\": \"srgb\"}"
#define GEOMETRY "\"geometry\": {\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1}"
#define LIGHTS \
  "\"lights\": [{\"type\": \"flash\", \"offset\": [0.1, 0, 0], \"intensity\": [1, 1, 1]}]"
#define VALID \
  "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY ", " LIGHTS "}"

static cf_status read_text(const char *text, cf_capture_spec *spec, cf_error *err) {
  char path[256];
  snprintf(path, sizeof path, "%s/capture.json", dir);
  FILE *f = fopen(path, "w");
  if (!f) return CF_EIO;
  fputs(text, f);
  fclose(f);
  return cf_capture_spec_read(path, spec, err);
}

/* The text must be refused with `status`, and the message must contain
 * the file's name and `expected`. */
static void refused(const char *what, const char *text, cf_status status, const char *expected) {
  cf_capture_spec spec;
  cf_error err = {0};
  cf_status s = read_text(text, &spec, &err);
  CHECK(s == status, "%s: status %s, expected %s (%s)", what, cf_status_name(s),
        cf_status_name(status), err.message);
  CHECK(strstr(err.message, "capture.json") && strstr(err.message, expected),
        "%s: message '%s' lacks '%s'", what, err.message, expected);
  printf("%-34s -> %s\n", what, err.message + strlen(dir) + 1);
  if (s == CF_OK) cf_capture_spec_free(&spec);
}

static void valid_file(void) {
  cf_capture_spec spec;
  cf_error err = {0};
  CHECK(read_text(VALID, &spec, &err) == CF_OK, "valid file: %s", err.message);
  if (err.status != CF_OK) return;
  CHECK(spec.num_images == 2 && strstr(spec.image_paths[1], "/images/b.png"), "image paths");
  CHECK(strstr(spec.colmap_model, "/sparse/0") != NULL, "model path %s", spec.colmap_model);
  CHECK(spec.transfer == CF_TRANSFER_SRGB && isnan(spec.clip_level) && spec.black_level == 0.0,
        "colour defaults");
  CHECK(spec.exposure == CF_EXPOSURE_NONE && !spec.radiometry_relative && !spec.has_noise,
        "exposure, radiometry, noise defaults");
  CHECK(spec.margin_px == 2.0 && spec.radius == 1.0, "geometry defaults");
  CHECK(spec.num_lights == 1 && spec.lights[0].light.kind == CF_LIGHT_FLASH &&
            spec.lights[0].light.position[0] == 0.1,
        "the flash");
  cf_capture_spec_free(&spec);
}

int main(void) {
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  valid_file();
  refused("malformed JSON", "{\"clayfit_capture\": 1,,}", CF_EPARSE, "capture.json:1:");
  refused("top level not an object", "[1, 2]", CF_EPARSE, "must be an object");
  refused("duplicate key", "{\"clayfit_capture\": 1, \"clayfit_capture\": 1}", CF_EPARSE,
          "duplicate");
  refused("wrong version", "{\"clayfit_capture\": 2}", CF_ERANGE, "clayfit_capture: 2 is outside");
  refused("missing camera",
          "{\"clayfit_capture\": 1, " IMAGES ", " COLOUR ", " GEOMETRY ", " LIGHTS "}", CF_EPARSE,
          "missing required key 'camera'");
  refused("unknown top-level key",
          "{\"clayfit_capture\": 1, \"camara\": {}, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", " LIGHTS "}",
          CF_EPARSE, "unknown key 'camara'");
  refused("files not an array",
          "{\"clayfit_capture\": 1, " CAMERA ", \"images\": {\"files\": \"a.png\"}, " COLOUR
          ", " GEOMETRY ", " LIGHTS "}",
          CF_EPARSE, "images.files: expected an array, got a string");
  refused("file name not a string",
          "{\"clayfit_capture\": 1, " CAMERA ", \"images\": {\"files\": [\"a.png\", 7]}, " COLOUR
          ", " GEOMETRY ", " LIGHTS "}",
          CF_EPARSE, "images.files[1]: expected a string, got a number");
  refused("both files and list",
          "{\"clayfit_capture\": 1, " CAMERA
          ", \"images\": {\"files\": [\"a\"], \"list\": \"l.txt\"}, " COLOUR ", " GEOMETRY
          ", " LIGHTS "}",
          CF_EPARSE, "exactly one of 'files' and 'list'");
  refused("missing list file",
          "{\"clayfit_capture\": 1, " CAMERA ", \"images\": {\"list\": \"nothere.txt\"}, " COLOUR
          ", " GEOMETRY ", " LIGHTS "}",
          CF_ENOTFOUND, "nothere.txt");
  refused("unknown encoding",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES
          ", \"colour\": {\"encoding\": \"log\"}, " GEOMETRY ", " LIGHTS "}",
          CF_EPARSE, "colour.encoding: 'log' is not one of 'linear', 'srgb', 'gamma'");
  refused("misspelt colour key",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES
          ", \"colour\": {\"encoding\": \"srgb\", \"clip\": 1}, " GEOMETRY ", " LIGHTS "}",
          CF_EPARSE, "colour: unknown key 'clip'");
  refused("gamma without a value",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES
          ", \"colour\": {\"encoding\": \"gamma\"}, " GEOMETRY ", " LIGHTS "}",
          CF_EPARSE, "needs 'gamma'");
  refused("exposures of the wrong count",
          "{\"clayfit_capture\": 1, " CAMERA
          ", \"images\": {\"files\": [\"a\", \"b\"], \"exposures\": [1]}, \"colour\": "
          "{\"encoding\": \"srgb\", \"exposure\": \"given\"}, " GEOMETRY ", " LIGHTS "}",
          CF_EPARSE, "images.exposures: has 1 exposures for 2 images");
  refused("exposure given but none",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES
          ", \"colour\": {\"encoding\": \"srgb\", \"exposure\": \"given\"}, " GEOMETRY ", " LIGHTS
          "}",
          CF_EPARSE, "\"given\" needs images.exposures");
  refused(
      "number too large for JSON",
      "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR
      ", \"geometry\": {\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1e999}, " LIGHTS
      "}",
      CF_EPARSE, "capture.json:1:");
  refused("negative radius",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR
          ", \"geometry\": {\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": -1}, " LIGHTS
          "}",
          CF_ERANGE, "geometry.radius: -1 must be greater than 0");
  refused("sphere without radius",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR
          ", \"geometry\": {\"type\": \"sphere\", \"center\": [0, 0, 0]}, " LIGHTS "}",
          CF_EPARSE, "needs 'center' and 'radius'");
  refused("centre with two numbers",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR
          ", \"geometry\": {\"type\": \"sphere\", \"center\": [0, 0], \"radius\": 1}, " LIGHTS "}",
          CF_EPARSE, "geometry.center: expected 3 numbers, got 2");
  refused("normal map with a COLMAP camera",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR
          ", \"geometry\": {\"type\": \"normal_map\", \"file\": \"n.pfm\"}, " LIGHTS "}",
          CF_EPARSE, "needs an orthographic camera");
  refused("no lights",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": []}",
          CF_EPARSE, "lights: needs 1 to 64 lights");
  refused("flash without an offset",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [{\"type\": \"flash\", \"intensity\": [1, 1, 1]}]}",
          CF_EPARSE, "lights[0]: give exactly one of 'offset' and 'offset_m'");
  refused("offset in metres without a scale",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [{\"type\": \"flash\", \"offset_m\": [0, 0, 0], \"intensity\": [1, 1, "
          "1]}]}",
          CF_EPARSE, "needs scale.sphere_radius_m");
  refused("negative intensity",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [{\"type\": \"point\", \"position\": [0, 0, 5], \"intensity\": [1, -1, "
          "1]}]}",
          CF_ERANGE, "lights[0].intensity[1]: -1 must be 0 or greater");
  refused("zero direction",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 0], \"irradiance\": "
          "[1, 1, 1]}]}",
          CF_EPARSE, "lights[0].direction: a direction needs a finite, non-zero length");
  refused("point light, orthographic camera",
          "{\"clayfit_capture\": 1, \"camera\": {\"type\": \"orthographic\"}, " IMAGES ", " COLOUR
          ", \"geometry\": {\"type\": \"sphere_from_silhouettes\"}, \"lights\": [{\"type\": "
          "\"point\", \"position\": [0, 0, 5], \"intensity\": [1, 1, 1]}]}",
          CF_EPARSE, "lights[0]: an orthographic camera has no world positions");
  refused("environment map, not a rotation",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [{\"type\": \"environment\", \"file\": \"e.exr\", \"rotation\": [2, 0, "
          "0, 0, 1, 0, 0, 0, 1]}]}",
          CF_EPARSE, "lights[0].rotation: environment map rotation is not orthonormal");
  refused("environment map, a mirror (the old convention's fix)",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [{\"type\": \"environment\", \"file\": \"e.exr\", \"rotation\": [-1, 0, "
          "0, 0, 0, -1, 0, 1, 0]}]}",
          CF_EPARSE, "lights[0].rotation: environment map rotation has determinant -1: a mirror");
  refused("light of unknown type",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [{\"type\": \"laser\"}]}",
          CF_EPARSE, "lights[0].type: 'laser' is not one of");
  refused("light not an object",
          "{\"clayfit_capture\": 1, " CAMERA ", " IMAGES ", " COLOUR ", " GEOMETRY
          ", \"lights\": [3]}",
          CF_EPARSE, "lights[0]: expected an object, got a number");
  char command[512];
  snprintf(command, sizeof command, "rm -rf '%s'", dir);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_finish("test_capture_file");
}
