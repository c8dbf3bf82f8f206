/* clayfit export: a fit's material as a preset for a renderer
 * (clayfit/export.h): json, MaterialX, glTF, Blender, Mitsuba. */
#include <getopt.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/export.h"
#include "clayfit/fit_file.h"
#include "cli.h"
#include "out_path.h"

static void export_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit export FIT.json --format F -o PATH\n\n"
          "Writes the material fitted in FIT.json (clayfit fit's output) for a renderer:\n"
          "  json          clayfit's own preset (data_schema/preset.schema.json), lossless:\n"
          "                clayfit eval --preset PATH evaluates it\n"
          "  mtlx          MaterialX 1.38 standard_surface\n"
          "  mtlx-openpbr  MaterialX 1.39 open_pbr_surface\n"
          "  gltf          glTF 2.0 .gltf: a sphere with the material (KHR_materials_clearcoat,\n"
          "                _ior, _specular)\n"
          "  blender       a Blender Python script building a Principled BSDF (v2 in\n"
          "                Blender 4, v1 in Blender 3.x)\n"
          "  mitsuba       a Mitsuba 3 scene fragment (diffuse, roughplastic or principled)\n"
          "  glsl          a three.js ShaderMaterial (ES module, GLSL ES 3.0) evaluating the\n"
          "                model exactly (docs/shaders.md)\n"
          "  unity         a folder for a Unity project's Assets: a built-in pipeline shader\n"
          "                (HLSL) evaluating the model exactly, a material, .meta files\n"
          "No target has every term of the models: each file says in a comment (glTF: in\n"
          "asset.extras) what maps exactly, approximately, and what is dropped; a value a\n"
          "target cannot take is a warning on stderr (--quiet silences warnings).\n"
          "PATH's folder must exist and be writable (checked before FIT.json is read);\n"
          "for unity, PATH is the folder written (created if missing).\n");
}

int cmd_export(int argc, char **argv, cli_context *ctx) {
  enum { OPT_FORMAT = 'f', OPT_OUTPUT = 'o', OPT_HELP = 'h' };
  static const struct option options[] = {{"format", required_argument, NULL, OPT_FORMAT},
                                          {"output", required_argument, NULL, OPT_OUTPUT},
                                          {"help", no_argument, NULL, OPT_HELP},
                                          {0}};
  const char *format_text = NULL, *output = NULL;
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "o:", options, NULL)) != -1;) {
    switch (c) {
      case OPT_FORMAT:
        format_text = optarg;
        break;
      case OPT_OUTPUT:
        output = optarg;
        break;
      case OPT_HELP:
        export_usage(stdout);
        return CLI_EXIT_OK;
      default:
        return cli_bad_option("export", argv);
    }
  }
  if (optind + 1 != argc || !format_text || !output) {
    cli_report("export", "expected FIT.json --format F -o PATH (see clayfit export --help)");
    return CLI_EXIT_USAGE;
  }
  const char *fit_path = argv[optind];
  cf_error err = {0};
  cf_export_format format;
  if (cf_export_format_find(format_text, &format, &err) != CF_OK ||
      cli_check_output("-o", output, format == CF_EXPORT_UNITY ? CLI_OUT_FOLDER : CLI_OUT_FILE,
                       &err) != CF_OK) {
    cli_report("export", err.message);
    return CLI_EXIT_USAGE;
  }
  cf_fit_file fit;
  cf_status read = cf_fit_file_read(fit_path, &fit, &err);
  if (read != CF_OK) {
    cli_report("export", err.message);
    return read == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  const char *version_warning = cf_fit_file_version_warning(&fit);
  if (version_warning && !ctx->quiet)
    fprintf(stderr, "clayfit export: warning: %s: %s\n", fit_path, version_warning);
  cf_export_warnings warnings = {0};
  cf_status s = cf_export_write(&fit, fit_path, format, output, &warnings, &err);
  cf_fit_file_free(&fit);
  if (s != CF_OK) {
    cli_report("export", err.message);
    return s == CF_EIO || s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  if (!ctx->quiet) {
    for (int i = 0; i < warnings.count; ++i)
      fprintf(stderr, "clayfit export: warning: %s\n", warnings.text[i]);
    fprintf(stderr, "clayfit export: wrote %s (%s)\n", output, cf_export_format_name(format));
  }
  return CLI_EXIT_OK;
}
