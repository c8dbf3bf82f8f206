/* clayfit models: the model ladder and its parameters, from the table. */
#include <getopt.h>
#include <string.h>

#include "clayfit/model.h"
#include "cli.h"
#include "json_out.h"

void cli_print_model_table(FILE *out) {
  fprintf(out, "models (the ladder of docs/model.md §3; code or name selects one):\n");
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    const cf_model_info *model = cf_model_info_get((cf_model_id)m);
    fprintf(out, "  %s %-11s %s\n    parameters:", model->code, model->name, model->summary);
    for (int k = 0; k < model->param_count; ++k)
      fprintf(out, " %s", cf_param_info_get(model->params[k])->name);
    fprintf(out, "\n");
  }
  fprintf(out,
          "\nparameters (RGB ones take 'r,g,b' or one number for all three; "
          "unit 1 = dimensionless):\n"
          "  %-18s %-5s %-4s %-8s %-15s %s\n",
          "name", "kind", "unit", "default", "range", "meaning");
  for (int p = 0; p < CF_PARAM_COUNT; ++p) {
    const cf_param_info *info = cf_param_info_get((cf_param_id)p);
    char range[32];
    snprintf(range, sizeof range, "[%g, %g]", info->lower, info->upper);
    fprintf(out, "  %-18s %-5s %-4s %-8g %-15s %s\n", info->name,
            info->components == 3 ? "RGB" : "1", info->unit, info->default_value, range,
            info->meaning);
  }
}

static json_t *model_table_json(void) {
  json_t *models = json_array();
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    const cf_model_info *model = cf_model_info_get((cf_model_id)m);
    json_t *params = json_array();
    for (int k = 0; k < model->param_count; ++k) {
      const cf_param_info *info = cf_param_info_get(model->params[k]);
      json_array_append_new(
          params, json_pack("{s:s, s:s, s:i, s:i, s:s, s:f, s:f, s:f, s:s}", "name", info->name,
                            "symbol", info->symbol, "components", info->components, "offset",
                            model->offsets[k], "unit", info->unit, "default", info->default_value,
                            "lower", info->lower, "upper", info->upper, "meaning", info->meaning));
    }
    json_array_append_new(
        models, json_pack("{s:s, s:s, s:s, s:i, s:o}", "code", model->code, "name", model->name,
                          "summary", model->summary, "dim", model->dim, "parameters", params));
  }
  return json_pack("{s:o}", "models", models);
}

int cmd_models(int argc, char **argv, cli_context *ctx) {
  (void)ctx;
  static const struct option options[] = {
      {"json", no_argument, NULL, 'j'}, {"help", no_argument, NULL, 'h'}, {0}};
  int as_json = 0;
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "jh", options, NULL)) != -1;) {
    if (c == 'j') {
      as_json = 1;
    } else if (c == 'h') {
      printf("usage: clayfit models [--json]\n\n");
      cli_print_model_table(stdout);
      return CLI_EXIT_OK;
    } else {
      return cli_bad_option("models", argv);
    }
  }
  if (optind < argc) {
    cli_report("models", "unexpected argument");
    return CLI_EXIT_USAGE;
  }
  if (as_json) return json_print(stdout, model_table_json()) ? CLI_EXIT_FAILURE : CLI_EXIT_OK;
  cli_print_model_table(stdout);
  return CLI_EXIT_OK;
}
