/* The shared shader body: docs/model.md §1.2, §2 and §3 (M0-M4) without
 * derivatives, one function a term as in src/model/terms.h, in a subset
 * of GLSL ES 3.0 and HLSL: float, float2, float3 (GLSL's prelude maps them
 * to vec2, vec3), structs, `#if`, and only built-ins both languages name
 * alike (sqrt, exp, log, max, dot). No backslash, backtick or `${` (the
 * GLSL writer puts it in a JavaScript template literal), no int-to-float
 * conversions (GLSL ES has none), no names either language reserves
 * (half, point, line, sample, input, output, precise). */
#include <stdint.h>
#include <string.h>

#include "core/vec.h"
#include "shader_internal.h"

static const char glsl_prelude[] =
    "// GLSL ES 3.0 prelude: the shared body's HLSL vector types\n"
    "#define float2 vec2\n"
    "#define float3 vec3\n"
    "#define float4 vec4\n";

static const char hlsl_prelude[] = "// HLSL prelude: the shared body is HLSL's types already\n";

static const char shared_begin[] =
    "// ---- clayfit shared body: begin (docs/model.md; generated, do not edit)\n";

/* The one source of the maths, a line a string (C99 caps a literal at 4095
 * characters), after shared_begin and the constants (the C ones, every
 * digit printed). Equation numbers are docs/model.md's. */
