/* The fitted material, interactive (report_internal.h, docs/report.md "The
 * material, interactive"): the sphere under the capture's lighting as
 * clayfit renders it (viewer/clayfit.png), and the same view in three.js
 * with the exact GLSL material that `clayfit export --format glsl` writes
 * (viewer/material.js), rotatable, through the three.js bundle built beside
 * clayfit (viewer/three_viewer.js). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "clayfit/shader.h"
#include "clayfit/thumbnail.h"
#include "core/file.h"
#include "core/vec.h"
#include "report_internal.h"

/* three.js' bundle and the converted module are read whole: a bound on
 * what is copied (three.js 0.187 minified with the viewer: 0.7 MB). */
#define VIEWER_MAX_FILE (64u << 20)

/* The image the view is taken from: the one with the most observations. */
static size_t view_image(const report_data *d) {
  size_t best = 0;
  for (size_t k = 1; k < d->images; ++k)
    if (d->observations[k] > d->observations[best]) best = k;
  return best;
}

/* The camera frame of image k from its observations: z toward the camera
 * (the view where the normal faces it, n·v largest: the sphere centre's
 * direction to the camera), x along the image's columns (the normals'
 * change with the pixel's x, orthogonal to z), y = z × x (up). *front is
 * the observation facing the camera. 0 when the image has too few. */
static int camera_frame(const report_data *d, size_t k, double frame[3][3], size_t *front) {
  const cf_observations *o = d->obs;
  double best = -2.0, mean_x = 0.0, count = 0.0;
  for (size_t i = d->first[k]; i < d->last[k]; ++i) {
    if (o->image[i] != k) continue;
    double c = cf_dot3(o->normal + 3 * i, o->view + 3 * i);
    if (c > best) best = c, *front = i;
    mean_x += o->pixel[2 * i], count += 1.0;
  }
  if (count < 3.0) return 0;
  mean_x /= count;
  double gx[3] = {0.0, 0.0, 0.0};
  for (size_t i = d->first[k]; i < d->last[k]; ++i)
    if (o->image[i] == k)
      for (int c = 0; c < 3; ++c) gx[c] += (o->pixel[2 * i] - mean_x) * o->normal[3 * i + c];
  memcpy(frame[2], o->view + 3 * *front, sizeof frame[2]);
  double along = cf_dot3(gx, frame[2]);
  for (int c = 0; c < 3; ++c) frame[0][c] = gx[c] - along * frame[2][c];
  frame[1][0] = frame[2][1] * frame[0][2] - frame[2][2] * frame[0][1];
  frame[1][1] = frame[2][2] * frame[0][0] - frame[2][0] * frame[0][2];
  frame[1][2] = frame[2][0] * frame[0][1] - frame[2][1] * frame[0][0];
  return cf_normalize3(frame[0]) && cf_normalize3(frame[1]) && cf_normalize3(frame[2]);
}

/* The lights at the observation facing the camera, as directional lights
 * in the camera frame: every slot with irradiance (an environment's
 * median-cut directions, 32 by default), the strongest CF_SPHERE_MAX_LIGHTS
 * when there are more. */
static void front_lights(const report_data *d, size_t i, double frame[3][3], report_view *v) {
  const cf_observations *o = d->obs;
  v->slots = 0;
  v->light_count = 0;
  for (int j = 0; j < o->lights; ++j) {
    const double *l = o->light_dir + 3 * ((size_t)o->lights * i + (size_t)j);
    const double *e = o->irradiance + 3 * ((size_t)o->lights * i + (size_t)j);
    double power = e[0] + e[1] + e[2];
    if (!(power > 0.0) || !isfinite(power)) continue;
    ++v->slots;
    int at = v->light_count < CF_SPHERE_MAX_LIGHTS ? v->light_count++ : CF_SPHERE_MAX_LIGHTS;
    while (at > 0) { /* insertion by power, strongest first */
      const double *q = v->irradiance + 3 * (at - 1);
      if (q[0] + q[1] + q[2] >= power) break;
      if (at < CF_SPHERE_MAX_LIGHTS) {
        memcpy(v->direction + 3 * at, v->direction + 3 * (at - 1), 3 * sizeof(double));
        memcpy(v->irradiance + 3 * at, q, 3 * sizeof(double));
      }
      --at;
    }
    if (at >= CF_SPHERE_MAX_LIGHTS) continue;
    for (int c = 0; c < 3; ++c) {
      v->direction[3 * at + c] = cf_dot3(l, frame[c]);
      v->irradiance[3 * at + c] = e[c];
    }
  }
}

/* The exposure that puts an albedo-1 Lambertian sphere's brightest pixel
 * under these lights at the display curve's knee (as the standard light's
 * thumbnail does), applied to the irradiances. */
