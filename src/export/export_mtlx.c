/* MaterialX: standard_surface (document version 1.38) or open_pbr_surface
 * (1.39, where it was added). Input names and the way each input is used
 * are those of the nodedefs and nodegraphs of the MaterialX distribution:
 * libraries/bxdf/standard_surface.mtlx (ND_standard_surface_surfaceshader,
 * NG_standard_surface_surfaceshader_100) and
 * libraries/bxdf/open_pbr_surface.mtlx (ND_open_pbr_surface_surfaceshader),
 * github.com/AcademySoftwareFoundation/MaterialX. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "export_internal.h"

typedef struct mtlx_input {
  const char *name;
  int components; /* 1 float, 3 color3 */
  double value[3];
} mtlx_input;

enum { MTLX_MAX_INPUTS = 24 };

typedef struct mtlx_shader {
  int count;
  mtlx_input input[MTLX_MAX_INPUTS];
} mtlx_shader;

static void set1(mtlx_shader *s, const char *name, double x) {
  s->input[s->count++] = (mtlx_input){name, 1, {x, 0, 0}};
}

static void set3(mtlx_shader *s, const char *name, const double *x) {
  s->input[s->count++] = (mtlx_input){name, 3, {x[0], x[1], x[2]}};
}

/* A [0, 1] input (the nodedef's uimin/uimax): a value outside is written
 * as it is and reported. */
static void check_unit(preset_notes *n, const char *name, double x) {
  if (x < 0.0 || x > 1.0)
    preset_note(n, PRESET_RANGE, "%s = %.6g is outside the nodedef's range [0, 1]", name, x);
}

/* M4 in standard_surface: the film as the coat, the clay's interface as
 * the specular lobe. */
static void standard_surface_clay(const export_material *m, mtlx_shader *s, preset_notes *n) {
  set1(s, "specular_roughness", m->base_roughness);
  set1(s, "specular_IOR", m->base_ior_rel);
  set1(s, "coat", 1.0);
  set3(s, "coat_color", m->transmittance);
  set1(s, "coat_roughness", m->film_roughness);
  set1(s, "coat_IOR", m->film_ior);
  set1(s, "coat_affect_color", 0.0);
  set1(s, "coat_affect_roughness", 0.0);
  preset_note(n, PRESET_EXACT,
              "film_roughness %.6g -> coat_roughness (GGX, alpha = r^2, height-correlated "
              "Smith as clayfit)",
              m->film_roughness);
  preset_note(n, PRESET_APPROX,
              "film_f0 %.6g -> coat_IOR %.6g: the coat's dielectric_bsdf uses the exact "
              "dielectric Fresnel, not Schlick's",
              m->film_f0, m->film_ior);
  preset_note(n, PRESET_APPROX,
              "base lobe: specular_roughness = base_roughness %.6g, specular_IOR = the "
              "relative IOR %.6g (standard_surface's nodegraph gives specular_IOR to the "
              "base's dielectric_bsdf as it is, also under the coat, so the lobe's F0 stays "
              "base_f0 %.6g); the lobe is evaluated at the outside directions, not the "
              "refracted l', v', and without the film's 1/eta1^2 and T(c_i) T(c_o)",
              m->base_roughness, m->base_ior_rel, m->base_f0);
  preset_note(n, PRESET_APPROX,
              "the diffuse under the film: the layer nodes scale it by the coat's and the "
              "base lobe's directional albedo instead of clayfit's transmissions");
  preset_note(n, PRESET_DROPPED,
              "the recycling factor K (light the film reflects back down to the clay)");
}