static const char *const shared_body[] = {
    "\n",
    "// the fitted parameters (docs/model.md §1.5); a rung reads its own\n",
    "struct cf_params {\n",
    "  float3 albedo;\n",
    "  float sigma;\n",
    "  float roughness;\n",
    "  float f0;\n",
    "  float coat_weight;\n",
    "  float coat_gloss;\n",
    "  float film_roughness;\n",
    "  float film_f0;\n",
    "  float3 tau;\n",
    "  float base_roughness;\n",
    "  float base_f0;\n",
    "  float tail;\n",
    "};\n",
    "\n",
    "// the invariants of a pair (3): cosines, |l_t + v_t|^2, l_t . v_t\n",
    "struct cf_geometry {\n",
    "  float ci;\n",
    "  float co;\n",
    "  float t_sq;\n",
    "  float g;\n",
    "};\n",
    "\n",
    "// the half vector from the invariants (4)\n",
    "struct cf_half_vec {\n",
    "  float sin2;\n",
    "  float cos2;\n",
    "  float cd;\n",
    "};\n",
    "\n",
    "cf_half_vec cf_half_vector(float t_sq, float c_sum) {\n",
    "  cf_half_vec h;\n",
    "  float c2 = c_sum * c_sum;\n",
    "  float s_sq = t_sq + c2;\n",
    "  h.sin2 = t_sq / s_sq;\n",
    "  h.cos2 = c2 / s_sq;\n",
    "  h.cd = 0.5 * sqrt(s_sq);\n",
    "  return h;\n",
    "}\n",
    "\n",
    "// u = eta^2 - 1 from F0 (7), (22); exactly 0 at F0 = 0\n",
    "float cf_fresnel_u(float f0) {\n",
    "  float s = sqrt(f0);\n",
    "  float m = 1.0 - s;\n",
    "  return 4.0 * s / (m * m);\n",
    "}\n",
    "\n",
    "// the exact dielectric Fresnel (8) at cosine c, g = sqrt(u + c^2):\n",
    "// x = F, y = 1 - F, both without cancellation\n",
    "float2 cf_fresnel_dielectric(float u, float c, float g) {\n",
    "  if (u == 0.0) return float2(0.0, 1.0);\n",
    "  float eta2 = 1.0 + u;\n",
    "  float a = c + g;\n",
    "  float cc = eta2 * c + g;\n",
    "  float ua = u / a;\n",
    "  float rs = -ua / a;\n",
    "  float rp = ua * (c * a - 1.0) / cc;\n",
    "  float t = 2.0 * c * g * (1.0 / (a * a) + eta2 / (cc * cc));\n",
    "  return float2(0.5 * (rs * rs + rp * rp), t);\n",
    "}\n",
    "\n",
    "float2 cf_fresnel(float u, float c) {\n",
    "  return cf_fresnel_dielectric(u, c, sqrt(u + c * c));\n",
    "}\n",
    "\n",
    "// Schlick's (8s), Burley's clear coat only\n",
    "float cf_fresnel_schlick(float f0, float c) {\n",
    "  float x = 1.0 - c;\n",
    "  x = x > 0.0 ? x : 0.0;\n",
    "  x = x < 1.0 ? x : 1.0;\n",
    "  float x2 = x * x;\n",
    "  return f0 + (1.0 - f0) * x2 * x2 * x;\n",
    "}\n",
    "\n",
    "// the cosine-weighted mean of F for light from air (27), closed form\n",
    "float cf_fresnel_mean(float eta) {\n",
    "  float e2 = eta * eta;\n",
    "  float e4 = e2 * e2;\n",
    "  float em = eta - 1.0;\n",
    "  float ep = eta + 1.0;\n",
    "  float e2m = e2 - 1.0;\n",
    "  float e2p = e2 + 1.0;\n",
    "  float e4m = e4 - 1.0;\n",
    "  return 0.5 + em * (3.0 * eta + 1.0) / (6.0 * ep * ep) +\n",
    "         e2 * e2m * e2m / (e2p * e2p * e2p) * log(em / ep) -\n",
    "         2.0 * e2 * eta * (e2 + 2.0 * eta - 1.0) / (e2p * e4m) +\n",
    "         8.0 * e4 * (e4 + 1.0) / (e2p * e4m * e4m) * log(eta);\n",
    "}\n",
    "\n",
    "// GGX (9), the form without cancellation at the peak\n",
    "float cf_ggx_d(float a2, float sin2, float cos2) {\n",
    "  float q = sin2 + a2 * cos2;\n",
    "  return a2 * CF_INV_PI / (q * q);\n",
    "}\n",
    "\n",
    "// height-correlated Smith visibility (10)\n",
    "float cf_smith_v(float a2, float ci, float co) {\n",
    "  float li = sqrt(a2 + ci * ci * (1.0 - a2));\n",
    "  float lo = sqrt(a2 + co * co * (1.0 - a2));\n",
    "  return 0.5 / (co * li + ci * lo);\n",
    "}\n",
    "\n",
    "#if CLAYFIT_TAILED\n",
    "// ---- the STD lobe with the tail gamma (docs/model.md §2.8), for M2T, M4T\n",
    "// log(1 + x) without the rounding of 1 + x\n",
    "float cf_log1p(float x) {\n",
    "  float y = 1.0 + x;\n",
    "  float d = y - 1.0;\n",
    "  return d == 0.0 ? x : log(y) * (x / d);\n",
    "}\n",
    "\n",
    "// STD's D (T1): r^gamma / (pi alpha^2 cos^4), ln r = -ln(1 + x)\n",
    "float cf_std_d(float a2, float tail, float sin2, float cos2) {\n",
    "  float x = sin2 / ((tail - 1.0) * a2 * cos2);\n",
    "  return exp(-tail * cf_log1p(x)) * CF_INV_PI / (a2 * cos2 * cos2);\n",
    "}\n",
    "\n",
    "// Gamma(x + 1/2) / Gamma(x), x > 0: upward recurrence to x >= 8, then the\n",
    "// asymptotic series (DLMF 5.11.13; 5e-8 relative)\n",
    "float cf_gamma_ratio(float x) {\n",
    "  float f = 1.0;\n",
    "  for (int i = 0; i < 8; ++i) {\n",
    "    if (x >= 8.0) break;\n",
    "    f = f * x / (x + 0.5);\n",
    "    x = x + 1.0;\n",
    "  }\n",
    "  float y = 1.0 / x;\n",
    "  float series = 0.0078125 + y * (0.0048828125 - y * 0.000640869140625);\n",
    "  return f * sqrt(x) * (1.0 - y * (0.125 - y * series));\n",
    "}\n",
    "\n",
    "// the continued fraction of the incomplete beta function (DLMF 8.17.22,\n",
    "// modified Lentz): B_x(a, b) = x^a (1 - x)^b / a * cf_beta_cf(a, b, x)\n",
    "float cf_beta_cf(float a, float b, float x) {\n",
    "  float c = 1.0;\n",
    "  float d = 1.0 - (a + b) * x / (a + 1.0);\n",
    "  d = 1.0 / (abs(d) < 1e-30 ? 1e-30 : d);\n",
    "  float h = d;\n",
    "  for (int m = 1; m <= 64; ++m) {\n",
    "    float fm = float(m);\n",
    "    float aa = fm * (b - fm) * x / ((a - 1.0 + 2.0 * fm) * (a + 2.0 * fm));\n",
    "    d = 1.0 + aa * d;\n",
    "    d = 1.0 / (abs(d) < 1e-30 ? 1e-30 : d);\n",
    "    c = 1.0 + aa / c;\n",
    "    c = abs(c) < 1e-30 ? 1e-30 : c;\n",
    "    h = h * d * c;\n",
    "    aa = -(a + fm) * (a + b + fm) * x / ((a + 2.0 * fm) * (a + 1.0 + 2.0 * fm));\n",
    "    d = 1.0 + aa * d;\n",
    "    d = 1.0 / (abs(d) < 1e-30 ? 1e-30 : d);\n",
    "    c = 1.0 + aa / c;\n",
    "    c = abs(c) < 1e-30 ? 1e-30 : c;\n",
    "    float del = d * c;\n",
    "    h = h * del;\n",
    "    if (abs(del - 1.0) < 1e-7) break;\n",
    "  }\n",
    "  return h;\n",
    "}\n",
    "\n",
    "// STD's masking in the shape of (10)'s shorthand, L = c (1 + 2 Lambda) (T4):\n",
    "// L = c + K (2E - c T), T = B_z(a, 1/2), or from the complement\n",
    "// L = 2 K E + c K B_{1-z}(1/2, a) where the fraction converges slowly\n",
    "float cf_std_l(float a2, float tail, float c) {\n",
    "  float a = tail - 1.0;\n",
    "  float k = cf_gamma_ratio(a) * 0.564189583547756;\n",
    "  float s2 = 1.0 - c * c;\n",
    "  float q = s2 * a * a2 + c * c;\n",
    "  float z = s2 * a * a2 / q;\n",
    "  float e = pow(z, a) * sqrt(q) / (2.0 * a - 1.0);\n",
    "  if (z < (a + 1.0) / (a + 2.5))\n",
    "    return c + k * (2.0 * e - c * pow(z, a) * sqrt(1.0 - z) / a * cf_beta_cf(a, 0.5, z));\n",
    "  float w = 1.0 - z;\n",
    "  return 2.0 * k * e + c * k * sqrt(w) * pow(z, a) * 2.0 * cf_beta_cf(0.5, a, w);\n",
    "}\n",
    "\n",
    "// STD's height-correlated visibility (T6); 0 for gamma <= 3/2\n",
    "float cf_std_v(float a2, float tail, float ci, float co) {\n",
    "  if (tail <= 1.5) return 0.0;\n",
    "  return 0.5 / (co * cf_std_l(a2, tail, ci) + ci * cf_std_l(a2, tail, co));\n",
    "}\n",
    "#endif\n",
    "\n",
    "// the microfacet lobe S (11), (T7); u from F0, a2 = r^4 (6), the tail\n",
    "// gamma used by the tailed rungs only\n",
    "float cf_specular(float u, float a2, float tail, cf_half_vec h, float ci, float co) {\n",
    "#if CLAYFIT_TAILED\n",
    "  float dv = cf_std_d(a2, tail, h.sin2, h.cos2) * cf_std_v(a2, tail, ci, co);\n",
    "  return cf_fresnel(u, h.cd).x * dv;\n",
    "#else\n",
    "  return cf_fresnel(u, h.cd).x * cf_ggx_d(a2, h.sin2, h.cos2) * cf_smith_v(a2, ci, co);\n",
    "#endif\n",
    "}\n",
    "// Oren-Nayar (12)-(14) over rho / pi: A + B max(0, g) / max(ci, co)\n",
    "float cf_oren_nayar(float sigma, float g, float ci, float co) {\n",
    "  float s2 = sigma * sigma;\n",
    "  float a = 1.0 - 0.5 * s2 / (s2 + 0.33);\n",
    "  float b = 0.45 * s2 / (s2 + 0.09);\n",
    "  float x = g > 0.0 ? g / max(ci, co) : 0.0;\n",
    "  return a + b * x;\n",
    "}\n",
    "\n",
    "// Burley's GTR1 (15), width from the gloss (16)\n",
    "float cf_gtr1_d(float gloss, float sin2, float cos2) {\n",
    "  float a = 0.1 - 0.099 * gloss;\n",
    "  float a2 = a * a;\n",
    "  return (a2 - 1.0) / (CF_PI * log(a2) * (sin2 + a2 * cos2));\n",
    "}\n",
    "\n",
    "// Burley's separable Smith visibility (17)\n",
    "float cf_smith_separable(float ag2, float ci, float co) {\n",
    "  float gi = ci + sqrt(ag2 + ci * ci - ag2 * ci * ci);\n",
    "  float go = co + sqrt(ag2 + co * co - ag2 * co * co);\n",
    "  return 1.0 / (gi * go);\n",
    "}\n",
    "\n",
    "// M0 (18) and M1 (19)\n",
    "float3 cf_lambert(cf_params p) {\n",
    "  return p.albedo * CF_INV_PI;\n",
    "}\n",
    "\n",
    "float3 cf_diffuse(cf_params p, cf_geometry geo) {\n",
    "  return p.albedo * (CF_INV_PI * cf_oren_nayar(p.sigma, geo.g, geo.ci, geo.co));\n",
    "}\n",
    "\n",
    "// M2 (20)\n",
    "float3 cf_dielectric(cf_params p, cf_geometry geo) {\n",
    "  float u = cf_fresnel_u(p.f0);\n",
    "  float a2 = p.roughness * p.roughness * p.roughness * p.roughness;\n",
    "  cf_half_vec h = cf_half_vector(geo.t_sq, geo.ci + geo.co);\n",
    "  float s = cf_specular(u, a2, p.tail, h, geo.ci, geo.co);\n",
    "  float t = cf_fresnel(u, geo.ci).y * cf_fresnel(u, geo.co).y;\n",
    "  return s + t * cf_diffuse(p, geo);\n",
    "}\n",
    "\n",
    "// M3 (21): M2 plus Burley's coat (F0 0.04 Schlick, 0.25, alpha_g 0.25)\n",
    "float3 cf_clearcoat(cf_params p, cf_geometry geo) {\n",
    "  cf_half_vec h = cf_half_vector(geo.t_sq, geo.ci + geo.co);\n",
    "  float coat = p.coat_weight * 0.25 * cf_fresnel_schlick(0.04, h.cd) *\n",
    "               cf_gtr1_d(p.coat_gloss, h.sin2, h.cos2) *\n",
    "               cf_smith_separable(0.0625, geo.ci, geo.co);\n",
    "  return cf_dielectric(p, geo) + coat;\n",
    "}\n",
    "\n",
    "// M4 (22)-(30): the absorbing film over the clay body\n",
    "float3 cf_clay(cf_params p, cf_geometry geo) {\n",
    "  float s1 = sqrt(p.film_f0);\n",
    "  float u1 = cf_fresnel_u(p.film_f0);\n",
    "  float eta1 = (1.0 + s1) / (1.0 - s1);\n",
    "  float inv_eta = (1.0 - s1) / (1.0 + s1);\n",
    "  float inv_eta2 = inv_eta * inv_eta;\n",
    "  float u2 = cf_fresnel_u(p.base_f0);\n",
    "  float a2_1 = p.film_roughness * p.film_roughness * p.film_roughness * p.film_roughness;\n",
    "  float a2_2 = p.base_roughness * p.base_roughness * p.base_roughness * p.base_roughness;\n",
    "  // step 8's first term: the film's lobe in air\n",
    "  cf_half_vec h = cf_half_vector(geo.t_sq, geo.ci + geo.co);\n",
    "  float top = cf_specular(u1, a2_1, p.tail, h, geo.ci, geo.co);\n",
    "  // steps 2-4: refracted cosines (23), their roots are the film's g; T(ci) T(co) (25)\n",
    "  float root_i = sqrt(u1 + geo.ci * geo.ci);\n",
    "  float root_o = sqrt(u1 + geo.co * geo.co);\n",
    "  float ci_b = root_i * inv_eta;\n",
    "  float co_b = root_o * inv_eta;\n",
    "  float t1 = cf_fresnel_dielectric(u1, geo.ci, root_i).y *\n",
    "             cf_fresnel_dielectric(u1, geo.co, root_o).y;\n",
    "  // step 3: the refracted pair's invariants (24)\n",
    "  cf_half_vec hb = cf_half_vector(geo.t_sq * inv_eta2, ci_b + co_b);\n",
    "  float g_b = geo.g * inv_eta2;\n",
    "  // step 5: absorption (26); step 6: recycling (27), (28)\n",
    "  float3 absorption = exp(-p.tau * (1.0 / ci_b + 1.0 / co_b));\n",
    "  float fbar_i = 1.0 - (1.0 - cf_fresnel_mean(eta1)) * inv_eta2;\n",
    "  float3 k = 1.0 / (1.0 - p.albedo * fbar_i * exp(-4.0 * p.tau));\n",
    "  // step 7: the base (29)\n",
    "  float base_s = cf_specular(u2, a2_2, p.tail, hb, ci_b, co_b);\n",
    "  float t2 = cf_fresnel(u2, ci_b).y * cf_fresnel(u2, co_b).y;\n",
    "  float on = CF_INV_PI * cf_oren_nayar(p.sigma, g_b, ci_b, co_b);\n",
    "  float3 base = base_s + k * p.albedo * (t2 * on);\n",
    "  // step 8 (30)\n",
    "  return top + (t1 * inv_eta2) * absorption * base;\n",
    "}\n",
    "\n",
    "// f(l, v) of the exported rung for unit n, l, v (1.3: the BRDF, 1/sr);\n",
    "// 0 where the pair is not lit (2)\n",
    "float3 cf_brdf(cf_params p, float3 n, float3 l, float3 v) {\n",
    "  cf_geometry geo;\n",
    "  geo.ci = dot(n, l);\n",
    "  geo.co = dot(n, v);\n",
    "  if (!(geo.ci > 0.0 && geo.co > 0.0)) return float3(0.0, 0.0, 0.0);\n",
    "  float3 lt = l - geo.ci * n;\n",
    "  float3 vt = v - geo.co * n;\n",
    "  float3 t = lt + vt;\n",
    "  geo.t_sq = dot(t, t);\n",
    "  geo.g = dot(lt, vt);\n",
    "#if CLAYFIT_MODEL == 0\n",
    "  return cf_lambert(p);\n",
    "#elif CLAYFIT_MODEL == 1\n",
    "  return cf_diffuse(p, geo);\n",
    "#elif CLAYFIT_MODEL == 2\n",
    "  return cf_dielectric(p, geo);\n",
    "#elif CLAYFIT_MODEL == 3\n",
    "  return cf_clearcoat(p, geo);\n",
    "#else\n",
    "  return cf_clay(p, geo);\n",
    "#endif\n",
    "}\n",
    "\n",
    "// the radiance (5) a light of irradiance e (normal to l) reflects toward v\n",
    "float3 cf_radiance(cf_params p, float3 n, float3 l, float3 v, float3 e) {\n",
    "  float ci = dot(n, l);\n",
    "  return ci > 0.0 ? cf_brdf(p, n, l, v) * e * ci : float3(0.0, 0.0, 0.0);\n",
    "}\n",
    "// ---- clayfit shared body: end\n",
};

