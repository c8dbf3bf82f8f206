/* clayfit bench eval: evaluations per second of every model, value only and
 * value + gradient, on one thread, over a fixed random set of directions.
 * Then the specular lobe alone (GGX, and STD's exact and tabulated), and
 * the STD table's build. A benchmark prints numbers; it asserts nothing. */
#include <getopt.h>
#include <stdlib.h>
#include <string.h>

#include "args.h"
#include "clayfit/lobe.h"
#include "clayfit/model.h"
#include "cli.h"
#include "core/clock.h"
#include "core/rng.h"
#include "json_out.h"

enum { BENCH_SEED = 20261122 };

typedef enum bench_mode {
  MODE_VALUE,
  MODE_VALUE_GRAD,
  MODE_DIRECTIONS_GRAD,
  MODE_COUNT
} bench_mode;
static const char *const mode_names[MODE_COUNT] = {"value", "value+grad",
                                                   "value+grad from directions"};

typedef struct bench_data {
  size_t count;
  double *n, *l, *v;     /* 3 × count each */
  cf_geometry *geometry; /* count */
  double *f, *grad;      /* 3 × count, 3 × CF_MAX_DIM × count */
} bench_data;

/* Normals uniform on the sphere, l and v uniform on each normal's
 * hemisphere: every observation is lit, none is special. */
static int bench_data_init(bench_data *d, size_t count) {
  d->count = count;
  d->n = malloc(3 * count * sizeof *d->n);
  d->l = malloc(3 * count * sizeof *d->l);
  d->v = malloc(3 * count * sizeof *d->v);
  d->geometry = malloc(count * sizeof *d->geometry);
  d->f = malloc(3 * count * sizeof *d->f);
  d->grad = malloc(3 * (size_t)CF_MAX_DIM * count * sizeof *d->grad);
  if (!d->n || !d->l || !d->v || !d->geometry || !d->f || !d->grad) return -1;
  cf_rng rng = cf_rng_seed(BENCH_SEED);
  for (size_t i = 0; i < count; ++i) {
    cf_rng_unit_vector(&rng, d->n + 3 * i);
    cf_rng_hemisphere(&rng, d->n + 3 * i, d->l + 3 * i);
    cf_rng_hemisphere(&rng, d->n + 3 * i, d->v + 3 * i);
    d->geometry[i] = cf_geometry_from_directions(d->n + 3 * i, d->l + 3 * i, d->v + 3 * i);
  }
  return 0;
}

static void bench_data_free(bench_data *d) {
  free(d->n);
  free(d->l);
  free(d->v);
  free(d->geometry);
  free(d->f);
  free(d->grad);
}

static void run_pass(const bench_data *d, cf_model_id model, const double *params,
                     bench_mode mode) {
  if (mode == MODE_VALUE)
    cf_eval_batch(model, params, d->count, d->geometry, d->f, NULL);
  else if (mode == MODE_VALUE_GRAD)
    cf_eval_batch(model, params, d->count, d->geometry, d->f, d->grad);
  else
    cf_eval_batch_directions(model, params, d->count, d->n, d->l, d->v, d->f, d->grad);
}

