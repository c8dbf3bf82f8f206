/* three.js: an ES module with a GLSL ES 3.0 ShaderMaterial that evaluates
 * the fitted model exactly (the shared body of shader.c), the fitted
 * values as uniforms, point and directional lights as uniforms, linear
 * radiance out (docs/shaders.md). The module imports nothing: the page
 * passes its THREE, so it works with any bundling of three.js. */
#include <stdio.h>

#include "shader_internal.h"

enum { MAX_LIGHTS = 8 };

static const char vertex_shader[] =
    "out vec3 vClayfitWorldPosition;\n"
    "out vec3 vClayfitWorldNormal;\n"
    "void main() {\n"
    "  vec4 world = modelMatrix * vec4(position, 1.0);\n"
    "  vClayfitWorldPosition = world.xyz;\n"
    "  vClayfitWorldNormal = mat3(modelMatrix) * normal; // no non-uniform scale\n"
    "  gl_Position = projectionMatrix * viewMatrix * world;\n"
    "}\n";

/* After the shared body: the uniforms, and the surface point either from
 * the mesh or, with CLAYFIT_ANALYTIC_SPHERE, from the camera ray through
 * this fragment intersected with the sphere clayfitSphere (exact normals at
 * pixel centres whatever mesh covers the sphere). */
static const char fragment_main[] =
    "uniform vec3 clayfitAlbedo;\n"
    "uniform float clayfitDiffuseRoughness;\n"
    "uniform float clayfitRoughness;\n"
    "uniform float clayfitF0;\n"
    "uniform float clayfitCoatWeight;\n"
    "uniform float clayfitCoatGloss;\n"
    "uniform float clayfitFilmRoughness;\n"
    "uniform float clayfitFilmF0;\n"
    "uniform vec3 clayfitOpticalDepth;\n"
    "uniform float clayfitBaseRoughness;\n"
    "uniform float clayfitBaseF0;\n"
    "uniform float clayfitTail;\n"
    "uniform float clayfitExposure;\n"
    "uniform int clayfitLightCount;\n"
    "// xyz and w = 1: a point light at xyz, intensity (W/sr) per channel;\n"
    "// w = 0: a directional light toward xyz, irradiance (W/m^2) per channel\n"
    "uniform vec4 clayfitLightPosition[CLAYFIT_MAX_LIGHTS];\n"
    "uniform vec3 clayfitLightIntensity[CLAYFIT_MAX_LIGHTS];\n"
    "// CLAYFIT_ANALYTIC_SPHERE: the sphere (centre, radius), and what maps a\n"
    "// fragment to its camera ray (set by the material's onBeforeRender)\n"
    "uniform vec4 clayfitSphere;\n"
    "uniform vec4 clayfitViewport;\n"
    "uniform mat4 clayfitProjectionInverse;\n"
    "uniform mat4 clayfitCameraToWorld;\n"
    "in vec3 vClayfitWorldPosition;\n"
    "in vec3 vClayfitWorldNormal;\n"
    "layout(location = 0) out highp vec4 clayfitFragColor; // GLSL3: the shader declares it\n"
    "\n"
    "cf_params clayfit_params() {\n"
    "  cf_params p;\n"
    "  p.albedo = clayfitAlbedo;\n"
    "  p.sigma = clayfitDiffuseRoughness;\n"
    "  p.roughness = clayfitRoughness;\n"
    "  p.f0 = clayfitF0;\n"
    "  p.coat_weight = clayfitCoatWeight;\n"
    "  p.coat_gloss = clayfitCoatGloss;\n"
    "  p.film_roughness = clayfitFilmRoughness;\n"
    "  p.film_f0 = clayfitFilmF0;\n"
    "  p.tau = clayfitOpticalDepth;\n"
    "  p.base_roughness = clayfitBaseRoughness;\n"
    "  p.base_f0 = clayfitBaseF0;\n"
    "  p.tail = clayfitTail;\n"
    "  return p;\n"
    "}\n"
    "\n"
    "void main() {\n"
    "  vec3 x = vClayfitWorldPosition;\n"
    "  vec3 n = normalize(vClayfitWorldNormal);\n"
    "  vec3 v = normalize(cameraPosition - x);\n"
    "#ifdef CLAYFIT_ANALYTIC_SPHERE\n"
    "  // the camera ray through this pixel's centre, from gl_FragCoord (exact)\n"
    "  vec2 ndc = 2.0 * (gl_FragCoord.xy - clayfitViewport.xy) / clayfitViewport.zw - 1.0;\n"
    "  vec4 near_h = clayfitProjectionInverse * vec4(ndc, -1.0, 1.0);\n"
    "  vec4 far_h = clayfitProjectionInverse * vec4(ndc, 1.0, 1.0);\n"
    "  vec3 near_p = near_h.xyz / near_h.w;\n"
    "  vec3 o = (clayfitCameraToWorld * vec4(near_p, 1.0)).xyz;\n"
    "  vec3 d = normalize(mat3(clayfitCameraToWorld) * (far_h.xyz / far_h.w - near_p));\n"
    "  // the sphere's hit without cancellation: q is the centre's offset to the\n"
    "  // ray's closest point, the hit is q - sqrt(r^2 - |q|^2) d from the centre\n"
    "  vec3 oc = o - clayfitSphere.xyz;\n"
    "  float b = dot(d, oc);\n"
    "  vec3 q = oc - b * d;\n"
    "  float disc = clayfitSphere.w * clayfitSphere.w - dot(q, q);\n"
    "  if (disc < 0.0 || -b - sqrt(disc) < 0.0) discard;\n"
    "  vec3 offset = q - sqrt(disc) * d;\n"
    "  x = clayfitSphere.xyz + offset;\n"
    "  n = offset / clayfitSphere.w;\n"
    "  v = -d;\n"
    "#endif\n"
    "  cf_params p = clayfit_params();\n"
    "  vec3 radiance = vec3(0.0);\n"
    "  for (int j = 0; j < CLAYFIT_MAX_LIGHTS; ++j) {\n"
    "    if (j >= clayfitLightCount) break;\n"
    "    vec4 light = clayfitLightPosition[j];\n"
    "    vec3 e = clayfitLightIntensity[j];\n"
    "    vec3 l = normalize(light.xyz);\n"
    "    if (light.w != 0.0) {\n"
    "      vec3 to_light = light.xyz - x;\n"
    "      float d2 = dot(to_light, to_light);\n"
    "      l = to_light * inversesqrt(d2);\n"
    "      e = e / d2; // (36)\n"
    "    }\n"
    "    radiance += cf_radiance(p, n, l, v, e);\n"
    "  }\n"
    "  clayfitFragColor = vec4(radiance * clayfitExposure, 1.0);\n"
    "}\n";

