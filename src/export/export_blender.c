/* A Blender Python script that builds the material with a Principled BSDF,
 * for both of its generations: the script reads bpy.app.version and sets
 * INPUTS (Blender 4, Principled v2) or INPUTS_V1 (Blender 3.x, Principled
 * v1). Input names are those of source/blender/nodes/shader/nodes/
 * node_shader_bsdf_principled.cc of each. Blender 4: "Base Color",
 * "Roughness", "IOR", "Diffuse Roughness" (4.3+), "Specular IOR Level",
 * "Coat Weight", "Coat Roughness", "Coat IOR", "Coat Tint"; Cycles
 * (intern/cycles/kernel/svm/closure.h) uses the base's IOR as it is under the
 * coat, alpha = roughness^2, and applies the coat tint as tint^(1/cos) along
 * the refracted view ray. Blender 3.x: "Specular" (F0 = 0.08 specular, with
 * the exact dielectric Fresnel of that F0's IOR), "Roughness" (the GGX lobe's
 * and Burley's diffuse retro-reflection's), "Clearcoat" (Burley's lobe:
 * 0.25 clearcoat x F(IOR 1.5) x GTR1 of width a = roughness^2, separable
 * Smith with alpha 0.25), no coat IOR, tint or diffuse roughness; diffuse
 * and specular are added, not layered. docs/presets.md gives both mappings
 * and docs/fidelity.md what they cost in Blender 3.4's Cycles. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "export_internal.h"

typedef struct blender_input {
  const char *name;
  int components; /* 1 or 4 (RGBA) */
  double value[4];
  int optional; /* absent before Blender 4.3 */
} blender_input;

/* The inputs the script sets, in order. */
typedef struct blender_inputs {
  blender_input in[16];
  int count;
} blender_inputs;

static void set1(blender_inputs *b, const char *name, double x) {
  b->in[b->count++] = (blender_input){name, 1, {x, 0, 0, 0}, 0};
}

static void set4(blender_inputs *b, const char *name, const double *x) {
  b->in[b->count++] = (blender_input){name, 4, {x[0], x[1], x[2], 1.0}, 0};
}

/* Every model: the base colour and the diffuse roughness. */
static void diffuse_inputs(const export_material *m, preset_notes *n, blender_inputs *b) {
  double sigma = export_sigma_fujii(m->sigma);
  set4(b, "Base Color", m->albedo);
  set1(b, "Metallic", 0.0);
  b->in[b->count++] = (blender_input){"Diffuse Roughness", 1, {sigma, 0, 0, 0}, 1};
  if (m->model != CF_MODEL_LAMBERT)
    preset_note(n, PRESET_APPROX,
                "Diffuse Roughness = B/A = %.6g (sigma %.6g rad): Blender 4.3+ uses the "
                "energy-preserving Oren-Nayar (as OpenPBR) whose roughness is Fujii's sigma_F "
                "in f ~ 1 + sigma_F s/t; B/A keeps clayfit's ratio of the angular to the "
                "constant term. Blender before 4.3 has no such input: the script says so and "
                "the diffuse is Lambertian there",
                sigma, m->sigma);
}

/* M0 and M1: no specular lobe. */
static void no_specular_inputs(const export_material *m, preset_notes *n, blender_inputs *b) {
  set1(b, "Roughness", 0.5);
  set1(b, "IOR", 1.5);
  set1(b, "Specular IOR Level", 0.0);
  set1(b, "Coat Weight", 0.0);
  preset_note(n, PRESET_EXACT,
              "no specular lobe in %s: Specular IOR Level 0 (F0 times 0: Cycles then skips "
              "the specular component)",
              m->info->code);
}