static int compare_doubles(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

typedef struct timing {
  double median_ns, best_ns; /* per evaluation */
  int passes;
} timing;

/* Nanoseconds per evaluation over passes lasting min_time in all: the
 * median, and the best pass (on a shared machine, noise only adds time). */
static timing time_mode(const bench_data *d, cf_model_id model, const double *params,
                        bench_mode mode, double min_time) {
  enum { MAX_PASSES = 1000 };
  double per_eval[MAX_PASSES];
  run_pass(d, model, params, mode); /* warm-up */
  int passes = 0;
  double start = cf_now_seconds();
  while (passes < MAX_PASSES && (passes < 5 || cf_now_seconds() - start < min_time)) {
    double t0 = cf_now_seconds();
    run_pass(d, model, params, mode);
    per_eval[passes++] = (cf_now_seconds() - t0) * 1e9 / (double)d->count;
  }
  qsort(per_eval, (size_t)passes, sizeof per_eval[0], compare_doubles);
  return (timing){per_eval[passes / 2], per_eval[0], passes};
}

/* ---- the specular lobe alone, D V (clayfit/lobe.h, issue 18): GGX's,
 * STD's with its exact masking, and STD's with the masking tabulated once
 * per γ; and the table's build, the cost a model's prepare adds ---- */

static const char *const lobe_names[CF_LOBE_KIND_COUNT] = {"GGX", "STD exact", "STD tabulated"};

/* The median ns per call of `pass` over passes lasting min_time in all. */
static double median_ns(double (*pass)(void *), void *user, double calls, double min_time) {
  enum { MAX_PASSES = 1000 };
  double per_call[MAX_PASSES];
  volatile double sink = pass(user); /* warm-up */
  int passes = 0;
  double start = cf_now_seconds();
  while (passes < MAX_PASSES && (passes < 5 || cf_now_seconds() - start < min_time)) {
    double t0 = cf_now_seconds();
    sink += pass(user);
    per_call[passes++] = (cf_now_seconds() - t0) * 1e9 / calls;
  }
  (void)sink;
  qsort(per_call, (size_t)passes, sizeof per_call[0], compare_doubles);
  return per_call[passes / 2];
}

typedef struct lobe_job {
  const bench_data *d;
  cf_lobe *lobe;
  double gamma;
  cf_lobe_kind kind;
  int grad, exact_build;
} lobe_job;

static double lobe_job_pass(void *user) {
  const lobe_job *j = user;
  return cf_lobe_sum(j->lobe, j->kind, j->d->count, j->d->geometry, j->grad);
}

static double build_job_pass(void *user) { /* 100 builds of the table */
  lobe_job *j = user;
  double entry = 0.0;
  for (int i = 0; i < 100; ++i)
    entry = cf_lobe_tabulate(j->lobe, j->gamma + 1e-9 * i, j->exact_build);
  return entry;
}

static void time_lobes(const bench_data *d, double min_time) {
  double r = 0.3, gamma = 2.5;
  lobe_job job = {d, cf_lobe_new(r, gamma), gamma, CF_LOBE_GGX, 0, 0};
  if (!job.lobe) {
    fprintf(stderr, "clayfit bench eval: out of memory\n");
    return;
  }
  printf(
      "\nthe specular lobe D V alone (no Fresnel), roughness %g, STD tail gamma %g, "
      "median ns per evaluation\n%-16s %14s %14s\n",
      r, gamma, "lobe", "value", "value+grad");
  for (int kind = 0; kind < CF_LOBE_KIND_COUNT; ++kind) {
    double ns[2];
    for (int grad = 0; grad < 2; ++grad) {
      job.kind = (cf_lobe_kind)kind, job.grad = grad;
      /* the exact masking is 20-40x slower: a fraction of the time suffices */
      ns[grad] = median_ns(lobe_job_pass, &job, (double)d->count,
                           kind == CF_LOBE_STD_EXACT ? 0.2 * min_time : min_time);
    }
    printf("%-16s %14.1f %14.1f\n", lobe_names[kind], ns[0], ns[1]);
  }
  double us[2];
  for (int exact = 0; exact < 2; ++exact) {
    job.exact_build = exact;
    us[exact] = 1e-3 * median_ns(build_job_pass, &job, 100.0, exact ? 0.2 * min_time : min_time);
  }
  printf(
      "STD table build per prepare: %.2f us from the grid over gamma (%.1f us from the exact "
      "masking)\n",
      us[0], us[1]);
  fflush(stdout);
  cf_lobe_free(job.lobe);
}

static void bench_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit bench eval [--count N] [--min-time SECONDS] [--json]\n\n"
          "Times the evaluator on one thread: every model, value only and value +\n"
          "gradient (from precomputed geometry, the fitter's hot path, and from\n"
          "directions), over N fixed random observations (default 65536) with the\n"
          "models' default parameters. Reports the median and the best pass over\n"
          "passes lasting at least --min-time seconds (default 0.5) per case.\n"
          "Then (not with --json) the specular lobe D V alone: GGX's, STD's with its\n"
          "exact masking and with the masking tabulated once per tail, and the\n"
          "table's build per prepare.\n");
}

/* Every model and mode timed: the table on stdout (or a line of progress
 * on stderr with --json), the rows for the JSON. */
/* The tail the tailed twins are timed at (their default, 2, is GGX). */
#define BENCH_TAIL 2.5

