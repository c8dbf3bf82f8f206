/* A Blender 4 Python script that builds the material with a Principled
 * BSDF. Input names are Blender 4's (source/blender/nodes/shader/nodes/
 * node_shader_bsdf_principled.cc: "Base Color", "Roughness", "IOR",
 * "Diffuse Roughness" (4.3+), "Specular IOR Level", "Coat Weight", "Coat
 * Roughness", "Coat IOR", "Coat Tint"); how Cycles uses them is in
 * intern/cycles/kernel/svm/closure.h (the base's IOR is used as it is
 * under the coat; alpha = roughness^2; the coat tint is applied as
 * tint^(1/cos) along the refracted view ray). */
#include <math.h>
#include <stdio.h>

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
static void diffuse_inputs(const export_material *m, export_notes *n, blender_inputs *b) {
  double sigma = export_sigma_fujii(m->sigma);
  set4(b, "Base Color", m->albedo);
  set1(b, "Metallic", 0.0);
  b->in[b->count++] = (blender_input){"Diffuse Roughness", 1, {sigma, 0, 0, 0}, 1};
  if (m->model != CF_MODEL_LAMBERT)
    export_note(n, EXPORT_APPROX,
                "Diffuse Roughness = B/A = %.6g (sigma %.6g rad): Blender 4.3+ uses the "
                "energy-preserving Oren-Nayar (as OpenPBR) whose roughness is Fujii's sigma_F "
                "in f ~ 1 + sigma_F s/t; B/A keeps clayfit's ratio of the angular to the "
                "constant term. Blender before 4.3 has no such input: the script says so and "
                "the diffuse is Lambertian there",
                sigma, m->sigma);
}

/* M0 and M1: no specular lobe. */
static void no_specular_inputs(const export_material *m, export_notes *n, blender_inputs *b) {
  set1(b, "Roughness", 0.5);
  set1(b, "IOR", 1.5);
  set1(b, "Specular IOR Level", 0.0);
  set1(b, "Coat Weight", 0.0);
  export_note(n, EXPORT_EXACT,
              "no specular lobe in %s: Specular IOR Level 0 (F0 times 0: Cycles then skips "
              "the specular component)",
              m->info->code);
}

/* M4: the film as the coat, the clay's interface as the base lobe. */
static void clay_inputs(const export_material *m, export_notes *n, blender_inputs *b) {
  double tint[3] = {m->transmittance[0], m->transmittance[1], m->transmittance[2]};
  set1(b, "Roughness", m->base_roughness);
  set1(b, "IOR", m->base_ior_rel);
  set1(b, "Specular IOR Level", 0.5);
  set1(b, "Coat Weight", 1.0);
  set1(b, "Coat Roughness", m->film_roughness);
  set1(b, "Coat IOR", m->film_ior);
  set4(b, "Coat Tint", tint);
  export_note(n, EXPORT_EXACT, "film_roughness %.6g -> Coat Roughness (GGX, alpha = r^2)",
              m->film_roughness);
  export_note(n, EXPORT_APPROX,
              "film_f0 %.6g -> Coat IOR %.6g (Cycles: the exact dielectric Fresnel); Coat Tint "
              "exp(-2 tau), applied by Cycles once along the refracted view ray as "
              "tint^(1/cos): the round trip at normal incidence",
              m->film_f0, m->film_ior);
  export_note(n, EXPORT_APPROX,
              "base lobe: Roughness = base_roughness %.6g, IOR = the relative IOR %.6g "
              "(Cycles uses IOR as it is under the coat, so the lobe's F0 is base_f0 %.6g); "
              "not at the refracted directions",
              m->base_roughness, m->base_ior_rel, m->base_f0);
  export_note(n, EXPORT_DROPPED, "the recycling factor K");
}

/* M2 and M3: the dielectric lobe, and M3's clear coat. */
static void specular_inputs(const export_material *m, export_notes *n, blender_inputs *b) {
  set1(b, "Roughness", m->roughness);
  set1(b, "IOR", m->ior);
  set1(b, "Specular IOR Level", 0.5);
  export_note(n, EXPORT_EXACT, "roughness %.6g -> Roughness (GGX, alpha = r^2)", m->roughness);
  export_note(n, EXPORT_APPROX,
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
  export_note(n, EXPORT_APPROX,
              "Burley's clear coat (GTR1 width a = %.6g) -> Coat Weight = 0.25 coat_weight "
              "= %.6g, Coat IOR 1.5 (F0 0.04), Coat Roughness = sqrt(a) = %.6g: GGX "
              "without GTR1's tail, darkening the base",
              m->gtr1_a, weight, r);
}

/* The script: the header comment, the inputs, the function that sets them. */
static void write_script(export_text *t, const cf_fit_file *fit, const char *fit_path,
                         const export_material *m, const export_notes *n, const blender_inputs *b) {
  export_printf(t, "# Blender 4 (bpy): builds the material with a Principled BSDF.\n");
  export_printf(t, "# Run it in Blender's Python console or: blender --python THIS_FILE\n#\n");
  export_provenance(t, fit, fit_path, "# ", text_escape_python_comment);
  export_printf(t, "#\n");
  export_notes_write(t, n, "# ");
  export_printf(t, "\nimport bpy\n\nNAME = \"clayfit_%s\"\n\n", m->info->name);
  export_printf(t, "# Principled BSDF input -> value (linear RGB colours)\nINPUTS = {\n");
  for (int i = 0; i < b->count; ++i) {
    const blender_input *in = &b->in[i];
    if (in->components == 4)
      export_printf(t, "    \"%s\": (%.9g, %.9g, %.9g, 1.0),\n", in->name, in->value[0],
                    in->value[1], in->value[2]);
    else
      export_printf(t, "    \"%s\": %.9g,\n", in->name, in->value[0]);
  }
  export_printf(t, "}\n# inputs an older Blender 4 may lack\nOPTIONAL = {");
  for (int i = 0; i < b->count; ++i)
    if (b->in[i].optional) export_printf(t, "\"%s\"", b->in[i].name);
  export_printf(t,
                "}\n\n\n"
                "def build(name=NAME):\n"
                "    \"\"\"Create (or reuse) the material and set its Principled BSDF.\"\"\"\n"
                "    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)\n"
                "    material.use_nodes = True\n"
                "    nodes = material.node_tree.nodes\n"
                "    bsdf = next((n for n in nodes if n.type == \"BSDF_PRINCIPLED\"), None)\n"
                "    if bsdf is None:\n"
                "        bsdf = nodes.new(\"ShaderNodeBsdfPrincipled\")\n"
                "    for key, value in INPUTS.items():\n"
                "        if key not in bsdf.inputs:\n"
                "            if key in OPTIONAL:\n"
                "                print(f\"clayfit: this Blender has no '{key}' input \"\n"
                "                      \"(Blender 4.3 added it): left out\")\n"
                "                continue\n"
                "            raise RuntimeError(f\"the Principled BSDF has no input '{key}': \"\n"
                "                               \"Blender 4.0 or later is needed\")\n"
                "        bsdf.inputs[key].default_value = value\n"
                "    return material\n\n\n"
                "if __name__ == \"__main__\":\n"
                "    build()\n");
}

cf_status export_blender(const cf_fit_file *fit, const char *fit_path, const char *path,
                         export_notes *n, cf_error *err) {
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
  export_text t = {0};
  write_script(&t, fit, fit_path, &m, n, &b);
  return export_text_write(&t, path, err);
}