/* M4: the film as the coat, the clay's interface as the base lobe. */
static void clay_inputs(const export_material *m, preset_notes *n, blender_inputs *b) {
  double tint[3] = {m->transmittance[0], m->transmittance[1], m->transmittance[2]};
  set1(b, "Roughness", m->base_roughness);
  set1(b, "IOR", m->base_ior_rel);
  set1(b, "Specular IOR Level", 0.5);
  set1(b, "Coat Weight", 1.0);
  set1(b, "Coat Roughness", m->film_roughness);
  set1(b, "Coat IOR", m->film_ior);
  set4(b, "Coat Tint", tint);
  preset_note(n, PRESET_EXACT, "film_roughness %.6g -> Coat Roughness (GGX, alpha = r^2)",
              m->film_roughness);
  preset_note(n, PRESET_APPROX,
              "film_f0 %.6g -> Coat IOR %.6g (Cycles: the exact dielectric Fresnel); Coat Tint "
              "exp(-2 tau), applied by Cycles once along the refracted view ray as "
              "tint^(1/cos): the round trip at normal incidence",
              m->film_f0, m->film_ior);
  preset_note(n, PRESET_APPROX,
              "base lobe: Roughness = base_roughness %.6g, IOR = the relative IOR %.6g "
              "(Cycles uses IOR as it is under the coat, so the lobe's F0 is base_f0 %.6g); "
              "not at the refracted directions",
              m->base_roughness, m->base_ior_rel, m->base_f0);
  preset_note(n, PRESET_DROPPED, "the recycling factor K");
}

/* M2 and M3: the dielectric lobe, and M3's clear coat. */
static void specular_inputs(const export_material *m, preset_notes *n, blender_inputs *b) {
  set1(b, "Roughness", m->roughness);
  set1(b, "IOR", m->ior);
  set1(b, "Specular IOR Level", 0.5);
  preset_note(n, PRESET_EXACT, "roughness %.6g -> Roughness (GGX, alpha = r^2)", m->roughness);
  preset_note(n, PRESET_APPROX,
              "f0 %.6g -> IOR %.6g: Cycles' generalised Schlick Fresnel and its albedo-scaled "
              "layering of the diffuse (not (1 - F(c_i))(1 - F(c_o)))",
              m->f0, m->ior);
  if (m->model != CF_MODEL_CLEARCOAT) {
    set1(b, "Coat Weight", 0.0);
    return;
  }
  double weight = m->ggx_coat_weight, r = m->ggx_coat_roughness;
  set1(b, "Coat Weight", weight);
  set1(b, "Coat Roughness", r);
  set1(b, "Coat IOR", 1.5);
  preset_note(n, PRESET_APPROX,
              "Burley's clear coat (GTR1 width a = %.6g) -> Coat Weight = 0.25 coat_weight "
              "= %.6g, Coat IOR 1.5 (F0 0.04), Coat Roughness = sqrt(a) = %.6g: GGX "
              "without GTR1's tail, darkening the base",
              m->gtr1_a, weight, r);
}

/* ---- Blender 3.x: Principled v1 ---- */

/* Principled v1's diffuse is Burley's, added to the lobes (Cycles 3.x
 * bsdf_principled_diffuse.h), with the lobe's Roughness:
 * f = colour/pi ((1 - F_L/2)(1 - F_V/2) + RR (F_L + F_V + F_L F_V (RR - 1))),
 * F_x = (1 - c_x)^5, RR = roughness (1 + l.v). */
static double burley_diffuse(double r, double ci, double co, double lv) {
  double fl = pow(1.0 - ci, 5.0), fv = pow(1.0 - co, 5.0), rr = r * (1.0 + lv);
  return ((1.0 - 0.5 * fl) * (1.0 - 0.5 * fv) + rr * (fl + fv + fl * fv * (rr - 1.0))) / CF_PI;
}

enum { V1_ROUGHNESS_STEPS = 20 };

/* Burley's diffuse at the Roughness of the variant: *(double *)ctx when it
 * is fixed (>= 0), else variant / V1_ROUGHNESS_STEPS. */
static double v1_basis(const void *ctx, int variant, const double l[3], const double v[3]) {
  double fixed_r = *(const double *)ctx;
  double r = fixed_r >= 0.0 ? fixed_r : (double)variant / V1_ROUGHNESS_STEPS;
  return burley_diffuse(r, l[2], v[2], l[0] * v[0] + l[1] * v[1] + l[2] * v[2]);
}

/* The v1 diffuse that best reproduces the model's: Base Color (per channel)
 * and, where the Roughness is free (M0, M1: no lobe), the Roughness, by least
 * squares over the metric of the tailed lobes' GGX (docs/presets.md;
 * export_fit_diffuse_colour). It is scene-free; on the fidelity table's
 * scene it takes M2's relative RMSE in Blender 3.4 from 18.3 % (Base Color =
 * albedo) or 8.4 % (albedo (1 - F0)^2) to 5.7 %, M4's from 21.4 % (albedo
 * exp(-2 tau)) to 0.7 % (docs/fidelity.md). */
