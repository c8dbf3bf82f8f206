/* Unity's built-in render pipeline: a folder for Assets/ holding a
 * ShaderLab shader (HLSL, CGPROGRAM) that evaluates the fitted model
 * exactly (the shared body of shader.c), a material with the fitted
 * values, and their .meta files, whose GUIDs are hashes of the content
 * (the same fit gives the same GUIDs; the material names its shader's).
 * Forward rendering: the ForwardBase pass takes the main directional
 * light, ForwardAdd one more light each (docs/shaders.md). */
#include <stdio.h>
#include <string.h>

#include "core/file.h"
#include "shader_internal.h"

/* Properties: Vector for RGB values (a Color would be converted from sRGB
 * in a linear-space project), Range for scalars (the parameter table's). */
/* A scalar property with the parameter table's range (docs/model.md §1.6). */
static void property_range(preset_text *t, const char *property, const char *label, cf_param_id id,
                           double value) {
  const cf_param_info *p = cf_param_info_get(id);
  preset_printf(t, "    %s (\"%s\", Range(%.9g, %.9g)) = %.9g\n", property, label, p->lower,
                p->upper, value);
}

static void properties(preset_text *t, const shader_material *m) {
  int rung = m->rung;
  preset_printf(t, "  Properties {\n");
  preset_printf(t, "    _Albedo (\"albedo (linear RGB)\", Vector) = (%.9g, %.9g, %.9g, 0)\n",
                m->albedo[0], m->albedo[1], m->albedo[2]);
  if (rung >= 1)
    property_range(t, "_DiffuseRoughness", "diffuse_roughness (rad)", CF_PARAM_DIFFUSE_ROUGHNESS,
                   m->sigma);
  if (rung == 2 || rung == 3) {
    property_range(t, "_Roughness", "roughness", CF_PARAM_ROUGHNESS, m->roughness);
    property_range(t, "_F0", "f0", CF_PARAM_F0, m->f0);
  }
  if (rung == 3) {
    property_range(t, "_CoatWeight", "coat_weight", CF_PARAM_COAT_WEIGHT, m->coat_weight);
    property_range(t, "_CoatGloss", "coat_gloss", CF_PARAM_COAT_GLOSS, m->coat_gloss);
  }
  if (rung == 4) {
    property_range(t, "_FilmRoughness", "film_roughness", CF_PARAM_FILM_ROUGHNESS,
                   m->film_roughness);
    property_range(t, "_FilmF0", "film_f0", CF_PARAM_FILM_F0, m->film_f0);
    preset_printf(t,
                  "    _OpticalDepth (\"optical_depth (RGB)\", Vector) = (%.9g, %.9g, %.9g, 0)\n",
                  m->tau[0], m->tau[1], m->tau[2]);
    property_range(t, "_BaseRoughness", "base_roughness", CF_PARAM_BASE_ROUGHNESS,
                   m->base_roughness);
    property_range(t, "_BaseF0", "base_f0", CF_PARAM_BASE_F0, m->base_f0);
  }
  if (m->tailed) property_range(t, "_Tail", "tail (gamma)", CF_PARAM_TAIL, m->tail);
  preset_printf(t, "    _Exposure (\"exposure\", Float) = 1\n  }\n");
}

/* The glue after the shared body: the properties into cf_params, and the
 * vertex and fragment functions of both passes. Marked so that the tests
 * can compile it with stubs of Unity's include files. */
