/* clayfit fit: a capture's observations to fitted material parameters with
 * their uncertainty, written to OUTDIR/fit.json. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "args.h"
#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "cli.h"
#include "core/clock.h"
#include "core/file.h"
#include "fit/fit_json.h"

enum { MAX_ASSIGNMENTS = 64 };

static void fit_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit fit CAPTURE -o OUTDIR [--model auto|M] [--hold name=value ...]\n"
          "                   [--free name ...] [--loss huber|cauchy|none] [--loss-scale K]\n"
          "                   [--fit-exposures] [--no-multistart] [--density D]\n"
          "                   [--footprint auto|centre|S] [--footprint-tolerance T]\n"
          "                   [--budget N|all] [--sampling uniform|stratified|importance]\n"
          "                   [--max-iterations N] [--threads N]\n\n"
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
          "  --fit-exposures     fit each image's exposure (their mean log stays 0)\n"
          "  --no-multistart     start from the closed-form albedo and defaults only\n"
          "  --density D         the film's known thickness, for density and absorption\n"
          "                      (default: MODEL.md's convention, mean absorption 0.8)\n"
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
          "  --threads N         solver threads (default 2)\n");
}

/* --hold and --free into one model's options. With known (the model
 * choice: one flag per hold, then per free), a name the model lacks is
 * skipped and the flags mark the names some model has. */
static cf_status apply_holds(cf_fit_options *o, const char **holds, int hold_count,
                             const char **frees, int free_count, int *known, cf_error *err) {
  int given[CF_MAX_DIM] = {0};
  cf_status s = CF_OK;
  for (int i = 0; s == CF_OK && i < hold_count; ++i) {
    s = cli_apply_param(o->model, "--hold", holds[i], o->hold_value, given, err);
    if (known && s == CF_ENOTFOUND)
      s = CF_OK;
    else if (known && s == CF_OK)
      known[i] = 1;
  }
  for (int k = 0; k < CF_MAX_DIM; ++k) o->hold[k] = given[k];
  for (int i = 0; s == CF_OK && i < free_count; ++i) {
    int slot = 0;
    const cf_param_info *info = NULL;
    s = cf_model_param_find(o->model, frees[i], &slot, &info, err);
    if (known && s == CF_ENOTFOUND) {
      s = CF_OK;
      continue;
    }
    if (known && s == CF_OK) known[hold_count + i] = 1;
    for (int c = 0; s == CF_OK && c < info->components; ++c) {
      if (o->hold[slot + c])
        return cf_error_set(err, CF_EINVAL, "%s is both held and freed", info->name);
      o->free[slot + c] = 1;
    }
  }
  return s;
}

/* The options every model shares. */
typedef struct fit_settings {
  cf_loss loss;
  double loss_scale, density;
  int fit_exposures, multistart, max_iterations, threads;
  int footprint;
  double footprint_tolerance;
  size_t budget;
  cf_sampling sampling;
} fit_settings;

static cf_status model_options(cf_model_id model, const fit_settings *set, const char **holds,
                               int hold_count, const char **frees, int free_count, int *known,
                               cf_fit_options *o, cf_error *err) {
  cf_fit_default_options(o, model);
  o->loss = set->loss;
  o->loss_scale = set->loss_scale;
  o->fit_exposures = set->fit_exposures;
  o->multistart = set->multistart;
  o->max_iterations = set->max_iterations;
  o->threads = set->threads;
  o->density = set->density;
  o->footprint = set->footprint;
  o->footprint_tolerance = set->footprint_tolerance;
  o->budget = set->budget;
  o->sampling = set->sampling;
  return apply_holds(o, holds, hold_count, frees, free_count, known, err);
}

/* The options of every model of the ladder (--model auto): a --hold or
 * --free applies to the models that have the parameter, and must name one
 * that some model has. */
