/* clayfit eval: the BRDF of one model for one set of directions, as JSON
 * (schema: data_schema/eval.schema.json). */
#include <getopt.h>
#include <string.h>

#include "args.h"
#include "clayfit/export.h"
#include "clayfit/model.h"
#include "cli.h"
#include "json_out.h"

enum { MAX_PARAM_ASSIGNMENTS = 64 };

static void eval_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit eval --model M --light x,y,z --view x,y,z\n"
          "                    [--normal x,y,z] [--param name=value ...] [--grad]\n"
          "       clayfit eval --preset PRESET.json --light x,y,z --view x,y,z [...]\n\n"
          "Prints the BRDF f(l, v) per linear-RGB channel in 1/sr (f, not "
          "f*cos) as JSON.\n"
          "Directions point away from the surface and are normalised; the "
          "normal defaults\n"
          "to 0,0,1. Parameters not given take their defaults. Roughness is "
          "perceptual\n"
          "(alpha = r^2). With --grad the JSON also holds df/dparameter for "
          "every\n"
          "parameter: gradient.NAME[c] for a scalar, gradient.NAME[c][k] = "
          "df_c/dNAME_k\n"
          "for an RGB one (c, k = 0 red, 1 green, 2 blue).\n"
          "--preset takes the model and its parameters from a json preset (clayfit export\n"
          "--format json); --param then overrides them.\n\n");
  cli_print_model_table(out);
}

static json_t *params_json(const cf_model_info *m, const double *params) {
  json_t *object = json_object();
  for (int k = 0; k < m->param_count; ++k) {
    const cf_param_info *info = cf_param_info_get(m->params[k]);
    const double *x = params + m->offsets[k];
    json_object_set_new(object, info->name,
                        info->components == 3 ? json_doubles(x, 3) : json_real(x[0]));
  }
  return object;
}

/* gradient.NAME[c] (scalar) or gradient.NAME[c][k] (RGB), c = channel of f. */
static json_t *gradient_json(const cf_model_info *m, const double *grad) {
  json_t *object = json_object();
  for (int k = 0; k < m->param_count; ++k) {
    const cf_param_info *info = cf_param_info_get(m->params[k]);
    int slot = m->offsets[k];
    json_t *rows = json_array();
    for (int c = 0; c < 3; ++c) {
      const double *row = grad + c * m->dim + slot;
      json_array_append_new(rows, info->components == 3 ? json_doubles(row, 3) : json_real(row[0]));
    }
    json_object_set_new(object, info->name, rows);
  }
  return object;
}

typedef struct eval_args {
  const char *model_text, *light_text, *view_text, *normal_text, *preset;
  const char *assignments[MAX_PARAM_ASSIGNMENTS];
  int assignment_count, want_grad;
} eval_args;

/* The command line into a. Returns -1 to go on, else the exit status (after
 * the usage, or the reason on stderr). */
static int parse_eval_args(int argc, char **argv, eval_args *a) {
  enum {
    OPT_MODEL = 'm',
    OPT_PARAM = 'p',
    OPT_LIGHT = 'l',
    OPT_VIEW = 'v',
    OPT_NORMAL = 'n',
    OPT_GRAD = 'g',
    OPT_PRESET = 'P',
    OPT_HELP = 'h'
  };
  static const struct option options[] = {{"model", required_argument, NULL, OPT_MODEL},
                                          {"param", required_argument, NULL, OPT_PARAM},
                                          {"light", required_argument, NULL, OPT_LIGHT},
                                          {"view", required_argument, NULL, OPT_VIEW},
                                          {"normal", required_argument, NULL, OPT_NORMAL},
                                          {"grad", no_argument, NULL, OPT_GRAD},
                                          {"preset", required_argument, NULL, OPT_PRESET},
                                          {"help", no_argument, NULL, OPT_HELP},
                                          {0}};
  memset(a, 0, sizeof *a);
  a->normal_text = "0,0,1";
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "", options, NULL)) != -1;) {
    if (c == OPT_MODEL)
      a->model_text = optarg;
    else if (c == OPT_LIGHT)
      a->light_text = optarg;
    else if (c == OPT_VIEW)
      a->view_text = optarg;
    else if (c == OPT_NORMAL)
      a->normal_text = optarg;
    else if (c == OPT_GRAD)
      a->want_grad = 1;
    else if (c == OPT_PRESET)
      a->preset = optarg;
    else if (c == OPT_PARAM && a->assignment_count == MAX_PARAM_ASSIGNMENTS) {
      cli_report("eval", "too many --param options");
      return CLI_EXIT_USAGE;
    } else if (c == OPT_PARAM)
      a->assignments[a->assignment_count++] = optarg;
    else if (c == OPT_HELP) {
      eval_usage(stdout);
      return CLI_EXIT_OK;
    } else
      return cli_bad_option("eval", argv);
  }
  return -1;
}

