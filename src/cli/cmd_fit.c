/* clayfit fit: a capture's observations to fitted material parameters with
 * their uncertainty, written to OUTDIR/fit.json. */
#define _XOPEN_SOURCE 700 /* realpath (XSI) */
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "args.h"
#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "clayfit/fit_file.h"
#include "cli.h"
#include "core/clock.h"
#include "core/file.h"
#include "core/text_escape.h"
#include "out_path.h"

enum { MAX_ASSIGNMENTS = CF_FIT_MAX_NAMED };

static void fit_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit fit CAPTURE -o OUTDIR [--model auto|M] [--hold name=value ...]\n"
          "                   [--free name ...] [--loss huber|cauchy|none] [--loss-scale K]\n"
          "                   [--fit-exposures | --fit-gains per-image|per-light|per-image-rgb]\n"
          "                   [--no-multistart] [--jpeg-plain] [--density D]\n"
          "                   [--footprint auto|centre|S] [--footprint-tolerance T]\n"
          "                   [--budget N|all] [--sampling uniform|stratified|importance]\n"
          "                   [--max-iterations N] [--threads N] [--trace]\n\n"
          "Fits the model to the capture's observations and writes OUTDIR/fit.json\n"
          "(data_schema/fit.schema.json): parameters with units, standard deviations and\n"
          "correlations, what was held and why, the model choice, residual statistics\n"
          "per image, the solver's summary, every start of the multi-start.\n\n"
          "  --model auto        (default) fit the ladder M0..M4 on a sample and keep the\n"
          "                      simplest model that no richer one clearly beats, by BIC\n"
          "                      and by the error on held-out images; then fit it to all\n"
          "  --model M           force model M (M0..M4, or its name; clayfit models)\n"
          "  --hold name=value   hold a parameter (RGB ones: r,g,b or one number); with\n"
          "                      auto, in every model that has it\n"
          "  --free name         fit a parameter that would be held (the interface F0 that\n"
          "                      sets the scale of a capture with relative radiometry)\n"
          "  --loss L            robust loss in units of the noise (default huber)\n"
          "  --loss-scale K      where it starts, in noise sigmas (default 3)\n"
          "  --fit-exposures     fit each image's exposure, a gain per photo (their mean log\n"
          "                      stays 0; refused, exit 2, when the capture cannot tell a\n"
          "                      gain from the material); the same as --fit-gains per-image\n"
          "  --fit-gains G       none, per-image, per-light: a gain per light, shared by the\n"
          "                      images one light lights (a directional_per_image light is\n"
          "                      one light for the images whose rows are the same), or\n"
          "                      per-image-rgb: a gain per image and channel (a white\n"
          "                      balance, for lights of different colours)\n"
          "  --no-multistart     start from the closed-form albedo and defaults only\n");
  fprintf(out,
          "  --jpeg-plain        compare JPEG photos as they are; by default the fit's\n"
          "                      prediction is coded as each photo's own tables and chroma\n"
          "                      code it, and the codec's error taken out (docs/model.md 6.2)\n"
          "  --density D         the film's known thickness, for density and absorption\n"
          "                      (default: mean absorption 0.8, docs/model.md §3.6)\n"
          "  --footprint F       pixel footprints: auto (default) integrates a pixel with\n"
          "                      S x S Gauss-Legendre samples where a lobe is narrower\n"
          "                      than the pixel;\n"
          "                      centre evaluates pixel centres only; a number S samples\n"
          "                      every pixel S x S (as synth --supersample S renders)\n"
          "  --footprint-tolerance T  auto's relative error of a lobe over a pixel\n"
          "                      (default 0.002)\n"
          "  --budget N|all      fit on at most N observations (default 100000; all: every\n"
          "                      one), drawn by\n"
          "  --sampling S        uniform, stratified by half-angle (default), or importance\n"
          "                      (the highlights and the silhouette kept); each weighed by\n"
          "                      the inverse of its chance (clayfit bench fit: the curve).\n"
          "                      The standard deviations are then the sample's, the\n"
          "                      residual statistics in fit.json estimates for every\n"
          "                      observation (clayfit report evaluates each one)\n"
          "  --max-iterations N  per solve (default 100)\n"
          "  --trace             every iteration of every solve on stderr, with the\n"
          "                      solver's decisions around it (to study convergence)\n"
          "  --threads N         solver threads (default 2)\n" CLI_IMAGE_MEMORY_USAGE);
}