static json_t *time_all(bench_data *d, long count, double min_time, int as_json,
                        const cli_context *ctx) {
  json_t *rows = json_array();
  if (!as_json)
    printf(
        "clayfit bench eval: %ld observations, one thread, default parameters (tail %g), "
        "passes of at least %g s in all\n%-22s %-28s %14s %12s %16s\n",
        count, BENCH_TAIL, min_time, "model", "mode", "median ns/eval", "best ns/eval", "median evals/s");
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    const cf_model_info *info = cf_model_info_get((cf_model_id)m);
    double params[CF_MAX_DIM];
    cf_model_default_params(info->id, params);
    /* a tailed twin at its default tail 2 runs GGX's code: time a tail */
    if (info->tail_slot >= 0) params[info->tail_slot] = BENCH_TAIL;
    for (int mode = 0; mode < MODE_COUNT; ++mode) {
      /* the table's rows show progress; with --json, a line on stderr */
      if (as_json && !ctx->quiet)
        fprintf(stderr, "\rbench eval: %s %-28s", info->code, mode_names[mode]);
      timing t = time_mode(d, info->id, params, (bench_mode)mode, min_time);
      json_array_append_new(
          rows,
          json_pack("{s:s, s:s, s:s, s:f, s:f, s:f, s:i}", "code", info->code, "model", info->name,
                    "mode", mode_names[mode], "median_ns_per_eval", t.median_ns, "best_ns_per_eval",
                    t.best_ns, "median_evals_per_second", 1e9 / t.median_ns, "passes", t.passes));
      if (!as_json) {
        char label[32];
        snprintf(label, sizeof label, "%s %s", info->code, info->name);
        printf("%-22s %-28s %14.1f %12.1f %16.3e\n", label, mode_names[mode], t.median_ns,
               t.best_ns, 1e9 / t.median_ns);
        fflush(stdout);
      }
    }
  }
  if (as_json && !ctx->quiet) fprintf(stderr, "\r%60s\r", "");
  return rows;
}

int cmd_bench(int argc, char **argv, cli_context *ctx) {
  if (argc > 1 && strcmp(argv[1], "fit") == 0) return cmd_bench_fit(argc - 1, argv + 1, ctx);
  static const struct option options[] = {{"count", required_argument, NULL, 'c'},
                                          {"min-time", required_argument, NULL, 't'},
                                          {"json", no_argument, NULL, 'j'},
                                          {"help", no_argument, NULL, 'h'},
                                          {0}};
  long count = 65536;
  double min_time = 0.5;
  int as_json = 0;
  cf_error err = {0};
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "", options, NULL)) != -1;) {
    cf_status s = CF_OK;
    if (c == 'c')
      s = cli_parse_count(optarg, "--count", 1, 100000000, &count, &err);
    else if (c == 't')
      s = cli_parse_number(optarg, "--min-time", &min_time, &err);
    else if (c == 'j')
      as_json = 1;
    else if (c == 'h') {
      bench_usage(stdout);
      return CLI_EXIT_OK;
    } else {
      return cli_bad_option("bench", argv);
    }
    if (s != CF_OK) {
      cli_report("bench", err.message);
      return CLI_EXIT_USAGE;
    }
  }
  if (optind >= argc || strcmp(argv[optind], "eval") != 0 || optind + 1 != argc) {
    cli_report("bench", "expected 'bench eval' or 'bench fit'");
    return CLI_EXIT_USAGE;
  }
  if (!(min_time >= 0.0 && min_time <= 600.0)) {
    cli_report("bench", "--min-time must be in [0, 600] seconds");
    return CLI_EXIT_USAGE;
  }

  bench_data d = {0};
  if (bench_data_init(&d, (size_t)count) != 0) {
    bench_data_free(&d);
    cli_report("bench", "out of memory for the observations");
    return CLI_EXIT_FAILURE;
  }
  json_t *rows = time_all(&d, count, min_time, as_json, ctx);
  if (!as_json) time_lobes(&d, min_time);
  bench_data_free(&d);
  if (as_json)
    return json_print(stdout, json_pack("{s:s, s:I, s:i, s:o}", "benchmark", "eval", "observations",
                                        (json_int_t)count, "threads", 1, "results", rows))
               ? CLI_EXIT_FAILURE
               : CLI_EXIT_OK;
  json_decref(rows);
  return CLI_EXIT_OK;
}
