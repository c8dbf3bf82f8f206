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

cf_status export_blender(const cf_fit_file *fit, const char *fit_path, const char *path,
                         export_notes *n, cf_error *err) {
  export_material m;
  export_material_from_fit(fit, &m);
  export_common_notes(n, &m);
  blender_input in[16];
  int count = 0;
#define SET1(NAME, X)             \
  in[count++] = (blender_input) { \
    NAME, 1, {(X), 0, 0, 0}, 0    \
  }
#define SET4(NAME, X)                         \
  in[count++] = (blender_input) {             \
    NAME, 4, {(X)[0], (X)[1], (X)[2], 1.0}, 0 \
  }
  double sigma = export_sigma_fujii(m.sigma);
  SET4("Base Color", m.albedo);
  SET1("Metallic", 0.0);
  in[count++] = (blender_input){"Diffuse Roughness", 1, {sigma, 0, 0, 0}, 1};
  if (m.model != CF_MODEL_LAMBERT)
    export_note(n, EXPORT_APPROX,
                "Diffuse Roughness = B/A = %.6g (sigma %.6g rad): Blender 4.3+ uses the "
                "energy-preserving Oren-Nayar (as OpenPBR) whose roughness is Fujii's sigma_F "
                "in f ~ 1 + sigma_F s/t; B/A keeps MODEL.md's ratio of the angular to the "
                "constant term. Blender before 4.3 has no such input: the script says so and "
                "the diffuse is Lambertian there",
                sigma, m.sigma);
  if (m.model == CF_MODEL_LAMBERT || m.model == CF_MODEL_OREN_NAYAR) {
    SET1("Roughness", 0.5);
    SET1("IOR", 1.5);
    SET1("Specular IOR Level", 0.0);
    SET1("Coat Weight", 0.0);
    export_note(n, EXPORT_EXACT,
                "no specular lobe in %s: Specular IOR Level 0 (F0 times 0: Cycles then skips "
                "the specular component)",
                m.info->code);
  } else if (m.model == CF_MODEL_CLAY) {
    double tint[3] = {m.transmittance[0], m.transmittance[1], m.transmittance[2]};
    SET1("Roughness", m.base_roughness);
    SET1("IOR", m.base_ior_rel);
    SET1("Specular IOR Level", 0.5);
    SET1("Coat Weight", 1.0);
    SET1("Coat Roughness", m.film_roughness);
    SET1("Coat IOR", m.film_ior);
    SET4("Coat Tint", tint);
    export_note(n, EXPORT_EXACT, "film_roughness %.6g -> Coat Roughness (GGX, alpha = r^2)",
                m.film_roughness);
    export_note(n, EXPORT_APPROX,
                "film_f0 %.6g -> Coat IOR %.6g (Cycles: the exact dielectric Fresnel); Coat Tint "
                "exp(-2 tau), applied by Cycles once along the refracted view ray as "
                "tint^(1/cos): the round trip at normal incidence",
                m.film_f0, m.film_ior);
    export_note(n, EXPORT_APPROX,
                "base lobe: Roughness = base_roughness %.6g, IOR = the relative IOR %.6g "
                "(Cycles uses IOR as it is under the coat, so the lobe's F0 is base_f0 %.6g); "
                "not at the refracted directions",
                m.base_roughness, m.base_ior_rel, m.base_f0);
    export_note(n, EXPORT_DROPPED, "the recycling factor K");
  } else {
    SET1("Roughness", m.roughness);
    SET1("IOR", m.ior);
    SET1("Specular IOR Level", 0.5);
    export_note(n, EXPORT_EXACT, "roughness %.6g -> Roughness (GGX, alpha = r^2)", m.roughness);
    export_note(n, EXPORT_APPROX,
                "f0 %.6g -> IOR %.6g: Cycles' generalised Schlick Fresnel and its albedo-scaled "
                "layering of the diffuse (not (1 - F(c_i))(1 - F(c_o)))",
                m.f0, m.ior);
    if (m.model == CF_MODEL_CLEARCOAT) {
      double weight = 0.25 * m.coat_weight, r = sqrt(m.gtr1_a);
      SET1("Coat Weight", weight);
      SET1("Coat Roughness", r);
      SET1("Coat IOR", 1.5);
      export_note(n, EXPORT_APPROX,
                  "Burley's clear coat (GTR1 width a = %.6g) -> Coat Weight = 0.25 coat_weight "
                  "= %.6g, Coat IOR 1.5 (F0 0.04), Coat Roughness = sqrt(a) = %.6g: GGX "
                  "without GTR1's tail, darkening the base",
                  m.gtr1_a, weight, r);
    } else {
      SET1("Coat Weight", 0.0);
    }
  }
#undef SET1
#undef SET4
  export_text t = {0};
  export_printf(&t, "# Blender 4 (bpy): builds the material with a Principled BSDF.\n");
  export_printf(&t, "# Run it in Blender's Python console or: blender --python THIS_FILE\n#\n");
  export_provenance(&t, fit, fit_path, "# ");
  export_printf(&t, "#\n");
  export_notes_write(&t, n, "# ");
  export_printf(&t, "\nimport bpy\n\nNAME = \"clayfit_%s\"\n\n", m.info->name);
  export_printf(&t, "# Principled BSDF input -> value (linear RGB colours)\nINPUTS = {\n");
  for (int i = 0; i < count; ++i) {
    if (in[i].components == 4)
      export_printf(&t, "    \"%s\": (%.9g, %.9g, %.9g, 1.0),\n", in[i].name, in[i].value[0],
                    in[i].value[1], in[i].value[2]);
    else
      export_printf(&t, "    \"%s\": %.9g,\n", in[i].name, in[i].value[0]);
  }
  export_printf(&t, "}\n# inputs an older Blender 4 may lack\nOPTIONAL = {");
  for (int i = 0; i < count; ++i)
    if (in[i].optional) export_printf(&t, "\"%s\"", in[i].name);
  export_printf(&t,
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
  return export_text_write(&t, path, err);
}
