/* clayfit bench fit: the fit's speed against its error. For each capture
 * (synthetic ones of growing size, rendered first, and any given), the fit
 * with every observation and with pixel budgets drawn by each sampling
 * strategy; for each run its wall time, peak memory, relative RMSE over all
 * observations and (synthetic) every parameter's error against the truth;
 * the Pareto front; the evaluator's floor; the scaling with the number of
 * observations. A benchmark prints numbers; it asserts nothing. Each run is
 * a child process, so that its peak memory is its own; so is every
 * rendering: the parent never starts an image library's thread pool
 * (OpenImageIO's, for a format clayfit does not read itself), which a
 * forked child would inherit without its threads (and hang). */
#define _GNU_SOURCE /* wait4 */
#include <getopt.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "args.h"
#include "clayfit/capture.h"
#include "clayfit/fit.h"
#include "clayfit/synth.h"
#include "cli.h"
#include "core/clock.h"
#include "core/file.h"
#include "core/json_reader.h"
#include "out_path.h"

enum { MAX_CAPTURES = 8, MAX_BUDGETS = 8, MAX_RUNS = 256 };

/* One run's figures, passed from the child through a pipe. */
typedef struct run_figures {
  int ok;
  size_t observations;
  double seconds, solve_seconds, relative_rmse, worst_error;
  int iterations;
  double params[CF_MAX_DIM];
  double floor_seconds; /* one value+gradient pass over all observations */
  char message[256];
} run_figures;

typedef struct run {
  size_t capture, observations, budget; /* budget 0: all */
  cf_sampling sampling;
  run_figures f;
  double peak_mb;
  int pareto;
} run;

typedef struct bench_capture {
  char path[4096], name[128];
  int has_truth;
  cf_model_id model;
  double truth[CF_MAX_DIM];
  size_t observations;
} bench_capture;

static void usage(FILE *out) {
  fprintf(out,
          "usage: clayfit bench fit [--sizes LIST] [--capture FILE ...] [--model M]\n"
          "                         [--budgets LIST] [--work DIR] [--json FILE]\n\n"
          "The fit's speed against its error. Renders synthetic captures of --model at\n"
          "its default parameters (default M4; float EXR,\n"
          "one sample per pixel, the default noise) of each size in --sizes (images x\n"
          "width x height, default 2x240x180,8x320x240,16x480x360: about 1e4, 1.5e5 and\n"
          "7e5 observations), adds the captures given with --capture, and fits each\n"
          "(with --model; pixel centres) with every\n"
          "observation and with each budget of --budgets (default 100000,30000,10000)\n"
          "drawn uniform, stratified and importance. Prints per run the wall time, peak\n"
          "memory, relative RMSE over all observations and the worst parameter error\n"
          "against the truth (of max(|truth|, range)); marks the Pareto front; gives the\n"
          "evaluator's floor (one value+gradient pass times the iterations) and the\n"
          "scaling of time and memory with the observations.\n");
}

/* The worst error of a fit against the truth over the model's slots, in
 * units of max(|truth|, range width). */
static double worst_error(cf_model_id model, const double *fitted, const double *truth) {
  double worst = 0.0;
  for (int k = 0; k < cf_model_info_get(model)->dim; ++k)
    worst = fmax(worst, cf_model_slot_error(model, k, fitted[k], truth[k]));
  return worst;
}

/* The time of one value+gradient pass of the evaluator over every
 * observation's geometry (the best of three). */