static cf_status v1_diffuse_fit(const cf_fit_file *fit, double fixed_r, double colour[3],
                                double *roughness, double *loss, cf_error *err) {
  export_diffuse_colour d;
  cf_status s = export_fit_diffuse_colour(fit, v1_basis, &fixed_r,
                                          fixed_r >= 0.0 ? 1 : V1_ROUGHNESS_STEPS + 1,
                                          "Blender 3.x diffuse fit", &d, err);
  if (s != CF_OK) return s;
  *roughness = fixed_r >= 0.0 ? fixed_r : (double)d.variant / V1_ROUGHNESS_STEPS;
  memcpy(colour, d.colour, 3 * sizeof(double));
  *loss = d.loss;
  return CF_OK;
}

/* What every model sets: no metal, subsurface, sheen, transmission or
 * anisotropy; the diffuse colour and Roughness of v1_diffuse_fit. */
static void v1_common(const double colour[3], double roughness, blender_inputs *b) {
  set4(b, "Base Color", colour);
  set1(b, "Metallic", 0.0);
  set1(b, "Subsurface", 0.0);
  set1(b, "Specular Tint", 0.0);
  set1(b, "Sheen", 0.0);
  set1(b, "Transmission", 0.0);
  set1(b, "Anisotropic", 0.0);
  set1(b, "Roughness", roughness);
}

static void v1_diffuse_note(preset_notes *n, const export_material *m, const double colour[3],
                            double roughness, double loss, const char *what) {
  preset_note(n, PRESET_APPROX,
              "Base Color %.6g, %.6g, %.6g: the colour of Cycles' Burley diffuse (Roughness "
              "%.6g) closest to the model's diffuse (%s) by least squares over the sphere "
              "metric of docs/presets.md; what Burley's cannot follow: %.1f %% RMS of the "
              "diffuse (albedo %.6g, %.6g, %.6g, sigma %.6g rad)",
              colour[0], colour[1], colour[2], roughness, what, 100.0 * loss, m->albedo[0],
              m->albedo[1], m->albedo[2], m->sigma);
}

/* M0 and M1: Specular 0 is no lobe (F0 0: IOR 1, F = 0); the Roughness only
 * shapes Burley's diffuse, so it is fitted too. */
static cf_status v1_no_specular(const cf_fit_file *fit, const export_material *m, preset_notes *n,
                                blender_inputs *b, cf_error *err) {
  double colour[3], r, loss;
  cf_status s = v1_diffuse_fit(fit, -1.0, colour, &r, &loss, err);
  if (s != CF_OK) return s;
  v1_common(colour, r, b);
  set1(b, "Specular", 0.0);
  set1(b, "Clearcoat", 0.0);
  preset_note(n, PRESET_EXACT, "Specular 0: no specular lobe in %s", m->info->code);
  v1_diffuse_note(n, m, colour, r, loss,
                  m->model == CF_MODEL_LAMBERT ? "Lambert" : "Oren-Nayar, with its sigma");
  return CF_OK;
}

/* M2, M3 (and M2T as its GGX): the lobe exactly (GGX, exact Fresnel); the
 * diffuse with the lobe's Roughness. */
static cf_status v1_specular(const cf_fit_file *fit, const export_material *m, preset_notes *n,
                             blender_inputs *b, cf_error *err) {
  double colour[3], r, loss;
  cf_status s = v1_diffuse_fit(fit, m->roughness, colour, &r, &loss, err);
  if (s != CF_OK) return s;
  v1_common(colour, m->roughness, b);
  set1(b, "Specular", m->f0 / 0.08);
  set1(b, "IOR", m->ior);
  preset_note(n, PRESET_EXACT,
              "f0 %.6g -> Specular = f0 / 0.08 = %.6g (Cycles: the exact dielectric Fresnel of "
              "IOR %.6g, as the model's); roughness %.6g -> Roughness (GGX, alpha = r^2; "
              "distribution GGX, not MULTI_GGX)",
              m->f0, m->f0 / 0.08, m->ior, m->roughness);
  v1_diffuse_note(n, m, colour, r, loss,
                  "Oren-Nayar through the interface, (1 - F(c_i))(1 - F(c_o)) ON: Principled v1 "
                  "adds its diffuse to the lobe");
  if (m->f0 > 0.08)
    preset_note(n, PRESET_APPROX,
                "Specular %.6g is above the slider's 1 (F0 0.08): Blender takes it from Python",
                m->f0 / 0.08);
  if (m->model != CF_MODEL_CLEARCOAT) {
    set1(b, "Clearcoat", 0.0);
    return CF_OK;
  }
  set1(b, "Clearcoat", m->coat_weight);
  set1(b, "Clearcoat Roughness", sqrt(m->gtr1_a));
  preset_note(n, PRESET_EXACT,
              "Burley's clear coat -> Clearcoat = coat_weight %.6g, Clearcoat Roughness = "
              "sqrt(a) = %.6g (Cycles: GTR1 of width roughness^2, separable Smith with alpha "
              "0.25, weight 0.25: Burley's lobe; its F is the exact Fresnel of IOR 1.5 where "
              "the model has Schlick's of F0 0.04)",
              m->coat_weight, sqrt(m->gtr1_a));
  return CF_OK;
}