static void standard_surface(const export_material *m, mtlx_shader *s, preset_notes *n) {
  double sigma = export_sigma_materialx_glsl(m->sigma);
  set1(s, "base", 1.0);
  set3(s, "base_color", m->albedo);
  set1(s, "diffuse_roughness", sigma);
  set1(s, "metalness", 0.0);
  if (m->model != CF_MODEL_LAMBERT)
    preset_note(n, PRESET_EXACT,
                "diffuse_roughness = sigma / pi = %.6g (sigma %.6g rad): MaterialX's GLSL "
                "oren_nayar_diffuse_bsdf (libraries/pbrlib/genglsl/lib/mx_microfacet_diffuse.glsl, "
                "mx_oren_nayar_diffuse) uses sigma^2 = (roughness pi)^2 and clayfit's A, B and "
                "s/t; the OSL backend passes the same number to OSL's oren_nayar closure, whose "
                "roughness is Fujii's improved form: approximate there",
                sigma, m->sigma);
  if (m->model == CF_MODEL_LAMBERT || m->model == CF_MODEL_OREN_NAYAR) {
    set1(s, "specular", 0.0);
    set1(s, "coat", 0.0);
    preset_note(n, PRESET_EXACT,
                "no specular lobe in %s: specular = 0 (the specular layer's top has weight 0 and "
                "passes the diffuse unchanged)",
                m->info->code);
    return;
  }
  set1(s, "specular", 1.0);
  set3(s, "specular_color", (double[3]){1, 1, 1});
  if (m->model == CF_MODEL_CLAY) {
    standard_surface_clay(m, s, n);
    return;
  }
  set1(s, "specular_roughness", m->roughness);
  set1(s, "specular_IOR", m->ior);
  preset_note(n, PRESET_EXACT, "roughness %.6g -> specular_roughness (GGX, alpha = r^2)",
              m->roughness);
  preset_note(n, PRESET_APPROX,
              "f0 %.6g -> specular_IOR %.6g: dielectric_bsdf uses the exact dielectric Fresnel "
              "(Schlick's in clayfit), and the layer node scales the diffuse by the lobe's "
              "directional albedo instead of (1 - F(c_i))(1 - F(c_o))",
              m->f0, m->ior);
  if (m->model == CF_MODEL_CLEARCOAT) {
    double weight = m->ggx_coat_weight, r = m->ggx_coat_roughness;
    set1(s, "coat", weight);
    set1(s, "coat_roughness", r);
    set1(s, "coat_IOR", 1.5);
    preset_note(n, PRESET_APPROX,
                "Burley's clear coat (coat_weight %.6g, coat_gloss %.6g: GTR1 width a = %.6g) "
                "-> a GGX coat: coat = 0.25 coat_weight = %.6g (Burley's 0.25), coat_IOR 1.5 "
                "(his F0 0.04), coat_roughness = sqrt(a) = %.6g (alpha = a); GTR1's long tail "
                "and the fixed 0.25 geometry width are lost, and the coat darkens the layers "
                "below it, which Burley's does not",
                m->coat_weight, m->coat_gloss, m->gtr1_a, weight, r);
  } else {
    set1(s, "coat", 0.0);
  }
}

static void open_pbr_surface(const export_material *m, mtlx_shader *s, preset_notes *n) {
  double sigma = export_sigma_fujii(m->sigma);
  set1(s, "base_weight", 1.0);
  set3(s, "base_color", m->albedo);
  set1(s, "base_diffuse_roughness", sigma);
  set1(s, "base_metalness", 0.0);
  if (m->model != CF_MODEL_LAMBERT)
    preset_note(n, PRESET_APPROX,
                "base_diffuse_roughness = B/A = %.6g (sigma %.6g rad): OpenPBR's diffuse is the "
                "energy-preserving Oren-Nayar (EON, Portsmouth et al. 2025; "
                "oren_nayar_diffuse_bsdf with energy_compensation true in "
                "libraries/bxdf/open_pbr_surface.mtlx) whose roughness is Fujii's sigma_F in "
                "f ~ 1 + sigma_F s/t: B/A keeps clayfit's ratio of the angular to the constant "
                "term; EON's normalisation and multiple-scattering term differ",
                sigma, m->sigma);
  if (m->model == CF_MODEL_LAMBERT || m->model == CF_MODEL_OREN_NAYAR) {
    set1(s, "specular_weight", 0.0);
    set1(s, "coat_weight", 0.0);
    preset_note(n, PRESET_EXACT,
                "no specular lobe in %s: specular_weight = 0 (scales the dielectric F0 to 0)",
                m->info->code);
    return;
  }
  set1(s, "specular_weight", 1.0);
  set3(s, "specular_color", (double[3]){1, 1, 1});
  if (m->model == CF_MODEL_CLAY) {
    set1(s, "specular_roughness", m->base_roughness);
    set1(s, "specular_ior", m->base_ior_abs);
    set1(s, "coat_weight", 1.0);
    set3(s, "coat_color", m->transmittance);
    set1(s, "coat_roughness", m->film_roughness);
    set1(s, "coat_ior", m->film_ior);
    preset_note(n, PRESET_EXACT, "film_roughness %.6g -> coat_roughness (GGX, alpha = r^2)",
                m->film_roughness);
    preset_note(n, PRESET_APPROX,
                "film_f0 %.6g -> coat_ior %.6g: the exact dielectric Fresnel, not Schlick's",
                m->film_f0, m->film_ior);
    preset_note(n, PRESET_APPROX,
                "base lobe: specular_ior = the clay's IOR in air %.6g (OpenPBR divides "
                "specular_ior by coat_ior under the coat, node specular_to_coat_ior_ratio, "
                "which gives back the relative IOR %.6g of base_f0 %.6g); specular_roughness "
                "%.6g, which OpenPBR roughens under the coat (min(1, 2 r_c^4 + r_s^4)^(1/4)); "
                "the lobe is not evaluated at the refracted directions",
                m->base_ior_abs, m->base_ior_rel, m->base_f0, m->base_roughness);
    preset_note(n, PRESET_APPROX,
                "coat_darkening is left at OpenPBR's 1: its internal-reflection darkening is "
                "OpenPBR's counterpart of clayfit's recycling factor K, with the opposite "
                "sign");
    return;
  }
  set1(s, "specular_roughness", m->roughness);
  set1(s, "specular_ior", m->ior);
  preset_note(n, PRESET_EXACT, "roughness %.6g -> specular_roughness (GGX, alpha = r^2)",
              m->roughness);
  preset_note(n, PRESET_APPROX,
              "f0 %.6g -> specular_ior %.6g: the exact dielectric Fresnel, and the diffuse "
              "scaled by the lobe's directional albedo",
              m->f0, m->ior);
  if (m->model == CF_MODEL_CLEARCOAT) {
    double weight = m->ggx_coat_weight, r = m->ggx_coat_roughness;
    set1(s, "coat_weight", weight);
    set1(s, "coat_roughness", r);
    set1(s, "coat_ior", 1.5);
    preset_note(n, PRESET_APPROX,
                "Burley's clear coat (GTR1 width a = %.6g) -> coat_weight = 0.25 coat_weight = "
                "%.6g, coat_ior 1.5, coat_roughness = sqrt(a) = %.6g; GTR1's tail is lost and "
                "the coat darkens and roughens the base",
                m->gtr1_a, weight, r);
  } else {
    set1(s, "coat_weight", 0.0);
  }
}

