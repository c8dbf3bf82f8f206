/* clayfit library compare LIBRARY A B [-o DIR]: two entries of a material
 * library side by side (docs/batch.md, "Comparing entries"). */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/library.h"
#include "cli.h"
#include "out_path.h"

static void library_usage(FILE *out) {
  fprintf(out,
          "usage: clayfit library compare LIBRARY A B [-o DIR]\n\n"
          "Prints two fitted entries of a library (clayfit batch) side by side: model,\n"
          "relative RMSE, each parameter's value ± sd in A and B, and their difference in\n"
          "standard deviations, (A - B) / sqrt(sdA² + sdB²) (a held parameter's sd counts\n"
          "0; parameters of one model only are marked). Then the difference of their\n"
          "renders under the thumbnails' standard light (linear radiance).\n\n"
          "  -o DIR   also write a.png, b.png, difference.png (a diverging scale, the\n"
          "           scale in compare.json and compare.html), a.exr, b.exr and\n"
          "           difference.exr (linear, A - B), compare.json and compare.html\n\n"
          "exit status: 0 compared, 1 DIR could not be written, 2 invalid command line\n"
          "(DIR not a writable folder), not a library, an unknown, failed or missing entry\n");
}

static const struct option library_options[] = {
    {"output", required_argument, NULL, 'o'}, {"help", no_argument, NULL, 'h'}, {0}};

/* "0.5 ± 0.01", "0.05 (no sd)", "(not in M0)" into out. */
static void value_text(char *out, size_t size, int present, double v, double sd,
                       const char *model) {
  if (!present) snprintf(out, size, "(not in %s)", model);
  else if (isfinite(sd)) snprintf(out, size, "%.6g ± %.3g", v, sd);
  else snprintf(out, size, "%.6g (no sd)", v);
}

static void print_comparison(const cf_library_comparison *c) {
  static const char *const channel[3] = {".r", ".g", ".b"};
  const char *ma = cf_model_info_get(c->a.model)->code, *mb = cf_model_info_get(c->b.model)->code;
  printf("%-20s %-26s %-26s %s\n", "", "A", "B", "(A-B)/sd");
  printf("%-20s %-26s %-26s\n", "entry", c->a.name, c->b.name);
  printf("%-20s %-26s %-26s\n", "model", ma, mb);
  char ra[32], rb[32];
  snprintf(ra, sizeof ra, "%.4g %%", 100.0 * c->a.relative_rmse);
  snprintf(rb, sizeof rb, "%.4g %%", 100.0 * c->b.relative_rmse);
  printf("%-20s %-26s %-26s\n", "relative RMSE", ra, rb);
  for (size_t i = 0; i < c->count; ++i) {
    const cf_library_param_diff *d = &c->diffs[i];
    char name[64], a[64], b[64], z[32];
    snprintf(name, sizeof name, "%s%s", d->name, d->components == 3 ? channel[d->component] : "");
    value_text(a, sizeof a, d->in_a, d->a, d->sd_a, ma);
    value_text(b, sizeof b, d->in_b, d->b, d->sd_b, mb);
    if (isfinite(d->z)) snprintf(z, sizeof z, "%.6g", d->z);
    else snprintf(z, sizeof z, "%s", d->in_a && d->in_b ? "n/a (no sd)" : "-");
    printf("%-20s %-26s %-26s %s\n", name, a, b, z);
  }
  printf("renders (standard light, linear): max |A-B| %.4g, RMS %.4g\n", c->max_abs_difference,
         c->rms_difference);
}

static int compare(int argc, char **argv) {
  const char *dir = NULL;
  optind = 1;
  opterr = 0;
  for (int c; (c = getopt_long(argc, argv, "o:", library_options, NULL)) != -1;) {
    if (c == 'o')
      dir = optarg;
    else if (c == 'h') {
      library_usage(stdout);
      return CLI_EXIT_OK;
    } else
      return cli_bad_option("library compare", argv);
  }
  if (optind + 3 != argc) {
    cli_report("library compare", "expected LIBRARY A B (see clayfit library --help)");
    return CLI_EXIT_USAGE;
  }
  cf_library_comparison comparison;
  cf_error err = {0};
  if (dir && cli_check_output("-o", dir, CLI_OUT_FOLDER, &err) != CF_OK) {
    cli_report("library compare", err.message);
    return CLI_EXIT_USAGE;
  }
  cf_status s = cf_library_compare(argv[optind], argv[optind + 1], argv[optind + 2], &comparison,
                                   &err);
  if (s != CF_OK) {
    cli_report("library compare", err.message);
    return s == CF_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  print_comparison(&comparison);
  if (dir) s = cf_library_comparison_write(&comparison, dir, &err);
  if (dir && s == CF_OK) printf("wrote %s/compare.html\n", dir);
  if (s != CF_OK) cli_report("library compare", err.message);
  cf_library_comparison_free(&comparison);
  return s == CF_OK ? CLI_EXIT_OK : CLI_EXIT_FAILURE;
}

int cmd_library(int argc, char **argv, cli_context *ctx) {
  (void)ctx;
  if (argc >= 2 && (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)) {
    library_usage(stdout);
    return CLI_EXIT_OK;
  }
  if (argc < 2 || strcmp(argv[1], "compare") != 0) {
    cli_report("library", "expected a subcommand: compare (see clayfit library --help)");
    return CLI_EXIT_USAGE;
  }
  return compare(argc - 1, argv + 1);
}