static double floor_pass(const cf_capture *capture, cf_model_id model, const double *params) {
  const cf_observations *o = cf_capture_observations(capture);
  size_t pairs = o->count * (size_t)o->lights;
  cf_geometry *g = malloc((pairs ? pairs : 1) * sizeof *g);
  double *f = malloc(3 * (pairs ? pairs : 1) * sizeof *f);
  double *grad = malloc(3 * (size_t)CF_MAX_DIM * (pairs ? pairs : 1) * sizeof *grad);
  double best = NAN;
  if (g && f && grad) {
    for (size_t i = 0; i < o->count; ++i)
      for (int j = 0; j < o->lights; ++j)
        g[i * (size_t)o->lights + (size_t)j] = cf_geometry_from_directions(
            o->normal + 3 * i, o->light_dir + 3 * (i * (size_t)o->lights + (size_t)j),
            o->view + 3 * i);
    for (int rep = 0; rep < 3; ++rep) {
      double t0 = cf_now_seconds();
      cf_eval_batch(model, params, pairs, g, f, grad);
      double t = cf_now_seconds() - t0;
      if (!(t >= best)) best = t;
    }
  }
  free(g);
  free(f);
  free(grad);
  return best;
}

/* In the child: load, fit, evaluate on every observation. */
static run_figures fit_once(const bench_capture *bc, size_t budget, cf_sampling sampling) {
  run_figures r;
  memset(&r, 0, sizeof r);
  cf_error err = {0};
  double t0 = cf_now_seconds();
  cf_capture *capture = NULL;
  cf_status s = cf_capture_load(bc->path, NULL, &capture, &err);
  cf_fit_options o;
  cf_fit_default_options(&o, bc->model);
  o.footprint = 1;
  o.budget = budget;
  o.sampling = sampling;
  cf_fit_result fit, all;
  if (s == CF_OK) r.observations = cf_capture_observations(capture)->count;
  if (s == CF_OK) s = cf_fit_run(capture, &o, &fit, &err);
  r.seconds = cf_now_seconds() - t0;
  if (s == CF_OK) {
    r.solve_seconds = fit.stage_seconds[CF_FIT_STAGE_SOLVE];
    r.iterations = fit.iterations;
    memcpy(r.params, fit.params, sizeof r.params);
    s = cf_fit_evaluate(capture, &fit, NULL, &o, &all, &err);
    if (s == CF_OK) {
      r.relative_rmse = all.relative_rmse;
      cf_fit_result_free(&all);
    }
    if (budget == 0) r.floor_seconds = floor_pass(capture, bc->model, fit.params);
    r.worst_error = bc->has_truth ? worst_error(bc->model, fit.params, bc->truth) : NAN;
    cf_fit_result_free(&fit);
  }
  r.ok = s == CF_OK;
  if (!r.ok) snprintf(r.message, sizeof r.message, "%.199s", err.message);
  cf_capture_free(capture);
  return r;
}

/* A run in a child process: its figures and its peak resident memory. */
static int run_child(const bench_capture *bc, run *out) {
  int fd[2];
  if (pipe(fd) != 0) return -1;
  fflush(NULL);
  pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    close(fd[0]);
    run_figures r = fit_once(bc, out->budget, out->sampling);
    ssize_t written = write(fd[1], &r, sizeof r);
    _exit(written == (ssize_t)sizeof r ? 0 : 1);
  }
  close(fd[1]);
  ssize_t got = read(fd[0], &out->f, sizeof out->f);
  close(fd[0]);
  int status = 0;
  struct rusage usage;
  if (wait4(pid, &status, 0, &usage) < 0 || got != (ssize_t)sizeof out->f) {
    out->f.ok = 0;
    snprintf(out->f.message, sizeof out->f.message, "the run's process failed");
  }
  out->peak_mb = (double)usage.ru_maxrss / 1024.0; /* kilobytes on Linux */
  return 0;
}