/* M4 (and M4T as its GGX): the film's lobe as the specular lobe (GGX and
 * exact Fresnel, as the model's top); everything under the film as the
 * diffuse colour; the base's lobe, seen through the film, as the clear coat. */
static cf_status v1_clay(const cf_fit_file *fit, const export_material *m, preset_notes *n,
                         blender_inputs *b, cf_error *err) {
  double colour[3], r, loss, eta1 = m->film_ior;
  cf_status s = v1_diffuse_fit(fit, m->film_roughness, colour, &r, &loss, err);
  if (s != CF_OK) return s;
  v1_common(colour, m->film_roughness, b);
  set1(b, "Specular", m->film_f0 / 0.08);
  set1(b, "IOR", eta1);
  /* the base's lobe through the film at normal incidence: F0_2 (1 - F0_1)^2
   * e^(-2 tau) / eta1^2; Cycles' clear coat has F0 0.25 x 0.04 x Clearcoat */
  double t1 = 1.0 - m->film_f0;
  double tmean = (m->transmittance[0] + m->transmittance[1] + m->transmittance[2]) / 3.0;
  double coat = fmin(1.0, m->base_f0 * t1 * t1 * tmean / (eta1 * eta1) / 0.01);
  set1(b, "Clearcoat", coat);
  set1(b, "Clearcoat Roughness", m->base_roughness);
  preset_note(n, PRESET_EXACT,
              "the film's lobe -> Specular = film_f0 / 0.08 = %.6g (the exact Fresnel of IOR "
              "%.6g), Roughness = film_roughness %.6g (GGX)",
              m->film_f0 / 0.08, eta1, m->film_roughness);
  v1_diffuse_note(n, m, colour, r, loss,
                  "the base seen through the film: its transmission, absorption, 1/eta1^2 and "
                  "recycling K");
  preset_note(n, PRESET_APPROX,
              "the base's lobe -> Clearcoat = base_f0 (1 - film_f0)^2 mean(exp(-2 tau)) / "
              "eta1^2 / 0.01 = %.6g, Clearcoat Roughness = base_roughness %.6g: GTR1, not GGX, "
              "and not refracted",
              coat, m->base_roughness);
  return CF_OK;
}

static void write_inputs(preset_text *t, const char *name, const blender_inputs *b) {
  preset_printf(t, "%s = {\n", name);
  for (int i = 0; i < b->count; ++i) {
    const blender_input *in = &b->in[i];
    if (in->components == 4)
      preset_printf(t, "    \"%s\": (%.9g, %.9g, %.9g, 1.0),\n", in->name, in->value[0],
                    in->value[1], in->value[2]);
    else
      preset_printf(t, "    \"%s\": %.9g,\n", in->name, in->value[0]);
  }
  preset_printf(t, "}\n");
}

/* The script: the header comment, both generations' inputs, the function
 * that picks one by bpy.app.version and sets it. */
