/* libFuzzer target for the capture file reader (cf_capture_spec_read,
 * src/capture/capture_spec.c; built and run by scripts/fuzz.sh): the bytes
 * are a capture.json in a scratch folder that also holds names.txt, an
 * image list the file may name ("images": {"list": "names.txt"}). Only the
 * file is read and checked: no image, model or light file is loaded.
 * Besides crashes and sanitizer reports, a broken promise aborts: a failure
 * leaves the spec empty and names the file; a success keeps every value
 * within the ranges the loader relies on. */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE
#endif
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "capture/capture_spec.h"
#include "fuzz_files.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int unit(const double v[3]) {
  double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return fabs(n - 1.0) < 1e-9;
}

static int finite3(const double v[3]) {
  return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static int nonnegative3(const double v[3]) {
  return finite3(v) && v[0] >= 0.0 && v[1] >= 0.0 && v[2] >= 0.0;
}

static void check_images(const cf_capture_spec *s) {
  fuzz_require(s->num_images >= 1 && s->num_images <= (1u << 20), "1 to 2^20 images", "");
  fuzz_require(s->image_names && s->image_paths, "image names and paths", "");
  for (size_t i = 0; i < s->num_images; ++i) {
    fuzz_require(s->image_names[i] && s->image_names[i][0] && s->image_paths[i],
                 "a non-empty name and a path for every image", "");
    fuzz_require(!s->mask_paths || s->mask_paths[i], "a mask path for every image", "");
    fuzz_require(!s->exposures || (isfinite(s->exposures[i]) && s->exposures[i] > 0.0),
                 "exposures finite and positive", "");
  }
  fuzz_require((s->exposure == CF_EXPOSURE_GIVEN) == (s->exposures != NULL),
               "exposures given exactly when colour.exposure is \"given\"", "");
}

static void check_light(const cf_capture_spec *s, const cf_light_spec *l) {
  switch (l->kind) {
    case CF_LIGHT_SPEC_SINGLE:
      fuzz_require(nonnegative3(l->light.intensity), "a light's intensity finite, >= 0", "");
      if (l->light.kind == CF_LIGHT_DIRECTIONAL)
        fuzz_require(unit(l->light.direction), "a directional light's direction unit", "");
      else
        fuzz_require(finite3(l->light.position) && s->camera == CF_CAMERA_KIND_COLMAP,
                     "a positional light finite, with a COLMAP camera", "");
      break;
    case CF_LIGHT_SPEC_PER_IMAGE:
      /* a directions file, and an intensities file or "equal" (not both) */
      fuzz_require(l->directions && (l->intensities != NULL) != (l->intensities_equal != 0),
                   "per-image light files", "");
      break;
    case CF_LIGHT_SPEC_ENVIRONMENT:
      fuzz_require(
          l->file && l->count >= 1 && l->count <= 4096 && isfinite(l->scale) && l->scale > 0.0,
          "an environment map's file, count and scale", "");
      break;
  }
}

static void check_spec(const cf_capture_spec *s) {
  fuzz_require(s->path && s->dir && s->name, "path, folder and name", "");
  check_images(s);
  if (s->camera == CF_CAMERA_KIND_COLMAP)
    fuzz_require(s->colmap_model != NULL, "a COLMAP model folder", "");
  else
    fuzz_require(unit(s->view), "the orthographic view direction unit", "");
  fuzz_require(s->gamma >= 1e-3 && s->gamma <= 1e3 && isfinite(s->black_level) &&
                   (isnan(s->clip_level) || (isfinite(s->clip_level) && s->clip_level > 0.0)),
               "gamma, black and clip levels in range", "");
  fuzz_require(s->margin_px >= 0.0 && s->margin_px <= 1e4, "margin_px in [0, 1e4]", "");
  if (s->geometry == CF_GEOMETRY_SPHERE)
    fuzz_require(finite3(s->center) && isfinite(s->radius) && s->radius > 0.0,
                 "the sphere finite, its radius positive", "");
  if (s->geometry == CF_GEOMETRY_NORMAL_MAP)
    fuzz_require(s->normal_map && s->camera == CF_CAMERA_KIND_ORTHOGRAPHIC,
                 "a normal map's file, with an orthographic camera", "");
  fuzz_require(s->num_lights >= 1 && s->num_lights <= 64 && s->lights, "1 to 64 lights", "");
  for (size_t i = 0; i < s->num_lights; ++i) check_light(s, &s->lights[i]);
  if (s->has_reference) {
    const cf_reference_spec *r = &s->reference;
    fuzz_require(s->radiometry_relative && r->image < s->num_images && r->region[0] >= 0 &&
                     r->region[1] >= 0 && r->region[2] > r->region[0] &&
                     r->region[3] > r->region[1] && unit(r->normal),
                 "the reference's image, region and normal", "");
    for (int c = 0; c < 3; ++c)
      fuzz_require(r->albedo[c] > 0.0 && r->albedo[c] <= 1.0, "the reference's albedo in (0, 1]",
                   "");
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static int listed;
  char path[4096], list[4096];
  if (!listed) {
    fuzz_write_text("names.txt", "a.png\n  b.png \r\n\nsub/c.exr\n", list);
    listed = 1;
  }
  fuzz_write("capture.json", data, size, path);
  cf_capture_spec spec;
  cf_error err = {0};
  cf_status s = cf_capture_spec_read(path, &spec, &err);
  if (s != CF_OK) {
    fuzz_require(err.status == s && err.message[0], "a failure sets the error", err.message);
    fuzz_require(strstr(err.message, "capture.json") || strstr(err.message, "names.txt") ||
                     strstr(err.message, "out of memory"),
                 "a failure names the file", err.message);
    fuzz_require(!spec.path && !spec.num_images && !spec.lights, "a failure leaves the spec empty",
                 err.message);
    return 0;
  }
  check_spec(&spec);
  cf_capture_spec_free(&spec);
  return 0;
}