/* The truth of a synthetic capture (truth.json beside it), if any. */
static void read_truth(bench_capture *bc) {
  char dir[4096], path[4200];
  cf_error err = {0};
  bc->has_truth = 0;
  if (cf_path_dirname(bc->path, dir, sizeof dir, &err) != CF_OK) return;
  snprintf(path, sizeof path, "%s/truth.json", dir);
  json_error_t parse;
  json_t *doc = json_load_file(path, 0, &parse);
  if (!doc) return;
  const json_t *model = json_object_get(doc, "model"), *params = json_object_get(doc, "params");
  cf_model_id id;
  if (json_is_string(model) && cf_model_find(json_string_value(model), &id, &err) == CF_OK &&
      json_is_object(params) && id == bc->model) {
    const cf_model_info *m = cf_model_info_get(id);
    int complete = 1;
    for (int j = 0; j < m->param_count; ++j) {
      const cf_param_info *info = cf_param_info_get(m->params[j]);
      const json_t *v = json_object_get(params, info->name);
      for (int c = 0; c < info->components; ++c) {
        const json_t *x = info->components == 1 ? v : json_array_get(v, (size_t)c);
        if (!json_is_number(x))
          complete = 0;
        else
          bc->truth[m->offsets[j] + c] = json_number_value(x);
      }
    }
    bc->has_truth = complete;
  }
  json_decref(doc);
}

/* Mark the runs of each capture that no other run of it beats on both
 * time and relative RMSE. */
static void mark_pareto(run *runs, int n) {
  for (int a = 0; a < n; ++a) {
    runs[a].pareto = runs[a].f.ok;
    for (int b = 0; b < n && runs[a].pareto; ++b)
      if (b != a && runs[b].f.ok && runs[b].capture == runs[a].capture &&
          runs[b].f.seconds <= runs[a].f.seconds &&
          runs[b].f.relative_rmse <= runs[a].f.relative_rmse &&
          (runs[b].f.seconds < runs[a].f.seconds ||
           runs[b].f.relative_rmse < runs[a].f.relative_rmse))
        runs[a].pareto = 0;
  }
}

/* The exponent b of t ∝ n^b by least squares in log-log over the
 * all-observation runs of the synthetic captures. */
static double scaling_exponent(const run *runs, int n, int memory) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (int i = 0; i < n; ++i) {
    if (runs[i].budget != 0 || !runs[i].f.ok) continue;
    double x = log((double)runs[i].observations);
    double y = log(memory ? runs[i].peak_mb : runs[i].f.seconds);
    sx += x, sy += y, sxx += x * x, sxy += x * y, ++m;
  }
  if (m < 2 || sxx * m - sx * sx <= 0.0) return NAN;
  return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

static cf_status render(const char *work, cf_model_id model, int images, int width, int height,
                        bench_capture *bc, cf_error *err) {
  cf_synth_options o;
  cf_synth_default_options(&o);
  o.model = model;
  cf_model_default_params(model, o.params);
  const char *code = cf_model_info_get(model)->code;
  o.images = images;
  o.width = width;
  o.height = height;
  o.focal_px = 1.2 * width;
  o.format = CF_SYNTH_EXR;
  o.supersample = 1;
  char dir[3800];
  snprintf(dir, sizeof dir, "%s/synth_%s_%dx%dx%d", work, code, images, width, height);
  snprintf(bc->path, sizeof bc->path, "%s/capture.json", dir);
  snprintf(bc->name, sizeof bc->name, "synth %dx%dx%d (%s)", images, width, height, code);
  if (access(bc->path, R_OK) == 0) return CF_OK; /* rendered by an earlier run */
  fflush(NULL);
  pid_t pid = fork(); /* see the top of the file */
  if (pid < 0) return cf_error_set(err, CF_EIO, "cannot start a process to render %s", dir);
  if (pid == 0) _exit(cf_synth_write(dir, &o, NULL) == CF_OK ? 0 : 1);
  int status = 0;
  if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return cf_error_set(err, CF_EIO, "rendering %s failed", dir);
  return CF_OK;
}

/* ---- the command line ---- */

typedef struct bench_args {
  const char *sizes, *work, *json_path, *model_text;
  const char *given[MAX_CAPTURES];
  int given_count;
  double budgets[MAX_BUDGETS];
  int budget_count;
} bench_args;