/* One --hold "name=value" (an RGB parameter: "r,g,b" or one number for
 * all three) into h; the name is kept in name[64]. Which model has the
 * parameter is the fit layer's to check (cf_fit_model_options). */
static cf_status parse_hold(const char *text, char *name, cf_fit_hold *h, cf_error *err) {
  const char *equals = strchr(text, '=');
  if (!equals || equals == text)
    return cf_error_set(err, CF_EINVAL,
                        "--hold '%s': expected name=value (for example "
                        "albedo=0.8,0.5,0.3 or roughness=0.4)",
                        text);
  size_t length = (size_t)(equals - text);
  if (length >= 64) return cf_error_set(err, CF_EINVAL, "--hold '%s': name too long", text);
  memcpy(name, text, length);
  name[length] = '\0';
  char what[96];
  snprintf(what, sizeof what, "--hold %s", name);
  h->name = name;
  h->count = strchr(equals + 1, ',') ? 3 : 1;
  return h->count == 3 ? cli_parse_list(equals + 1, what, 3, h->value, err)
                       : cli_parse_number(equals + 1, what, &h->value[0], err);
}

/* With a fitted response curve the held-out score is in decoded units
 * (times σ's geometric mean: docs/model.md §6.8). Under the table, why
 * the chosen model was chosen, and what its parameters mean. */
static void print_choice(const cf_fit_choice *choice, int response_fitted) {
  printf("model choice (held out: %s; no robust loss in the held-out RMS; BIC margin %g, held-out "
         "margin %g %%, guard %g %%; %.3g s):\n",
         choice->heldout, choice->bic_margin, 100.0 * choice->heldout_margin,
         100.0 * choice->heldout_guard, choice->seconds);
  printf("  model  unknowns  BIC            %-20s  held-out rel. RMSE\n",
         response_fitted ? "held-out (decoded)" : "held-out RMS (sigma)");
  for (int m = 0; m < choice->count; ++m) {
    const cf_fit_candidate *c = &choice->candidate[m];
    const char *code = cf_model_info_get(c->model)->code;
    if (!c->ok) {
      printf("  %-5s  %s\n", code, c->note);
      continue;
    }
    printf("  %-5s  %8d  %-13.6g  %-20.5g  %.4g %%%s\n", code, c->parameters, c->bic,
           c->heldout_score, 100.0 * c->heldout_relative_rmse, c->chosen ? "   <- chosen" : "");
  }
  const cf_fit_candidate *chosen = cf_fit_choice_chosen(choice);
  if (chosen) printf("  %s chosen: %s\n", cf_model_info_get(chosen->model)->code, chosen->note);
  if (choice->reading[0]) printf("  meaning: %s\n", choice->reading);
  if (choice->ggx_cost_text[0]) printf("  %s\n", choice->ggx_cost_text);
}

/* A value and its standard deviation; at a bound of its range the sd is
 * not defined (the data prefer a value at or beyond the bound: fit.json
 * has null there), so the bound is named instead. */
static void print_value(double value, double sd, int at_bound, double lower, double upper) {
  if (at_bound)
    printf(" %.6g (at %s bound)", value,
           fabs(value - lower) <= fabs(value - upper) ? "lower" : "upper");
  else if (isfinite(sd))
    printf(" %.6g ± %.2g", value, sd);
  else
    printf(" %.6g (sd undefined)", value);
}

static void print_params(const cf_fit_result *r) {
  const cf_model_info *m = cf_model_info_get(r->model);
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    int k = m->offsets[j];
    printf("  %-18s", info->name);
    for (int c = 0; c < info->components; ++c)
      print_value(r->params[k + c], r->sd[k + c], r->status[k + c] == CF_PARAM_AT_BOUND,
                  info->lower, info->upper);
    printf("  %s", strcmp(info->unit, "1") ? info->unit : "");
    for (int c = 0; c < info->components; ++c)
      if (r->status[k + c] != CF_PARAM_FITTED && r->status[k + c] != CF_PARAM_AT_BOUND) {
        printf("  (%s)", cf_param_status_name(r->status[k + c]));
        break;
      }
    printf("\n");
  }
}

