/* clayfit report: the residual report of a fit (include/clayfit/report.h). */
#include <getopt.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/capture.h"
#include "clayfit/fit_file.h"
#include "clayfit/report.h"
#include "cli.h"

static void report_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit report FIT.json -o DIR [--capture CAPTURE]\n\n"
          "Writes the residual report of a fit (clayfit fit's fit.json) into DIR: index.html,\n"
          "a page that works offline, with the parameters and their uncertainties, what the\n"
          "capture does not constrain, the model choice, plots (residual against half-angle\n"
          "and view angle, histogram, the fitted lobe, convergence, time) and for every\n"
          "image its photo, the re-rendering with the fitted parameters and a signed residual\n"
          "heat map; report.json (data_schema/report.schema.json); images/ and plots/.\n\n"
          "  --capture CAPTURE  the capture to re-render (default: the one fit.json names)\n");
}

int cmd_report(int argc, char **argv, cli_context *ctx) {
  static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                          {"capture", required_argument, NULL, 'c'},
                                          {"help", no_argument, NULL, 'h'},
                                          {0}};
  const char *out_dir = NULL, *capture_path = NULL;
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "o:", options, NULL)) != -1;) {
    if (c == 'o')
      out_dir = optarg;
    else if (c == 'c')
      capture_path = optarg;
    else if (c == 'h') {
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
  cf_status s = cf_fit_file_read(fit_path, &fit, &err);
  if (s != CF_OK) {
    cli_report("report", err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  cf_capture_options load_options = {ctx->quiet ? NULL : cli_progress, "report"};
  cf_capture *capture = NULL;
  if (!capture_path) s = cf_fit_file_check_capture(&fit, fit_path, &err);
  if (s == CF_OK)
    s = cf_capture_load(capture_path ? capture_path : fit.capture_path, &load_options, &capture,
                        &err);
  if (s != CF_OK) {
    cli_report("report", err.message);
    cf_fit_file_free(&fit);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  cf_report_options report_options = {fit_path, CLAYFIT_VERSION, ctx->quiet ? NULL : cli_progress,
                                      "report"};
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
