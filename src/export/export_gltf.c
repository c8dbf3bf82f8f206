/* glTF 2.0 (Khronos, registry.khronos.org/glTF/specs/2.0): one material on
 * a UV sphere whose vertices are in a base64 data URI, so that the .gltf
 * is self-contained and opens in any viewer. The material uses the core
 * metallic-roughness model (Lambertian diffuse, GGX with height-correlated
 * Smith and Schlick's Fresnel on v.h: the glTF 2.0 spec, Appendix B) and
 * the extensions KHR_materials_clearcoat (coat F0 fixed at 0.04, IOR 1.5),
 * KHR_materials_ior and KHR_materials_specular where they apply. glTF JSON
 * has no comments: the notes are in asset.extras.clayfit. */
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/json_reader.h"
#include "export_internal.h"

enum { SPHERE_RINGS = 32, SPHERE_SEGMENTS = 64 };

static char *base64(const unsigned char *data, size_t size) {
  static const char table[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  char *out = malloc(4 * ((size + 2) / 3) + 1);
  if (!out) return NULL;
  size_t o = 0;
  for (size_t i = 0; i < size; i += 3) {
    uint32_t v = (uint32_t)data[i] << 16;
    if (i + 1 < size) v |= (uint32_t)data[i + 1] << 8;
    if (i + 2 < size) v |= data[i + 2];
    out[o++] = table[(v >> 18) & 63];
    out[o++] = table[(v >> 12) & 63];
    out[o++] = i + 1 < size ? table[(v >> 6) & 63] : '=';
    out[o++] = i + 2 < size ? table[v & 63] : '=';
  }
  out[o] = '\0';
  return out;
}

/* The unit sphere, y up (glTF's convention): positions and normals as
 * float32, then uint16 indices of counter-clockwise triangles seen from
 * outside. */
typedef struct sphere_mesh {
  unsigned char *bytes;
  size_t vertices, indices, position_bytes, index_bytes, size;
  float min[3], max[3];
} sphere_mesh;

static int make_sphere(sphere_mesh *s) {
  s->vertices = (size_t)(SPHERE_RINGS + 1) * (SPHERE_SEGMENTS + 1);
  s->indices = (size_t)SPHERE_RINGS * SPHERE_SEGMENTS * 6;
  s->position_bytes = s->vertices * 3 * sizeof(float);
  s->index_bytes = s->indices * sizeof(uint16_t);
  s->size = 2 * s->position_bytes + s->index_bytes;
  s->bytes = calloc(1, s->size);
  if (!s->bytes) return 0;
  float *position = (float *)s->bytes, *normal = (float *)(s->bytes + s->position_bytes);
  uint16_t *index = (uint16_t *)(s->bytes + 2 * s->position_bytes);
  for (int c = 0; c < 3; ++c) s->min[c] = 1e30f, s->max[c] = -1e30f;
  size_t v = 0;
  for (int i = 0; i <= SPHERE_RINGS; ++i) {
    double theta = CF_PI * i / SPHERE_RINGS;
    for (int j = 0; j <= SPHERE_SEGMENTS; ++j, ++v) {
      double phi = 2.0 * CF_PI * j / SPHERE_SEGMENTS;
      double p[3] = {sin(theta) * sin(phi), cos(theta), sin(theta) * cos(phi)};
      double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (int c = 0; c < 3; ++c) {
        position[3 * v + c] = (float)p[c];
        normal[3 * v + c] = (float)(p[c] / len);
        if (position[3 * v + c] < s->min[c]) s->min[c] = position[3 * v + c];
        if (position[3 * v + c] > s->max[c]) s->max[c] = position[3 * v + c];
      }
    }
  }
  size_t k = 0;
  for (int i = 0; i < SPHERE_RINGS; ++i)
    for (int j = 0; j < SPHERE_SEGMENTS; ++j) {
      uint16_t a = (uint16_t)(i * (SPHERE_SEGMENTS + 1) + j),
               b = (uint16_t)(a + SPHERE_SEGMENTS + 1);
      /* a (upper left), b below it; phi grows toward +x from +z */
      index[k++] = a, index[k++] = b, index[k++] = (uint16_t)(a + 1);
      index[k++] = (uint16_t)(a + 1), index[k++] = b, index[k++] = (uint16_t)(b + 1);
    }
  return 1;
}

static json_t *floats3(const float *x) {
  return json_pack("[f, f, f]", (double)x[0], (double)x[1], (double)x[2]);
}

static json_t *rgb(const double *x, int alpha) {
  json_t *a = json_pack("[f, f, f]", x[0], x[1], x[2]);
  if (alpha) json_array_append_new(a, json_real(1.0));
  return a;
}

/* A [0, 1] factor: outside, the nearest end is written (glTF's schema
 * allows nothing else) and the change reported. */
static double factor(preset_notes *n, const char *name, double x) {
  if (x >= 0.0 && x <= 1.0) return x;
  double y = x < 0.0 ? 0.0 : 1.0;
  preset_note(n, PRESET_RANGE, "%s = %.6g is outside glTF's range [0, 1]: written as %g", name, x,
              y);
  return y;
}

/* glTF's diffuse per unit colour (the spec's Appendix B, as three.js
 * r155+ computes it for a punctual light): Lambert, times 1 - F(v.h) of the
 * specular lobe (fresnel_mix; Schlick from F0 to F90), times 1 - coat
 * F_coat(n.v) (KHR_materials_clearcoat: F0 0.04, F90 1). */
typedef struct gltf_diffuse {
  double f0, f90, coat;
} gltf_diffuse;

static double schlick(double f0, double f90, double c) {
  double m = 1.0 - c;
  return f0 + (f90 - f0) * m * m * m * m * m;
}

static double gltf_basis(const void *ctx, int variant, const double l[3], const double v[3]) {
  (void)variant;
  const gltf_diffuse *g = ctx;
  double h[3] = {l[0] + v[0], l[1] + v[1], l[2] + v[2]};
  double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
  double vh = len > 0.0 ? (v[0] * h[0] + v[1] * h[1] + v[2] * h[2]) / len : 1.0;
  return (1.0 - schlick(g->f0, g->f90, vh)) * (1.0 - g->coat * schlick(0.04, 1.0, v[2])) / CF_PI;
}

/* baseColorFactor: the colour of glTF's diffuse closest to the model's
 * (export_fit_diffuse_colour). On docs/fidelity.md's scene in three.js it
 * takes M2 from 13.1 % (albedo) to 6.4 %, M4 (the film as the lobe) from
 * 20.3 % (albedo exp(-2 tau)) to 4.6 %. */
static cf_status gltf_colour(const cf_fit_file *fit, const export_material *m, gltf_diffuse g,
                             preset_notes *n, double base[3], cf_error *err) {
  export_diffuse_colour d;
  cf_status s = export_fit_diffuse_colour(fit, gltf_basis, &g, 1, "glTF diffuse colour", &d, err);
  if (s != CF_OK) return s;
  memcpy(base, d.colour, sizeof d.colour);
  preset_note(n, PRESET_APPROX,
              "baseColorFactor %.6g, %.6g, %.6g: the colour of glTF's Lambertian diffuse (times "
              "1 - F(v.h) and the coat's 1 - F(n.v)) closest to the model's diffuse by least "
              "squares over the sphere metric of docs/presets.md; what it cannot follow: %.1f %% "
              "RMS of the diffuse (albedo %.6g, %.6g, %.6g, sigma %.6g rad)",
              base[0], base[1], base[2], 100.0 * d.loss, m->albedo[0], m->albedo[1], m->albedo[2],
              m->sigma);
  return CF_OK;
}

/* M4 (and M4T as its GGX): the film's lobe as the specular lobe (GGX,
 * KHR_materials_ior of the film: its F0 exactly); everything under the film
 * as the diffuse colour; the base's lobe, seen through the film, as the
 * clear coat. The film as the clear coat (F0 fixed at 0.04) was 39.9 % off
 * in three.js, this is 4.6 % (docs/fidelity.md). */
static void clay_lobes(const export_material *m, preset_notes *n, json_t *ext, double *roughness,
                       gltf_diffuse *g) {
  double eta1 = m->film_ior, t1 = 1.0 - m->film_f0;
  double tmean = (m->transmittance[0] + m->transmittance[1] + m->transmittance[2]) / 3.0;
  /* the base's lobe at normal incidence: F0_2 (1 - F0_1)^2 e^(-2 tau) / eta1^2 */
  double coat = factor(n, "clearcoatFactor", m->base_f0 * t1 * t1 * tmean / (eta1 * eta1) / 0.04);
  *roughness = m->film_roughness;
  *g = (gltf_diffuse){m->film_f0, 1.0, coat};
  json_object_set_new(ext, "KHR_materials_ior", json_pack("{s:f}", "ior", eta1));
  json_object_set_new(ext, "KHR_materials_clearcoat",
                      json_pack("{s:f, s:f}", "clearcoatFactor", coat, "clearcoatRoughnessFactor",
                                m->base_roughness));
  preset_note(n, PRESET_EXACT,
              "the film's lobe -> roughnessFactor = film_roughness %.6g (GGX, alpha = r^2), "
              "KHR_materials_ior ior = the film's IOR %.6g (F0 = film_f0 %.6g)",
              m->film_roughness, eta1, m->film_f0);
  preset_note(n, PRESET_APPROX,
              "the base's lobe -> clearcoatFactor = base_f0 (1 - film_f0)^2 mean(exp(-2 tau)) / "
              "eta1^2 / 0.04 = %.6g (its reflectance at normal incidence through the film), "
              "clearcoatRoughnessFactor = base_roughness %.6g: not refracted, no tint",
              coat, m->base_roughness);
}

static cf_status material_json(const cf_fit_file *fit, const export_material *m, preset_notes *n,
                               json_t *used, json_t **material, cf_error *err) {
  json_t *ext = json_object();
  double base[3], roughness = 1.0;
  gltf_diffuse g = {0.0, 0.0, 0.0};
  if (m->model != CF_MODEL_LAMBERT)
    preset_note(n, PRESET_DROPPED,
                "diffuse_roughness sigma %.6g rad: glTF's diffuse is Lambertian (no ratified "
                "extension has diffuse roughness); the colour below absorbs what it can",
                m->sigma);
  if (m->model == CF_MODEL_LAMBERT || m->model == CF_MODEL_OREN_NAYAR) {
    json_object_set_new(ext, "KHR_materials_specular", json_pack("{s:f}", "specularFactor", 0.0));
    preset_note(n, PRESET_EXACT,
                "no specular lobe in %s: KHR_materials_specular specularFactor 0 (scales the "
                "dielectric Fresnel, grazing term included, to 0: the diffuse alone remains)",
                m->info->code);
  } else if (m->model == CF_MODEL_CLAY) {
    clay_lobes(m, n, ext, &roughness, &g);
  } else {
    roughness = m->roughness;
    g = (gltf_diffuse){m->f0, 1.0, 0.0};
    json_object_set_new(ext, "KHR_materials_ior", json_pack("{s:f}", "ior", m->ior));
    preset_note(n, PRESET_EXACT,
                "roughness %.6g -> roughnessFactor, f0 %.6g -> KHR_materials_ior ior %.6g: glTF's "
                "specular lobe is clayfit's (GGX, height-correlated Smith, Schlick on v.h)",
                m->roughness, m->f0, m->ior);
    if (m->model == CF_MODEL_CLEARCOAT) {
      double weight, r, loss;
      cf_status s = export_coat_ggx_fit(fit, &weight, &r, &loss, err);
      if (s != CF_OK) {
        json_decref(ext);
        return s;
      }
      g.coat = weight = factor(n, "clearcoatFactor", weight);
      json_object_set_new(
          ext, "KHR_materials_clearcoat",
          json_pack("{s:f, s:f}", "clearcoatFactor", weight, "clearcoatRoughnessFactor", r));
      preset_note(n, PRESET_APPROX,
                  "Burley's clear coat (coat_weight %.6g, GTR1 width a = %.6g) -> the GGX coat "
                  "closest to it by least squares over the sphere metric: clearcoatFactor %.6g, "
                  "clearcoatRoughnessFactor %.6g (%.1f %% RMS of the coat left; 0.25 coat_weight "
                  "and sqrt(a) were 16.4 %% off in three.js, docs/fidelity.md); it also darkens "
                  "the base",
                  m->coat_weight, m->gtr1_a, weight, r, 100.0 * loss);
    }
  }
  cf_status s = gltf_colour(fit, m, g, n, base, err);
  if (s != CF_OK) {
    json_decref(ext);
    return s;
  }
  const char *key;
  json_t *value;
  json_object_foreach(ext, key, value) json_array_append_new(used, json_string(key));
  *material = json_pack("{s:s, s:{s:o, s:f, s:f}, s:o}", "name", m->info->name,
                        "pbrMetallicRoughness", "baseColorFactor", rgb(base, 1), "metallicFactor",
                        0.0, "roughnessFactor", roughness, "extensions", ext);
  return CF_OK;
}

static json_t *notes_json(const preset_notes *n) {
  static const char *const names[] = {"exact", "approximate", "dropped", "out_of_range"};
  json_t *out = json_object();
  for (int kind = 0; kind < 4; ++kind) {
    json_t *list = json_array();
    for (int i = 0; i < n->count; ++i)
      if ((int)n->kind[i] == kind) json_array_append_new(list, json_string(n->text[i]));
    json_object_set_new(out, names[kind], list);
  }
  return out;
}

cf_status export_gltf(const cf_fit_file *fit, const char *fit_path, const char *path,
                      preset_notes *notes, cf_error *err) {
  export_material m;
  cf_status s_map = export_material_from_fit(fit, &m, err);
  if (s_map != CF_OK) return s_map;
  export_common_notes(notes, &m);
  json_t *used = json_array();
  json_t *material = NULL;
  cf_status s_mat = material_json(fit, &m, notes, used, &material, err);
  if (s_mat != CF_OK) {
    json_decref(used);
    cf_error_prefix(err, "%s", path);
    return s_mat;
  }
  sphere_mesh s = {0};
  if (!make_sphere(&s)) {
    json_decref(used);
    json_decref(material);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory for the sphere", path);
  }
  char *data = base64(s.bytes, s.size);
  size_t uri_size = data ? strlen(data) + 64 : 0;
  char *uri = data ? malloc(uri_size) : NULL;
  if (uri) snprintf(uri, uri_size, "data:application/octet-stream;base64,%s", data);
  free(data);
  preset_text prov = {0};
  preset_provenance(&prov, fit, fit_path, "", text_escape_utf8);
  json_t *doc = NULL;
  if (uri && !prov.failed) {
    float nmin[3] = {-1, -1, -1}, nmax[3] = {1, 1, 1};
    const float *normals = (const float *)(s.bytes + s.position_bytes);
    for (int c = 0; c < 3; ++c) nmin[c] = 1e30f, nmax[c] = -1e30f;
    for (size_t v = 0; v < s.vertices; ++v)
      for (int c = 0; c < 3; ++c) {
        float x = normals[3 * v + c];
        if (x < nmin[c]) nmin[c] = x;
        if (x > nmax[c]) nmax[c] = x;
      }
    doc = json_pack(
        "{s:{s:s, s:s, s:{s:{s:s, s:o}}}, s:i, s:[{s:[i]}], s:[{s:s, s:i}], "
        "s:[{s:s, s:[{s:{s:i, s:i}, s:i, s:i, s:i}]}], s:[o], "
        "s:[{s:I, s:s}], "
        "s:[{s:i, s:I, s:I, s:i}, {s:i, s:I, s:I, s:i}, {s:i, s:I, s:I, s:i}], "
        "s:[{s:i, s:i, s:I, s:s, s:o, s:o}, {s:i, s:i, s:I, s:s, s:o, s:o}, "
        "{s:i, s:i, s:I, s:s}], s:o}",
        "asset", "version", "2.0", "generator", "clayfit " CLAYFIT_EXPORT_VERSION, "extras",
        "clayfit", "provenance", prov.data, "mapping", notes_json(notes), "scene", 0, "scenes",
        "nodes", 0, "nodes", "name", "clayfit_sphere", "mesh", 0, "meshes", "name",
        "clayfit_sphere", "primitives", "attributes", "POSITION", 0, "NORMAL", 1, "indices", 2,
        "material", 0, "mode", 4, "materials", material, "buffers", "byteLength",
        (json_int_t)s.size, "uri", uri, "bufferViews", "buffer", 0, "byteOffset", (json_int_t)0,
        "byteLength", (json_int_t)s.position_bytes, "target", 34962, "buffer", 0, "byteOffset",
        (json_int_t)s.position_bytes, "byteLength", (json_int_t)s.position_bytes, "target", 34962,
        "buffer", 0, "byteOffset", (json_int_t)(2 * s.position_bytes), "byteLength",
        (json_int_t)s.index_bytes, "target", 34963, "accessors", "bufferView", 0, "componentType",
        5126, "count", (json_int_t)s.vertices, "type", "VEC3", "min", floats3(s.min), "max",
        floats3(s.max), "bufferView", 1, "componentType", 5126, "count", (json_int_t)s.vertices,
        "type", "VEC3", "min", floats3(nmin), "max", floats3(nmax), "bufferView", 2,
        "componentType", 5123, "count", (json_int_t)s.indices, "type", "SCALAR", "extensionsUsed",
        used);
    material = NULL;
    used = NULL;
  }
  json_decref(material);
  json_decref(used);
  free(uri);
  free(s.bytes);
  preset_text_free(&prov);
  if (!doc) return cf_error_set(err, CF_ENOMEM, "%s: could not build the glTF", path);
  if (json_array_size(json_object_get(doc, "extensionsUsed")) == 0)
    json_object_del(doc, "extensionsUsed");
  /* the index accessor's min and max are not required; the vertex ones are */
  cf_status written = json_write_file(doc, path, JSON_INDENT(1) | JSON_REAL_PRECISION(9), err);
  json_decref(doc);
  return written;
}