cf_status export_mtlx(const cf_fit_file *fit, const char *fit_path, const char *path, int openpbr,
                      preset_notes *notes, cf_error *err) {
  export_material m;
  cf_status s_map = export_material_from_fit(fit, &m, err);
  if (s_map != CF_OK) return s_map;
  mtlx_shader shader = {0};
  export_common_notes(notes, &m);
  if (openpbr)
    open_pbr_surface(&m, &shader, notes);
  else
    standard_surface(&m, &shader, notes);
  for (int i = 0; i < shader.count; ++i) { /* every input but the IORs is in [0, 1] */
    const mtlx_input *in = &shader.input[i];
    int is_ior = strstr(in->name, "IOR") != NULL || strstr(in->name, "ior") != NULL;
    if (!is_ior)
      for (int c = 0; c < in->components; ++c) check_unit(notes, in->name, in->value[c]);
  }
  preset_text t = {0};
  preset_printf(&t, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!--\n");
  preset_provenance(&t, fit, fit_path, "  ", text_escape_xml_comment);
  preset_printf(&t,
                "  MaterialX %s as defined in libraries/bxdf/%s.mtlx of the MaterialX "
                "distribution.\n",
                openpbr ? "1.39 open_pbr_surface" : "1.38 standard_surface",
                openpbr ? "open_pbr_surface" : "standard_surface");
  preset_notes_write(&t, notes, "  ");
  preset_printf(&t, "-->\n<materialx version=\"%s\" colorspace=\"lin_rec709\">\n",
                openpbr ? "1.39" : "1.38");
  const char *node = openpbr ? "open_pbr_surface" : "standard_surface";
  preset_printf(&t, "  <%s name=\"SR_clayfit_%s\" type=\"surfaceshader\">\n", node, m.info->name);
  for (int i = 0; i < shader.count; ++i) {
    const mtlx_input *in = &shader.input[i];
    if (in->components == 3)
      preset_printf(&t, "    <input name=\"%s\" type=\"color3\" value=\"%.9g, %.9g, %.9g\" />\n",
                    in->name, in->value[0], in->value[1], in->value[2]);
    else
      preset_printf(&t, "    <input name=\"%s\" type=\"float\" value=\"%.9g\" />\n", in->name,
                    in->value[0]);
  }
  preset_printf(&t, "  </%s>\n", node);
  preset_printf(&t,
                "  <surfacematerial name=\"M_clayfit_%s\" type=\"material\">\n"
                "    <input name=\"surfaceshader\" type=\"surfaceshader\" "
                "nodename=\"SR_clayfit_%s\" />\n"
                "  </surfacematerial>\n</materialx>\n",
                m.info->name, m.info->name);
  return preset_text_write(&t, path, err);
}
