/* clayfit report: the residual report of a fit (include/clayfit/report.h). */
#include <getopt.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clayfit/capture.h"
#include "clayfit/fit_file.h"
#include "clayfit/report.h"
#include "cli.h"
#include "out_path.h"

static void report_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit report FIT.json -o DIR [--capture CAPTURE]\n\n"
          "Writes the residual report of a fit (clayfit fit's fit.json) into DIR: index.html,\n"
          "a page that works offline, with the parameters and their uncertainties, what the\n"
          "capture does not constrain, the model choice, plots (residual against half-angle\n"
          "and view angle, histogram, the fitted lobe, convergence, time) and for every\n"
          "image its photo, the re-rendering with the fitted parameters and a signed residual\n"
          "heat map; report.json (data_schema/report.schema.json); images/ and plots/; and\n"
          "viewer/: the fitted sphere under the capture's lighting in three.js with the exact\n"
          "glsl material, rotatable, beside clayfit's rendering (three.js from the bundle\n"
          "clayfit-report-viewer.js built beside clayfit; without it the page says so).\n"
          "DIR is replaced whole (built beside it, then swapped in): it must be new, empty or\n"
          "an earlier report; any other folder or file is refused.\n\n"
          "  --capture CAPTURE  the capture to re-render (default: the one fit.json names); a\n"
          "                     copy must match the fit's capture in its lights and "
          "colours\n" CLI_IMAGE_MEMORY_USAGE);
}

/* Do two paths name the same file? */
static int same_file(const char *a, const char *b) {
  struct stat x, y;
  return stat(a, &x) == 0 && stat(b, &y) == 0 && x.st_dev == y.st_dev && x.st_ino == y.st_ino;
}

/* The capture to re-render: the fit's, or --capture's (other) once it is
 * found to be the same capture as the fit's: its lights and colours, not
 * only its images' names (cf_report_compare_captures). check receives how
 * it was checked, for report.json. */
static cf_status load_capture(const cf_fit_file *fit, const char *fit_path, const char *other,
                              const cf_capture_options *load, cf_capture **capture,
                              const char **check, cf_error *err) {
  *check = "the fit's capture";
  if (!other) {
    cf_status s = cf_fit_file_check_capture(fit, fit_path, err);
    return s == CF_OK ? cf_capture_load(fit->capture_path, load, capture, err) : s;
  }
  cf_status s = cf_capture_load(other, load, capture, err);
  if (s != CF_OK || same_file(other, fit->capture_path)) return s;
  cf_capture *own = NULL;
  cf_error why = {0};
  s = fit->capture_found ? cf_capture_load(fit->capture_path, load, &own, &why)
                         : cf_fit_file_check_capture(fit, fit_path, &why);
  if (s != CF_OK) {
    fprintf(stderr,
            "clayfit report: warning: %s is compared with the fit's capture by its images' "
            "names and counts only, since the fit's capture cannot be read (%s)\n",
            other, why.message);
    *check = "images' names and counts only: the fit's capture could not be read";
    return CF_OK;
  }
  s = cf_report_compare_captures(*capture, other, own, fit->capture_path, err);
  cf_capture_free(own);
  *check = "lights, colours and observations compared with the fit's capture";
  if (s != CF_OK) {
    cf_capture_free(*capture);
    *capture = NULL;
  }
  return s;
}

void cli_viewer_bundle(char *path, size_t size) {
  ssize_t n = readlink("/proc/self/exe", path, size - 1);
  char *slash = NULL;
  for (ssize_t i = 0; i < n; ++i)
    if (path[i] == '/') slash = path + i;
  const char name[] = "/clayfit-report-viewer.js";
  if (!slash || (size_t)(slash - path) + sizeof name > size) {
    path[0] = '\0';
    return;
  }
  memcpy(slash, name, sizeof name);
}

int cmd_report(int argc, char **argv, cli_context *ctx) {
  static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                          {"capture", required_argument, NULL, 'c'},
                                          {"max-image-memory", required_argument, NULL, 'G'},
                                          {"help", no_argument, NULL, 'h'},
                                          {0}};
  const char *out_dir = NULL, *capture_path = NULL;
  unsigned long long max_image_bytes = 0;
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "o:", options, NULL)) != -1;) {
    if (c == 'o')
      out_dir = optarg;
    else if (c == 'c')
      capture_path = optarg;
    else if (c == 'G') {
      cf_error bad = {0};
      if (cli_parse_image_memory(optarg, &max_image_bytes, &bad) != CF_OK) {
        cli_report("report", bad.message);
        return CLI_EXIT_USAGE;
      }
    } else if (c == 'h') {
      report_usage(stdout);
      return CLI_EXIT_OK;
    } else
      return cli_bad_option("report", argv);
  }
  if (optind + 1 != argc || !out_dir) {
    cli_report("report", "expected one fit.json and -o DIR (see clayfit report --help)");
    return CLI_EXIT_USAGE;
  }
  const char *fit_path = argv[optind];
  cf_error err = {0};
  cf_fit_file fit;
  cf_status s = cli_check_output("-o", out_dir, CLI_OUT_FOLDER_REPLACED, &err);
  if (s == CF_OK) s = cf_report_check_dir(out_dir, &err);
  if (s == CF_OK) s = cf_fit_file_read(fit_path, &fit, &err);
  if (s != CF_OK) {
    cli_report("report", err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  const char *version_warning = cf_fit_file_version_warning(&fit);
  if (version_warning && !ctx->quiet)
    fprintf(stderr, "clayfit report: warning: %s: %s\n", fit_path, version_warning);
  cf_capture_options load_options = {ctx->quiet ? NULL : cli_progress, "report", max_image_bytes};
  cf_capture *capture = NULL;
  const char *check = "";
  s = load_capture(&fit, fit_path, capture_path, &load_options, &capture, &check, &err);
  if (s != CF_OK) {
    cli_report("report", err.message);
    cf_fit_file_free(&fit);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  cf_report_options report_options = {fit_path,
                                      CLAYFIT_VERSION,
                                      ctx->quiet ? NULL : cli_progress,
                                      "report",
                                      capture_path ? capture_path : fit.capture_path,
                                      check,
                                      NULL};
  char bundle[4096];
  cli_viewer_bundle(bundle, sizeof bundle);
  report_options.viewer_bundle = bundle;
  s = cf_report_write(capture, &fit, out_dir, &report_options, &err);
  cf_capture_free(capture);
  cf_fit_file_free(&fit);
  if (s != CF_OK) {
    cli_report("report", err.message);
    return s == CF_EINVAL ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE;
  }
  if (!ctx->quiet) fprintf(stderr, "clayfit report: written %s/index.html\n", out_dir);
  printf("%s/index.html\n%s/report.json\n", out_dir, out_dir);
  return CLI_EXIT_OK;
}