/* The fitted per-image gains e_k ± sd, four to a line; or the gains per
 * light g_l ± sd, one a line. */
static void print_gains(const cf_fit_result *r, const cf_capture *capture) {
  if (r->light_count > 0 && r->light_gains && r->light_gains_sd && r->light_names) {
    printf("  gain per light (g_l ± sd inside each image's sum over its lights, mean log 0):\n");
    for (size_t l = 0; l < r->light_count; ++l)
      printf("    %-40s %.4f ± %.4f\n", r->light_names[l], r->light_gains[l], r->light_gains_sd[l]);
  }
  if (!r->exposure_sd || r->images < 2) return;
  double low = HUGE_VAL, high = 0.0, worst = 0.0;
  for (size_t k = 0; k < r->images; ++k) {
    low = fmin(low, r->exposures[k]);
    high = fmax(high, r->exposures[k]);
    worst = fmax(worst, r->exposure_sd[k] / r->exposures[k]);
  }
  if (!(worst > 0.0)) return; /* not fitted */
  printf("  gain per image (e_k ± sd, their mean log 0): %.4g to %.4g, sd at most %.2g %%\n", low,
         high, 100.0 * worst);
  for (size_t k = 0; k < r->images; ++k)
    printf("%s%-12.12s %.4f ± %.4f%s", k % 4 ? "  " : "    ",
           cf_capture_image_at(capture, k)->name, r->exposures[k], r->exposure_sd[k],
           k % 4 == 3 || k + 1 == r->images ? "\n" : "");
  if (!r->white_balance_fitted || !r->white_balance || !r->white_balance_sd) return;
  printf("  white balance per image (red and blue against green, each's mean log 0):\n");
  for (size_t k = 0; k < r->images; ++k) {
    const double *b = r->white_balance + 3 * k, *sd = r->white_balance_sd + 3 * k;
    printf("%s%-12.12s %.4f ± %.4f %.4f ± %.4f%s", k % 2 ? "  " : "    ",
           cf_capture_image_at(capture, k)->name, b[0], sd[0], b[2], sd[2],
           k % 2 == 1 || k + 1 == r->images ? "\n" : "");
  }
}

static void print_summary(const cf_fit_result *r, const cf_capture *capture, const char *path) {
  const cf_model_info *m = cf_model_info_get(r->model);
  printf(
      "model %s (%s): relative RMSE %.4g %% over %zu residuals (%zu censored, %zu beyond "
      "the robust loss), %d iterations, %s\n",
      m->code, m->name, 100.0 * r->relative_rmse, r->residuals, r->censored, r->rejected,
      r->iterations, r->termination);
  if (r->sample_count > 0)
    printf(
        "  a pixel budget: fitted to %zu of %zu observations (%s), each weighed by the inverse "
        "of its chance; the RMSEs are estimates for all of them (clayfit report: exact)\n",
        r->sample_count, r->population_count, cf_sampling_name(r->sampling));
  printf(
      "  without the highlight cores (%g px around each image's brightest pixel): %.4g %%; "
      "inside them: %.4g %% over %zu residuals\n",
      CF_FIT_CORE_RADIUS_PX, 100.0 * r->rest_relative_rmse, 100.0 * r->core_relative_rmse,
      r->core_residuals);
  print_params(r);
  if (r->scale_fitted) {
    printf("  %-18s", "scale");
    print_value(r->scale, r->scale_sd, 0, 0.0, 0.0);
    printf("\n");
  }
  if (r->response_fitted) { /* the slopes d log R / d log x at the knots */
    for (int j = 0; j < CF_RESPONSE_MODEL_KNOTS; ++j) {
      char name[32];
      snprintf(name, sizeof name, "response @ 1/%g", 1.0 / cf_response_model_knot(j));
      printf("  %-18s", j == 0 ? "response @ 1" : name);
      print_value(r->response[j],
                  sqrt(fmax(0.0, r->response_covariance[j * (CF_RESPONSE_MODEL_KNOTS + 1)])), 0,
                  0.0, 0.0);
      printf("%s\n", j == 0 ? "  (log-log slopes of the photos' unknown tone curve)" : "");
    }
  }
  print_gains(r, capture);
  printf("written: %s\n", path);
}