/* What the options must say together. Returns -1 if they do, else the
 * exit status with the reason on stderr. */
static int check_eval_args(int argc, char **argv, const eval_args *a) {
  if (optind < argc) {
    char message[160];
    snprintf(message, sizeof message, "unexpected argument '%s'", argv[optind]);
    cli_report("eval", message);
    return CLI_EXIT_USAGE;
  }
  if ((!a->model_text && !a->preset) || !a->light_text || !a->view_text) {
    cli_report("eval", "--model, --light and --view are required (see clayfit eval --help)");
    return CLI_EXIT_USAGE;
  }
  if (a->model_text && a->preset) {
    cli_report("eval", "--model and --preset exclude each other (the preset names its model)");
    return CLI_EXIT_USAGE;
  }
  return -1;
}

/* The model and its parameters (the preset's or the defaults, then
 * --param), and the directions. */
static cf_status eval_inputs(const eval_args *a, cf_model_id *model, double *params, double n[3],
                             double l[3], double v[3], cf_error *err) {
  int given[CF_MAX_DIM] = {0};
  cf_status s = a->preset ? cf_export_preset_read(a->preset, model, params, err)
                          : cf_model_find(a->model_text, model, err);
  if (s == CF_OK && !a->preset) cf_model_default_params(*model, params);
  for (int k = 0; s == CF_OK && k < a->assignment_count; ++k)
    s = cli_apply_param(*model, "--param", a->assignments[k], params, given, err);
  if (s == CF_OK) s = cf_params_check(*model, params, err);
  if (s == CF_OK) s = cli_parse_direction(a->light_text, "--light", l, err);
  if (s == CF_OK) s = cli_parse_direction(a->view_text, "--view", v, err);
  if (s == CF_OK) s = cli_parse_direction(a->normal_text, "--normal", n, err);
  return s;
}

int cmd_eval(int argc, char **argv, cli_context *ctx) {
  (void)ctx;
  eval_args a;
  int exit_status = parse_eval_args(argc, argv, &a);
  if (exit_status < 0) exit_status = check_eval_args(argc, argv, &a);
  if (exit_status >= 0) return exit_status;
  cf_error err = {0};
  cf_model_id model;
  double params[CF_MAX_DIM], n[3], l[3], v[3];
  cf_status s = eval_inputs(&a, &model, params, n, l, v, &err);
  if (s != CF_OK) {
    cli_report("eval", err.message);
    return CLI_EXIT_USAGE;
  }

  const cf_model_info *m = cf_model_info_get(model);
  double f[3], grad[3 * CF_MAX_DIM];
  cf_eval(model, params, n, l, v, f, a.want_grad ? grad : NULL);
  cf_geometry g = cf_geometry_from_directions(n, l, v);

  json_t *doc = json_object();
  json_object_set_new(doc, "model", json_string(m->name));
  json_object_set_new(doc, "code", json_string(m->code));
  json_object_set_new(doc, "quantity", json_string("BRDF f(l, v), not f*cos"));
  json_object_set_new(doc, "unit", json_string("1/sr"));
  json_object_set_new(doc, "normal", json_doubles(n, 3));
  json_object_set_new(doc, "light", json_doubles(l, 3));
  json_object_set_new(doc, "view", json_doubles(v, 3));
  json_object_set_new(doc, "cos_i", json_real(g.cos_i));
  json_object_set_new(doc, "cos_o", json_real(g.cos_o));
  json_object_set_new(doc, "lit", json_boolean(cf_geometry_is_lit(&g)));
  json_object_set_new(doc, "params", params_json(m, params));
  json_object_set_new(doc, "value", json_doubles(f, 3));
  if (a.want_grad) json_object_set_new(doc, "gradient", gradient_json(m, grad));
  return json_print(stdout, doc) ? CLI_EXIT_FAILURE : CLI_EXIT_OK;
}
