/* A Mitsuba 3 scene fragment: one <bsdf> in a <scene version="3.0.0">.
 * Plugins and parameter names are Mitsuba 3's (mitsuba.readthedocs.io,
 * "BSDFs": diffuse (reflectance), roughplastic (distribution, alpha,
 * int_ior, ext_ior, diffuse_reflectance, nonlinear), principled
 * (base_color, roughness, metallic, eta, spec_tint, clearcoat,
 * clearcoat_gloss)). Mitsuba 3 has no Oren-Nayar BSDF and no coating
 * plugin. roughplastic's alpha is the GGX width itself; principled's
 * roughness is perceptual (alpha = roughness^2, Burley 2012). */
#include <math.h>
#include <stdio.h>

#include "export_internal.h"

static void rgb(preset_text *t, const char *name, const double *x) {
  preset_printf(t, "    <rgb name=\"%s\" value=\"%.9g, %.9g, %.9g\"/>\n", name, x[0], x[1], x[2]);
}

static void num(preset_text *t, const char *name, double x) {
  preset_printf(t, "    <float name=\"%s\" value=\"%.9g\"/>\n", name, x);
}

/* M0 and M1: the diffuse plugin. */
static const char *diffuse_body(const export_material *m, preset_notes *n, preset_text *body) {
  rgb(body, "reflectance", m->albedo);
  preset_note(n, PRESET_EXACT, "%s has no specular lobe: the diffuse plugin (Lambert)",
              m->info->code);
  return "diffuse";
}

/* M2: roughplastic. */
static const char *roughplastic_body(const export_material *m, preset_notes *n, preset_text *body) {
  preset_printf(body, "    <string name=\"distribution\" value=\"ggx\"/>\n");
  num(body, "alpha", m->roughness * m->roughness);
  num(body, "int_ior", m->ior);
  num(body, "ext_ior", 1.0);
  rgb(body, "diffuse_reflectance", m->albedo);
  preset_printf(body, "    <boolean name=\"nonlinear\" value=\"false\"/>\n");
  preset_note(n, PRESET_EXACT, "roughness %.6g -> alpha = r^2 = %.6g (GGX)", m->roughness,
              m->roughness * m->roughness);
  preset_note(n, PRESET_APPROX,
              "f0 %.6g -> int_ior %.6g: roughplastic uses the exact dielectric Fresnel and "
              "scatters the diffuse inside the coating (internal reflection), not "
              "(1 - F(c_i))(1 - F(c_o))",
              m->f0, m->ior);
  return "roughplastic";
}

/* principled's parameters (M3, M4). */
typedef struct principled {
  double base[3], roughness, eta, clearcoat, gloss;
} principled;

/* M3: Burley's clear coat, as principled has it. */
static void clearcoat_principled(const export_material *m, preset_notes *n, principled *p) {
  p->clearcoat = m->coat_weight;
  p->gloss = m->coat_gloss;
  preset_note(n, PRESET_APPROX,
              "clearcoat = coat_weight %.6g, clearcoat_gloss = coat_gloss %.6g: principled "
              "is Burley's model, whose clear coat (GTR1, F0 0.04) M3 takes; its base "
              "(Burley's diffuse with retro-reflection, the exact Fresnel of eta %.6g, from "
              "f0 %.6g) differs from M2's; roughness %.6g is perceptual there too (alpha = "
              "roughness^2, Burley 2012)",
              m->coat_weight, m->coat_gloss, m->ior, m->f0, m->roughness);
}

/* M4: the film as principled's clear coat, its transmittance in the base
 * colour, the clay's interface as the base lobe. */