static void uniform_float(preset_text *t, const char *name, double value) {
  preset_printf(t, "    %s: { value: %.9g },\n", name, value);
}

static void uniform_vec3(preset_text *t, const char *name, const double *x) {
  preset_printf(t, "    %s: { value: new THREE.Vector3(%.9g, %.9g, %.9g) },\n", name, x[0], x[1],
                x[2]);
}

/* The fitted values; the parameters a rung does not have keep the table's
 * defaults (shader_material_read; unused by its code). */
static void write_uniforms(preset_text *t, const shader_material *m) {
  uniform_vec3(t, "clayfitAlbedo", m->albedo);
  uniform_float(t, "clayfitDiffuseRoughness", m->sigma);
  uniform_float(t, "clayfitRoughness", m->roughness);
  uniform_float(t, "clayfitF0", m->f0);
  uniform_float(t, "clayfitCoatWeight", m->coat_weight);
  uniform_float(t, "clayfitCoatGloss", m->coat_gloss);
  uniform_float(t, "clayfitFilmRoughness", m->film_roughness);
  uniform_float(t, "clayfitFilmF0", m->film_f0);
  uniform_vec3(t, "clayfitOpticalDepth", m->tau);
  uniform_float(t, "clayfitBaseRoughness", m->base_roughness);
  uniform_float(t, "clayfitBaseF0", m->base_f0);
  uniform_float(t, "clayfitTail", m->tail);
}