static const char unity_glue[] =
    "// ---- clayfit Unity glue: begin\n"
    "float4 _Albedo;\n"
    "float _DiffuseRoughness;\n"
    "float _Roughness;\n"
    "float _F0;\n"
    "float _CoatWeight;\n"
    "float _CoatGloss;\n"
    "float _FilmRoughness;\n"
    "float _FilmF0;\n"
    "float4 _OpticalDepth;\n"
    "float _BaseRoughness;\n"
    "float _BaseF0;\n"
    "float _Tail;\n"
    "float _Exposure;\n"
    "\n"
    "cf_params clayfit_params() {\n"
    "  cf_params p;\n"
    "  p.albedo = _Albedo.rgb;\n"
    "  p.sigma = _DiffuseRoughness;\n"
    "  p.roughness = _Roughness;\n"
    "  p.f0 = _F0;\n"
    "  p.coat_weight = _CoatWeight;\n"
    "  p.coat_gloss = _CoatGloss;\n"
    "  p.film_roughness = _FilmRoughness;\n"
    "  p.film_f0 = _FilmF0;\n"
    "  p.tau = _OpticalDepth.rgb;\n"
    "  p.base_roughness = _BaseRoughness;\n"
    "  p.base_f0 = _BaseF0;\n"
    "  p.tail = _Tail;\n"
    "  return p;\n"
    "}\n"
    "\n"
    "struct clayfit_v2f {\n"
    "  float4 pos : SV_POSITION;\n"
    "  float3 world_pos : TEXCOORD0;\n"
    "  float3 world_normal : TEXCOORD1;\n"
    "  LIGHTING_COORDS(2, 3)\n"
    "};\n"
    "\n"
    "clayfit_v2f clayfit_vert(appdata_base v) {\n"
    "  clayfit_v2f o;\n"
    "  o.pos = UnityObjectToClipPos(v.vertex);\n"
    "  o.world_pos = mul(unity_ObjectToWorld, v.vertex).xyz;\n"
    "  o.world_normal = UnityObjectToWorldNormal(v.normal);\n"
    "  TRANSFER_VERTEX_TO_FRAGMENT(o);\n"
    "  return o;\n"
    "}\n"
    "\n"
    "// Unity's light colour is pi times the irradiance it stands for (its\n"
    "// Standard shader's Lambert is albedo * colour * n.l): E = pi colour atten.\n"
    "float4 clayfit_frag(clayfit_v2f i) : SV_Target {\n"
    "  float3 n = normalize(i.world_normal);\n"
    "  float3 v = normalize(_WorldSpaceCameraPos.xyz - i.world_pos);\n"
    "  float3 l = normalize(UnityWorldSpaceLightDir(i.world_pos));\n"
    "  UNITY_LIGHT_ATTENUATION(atten, i, i.world_pos);\n"
    "  float3 e = UNITY_PI * _LightColor0.rgb * atten;\n"
    "  return float4(cf_radiance(clayfit_params(), n, l, v, e) * _Exposure, 1.0);\n"
    "}\n"
    "// ---- clayfit Unity glue: end\n";

static void shader_text(preset_text *t, const cf_fit_file *fit, const char *fit_path,
                        const shader_material *m, preset_notes *notes, const char *tag) {
  preset_provenance(t, fit, fit_path, "// ", text_escape_python_comment);
  preset_printf(t,
                "// Unity built-in render pipeline, forward rendering (docs/shaders.md): the\n"
                "// fitted model evaluated exactly, in linear radiance; use a linear colour\n"
                "// space project.\n");
  preset_notes_write(t, notes, "// ");
  preset_printf(t, "Shader \"clayfit/%s %s\" {\n", m->info->code, tag);
  properties(t, m);
  preset_printf(t,
                "  SubShader {\n"
                "    Tags { \"RenderType\" = \"Opaque\" }\n"
                "    CGINCLUDE\n"
                "    #include \"UnityCG.cginc\"\n"
                "    #include \"AutoLight.cginc\"\n"
                "    #include \"Lighting.cginc\"\n");
  shader_library(t, SHADER_HLSL, m);
  preset_printf(t, "%s", unity_glue);
  preset_printf(t,
                "    ENDCG\n"
                "    Pass {\n"
                "      Tags { \"LightMode\" = \"ForwardBase\" }\n"
                "      CGPROGRAM\n"
                "      #pragma vertex clayfit_vert\n"
                "      #pragma fragment clayfit_frag\n"
                "      #pragma multi_compile_fwdbase\n"
                "      ENDCG\n"
                "    }\n"
                "    Pass {\n"
                "      Tags { \"LightMode\" = \"ForwardAdd\" }\n"
                "      Blend One One\n"
                "      ZWrite Off\n"
                "      CGPROGRAM\n"
                "      #pragma vertex clayfit_vert\n"
                "      #pragma fragment clayfit_frag\n"
                "      #pragma multi_compile_fwdadd_fullshadows\n"
                "      ENDCG\n"
                "    }\n"
                "  }\n"
                "  FallBack \"VertexLit\"\n"
                "}\n");
}

static void mat_float(preset_text *t, const char *name, double value) {
  preset_printf(t, "    - %s: %.9g\n", name, value);
}

static void mat_vector(preset_text *t, const char *name, const double *x) {
  preset_printf(t, "    - %s: {r: %.9g, g: %.9g, b: %.9g, a: 0}\n", name, x[0], x[1], x[2]);
}