static cf_status ladder_options(const fit_settings *set, const char **holds, int hold_count,
                                const char **frees, int free_count,
                                cf_fit_options options[CF_MODEL_COUNT], cf_error *err) {
  int known[2 * MAX_ASSIGNMENTS] = {0};
  cf_status s = CF_OK;
  for (int m = 0; s == CF_OK && m < CF_MODEL_COUNT; ++m)
    s = model_options((cf_model_id)m, set, holds, hold_count, frees, free_count, known, &options[m],
                      err);
  for (int i = 0; s == CF_OK && i < hold_count + free_count; ++i) {
    if (known[i]) continue;
    const char *text = i < hold_count ? holds[i] : frees[i - hold_count];
    const char *equals = strchr(text, '=');
    int length = equals ? (int)(equals - text) : (int)strlen(text);
    s = cf_error_set(err, CF_ENOTFOUND,
                     "%s %.*s: no model of the ladder has a parameter of that "
                     "name (see clayfit models)",
                     i < hold_count ? "--hold" : "--free", length, text);
  }
  return s;
}

static void print_choice(const cf_fit_choice *choice) {
  printf("model choice (held out: %s; BIC margin %g, held-out margin %g %%; %.3g s):\n",
         choice->heldout, choice->bic_margin, 100.0 * choice->heldout_margin, choice->seconds);
  printf("  model  unknowns  BIC            held-out RMS (sigma)  held-out rel. RMSE\n");
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
}

static void print_summary(const cf_fit_result *r, const char *path) {
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
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    int k = m->offsets[j];
    printf("  %-18s", info->name);
    for (int c = 0; c < info->components; ++c)
      printf(" %.6g ± %.2g", r->params[k + c], r->sd[k + c]);
    printf("  %s", strcmp(info->unit, "1") ? info->unit : "");
    for (int c = 0; c < info->components; ++c)
      if (r->status[k + c] != CF_PARAM_FITTED) {
        printf("  (%s)", cf_param_status_name(r->status[k + c]));
        break;
      }
    printf("\n");
  }
  if (r->scale_fitted) printf("  %-18s %.6g ± %.2g\n", "scale", r->scale, r->scale_sd);
  if (r->response_fitted)
    printf("  %-18s %.6g ± %.2g  (the photos' unknown tone curve)\n", "response exponent",
           r->response, r->response_sd);
  printf("written: %s\n", path);
}