static void write_module(preset_text *t, const shader_material *m) {
  preset_printf(t, "export const clayfit = { model: \"%s\", tail: %.9g, maxLights: %d };\n\n",
                m->info->code, m->tail, MAX_LIGHTS);
  preset_printf(t, "export const vertexShader = `%s`;\n\n", vertex_shader);
  preset_printf(t, "export const fragmentShader = `");
  shader_library(t, SHADER_GLSL, m);
  preset_printf(t, "\n%s`;\n\n", fragment_main);
  preset_printf(t,
                "// The fitted values and the lights as three.js uniforms.\n"
                "export function clayfitUniforms(THREE) {\n"
                "  const positions = [], intensities = [];\n"
                "  for (let j = 0; j < %d; ++j) {\n"
                "    positions.push(new THREE.Vector4(0, 0, 1, 0));\n"
                "    intensities.push(new THREE.Vector3(0, 0, 0));\n"
                "  }\n"
                "  return {\n",
                MAX_LIGHTS);
  write_uniforms(t, m);
  preset_printf(t,
                "    clayfitExposure: { value: 1 },\n"
                "    clayfitLightCount: { value: 0 },\n"
                "    clayfitLightPosition: { value: positions },\n"
                "    clayfitLightIntensity: { value: intensities },\n"
                "    clayfitSphere: { value: new THREE.Vector4(0, 0, 0, 1) },\n"
                "    clayfitViewport: { value: new THREE.Vector4(0, 0, 1, 1) },\n"
                "    clayfitProjectionInverse: { value: new THREE.Matrix4() },\n"
                "    clayfitCameraToWorld: { value: new THREE.Matrix4() },\n"
                "  };\n"
                "}\n\n");
  preset_printf(
      t,
      "// options.lights: up to %d of { position: [x, y, z], intensity: [r, g, b] } (a\n"
      "// point light, intensity in W/sr) or { direction: [x, y, z], irradiance: [r, g, b] };\n"
      "// options.sphere: { center: [x, y, z], radius } shades that sphere exactly from\n"
      "// the camera ray through each pixel's centre (any mesh covering it: its\n"
      "// normals are not used); options.exposure.\n"
      "export function createClayfitMaterial(THREE, options = {}) {\n"
      "  const uniforms = clayfitUniforms(THREE);\n"
      "  const lights = options.lights || [];\n"
      "  if (lights.length > %d) throw new Error('clayfit: at most %d lights');\n"
      "  lights.forEach((light, j) => {\n"
      "    const point = light.position !== undefined;\n"
      "    const p = point ? light.position : light.direction;\n"
      "    const e = point ? light.intensity : light.irradiance;\n"
      "    uniforms.clayfitLightPosition.value[j].set(p[0], p[1], p[2], point ? 1 : 0);\n"
      "    uniforms.clayfitLightIntensity.value[j].set(e[0], e[1], e[2]);\n"
      "  });\n"
      "  uniforms.clayfitLightCount.value = lights.length;\n"
      "  if (options.exposure !== undefined) uniforms.clayfitExposure.value = options.exposure;\n"
      "  const defines = { CLAYFIT_MAX_LIGHTS: %d };\n"
      "  if (options.sphere) {\n"
      "    const c = options.sphere.center;\n"
      "    uniforms.clayfitSphere.value.set(c[0], c[1], c[2], options.sphere.radius);\n"
      "    defines.CLAYFIT_ANALYTIC_SPHERE = 1;\n"
      "  }\n"
      "  const material = new THREE.ShaderMaterial({\n"
      "    name: 'clayfit %s', glslVersion: THREE.GLSL3, vertexShader, fragmentShader,\n"
      "    uniforms, defines, toneMapped: false,\n"
      "  });\n"
      "  if (options.sphere) {\n"
      "    material.onBeforeRender = (renderer, scene, camera) => {\n"
      "      renderer.getCurrentViewport(uniforms.clayfitViewport.value);\n"
      "      uniforms.clayfitProjectionInverse.value.copy(camera.projectionMatrixInverse);\n"
      "      uniforms.clayfitCameraToWorld.value.copy(camera.matrixWorld);\n"
      "      material.uniformsNeedUpdate = true;\n"
      "    };\n"
      "  }\n"
      "  return material;\n"
      "}\n\n"
      "export default createClayfitMaterial;\n",
      MAX_LIGHTS, MAX_LIGHTS, MAX_LIGHTS, MAX_LIGHTS, m->info->code);
}

cf_status shader_glsl(const cf_fit_file *fit, const char *fit_path, const char *path,
                      cf_error *err) {
  shader_material m;
  shader_material_read(fit, &m);
  preset_notes notes = {0};
  preset_text t = {0};
  preset_provenance(&t, fit, fit_path, "// ", text_escape_python_comment);
  preset_printf(&t,
                "// A three.js ShaderMaterial (GLSL ES 3.0) evaluating this model exactly\n"
                "// (docs/shaders.md). Usage, with three.js as THREE:\n"
                "//   import { createClayfitMaterial } from './this-file.js';\n"
                "//   const material = createClayfitMaterial(THREE, {\n"
                "//     lights: [{ position: [0, 2, 5], intensity: [40, 40, 40] }] });\n"
                "// Output: linear radiance (no tone mapping, no sRGB encoding): render into\n"
                "// a float target, or add your own tone mapping.\n");
  shader_notes(&notes, &m,
               "lighting: point and directional lights as uniforms (at most 8), no "
               "image-based lighting or shadows; linear radiance out, which the page "
               "tone-maps and encodes as it chooses");
  preset_notes_write(&t, &notes, "// ");
  preset_printf(&t, "\n");
  write_module(&t, &m);
  return preset_text_write(&t, path, err);
}