static void film_principled(const export_material *m, preset_notes *n, principled *p) {
  double a = m->film_roughness * m->film_roughness;
  double g = (0.1 - a) / 0.099;
  p->clearcoat = m->film_f0 / 0.04;
  p->gloss = g;
  p->roughness = m->base_roughness;
  p->eta = m->base_ior_rel;
  for (int c = 0; c < 3; ++c) p->base[c] *= m->transmittance[c];
  if (p->clearcoat > 1.0) {
    preset_note(n, PRESET_RANGE,
                "clearcoat = film_f0 / 0.04 = %.6g is above 1: written as 1 (the film "
                "reflects more than principled's coat can)",
                p->clearcoat);
    p->clearcoat = 1.0;
  }
  if (g < 0.0 || g > 1.0) {
    p->gloss = g < 0.0 ? 0.0 : 1.0;
    preset_note(n, PRESET_RANGE,
                "clearcoat_gloss for film alpha %.6g would be %.6g, outside [0, 1] (GTR1 "
                "widths 0.001 to 0.1): written as %g",
                a, g, p->gloss);
  }
  preset_note(n, PRESET_APPROX,
              "the film -> principled's clear coat: clearcoat = film_f0 / 0.04 = %.6g (its F0 "
              "is fixed at 0.04), clearcoat_gloss from GTR1 width a = film alpha %.6g; GTR1 "
              "is not GGX and the coat has no colour: exp(-2 tau) multiplies base_color",
              m->film_f0 / 0.04, a);
  preset_note(n, PRESET_APPROX,
              "base lobe: roughness = base_roughness %.6g (perceptual, alpha = roughness^2), "
              "eta = the relative IOR %.6g (the "
              "base is evaluated as in air, so its F0 is base_f0 %.6g)",
              m->base_roughness, m->base_ior_rel, m->base_f0);
}

static const char *principled_body(const export_material *m, preset_notes *n, preset_text *body) {
  principled p = {{m->albedo[0], m->albedo[1], m->albedo[2]}, m->roughness, m->ior, 0.0, 0.0};
  if (m->model == CF_MODEL_CLEARCOAT)
    clearcoat_principled(m, n, &p);
  else
    film_principled(m, n, &p);
  if (p.eta <= 1.0)
    preset_note(n, PRESET_RANGE, "eta = %.6g: principled needs an IOR above 1 for a specular lobe",
                p.eta);
  rgb(body, "base_color", p.base);
  num(body, "roughness", p.roughness);
  num(body, "metallic", 0.0);
  num(body, "eta", p.eta);
  num(body, "spec_tint", 0.0);
  num(body, "clearcoat", p.clearcoat);
  num(body, "clearcoat_gloss", p.gloss);
  return "principled";
}

cf_status export_mitsuba(const cf_fit_file *fit, const char *fit_path, const char *path,
                         preset_notes *n, cf_error *err) {
  export_material m;
  cf_status s_map = export_material_from_fit(fit, &m, err);
  if (s_map != CF_OK) return s_map;
  export_common_notes(n, &m);
  if (m.model != CF_MODEL_LAMBERT)
    preset_note(n, PRESET_DROPPED,
                "diffuse_roughness sigma %.6g rad: Mitsuba 3 has no Oren-Nayar diffuse", m.sigma);
  preset_text body = {0};
  const char *type;
  if (m.model == CF_MODEL_LAMBERT || m.model == CF_MODEL_OREN_NAYAR)
    type = diffuse_body(&m, n, &body);
  else if (m.model == CF_MODEL_DIELECTRIC)
    type = roughplastic_body(&m, n, &body);
  else
    type = principled_body(&m, n, &body);
  preset_text t = {0};
  preset_printf(&t, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<!--\n");
  preset_provenance(&t, fit, fit_path, "  ", text_escape_xml_comment);
  preset_printf(&t, "  Mitsuba 3 scene fragment: include it or copy the <bsdf> into a scene.\n");
  preset_notes_write(&t, n, "  ");
  preset_printf(&t, "-->\n<scene version=\"3.0.0\">\n  <bsdf type=\"%s\" id=\"clayfit_%s\">\n",
                type, m.info->name);
  preset_printf(&t, "%s", body.failed || !body.data ? "" : body.data);
  int failed = body.failed;
  preset_text_free(&body);
  preset_printf(&t, "  </bsdf>\n</scene>\n");
  if (failed) t.failed = 1;
  return preset_text_write(&t, path, err);
}