static void write_script(preset_text *t, const cf_fit_file *fit, const char *fit_path,
                         const export_material *m, const preset_notes *n, const preset_notes *n1,
                         const blender_inputs *b, const blender_inputs *b1) {
  preset_printf(t,
                "# Blender (bpy): builds the material with a Principled BSDF, v2 in Blender 4,\n"
                "# v1 in Blender 3.x.\n");
  preset_printf(t, "# Run it in Blender's Python console or: blender --python THIS_FILE\n#\n");
  preset_provenance(t, fit, fit_path, "# ", text_escape_python_comment);
  preset_printf(t, "#\n# Blender 4 (Principled v2, INPUTS):\n");
  preset_notes_write(t, n, "# ");
  preset_printf(t, "#\n# Blender 3.x (Principled v1, INPUTS_V1):\n");
  preset_notes_write(t, n1, "# ");
  preset_printf(t, "\nimport bpy\n\nNAME = \"clayfit_%s\"\n\n", m->info->name);
  preset_printf(t, "# Blender 4 Principled BSDF input -> value (linear RGB colours)\n");
  write_inputs(t, "INPUTS", b);
  preset_printf(t, "# inputs an older Blender 4 may lack\nOPTIONAL = {");
  for (int i = 0; i < b->count; ++i)
    if (b->in[i].optional) preset_printf(t, "\"%s\"", b->in[i].name);
  preset_printf(t, "}\n# Blender 3.x Principled BSDF (v1) input -> value\n");
  write_inputs(t, "INPUTS_V1", b1);
  preset_printf(
      t,
      "\n\n"
      "def build(name=NAME):\n"
      "    \"\"\"Create (or reuse) the material and set its Principled BSDF.\"\"\"\n"
      "    v1 = bpy.app.version < (4, 0, 0)\n"
      "    inputs = INPUTS_V1 if v1 else INPUTS\n"
      "    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)\n"
      "    material.use_nodes = True\n"
      "    nodes = material.node_tree.nodes\n"
      "    bsdf = next((n for n in nodes if n.type == \"BSDF_PRINCIPLED\"), None)\n"
      "    if bsdf is None:\n"
      "        bsdf = nodes.new(\"ShaderNodeBsdfPrincipled\")\n"
      "    # the models' lobes are single-scattering GGX (Blender 4's default is\n"
      "    # MULTI_GGX)\n"
      "    bsdf.distribution = \"GGX\"\n"
      "    for key, value in inputs.items():\n"
      "        if key not in bsdf.inputs:\n"
      "            if not v1 and key in OPTIONAL:\n"
      "                print(f\"clayfit: this Blender has no '{key}' input \"\n"
      "                      \"(Blender 4.3 added it): left out\")\n"
      "                continue\n"
      "            raise RuntimeError(f\"the Principled BSDF of Blender \"\n"
      "                               f\"{bpy.app.version_string} has no input '{key}'\")\n"
      "        bsdf.inputs[key].default_value = value\n"
      "    return material\n\n\n"
      "if __name__ == \"__main__\":\n"
      "    build()\n");
}

cf_status export_blender(const cf_fit_file *fit, const char *fit_path, const char *path,
                         preset_notes *n, cf_error *err) {
  export_material m;
  cf_status s_map = export_material_from_fit(fit, &m, err);
  if (s_map != CF_OK) return s_map;
  export_common_notes(n, &m);
  blender_inputs b = {0};
  diffuse_inputs(&m, n, &b);
  if (m.model == CF_MODEL_LAMBERT || m.model == CF_MODEL_OREN_NAYAR)
    no_specular_inputs(&m, n, &b);
  else if (m.model == CF_MODEL_CLAY)
    clay_inputs(&m, n, &b);
  else
    specular_inputs(&m, n, &b);
  /* Blender 3.x: the same material in Principled v1, with its own notes */
  preset_notes n1 = {0};
  n1.range = n->range;
  n1.range_user = n->range_user;
  if (m.lobe_count > 0)
    preset_note(&n1, PRESET_APPROX, "each tailed lobe as its GGX, as for Blender 4 above");
  blender_inputs b1 = {0};
  cf_status s1 = m.model == CF_MODEL_LAMBERT || m.model == CF_MODEL_OREN_NAYAR
                     ? v1_no_specular(fit, &m, &n1, &b1, err)
                 : m.model == CF_MODEL_CLAY ? v1_clay(fit, &m, &n1, &b1, err)
                                            : v1_specular(fit, &m, &n1, &b1, err);
  if (s1 != CF_OK) return s1;
  preset_text t = {0};
  write_script(&t, fit, fit_path, &m, n, &n1, &b, &b1);
  return preset_text_write(&t, path, err);
}