/* The fit's value of entry `component` of parameter `id`, or the parameter
 * table's default when the model has no such parameter. */
static double fitted(const cf_fit_file *fit, cf_param_id id, int component) {
  const cf_model_info *info = cf_model_info_get(fit->result.model);
  for (int k = 0; k < info->param_count; ++k)
    if (info->params[k] == id) return fit->result.params[info->offsets[k] + component];
  return cf_param_info_get(id)->default_value;
}

void shader_material_read(const cf_fit_file *fit, shader_material *m) {
  memset(m, 0, sizeof *m);
  m->info = cf_model_info_get(fit->result.model);
  switch (m->info->ggx_twin) { /* a tailed model is its GGX twin with the tail */
    case CF_MODEL_LAMBERT:
      m->rung = 0;
      break;
    case CF_MODEL_OREN_NAYAR:
      m->rung = 1;
      break;
    case CF_MODEL_DIELECTRIC:
      m->rung = 2;
      break;
    case CF_MODEL_CLEARCOAT:
      m->rung = 3;
      break;
    default:
      m->rung = 4;
  }
  m->tailed = m->info->tail_slot >= 0;
  m->tail = fitted(fit, CF_PARAM_TAIL, 0);
  for (int c = 0; c < 3; ++c) {
    m->albedo[c] = fitted(fit, CF_PARAM_ALBEDO, c);
    m->tau[c] = fitted(fit, CF_PARAM_OPTICAL_DEPTH, c);
  }
  m->sigma = fitted(fit, CF_PARAM_DIFFUSE_ROUGHNESS, 0);
  m->roughness = fitted(fit, CF_PARAM_ROUGHNESS, 0);
  m->f0 = fitted(fit, CF_PARAM_F0, 0);
  m->coat_weight = fitted(fit, CF_PARAM_COAT_WEIGHT, 0);
  m->coat_gloss = fitted(fit, CF_PARAM_COAT_GLOSS, 0);
  m->film_roughness = fitted(fit, CF_PARAM_FILM_ROUGHNESS, 0);
  m->film_f0 = fitted(fit, CF_PARAM_FILM_F0, 0);
  m->base_roughness = fitted(fit, CF_PARAM_BASE_ROUGHNESS, 0);
  m->base_f0 = fitted(fit, CF_PARAM_BASE_F0, 0);
}