/* ---- the command line ---- */

typedef struct fit_command {
  const char *capture_path, *out_dir, *model_text;
  const char *holds[MAX_ASSIGNMENTS], *frees[MAX_ASSIGNMENTS];
  int hold_count, free_count;
  int trace;                          /* --trace: the solver's lines on stderr */
  unsigned long long max_image_bytes; /* --max-image-memory, 0: the default */
  cf_fit_options set;                 /* the settings every model shares (cf_fit_model_options) */
} fit_command;

static cf_status parse_loss(const char *text, cf_loss *loss, cf_error *err) {
  if (strcmp(text, "huber") == 0)
    *loss = CF_LOSS_HUBER;
  else if (strcmp(text, "cauchy") == 0)
    *loss = CF_LOSS_CAUCHY;
  else if (strcmp(text, "none") == 0)
    *loss = CF_LOSS_NONE;
  else
    return cf_error_set(err, CF_EINVAL, "--loss: '%s' is not huber, cauchy or none", text);
  return CF_OK;
}

/* --footprint: auto (0), centre (1) or S samples per side. */
static cf_status parse_footprint(const char *text, int *footprint, cf_error *err) {
  if (strcmp(text, "auto") == 0) {
    *footprint = 0;
    return CF_OK;
  }
  if (strcmp(text, "centre") == 0 || strcmp(text, "center") == 0) {
    *footprint = 1;
    return CF_OK;
  }
  long samples = 0;
  cf_status s =
      cli_parse_count(text, "--footprint", 1, CF_FIT_FOOTPRINT_MAX_SAMPLES, &samples, err);
  if (s != CF_OK)
    s = cf_error_set(err, CF_EINVAL,
                     "--footprint: '%s' is not auto, centre or a number of samples per side "
                     "from 1 to %d",
                     text, CF_FIT_FOOTPRINT_MAX_SAMPLES);
  *footprint = (int)samples;
  return s;
}

/* --budget: a number of observations, or all (0). */
static cf_status parse_budget(const char *text, size_t *budget, cf_error *err) {
  long n = 0;
  cf_status s = CF_OK;
  if (strcmp(text, "all") != 0 &&
      cli_parse_count(text, "--budget", 100, 2000000000L, &n, err) != CF_OK)
    s = cf_error_set(err, CF_EINVAL,
                     "--budget: '%s' is neither a number of observations (100 to 2e9) nor all",
                     text);
  *budget = (size_t)n;
  return s;
}

static cf_status parse_sampling(const char *text, cf_sampling *sampling, cf_error *err) {
  for (int k = 0; k < CF_SAMPLING_COUNT; ++k)
    if (strcmp(text, cf_sampling_name((cf_sampling)k)) == 0) {
      *sampling = (cf_sampling)k;
      return CF_OK;
    }
  return cf_error_set(err, CF_EINVAL, "--sampling: '%s' is not uniform, stratified or importance",
                      text);
}

/* A positive number (--loss-scale, --density). */
static cf_status parse_positive(const char *text, const char *flag, double *out, cf_error *err) {
  cf_status s = cli_parse_number(text, flag, out, err);
  if (s == CF_OK && !(*out > 0.0))
    s = cf_error_set(err, CF_ERANGE, "%s must be greater than 0", flag);
  return s;
}