/* --budgets: a list of at most MAX_BUDGETS numbers of observations. */
static cf_status parse_budgets(const char *text, bench_args *a, cf_error *err) {
  a->budget_count = 1;
  for (const char *p = text; *p; ++p) a->budget_count += *p == ',';
  cf_status s;
  if (a->budget_count > MAX_BUDGETS)
    s = cf_error_set(err, CF_EINVAL, "--budgets: at most %d", MAX_BUDGETS);
  else
    s = cli_parse_list(text, "--budgets", a->budget_count, a->budgets, err);
  for (int i = 0; s == CF_OK && i < a->budget_count; ++i)
    if (!(a->budgets[i] >= 100 && a->budgets[i] <= 1e9))
      s = cf_error_set(err, CF_ERANGE, "--budgets: %g is outside [100, 1e9]", a->budgets[i]);
  return s;
}

/* The command line into a. Returns -1 to go on, else the exit status
 * (--help, a bad option); other errors are left in *s and err. */
static int parse_bench_args(int argc, char **argv, bench_args *a, cf_status *s, cf_error *err) {
  static const struct option options[] = {
      {"sizes", required_argument, NULL, 's'}, {"capture", required_argument, NULL, 'c'},
      {"model", required_argument, NULL, 'm'}, {"budgets", required_argument, NULL, 'b'},
      {"work", required_argument, NULL, 'w'},  {"json", required_argument, NULL, 'j'},
      {"help", no_argument, NULL, 'h'},        {0}};
  *a = (bench_args){.sizes = "2x240x180,8x320x240,16x480x360",
                    .work = "out/bench",
                    .budgets = {100000, 30000, 10000},
                    .budget_count = 3};
  optind = 1;
  opterr = 0;
  for (int c; *s == CF_OK && (c = getopt_long(argc, argv, "", options, NULL)) != -1;) {
    if (c == 's')
      a->sizes = optarg;
    else if (c == 'c' && a->given_count < MAX_CAPTURES)
      a->given[a->given_count++] = optarg;
    else if (c == 'm')
      a->model_text = optarg;
    else if (c == 'w')
      a->work = optarg;
    else if (c == 'j')
      a->json_path = optarg;
    else if (c == 'b')
      *s = parse_budgets(optarg, a, err);
    else if (c == 'h') {
      usage(stdout);
      return CLI_EXIT_OK;
    } else
      return cli_bad_option("bench", argv);
  }
  if (*s == CF_OK && optind != argc)
    *s = cf_error_set(err, CF_EINVAL, "unexpected argument '%s'", argv[optind]);
  return -1;
}

/* The synthetic captures of --sizes (rendered unless an earlier run did),
 * then those given, each fitted with model. */
static cf_status prepare_captures(const bench_args *a, cf_model_id model, const cli_context *ctx,
                                  bench_capture *captures, int *count, cf_error *err) {
  cf_status s = cf_make_dirs(a->work, err);
  *count = 0;
  for (const char *p = a->sizes; s == CF_OK && *p && *count < MAX_CAPTURES;) {
    int images, width, height, used = 0;
    if (sscanf(p, "%dx%dx%d%n", &images, &width, &height, &used) != 3 || images < 1 ||
        images > 64 || width < 32 || height < 32 || width > 4096 || height > 4096)
      return cf_error_set(err, CF_EINVAL, "--sizes: '%s' is not IMAGESxWIDTHxHEIGHT[,...]", p);
    if (!ctx->quiet) fprintf(stderr, "clayfit bench: rendering %dx%dx%d\n", images, width, height);
    s = render(a->work, model, images, width, height, &captures[*count], err);
    captures[(*count)++].model = model;
    p += used;
    if (*p == ',') ++p;
  }
  for (int i = 0; s == CF_OK && i < a->given_count && *count < MAX_CAPTURES; ++i, ++*count) {
    bench_capture *bc = &captures[*count];
    snprintf(bc->path, sizeof bc->path, "%s", a->given[i]);
    snprintf(bc->name, sizeof bc->name, "%s", a->given[i]);
    bc->model = model;
  }
  return s;
}

/* ---- the runs ---- */

/* Every run: each capture with all its observations, then with each
 * budget below its count drawn by each sampling. Returns the number of
 * runs, or -1 when a fit on every observation failed (reported). */