void shader_library(preset_text *t, shader_lang lang, const shader_material *m) {
  preset_printf(t, "#define CLAYFIT_MODEL %d\n#define CLAYFIT_TAILED %d\n", m->rung, m->tailed);
  preset_printf(t, "%s", lang == SHADER_GLSL ? glsl_prelude : hlsl_prelude);
  preset_printf(t, "%s#define CF_PI %.17g\n#define CF_INV_PI %.17g\n", shared_begin, CF_PI,
                CF_INV_PI);
  for (size_t i = 0; i < sizeof shared_body / sizeof shared_body[0]; ++i)
    preset_printf(t, "%s", shared_body[i]);
}

void shader_notes(preset_notes *n, const shader_material *m, const char *lighting) {
  preset_note(n, PRESET_EXACT,
              "%s: the model's own formulas (docs/model.md §2, §3), every term as the fit "
              "evaluates it, not a mapping; in 32-bit floats (docs/shaders.md)",
              m->info->code);
  if (m->tailed)
    preset_note(n, PRESET_EXACT,
                "tail gamma %.6g: every lobe is STD's (docs/model.md §2.8, §3.8), its D (T1) "
                "and masking (T4) evaluated in the shader (the incomplete beta function by its "
                "continued fraction), not a GGX approximation",
                m->tail);
  preset_note(n, PRESET_APPROX, "%s", lighting);
}