/* One option with a value into the settings. */
static cf_status parse_setting(int c, const char *arg, cf_fit_options *set, cf_error *err) {
  long count = 0;
  cf_status s = CF_OK;
  switch (c) {
    case 'l':
      return parse_loss(arg, &set->loss, err);
    case 'k':
      return parse_positive(arg, "--loss-scale", &set->loss_scale, err);
    case 'd':
      return parse_positive(arg, "--density", &set->density, err);
    case 'f':
      return parse_footprint(arg, &set->footprint, err);
    case 'B':
      return parse_budget(arg, &set->budget, err);
    case 'S':
      return parse_sampling(arg, &set->sampling, err);
    case 'T':
      s = cli_parse_number(arg, "--footprint-tolerance", &set->footprint_tolerance, err);
      if (s == CF_OK && !(set->footprint_tolerance > 0.0 && set->footprint_tolerance < 1.0))
        s = cf_error_set(err, CF_ERANGE, "--footprint-tolerance must be in (0, 1)");
      return s;
    case 'i':
      s = cli_parse_count(arg, "--max-iterations", 1, 100000, &count, err);
      if (s == CF_OK) set->max_iterations = (int)count;
      return s;
    case 't':
      s = cli_parse_count(arg, "--threads", 1, 256, &count, err);
      if (s == CF_OK) set->threads = (int)count;
      return s;
  }
  return cf_error_set(err, CF_EINVAL, "unknown option");
}

static const struct option fit_long_options[] = {
    {"output", required_argument, NULL, 'o'},
    {"model", required_argument, NULL, 'm'},
    {"hold", required_argument, NULL, 'H'},
    {"free", required_argument, NULL, 'F'},
    {"loss", required_argument, NULL, 'l'},
    {"loss-scale", required_argument, NULL, 'k'},
    {"fit-exposures", no_argument, NULL, 'e'},
    {"fit-gains", required_argument, NULL, 'g'},
    {"no-multistart", no_argument, NULL, 'M'},
    {"density", required_argument, NULL, 'd'},
    {"max-iterations", required_argument, NULL, 'i'},
    {"threads", required_argument, NULL, 't'},
    {"help", no_argument, NULL, 'h'},
    {"footprint", required_argument, NULL, 'f'},
    {"footprint-tolerance", required_argument, NULL, 'T'},
    {"budget", required_argument, NULL, 'B'},
    {"sampling", required_argument, NULL, 'S'},
    {"trace", no_argument, NULL, 'R'},
    {"max-image-memory", required_argument, NULL, 'G'},
    {"jpeg-plain", no_argument, NULL, 'J'},
    {0}};

/* The command line into cmd. Returns -1 to go on, else the exit status
 * (--help, a bad option, too many --hold or --free; other errors are left
 * in *s and err for the caller). */
static int parse_command(int argc, char **argv, fit_command *cmd, cf_status *s, cf_error *err) {
  memset(cmd, 0, sizeof *cmd);
  cmd->model_text = "auto";
  cf_fit_default_options(&cmd->set, CF_MODEL_LAMBERT); /* 100 iterations, 2 threads */
  optind = 1;
  opterr = 0;
  for (int c; *s == CF_OK && (c = getopt_long(argc, argv, "o:", fit_long_options, NULL)) != -1;) {
    if (c == 'o') {
      cmd->out_dir = optarg;
    } else if (c == 'm') {
      cmd->model_text = optarg;
    } else if (c == 'H' || c == 'F') {
      int *count = c == 'H' ? &cmd->hold_count : &cmd->free_count;
      if (*count == MAX_ASSIGNMENTS) {
        cli_report("fit", "too many --hold or --free options");
        return CLI_EXIT_USAGE;
      }
      (c == 'H' ? cmd->holds : cmd->frees)[(*count)++] = optarg;
    } else if (c == 'e') {
      cmd->set.fit_exposures = CF_GAINS_PER_IMAGE;
    } else if (c == 'g') {
      if (!strcmp(optarg, "per-image"))
        cmd->set.fit_exposures = CF_GAINS_PER_IMAGE;
      else if (!strcmp(optarg, "per-light"))
        cmd->set.fit_exposures = CF_GAINS_PER_LIGHT;
      else if (!strcmp(optarg, "per-image-rgb"))
        cmd->set.fit_exposures = CF_GAINS_PER_IMAGE_RGB;
      else if (strcmp(optarg, "none"))
        *s = cf_error_set(err, CF_EINVAL,
                          "--fit-gains: '%s' is not none, per-image, per-light or per-image-rgb",
                          optarg);
      else
        cmd->set.fit_exposures = CF_GAINS_NONE;
    } else if (c == 'M') {
      cmd->set.multistart = 0;
    } else if (c == 'J') {
      cmd->set.jpeg_plain = 1;
    } else if (c == 'R') {
      cmd->trace = 1;
    } else if (c == 'G') {
      *s = cli_parse_image_memory(optarg, &cmd->max_image_bytes, err);
    } else if (c == 'h') {
      fit_usage(stdout);
      return CLI_EXIT_OK;
    } else if (c == '?' || c == ':') {
      return cli_bad_option("fit", argv);
    } else {
      *s = parse_setting(c, optarg, &cmd->set, err);
    }
  }
  if (*s == CF_OK && optind + 1 != argc)
    *s = cf_error_set(err, CF_EINVAL, "expected one capture file (see clayfit fit --help)");
  if (*s == CF_OK && !cmd->out_dir) *s = cf_error_set(err, CF_EINVAL, "-o OUTDIR is required");
  cmd->capture_path = *s == CF_OK ? argv[optind] : NULL;
  return -1;
}