int cmd_fit(int argc, char **argv, cli_context *ctx) {
  static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                          {"model", required_argument, NULL, 'm'},
                                          {"hold", required_argument, NULL, 'H'},
                                          {"free", required_argument, NULL, 'F'},
                                          {"loss", required_argument, NULL, 'l'},
                                          {"loss-scale", required_argument, NULL, 'k'},
                                          {"fit-exposures", no_argument, NULL, 'e'},
                                          {"no-multistart", no_argument, NULL, 'M'},
                                          {"density", required_argument, NULL, 'd'},
                                          {"max-iterations", required_argument, NULL, 'i'},
                                          {"threads", required_argument, NULL, 't'},
                                          {"help", no_argument, NULL, 'h'},
                                          {"footprint", required_argument, NULL, 'f'},
                                          {"footprint-tolerance", required_argument, NULL, 'T'},
                                          {"budget", required_argument, NULL, 'B'},
                                          {"sampling", required_argument, NULL, 'S'},
                                          {0}};
  const char *out_dir = NULL, *model_text = "auto";
  const char *holds[MAX_ASSIGNMENTS], *frees[MAX_ASSIGNMENTS];
  int hold_count = 0, free_count = 0;
  cf_fit_options defaults;
  cf_fit_default_options(&defaults, CF_MODEL_LAMBERT);
  fit_settings set = {defaults.loss,          defaults.loss_scale, defaults.density,
                      defaults.fit_exposures, defaults.multistart, defaults.max_iterations,
                      defaults.threads,       defaults.footprint,  defaults.footprint_tolerance,
                      defaults.budget,        defaults.sampling};
  long max_iterations = 100, threads = 2;
  cf_error err = {0};
  cf_status s = CF_OK;
  optind = 1;
  opterr = 0;
  for (int c; s == CF_OK && (c = getopt_long(argc, argv, "o:", options, NULL)) != -1;) {
    switch (c) {
      case 'o':
        out_dir = optarg;
        break;
      case 'm':
        model_text = optarg;
        break;
      case 'H':
      case 'F':
        if ((c == 'H' ? hold_count : free_count) == MAX_ASSIGNMENTS) {
          cli_report("fit", "too many --hold or --free options");
          return CLI_EXIT_USAGE;
        }
        if (c == 'H')
          holds[hold_count++] = optarg;
        else
          frees[free_count++] = optarg;
        break;
      case 'l':
        if (strcmp(optarg, "huber") == 0)
          set.loss = CF_LOSS_HUBER;
        else if (strcmp(optarg, "cauchy") == 0)
          set.loss = CF_LOSS_CAUCHY;
        else if (strcmp(optarg, "none") == 0)
          set.loss = CF_LOSS_NONE;
        else
          s = cf_error_set(&err, CF_EINVAL, "--loss: '%s' is not huber, cauchy or none", optarg);
        break;
      case 'k':
        s = cli_parse_number(optarg, "--loss-scale", &set.loss_scale, &err);
        if (s == CF_OK && !(set.loss_scale > 0.0))
          s = cf_error_set(&err, CF_ERANGE, "--loss-scale must be greater than 0");
        break;
      case 'e':
        set.fit_exposures = 1;
        break;
      case 'M':
        set.multistart = 0;
        break;
      case 'd':
        s = cli_parse_number(optarg, "--density", &set.density, &err);
        if (s == CF_OK && !(set.density > 0.0))
          s = cf_error_set(&err, CF_ERANGE, "--density must be greater than 0");
        break;
      case 'f':
        if (strcmp(optarg, "auto") == 0)
          set.footprint = 0;
        else if (strcmp(optarg, "centre") == 0 || strcmp(optarg, "center") == 0)
          set.footprint = 1;
        else {
          long samples = 0;
          s = cli_parse_count(optarg, "--footprint", 1, CF_FIT_FOOTPRINT_MAX_SAMPLES, &samples,
                              &err);
          if (s != CF_OK)
            s = cf_error_set(&err, CF_EINVAL,
                             "--footprint: '%s' is not auto, centre or a number of samples per "
                             "side from 1 to %d",
                             optarg, CF_FIT_FOOTPRINT_MAX_SAMPLES);
          set.footprint = (int)samples;
        }
        break;
      case 'B': {
        long budget = 0;
        if (strcmp(optarg, "all") != 0 &&
            cli_parse_count(optarg, "--budget", 100, 2000000000L, &budget, &err) != CF_OK)
          s = cf_error_set(&err, CF_EINVAL,
                           "--budget: '%s' is neither a number of observations (100 to 2e9) "
                           "nor all",
                           optarg);
        set.budget = (size_t)budget; /* all: 0 */
        break;
      }
      case 'S': {
        int found = 0;
        for (int k = 0; k < CF_SAMPLING_COUNT; ++k)
          if (strcmp(optarg, cf_sampling_name((cf_sampling)k)) == 0)
            set.sampling = (cf_sampling)k, found = 1;
        if (!found)
          s = cf_error_set(&err, CF_EINVAL,
                           "--sampling: '%s' is not uniform, stratified or importance", optarg);
        break;
      }
      case 'T':
        s = cli_parse_number(optarg, "--footprint-tolerance", &set.footprint_tolerance, &err);
        if (s == CF_OK && !(set.footprint_tolerance > 0.0 && set.footprint_tolerance < 1.0))
          s = cf_error_set(&err, CF_ERANGE, "--footprint-tolerance must be in (0, 1)");
        break;
      case 'i':
        s = cli_parse_count(optarg, "--max-iterations", 1, 100000, &max_iterations, &err);
        break;
      case 't':
        s = cli_parse_count(optarg, "--threads", 1, 256, &threads, &err);
        break;
      case 'h':
        fit_usage(stdout);
        return CLI_EXIT_OK;
      default:
        return cli_bad_option("fit", argv);
    }
  }
  set.max_iterations = (int)max_iterations;
  set.threads = (int)threads;
  if (s == CF_OK && optind + 1 != argc)
    s = cf_error_set(&err, CF_EINVAL, "expected one capture file (see clayfit fit --help)");
  if (s == CF_OK && !out_dir) s = cf_error_set(&err, CF_EINVAL, "-o OUTDIR is required");
  int automatic = strcmp(model_text, "auto") == 0;
  cf_fit_options ladder[CF_MODEL_COUNT];
  cf_model_id model = CF_MODEL_CLAY;
  if (s == CF_OK && !automatic) s = cf_model_find(model_text, &model, &err);
  if (s == CF_OK && automatic)
    s = ladder_options(&set, holds, hold_count, frees, free_count, ladder, &err);
  else if (s == CF_OK)
    s = model_options(model, &set, holds, hold_count, frees, free_count, NULL, &ladder[model],
                      &err);
  if (s != CF_OK) {
    cli_report("fit", err.message);
    return CLI_EXIT_USAGE;
  }

  double start = cf_now_seconds();
  cf_capture_options load_options = {ctx->quiet ? NULL : cli_progress, "fit"};
  cf_capture *capture = NULL;
  s = cf_capture_load(argv[optind], &load_options, &capture, &err);
  if (s != CF_OK) {
    cli_report("fit", err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  double load_seconds = cf_now_seconds() - start;
  cf_capture_summary summary;
  cf_capture_summarize(capture, &summary);
  for (size_t i = 0; i < summary.warnings && !ctx->quiet; ++i)
    fprintf(stderr, "clayfit fit: warning: %s\n", cf_capture_warning(capture, i));
  for (int m = 0; m < CF_MODEL_COUNT && !ctx->quiet; ++m) {
    ladder[m].progress = cli_progress;
    ladder[m].progress_user = "fit";
  }
  cf_fit_result result;
  cf_fit_choice choice;
  if (automatic) {
    s = cf_fit_auto(capture, ladder, &choice, &result, &err);
  } else {
    s = cf_fit_run(capture, &ladder[model], &result, &err);
  }
  const cf_fit_options *o = &ladder[automatic && s == CF_OK ? choice.chosen : model];
  double fit_seconds = cf_now_seconds() - start - load_seconds;
  char path[4096];
  if (s == CF_OK) s = cf_make_dirs(out_dir, &err);
  if (s == CF_OK) s = cf_path_join(out_dir, "fit.json", path, sizeof path, &err);
  if (s == CF_OK) {
    cf_fit_report report = {
        capture,         argv[optind], &result,       automatic ? &choice : NULL,
        CLAYFIT_VERSION, o->loss,      o->loss_scale, o->density,
        load_seconds,    fit_seconds,  o->footprint,  o->footprint_tolerance};
    s = cf_fit_write_json(path, &report, &err);
  }
  if (s == CF_OK) {
    for (int i = 0; i < result.warning_count && !ctx->quiet; ++i)
      fprintf(stderr, "clayfit fit: warning: %s\n", result.warnings[i]);
    if (automatic) print_choice(&choice);
    print_summary(&result, path);
  }
  if (automatic) cf_fit_choice_free(&choice);
  cf_fit_result_free(&result);
  cf_capture_free(capture);
  if (s != CF_OK) {
    cli_report("fit", err.message);
    return s == CF_ERANGE || s == CF_EINVAL ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE;
  }
  return CLI_EXIT_OK;
}