static cf_status expose(report_view *v, cf_error *err) {
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  view.size = 64;
  view.footprint_tolerance = 0.0;
  view.light_count = v->light_count;
  view.light_direction = v->direction;
  view.light_irradiance = v->irradiance;
  double white[3] = {1.0, 1.0, 1.0};
  cf_image lambert = {0};
  cf_status s = cf_sphere_render(CF_MODEL_LAMBERT, white, &view, &lambert, err);
  if (s != CF_OK) return s;
  double peak = 0.0;
  for (size_t p = 0; p < 3 * (size_t)view.size * (size_t)view.size; ++p)
    peak = fmax(peak, lambert.pixels[p]);
  cf_image_free(&lambert);
  v->exposure = peak > 0.0 ? CF_SPHERE_KNEE / peak : 1.0;
  for (int k = 0; k < 3 * v->light_count; ++k) v->irradiance[k] *= v->exposure;
  return CF_OK;
}

cf_status report_view_scene(const report_data *d, report_view *v, cf_error *err) {
  memset(v, 0, sizeof *v);
  v->image = view_image(d);
  double frame[3][3];
  size_t front = 0;
  if (d->images == 0 || !camera_frame(d, v->image, frame, &front))
    return cf_error_set(err, CF_EINVAL,
                        "the material's view: image %zu has too few observations for its camera",
                        v->image);
  front_lights(d, front, frame, v);
  if (v->light_count == 0)
    return cf_error_set(err, CF_EINVAL, "the material's view: no light reaches image %zu",
                        v->image);
  return expose(v, err);
}

/* ---- the files ---- */

/* The export's ES module as a classic script (Chromium runs no module from
 * file://): its top-level `export const`/`export function` declarations
 * lose `export`, `export default` goes, and the whole is wrapped in a
 * function that sets window.clayfitMaterial. The module's other lines are
 * the shaders' text and `//` comments (the export escapes line breaks in
 * the names it quotes), so none begins with `export`. */
static cf_status classic_script(const char *module, size_t size, char **out, size_t *out_size,
                                cf_error *err) {
  static const char head[] = "(function () {\n'use strict';\n";
  static const char tail[] =
      "\nwindow.clayfitMaterial = { clayfit, vertexShader, fragmentShader, clayfitUniforms, "
      "createClayfitMaterial };\n})();\n";
  char *s = malloc(sizeof head + size + sizeof tail);
  if (!s) return cf_error_set(err, CF_ENOMEM, "out of memory");
  size_t n = 0, exports = 0;
  memcpy(s, head, sizeof head - 1);
  n += sizeof head - 1;
  for (const char *line = module; line < module + size;) {
    const char *end = memchr(line, '\n', (size_t)(module + size - line));
    size_t len = end ? (size_t)(end - line) + 1 : (size_t)(module + size - line);
    if (len >= 15 && strncmp(line, "export default ", 15) == 0) {
      line += len;
      continue;
    }
    if (len >= 7 && strncmp(line, "export ", 7) == 0) line += 7, len -= 7, ++exports;
    memcpy(s + n, line, len);
    n += len;
    line += len;
  }
  memcpy(s + n, tail, sizeof tail - 1);
  n += sizeof tail - 1;
  if (exports != 5) { /* clayfit, vertexShader, fragmentShader, and the two functions */
    free(s);
    return cf_error_set(err, CF_EINVAL,
                        "the material's view: the glsl export has %zu exports, expected 5",
                        exports);
  }
  *out = s;
  *out_size = n;
  return CF_OK;
}

/* viewer/material.mjs (the glsl export as written) and viewer/material.js
 * (the same as a classic script). */
static cf_status write_material(const report_data *d, const char *dir, const char *fit_path,
                                cf_error *err) {
  char module_path[4200], script_path[4200];
  snprintf(module_path, sizeof module_path, "%s/viewer/material.mjs", dir);
  snprintf(script_path, sizeof script_path, "%s/viewer/material.js", dir);
  cf_status s = cf_shader_write(d->fit, fit_path, CF_SHADER_GLSL, module_path, err);
  char *module = NULL, *script = NULL;
  size_t size = 0, script_size = 0;
  if (s == CF_OK) s = cf_read_file(module_path, VIEWER_MAX_FILE, &module, &size, err);
  if (s == CF_OK) s = classic_script(module, size, &script, &script_size, err);
  if (s == CF_OK) s = cf_write_file(script_path, script, script_size, err);
  free(module);
  free(script);
  return s;
}

/* The bundle copied to viewer/three_viewer.js; v->absent says why not. */
static cf_status copy_bundle(const char *bundle, const char *dir, report_view *v, cf_error *err) {
  if (!bundle || !bundle[0]) {
    snprintf(v->absent, sizeof v->absent,
             "no bundle was given to the report writer: clayfit batch's reports have none");
    return CF_OK;
  }
  char *data = NULL;
  size_t size = 0;
  cf_error why = {0};
  if (cf_read_file(bundle, VIEWER_MAX_FILE, &data, &size, &why) != CF_OK) {
    snprintf(v->absent, sizeof v->absent, "%s", why.message);
    return CF_OK;
  }
  char path[4200];
  snprintf(path, sizeof path, "%s/viewer/three_viewer.js", dir);
  cf_status s = cf_write_file(path, data, size, err);
  free(data);
  return s;
}