/* --trace: a solver's line on stderr, after its model's code (the
 * ladder's models are fitted side by side). */
static void trace_line(void *user, const char *line) {
  const cf_fit_options *o = user;
  fprintf(stderr, "clayfit fit: %s: %s\n", cf_model_info_get(o->model)->code, line);
}

/* Each model's options: the ladder's (--model auto) or the one forced;
 * a held value out of its range refused before any work. */
static cf_status fit_options(const fit_command *cmd, int *automatic, cf_model_id *model,
                             cf_fit_options ladder[CF_MODEL_COUNT], cf_error *err) {
  *automatic = strcmp(cmd->model_text, "auto") == 0;
  *model = CF_MODEL_CLAY;
  cf_fit_hold holds[MAX_ASSIGNMENTS];
  char names[MAX_ASSIGNMENTS][64];
  cf_status s = CF_OK;
  for (int i = 0; s == CF_OK && i < cmd->hold_count; ++i)
    s = parse_hold(cmd->holds[i], names[i], &holds[i], err);
  if (s == CF_OK && *automatic) {
    s = cf_fit_ladder_options(&cmd->set, holds, cmd->hold_count, cmd->frees, cmd->free_count,
                              ladder, err);
    for (int m = 0; s == CF_OK && m < CF_MODEL_COUNT; ++m)
      s = cf_fit_check_options(&ladder[m], err);
    return s;
  }
  if (s == CF_OK) s = cf_model_find(cmd->model_text, model, err);
  if (s == CF_OK)
    s = cf_fit_model_options(*model, &cmd->set, holds, cmd->hold_count, cmd->frees, cmd->free_count,
                             NULL, &ladder[*model], err);
  if (s == CF_OK) s = cf_fit_check_options(&ladder[*model], err);
  return s;
}

/* The capture loaded, its warnings on stderr. */
static cf_status load_capture(const char *path, unsigned long long max_image_bytes,
                              const cli_context *ctx, cf_capture **capture, cf_error *err) {
  cf_capture_options load_options = {ctx->quiet ? NULL : cli_progress, "fit", max_image_bytes};
  cf_status s = cf_capture_load(path, &load_options, capture, err);
  if (s != CF_OK) return s;
  cf_capture_summary summary;
  cf_capture_summarize(*capture, &summary);
  for (size_t i = 0; i < summary.warnings && !ctx->quiet; ++i)
    fprintf(stderr, "clayfit fit: warning: %s\n", cf_capture_warning(*capture, i));
  return CF_OK;
}

/* The fit done: OUTDIR/fit.json written, the warnings on stderr, the
 * summary on stdout. */