static int run_all(bench_capture *captures, int count, const bench_args *a, const cli_context *ctx,
                   run *runs) {
  int n = 0;
  for (int i = 0; i < count; ++i) {
    for (int b = -1; b < a->budget_count; ++b) {
      size_t budget = b < 0 ? 0 : (size_t)a->budgets[b];
      if (budget && budget >= captures[i].observations) continue;
      for (int k = 0; k < (budget ? CF_SAMPLING_COUNT : 1) && n < MAX_RUNS; ++k) {
        run *r = &runs[n++];
        memset(r, 0, sizeof *r);
        r->capture = (size_t)i;
        r->observations = captures[i].observations;
        r->budget = budget;
        r->sampling = (cf_sampling)k;
        if (!ctx->quiet)
          fprintf(stderr, "clayfit bench: %s, %s\n", captures[i].name,
                  budget ? cf_sampling_name(r->sampling) : "all observations");
        if (run_child(&captures[i], r) != 0) r->f.ok = 0;
        if (b < 0 && !r->f.ok) {
          cli_report("bench", r->f.message);
          return -1;
        }
        if (b < 0) captures[i].observations = r->observations = r->f.observations;
      }
    }
  }
  return n;
}

/* ---- the figures ---- */

/* The table of runs on stdout; their rows for the JSON file. */
static json_t *print_runs(const run *runs, int n, const bench_capture *captures, int count) {
  printf("clayfit bench fit: %d captures, %d runs (each a process; wall time includes loading)\n",
         count, n);
  printf("%-24s %9s %8s %-10s %8s %9s %11s %12s %9s %6s %s\n", "capture", "observ.", "budget",
         "sampling", "time s", "peak MB", "rel. RMSE", "worst error", "solve s", "iters", "pareto");
  json_t *rows = json_array();
  for (int i = 0; i < n; ++i) {
    const run *r = &runs[i];
    const bench_capture *bc = &captures[r->capture];
    const char *sampling = r->budget ? cf_sampling_name(r->sampling) : "all";
    if (!r->f.ok) {
      printf("%-24s %9zu %8zu %-10s failed: %s\n", bc->name, r->observations, r->budget, sampling,
             r->f.message);
      continue;
    }
    printf("%-24s %9zu %8zu %-10s %8.2f %9.0f %10.4f%% %12.3g %9.2f %6d %s\n", bc->name,
           r->observations, r->budget, sampling, r->f.seconds, r->peak_mb,
           100.0 * r->f.relative_rmse, r->f.worst_error, r->f.solve_seconds, r->f.iterations,
           r->pareto ? "*" : "");
    json_array_append_new(
        rows, json_pack("{s:s, s:s, s:I, s:I, s:s, s:f, s:f, s:f, s:o, s:f, s:i, s:b}", "capture",
                        bc->name, "model", cf_model_info_get(bc->model)->code, "observations",
                        (json_int_t)r->observations, "budget", (json_int_t)r->budget, "sampling",
                        sampling, "seconds", r->f.seconds, "peak_mb", r->peak_mb, "relative_rmse",
                        r->f.relative_rmse, "worst_error", json_real_or_null(r->f.worst_error),
                        "solve_seconds", r->f.solve_seconds, "iterations", r->f.iterations,
                        "pareto", r->pareto));
  }
  return rows;
}

/* The evaluator's floor of each fit on every observation. */
static json_t *print_floors(const run *runs, int n, const bench_capture *captures) {
  printf(
      "\nthe evaluator's floor (one value+gradient pass over every observation x the "
      "iterations of the fit on all of them):\n");
  json_t *floors = json_array();
  for (int i = 0; i < n; ++i) {
    const run *r = &runs[i];
    if (r->budget || !r->f.ok || !(r->f.floor_seconds > 0.0)) continue;
    double floor = r->f.floor_seconds * r->f.iterations;
    printf(
        "  %-24s pass %.4f s x %d iterations = %.3f s; the solve stage %.2f s (overhead "
        "%.0f %%), the whole fit %.2f s\n",
        captures[r->capture].name, r->f.floor_seconds, r->f.iterations, floor, r->f.solve_seconds,
        100.0 * (r->f.solve_seconds / floor - 1.0), r->f.seconds);
    json_array_append_new(
        floors, json_pack("{s:s, s:f, s:i, s:f, s:f}", "capture", captures[r->capture].name,
                          "pass_seconds", r->f.floor_seconds, "iterations", r->f.iterations,
                          "floor_seconds", floor, "solve_seconds", r->f.solve_seconds));
  }
  return floors;
}