cf_status report_view_write(const report_data *d, const char *dir, const char *fit_path,
                            const char *bundle, report_view *v, cf_error *err) {
  char path[4200];
  snprintf(path, sizeof path, "%s/viewer", dir);
  if (mkdir(path, 0777) != 0) return cf_error_set(err, CF_EIO, "%s: %s", path, strerror(errno));
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  view.size = REPORT_VIEW_SIZE;
  view.light_count = v->light_count;
  view.light_direction = v->direction;
  view.light_irradiance = v->irradiance;
  cf_image linear = {0};
  cf_status s = cf_report_render_sphere(&d->fit->result, &view, &linear, err);
  snprintf(path, sizeof path, "%s/viewer/clayfit.png", dir);
  if (s == CF_OK) s = cf_sphere_write_png(&linear, path, err);
  cf_image_free(&linear);
  if (s == CF_OK) s = write_material(d, dir, fit_path, err);
  if (s == CF_OK) s = copy_bundle(bundle, dir, v, err);
  return s;
}

/* ---- the page ---- */

/* The scene as JSON (numbers only) for the canvas' data-scene. */
static void scene_json(FILE *f, const report_view *v) {
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  fprintf(f,
          "{&quot;size&quot;:%d,&quot;radius&quot;:%.17g,&quot;background&quot;:%.17g,"
          "&quot;knee&quot;:%.17g,&quot;lights&quot;:[",
          REPORT_VIEW_SIZE, view.radius, view.background[0], CF_SPHERE_KNEE);
  for (int k = 0; k < v->light_count; ++k) {
    const double *l = v->direction + 3 * k, *e = v->irradiance + 3 * k;
    fprintf(f,
            "%s{&quot;direction&quot;:[%.17g,%.17g,%.17g],&quot;irradiance&quot;:[%.17g,%.17g,"
            "%.17g]}",
            k ? "," : "", l[0], l[1], l[2], e[0], e[1], e[2]);
  }
  fputs("]}", f);
}

void report_view_html(FILE *f, const report_data *d, const report_view *v) {
  const cf_capture_image *im = cf_capture_image_at(d->capture, v->image);
  fputs(
      "<h2 id=\"material\">The material</h2>\n<p>The fitted sphere under the capture's "
      "lighting as seen from image ",
      f);
  text_escape_fputs(f, text_escape_html, im ? im->name : "");
  fprintf(f,
          ": %s%d of its %d light slots with irradiance, as directional lights with their "
          "direction and irradiance at the point facing the camera (a point light or flash "
          "there; an environment as its median-cut directions), exposed so that a white "
          "Lambertian sphere peaks at %g (&times;%.4g), orthographic. Left: three.js with the "
          "exact GLSL material of <code>clayfit export --format glsl</code> "
          "(<a href=\"viewer/material.mjs\">viewer/material.mjs</a>); drag to rotate it. "
          "Right: clayfit's own rendering of the starting view.</p>\n",
          v->light_count < v->slots ? "the strongest " : "", v->light_count, v->slots,
          CF_SPHERE_KNEE, v->exposure);
  fputs("<div class=\"viewer\">", f);
  if (v->absent[0]) {
    fputs(
        "<p id=\"viewer-absent\" class=\"warn\">The interactive view is absent: its "
        "three.js bundle is missing (",
        f);
    text_escape_fputs(f, text_escape_html, v->absent);
    fputs(
        "). clayfit's build makes it, <code>clayfit-report-viewer.js</code> beside the "
        "<code>clayfit</code> binary, when <code>build/tools/node_modules</code> holds three "
        "and esbuild (<code>scripts/install-deps.sh</code>); <code>clayfit report</code> then "
        "copies it into the report.</p>",
        f);
  } else {
    fprintf(f, "<canvas id=\"clayfit-view\" width=\"%d\" height=\"%d\" data-scene=\"",
            REPORT_VIEW_SIZE, REPORT_VIEW_SIZE);
    scene_json(f, v);
    fputs("\"></canvas>", f);
  }
  fprintf(f,
          "<img src=\"viewer/clayfit.png\" alt=\"clayfit's rendering\" width=\"%d\" "
          "height=\"%d\"></div>\n<p id=\"clayfit-view-status\">%s</p>\n",
          REPORT_VIEW_SIZE, REPORT_VIEW_SIZE,
          v->absent[0] ? "interactive view: absent (no three.js bundle)"
                       : "interactive view: not started (scripts off)");
  if (!v->absent[0])
    fputs(
        "<script src=\"viewer/material.js\"></script>\n"
        "<script src=\"viewer/three_viewer.js\"></script>\n",
        f);
}