cf_status cf_shader_write(const cf_fit_file *fit, const char *fit_path, cf_shader_format format,
                          const char *path, cf_error *err) {
  cf_status s = cf_params_check(fit->result.model, fit->result.params, err);
  if (s != CF_OK) return s;
  switch (format) {
    case CF_SHADER_GLSL:
      return shader_glsl(fit, fit_path, path, err);
    case CF_SHADER_UNITY:
      return shader_unity(fit, fit_path, path, err);
  }
  return cf_error_set(err, CF_EINVAL, "unknown shader format %d", (int)format);
}

/* FNV-1a, 64 bits, from a chosen basis. */
static uint64_t fnv1a(const unsigned char *data, size_t size, uint64_t hash) {
  for (size_t i = 0; i < size; ++i) {
    hash ^= data[i];
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

void shader_hash_guid(const char *text, size_t size, const char *salt, char guid[33]) {
  static const char hex[] = "0123456789abcdef";
  uint64_t h[2] = {0xcbf29ce484222325ULL, 0x84222325cbf29ce4ULL};
  for (int k = 0; k < 2; ++k) {
    h[k] = fnv1a((const unsigned char *)salt, strlen(salt), h[k]);
    h[k] = fnv1a((const unsigned char *)text, size, h[k]);
  }
  for (int i = 0; i < 32; ++i) guid[i] = hex[(h[i / 16] >> (4 * (15 - i % 16))) & 15];
  guid[32] = '\0';
}