/* Unity's YAML serialisation of a Material (class 21, fileID 2100000). */
static void material_text(preset_text *t, const shader_material *m, const char *name,
                          const char *shader_guid) {
  int rung = m->rung;
  preset_printf(t,
                "%%YAML 1.1\n%%TAG !u! tag:unity3d.com,2011:\n--- !u!21 &2100000\n"
                "Material:\n  serializedVersion: 6\n  m_ObjectHideFlags: 0\n"
                "  m_CorrespondingSourceObject: {fileID: 0}\n  m_PrefabInstance: {fileID: 0}\n"
                "  m_PrefabAsset: {fileID: 0}\n  m_Name: %s\n"
                "  m_Shader: {fileID: 4800000, guid: %s, type: 3}\n"
                "  m_ShaderKeywords: \n  m_LightmapFlags: 4\n  m_EnableInstancingVariants: 0\n"
                "  m_DoubleSidedGI: 0\n  m_CustomRenderQueue: -1\n  stringTagMap: {}\n"
                "  disabledShaderPasses: []\n  m_SavedProperties:\n    serializedVersion: 3\n"
                "    m_TexEnvs: []\n    m_Floats:\n",
                name, shader_guid);
  if (rung >= 1) mat_float(t, "_DiffuseRoughness", m->sigma);
  if (rung == 2 || rung == 3) {
    mat_float(t, "_Roughness", m->roughness);
    mat_float(t, "_F0", m->f0);
  }
  if (rung == 3) {
    mat_float(t, "_CoatWeight", m->coat_weight);
    mat_float(t, "_CoatGloss", m->coat_gloss);
  }
  if (rung == 4) {
    mat_float(t, "_FilmRoughness", m->film_roughness);
    mat_float(t, "_FilmF0", m->film_f0);
    mat_float(t, "_BaseRoughness", m->base_roughness);
    mat_float(t, "_BaseF0", m->base_f0);
  }
  if (m->tailed) mat_float(t, "_Tail", m->tail);
  mat_float(t, "_Exposure", 1.0);
  preset_printf(t, "    m_Colors:\n");
  mat_vector(t, "_Albedo", m->albedo);
  if (rung == 4) mat_vector(t, "_OpticalDepth", m->tau);
}

static void meta_text(preset_text *t, const char *guid, const char *importer) {
  preset_printf(t, "fileFormatVersion: 2\nguid: %s\n%s:\n  externalObjects: {}\n", guid, importer);
  if (strcmp(importer, "ShaderImporter") == 0)
    preset_printf(t, "  defaultTextures: []\n  nonModifiableTextures: []\n");
  else
    preset_printf(t, "  mainObjectFileID: 2100000\n");
  preset_printf(t, "  userData: \n  assetBundleName: \n  assetBundleVariant: \n");
}

/* dir/name, written; t freed. */
static cf_status write_in(preset_text *t, const char *dir, const char *name, cf_error *err) {
  char path[4096];
  cf_status s = cf_path_join(dir, name, path, sizeof path, err);
  if (s != CF_OK) {
    preset_text_free(t);
    return s;
  }
  return preset_text_write(t, path, err);
}

cf_status shader_unity(const cf_fit_file *fit, const char *fit_path, const char *path,
                       cf_error *err) {
  shader_material m;
  shader_material_read(fit, &m);
  preset_notes notes = {0};
  shader_notes(&notes, &m,
               "lighting: Unity's forward lights (ForwardBase, ForwardAdd) with their "
               "attenuation and shadows, E = pi x light colour x attenuation; no ambient "
               "or reflection probes; linear radiance out, which the camera tone-maps as "
               "it is set up");
  /* the shader's tag and GUID hash its material's values and the notes,
   * not the provenance: the same material gives the same files */
  preset_text key = {0};
  preset_printf(&key, "%s", m.info->code);
  for (int i = 0; i < CF_MAX_DIM; ++i) preset_printf(&key, " %.17g", fit->result.params[i]);
  for (int i = 0; i < notes.count; ++i) preset_printf(&key, "\n%s", notes.text[i]);
  if (key.failed) {
    preset_text_free(&key);
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory", path);
  }
  char shader_guid[33], mat_guid[33], tag[9], name[32];
  shader_hash_guid(key.data, key.size, "clayfit.shader", shader_guid);
  shader_hash_guid(key.data, key.size, "clayfit.mat", mat_guid);
  preset_text_free(&key);
  memcpy(tag, shader_guid, 8);
  tag[8] = '\0';
  snprintf(name, sizeof name, "clayfit %s %s", m.info->code, tag);

  cf_status s = cf_make_dirs(path, err);
  preset_text t = {0};
  if (s == CF_OK) {
    shader_text(&t, fit, fit_path, &m, &notes, tag);
    s = write_in(&t, path, "clayfit.shader", err);
  }
  if (s == CF_OK) {
    meta_text(&t, shader_guid, "ShaderImporter");
    s = write_in(&t, path, "clayfit.shader.meta", err);
  }
  if (s == CF_OK) {
    material_text(&t, &m, name, shader_guid);
    s = write_in(&t, path, "clayfit.mat", err);
  }
  if (s == CF_OK) {
    meta_text(&t, mat_guid, "NativeFormatImporter");
    s = write_in(&t, path, "clayfit.mat.meta", err);
  }
  return s;
}