/* The memory per observation between the smallest and the largest
 * capture's fits on every observation. */
static double bytes_per_observation(const run *runs, int n) {
  int lo = -1, hi = -1;
  for (int i = 0; i < n; ++i) {
    if (runs[i].budget || !runs[i].f.ok) continue;
    if (lo < 0 || runs[i].observations < runs[lo].observations) lo = i;
    if (hi < 0 || runs[i].observations > runs[hi].observations) hi = i;
  }
  if (lo < 0 || hi < 0 || runs[hi].observations <= runs[lo].observations) return NAN;
  return (runs[hi].peak_mb - runs[lo].peak_mb) * 1048576.0 /
         (double)(runs[hi].observations - runs[lo].observations);
}

/* The scaling on stdout, as the JSON file's "scaling". */
static json_t *print_scaling(const run *runs, int n) {
  double time_exponent = scaling_exponent(runs, n, 0),
         memory_exponent = scaling_exponent(runs, n, 1);
  printf("\nscaling (all observations): time ~ n^%.2f, peak memory ~ n^%.2f", time_exponent,
         memory_exponent);
  double per_observation = bytes_per_observation(runs, n);
  printf("; memory per observation %.0f bytes (between the smallest and the largest capture)\n",
         per_observation);
  return json_pack("{s:o, s:o, s:o}", "time_exponent", json_real_or_null(time_exponent),
                   "memory_exponent", json_real_or_null(memory_exponent), "bytes_per_observation",
                   json_real_or_null(per_observation));
}

int cmd_bench_fit(int argc, char **argv, cli_context *ctx) {
  bench_args a;
  cf_error err = {0};
  cf_status s = CF_OK;
  int exit_status = parse_bench_args(argc, argv, &a, &s, &err);
  if (exit_status >= 0) return exit_status;
  cf_model_id forced = CF_MODEL_CLAY;
  if (s == CF_OK && a.model_text) s = cf_model_find(a.model_text, &forced, &err);
  if (s == CF_OK) s = cli_check_output("--work", a.work, CLI_OUT_FOLDER, &err);
  if (s == CF_OK) s = cf_make_dirs(a.work, &err); /* --json may be in it */
  if (s == CF_OK && a.json_path) s = cli_check_output("--json", a.json_path, CLI_OUT_FILE, &err);
  bench_capture captures[MAX_CAPTURES];
  int count = 0;
  if (s == CF_OK) s = prepare_captures(&a, forced, ctx, captures, &count, &err);
  if (s != CF_OK) {
    cli_report("bench", err.message);
    return CLI_EXIT_USAGE;
  }
  for (int i = 0; i < count; ++i) read_truth(&captures[i]);

  run runs[MAX_RUNS];
  int n = run_all(captures, count, &a, ctx, runs);
  if (n < 0) return CLI_EXIT_USAGE;
  mark_pareto(runs, n);
  json_t *rows = print_runs(runs, n, captures, count);
  json_t *floors = print_floors(runs, n, captures);
  json_t *scaling = print_scaling(runs, n);
  json_t *doc = json_pack("{s:s, s:o, s:o, s:o}", "benchmark", "clayfit bench fit", "runs", rows,
                          "floor", floors, "scaling", scaling);
  int failed = a.json_path && (!doc || json_dump_file(doc, a.json_path, JSON_INDENT(2)) != 0);
  json_decref(doc);
  if (failed) {
    cli_report("bench", "could not write the JSON file");
    return CLI_EXIT_FAILURE;
  }
  return CLI_EXIT_OK;
}