static cf_status write_fit(const fit_command *cmd, const cf_capture *capture,
                           const cf_fit_options *o, const cf_fit_result *result,
                           const cf_fit_choice *choice, const double seconds[2],
                           const cli_context *ctx, cf_error *err) {
  char path[4096];
  cf_status s = cf_make_dirs(cmd->out_dir, err);
  if (s == CF_OK) s = cf_path_join(cmd->out_dir, "fit.json", path, sizeof path, err);
  if (s == CF_OK) {
    cf_fit_report report = {capture,       cmd->capture_path, result,
                            choice,        CLAYFIT_VERSION,   o->loss,
                            o->loss_scale, o->density,        seconds[0],
                            seconds[1],    o->footprint,      o->footprint_tolerance};
    s = cf_fit_write_json(path, &report, err);
  }
  if (s != CF_OK) return s;
  for (int i = 0; i < result->warning_count && !ctx->quiet; ++i)
    fprintf(stderr, "clayfit fit: warning: %s\n", result->warnings[i]);
  char reading[320];
  if (choice)
    print_choice(choice, result->response_fitted);
  else if (cf_fit_reading(result, reading, sizeof reading))
    printf("meaning: %s\n", reading);
  print_summary(result, capture, path);
  return CF_OK;
}

/* fit.json records the capture's path relative to its own folder (`..`s
 * and the folders of the capture's real path) as JSON text, which must be
 * UTF-8: a capture whose real path is not could not be recorded so that
 * report and export find it, so it is refused before the work. */
static cf_status check_recordable(const char *capture_path, cf_error *err) {
  char real[PATH_MAX];
  if (!realpath(capture_path, real)) return CF_OK; /* loading says why */
  if (text_is_utf8(real)) return CF_OK;
  char *shown = text_escape_alloc(text_escape_utf8, real);
  cf_status s = cf_error_set(err, CF_EINVAL,
                             "%s: the capture's path is not UTF-8 text, so fit.json could not "
                             "record where the capture is (rename its folders or file)",
                             shown ? shown : capture_path);
  free(shown);
  return s;
}

int cmd_fit(int argc, char **argv, cli_context *ctx) {
  fit_command cmd;
  cf_error err = {0};
  cf_status s = CF_OK;
  int exit_status = parse_command(argc, argv, &cmd, &s, &err);
  if (exit_status >= 0) return exit_status;
  int automatic = 0;
  cf_model_id model = CF_MODEL_CLAY;
  cf_fit_options ladder[CF_MODEL_COUNT];
  if (s == CF_OK) s = fit_options(&cmd, &automatic, &model, ladder, &err);
  if (s == CF_OK) s = cli_check_output_in("-o", cmd.out_dir, "fit.json", &err);
  if (s == CF_OK) s = check_recordable(cmd.capture_path, &err);
  if (s != CF_OK) {
    cli_report("fit", err.message);
    return CLI_EXIT_USAGE;
  }

  double start = cf_now_seconds();
  cf_capture *capture = NULL;
  s = load_capture(cmd.capture_path, cmd.max_image_bytes, ctx, &capture, &err);
  if (s != CF_OK) {
    cli_report("fit", err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  double seconds[2] = {cf_now_seconds() - start, 0.0}; /* load, fit */
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    if (!ctx->quiet) ladder[m].progress = cli_progress, ladder[m].progress_user = "fit";
    if (cmd.trace) ladder[m].trace = trace_line, ladder[m].trace_user = &ladder[m];
  }
  cf_fit_result result;
  cf_fit_choice choice;
  if (automatic)
    s = cf_fit_auto(capture, ladder, &choice, &result, &err);
  else
    s = cf_fit_run(capture, &ladder[model], &result, &err);
  seconds[1] = cf_now_seconds() - start - seconds[0];
  if (s == CF_OK)
    s = write_fit(&cmd, capture, &ladder[automatic ? choice.chosen : model], &result,
                  automatic ? &choice : NULL, seconds, ctx, &err);
  if (automatic) cf_fit_choice_free(&choice);
  cf_fit_result_free(&result);
  cf_capture_free(capture);
  if (s != CF_OK) {
    cli_report("fit", err.message);
    return s == CF_ERANGE || s == CF_EINVAL ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE;
  }
  return CLI_EXIT_OK;
}
