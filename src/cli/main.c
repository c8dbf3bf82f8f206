/* clayfit: measure what clay looks like. Dispatches to the subcommands. */
#include <getopt.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "args.h"
#include "cli.h"

typedef struct command {
  const char *name;
  int (*run)(int argc, char **argv, cli_context *ctx);
  const char *summary;
} command;

static const command commands[] = {
    {"eval", cmd_eval, "evaluate the BRDF (and its gradient) for one set of directions"},
    {"models", cmd_models, "list the model ladder and every parameter's unit and range"},
    {"synth", cmd_synth, "render a synthetic capture with known parameters"},
    {"lights", cmd_lights, "light directions (or a light probe) from photos of a chrome ball"},
    {"inspect", cmd_inspect, "load a capture, summarise it, draw the pixels it uses"},
    {"fit", cmd_fit, "fit a model to a capture: parameters, uncertainty, fit.json"},
    {"export", cmd_export, "a fit's material as a preset: json, MaterialX, glTF, Blender, Mitsuba"},
    {"report", cmd_report, "the residual report of a fit: HTML page, pictures, plots"},
    {"batch", cmd_batch, "fit many captures into a material library (docs/batch.md)"},
    {"library", cmd_library, "a material library's entries: 'library compare A B'"},
    {"bench", cmd_bench, "benchmarks: 'bench eval' (evaluator speed)"},
};
enum { COMMAND_COUNT = sizeof commands / sizeof commands[0] };

void cli_report(const char *command_name, const char *message) {
  fprintf(stderr, "clayfit %s: %s\n", command_name, message);
}

int cli_bad_option(const char *command_name, char **argv) {
  fprintf(stderr, "clayfit %s: unknown option or missing value in '%s' (see clayfit %s --help)\n",
          command_name, argv[optind - 1], command_name);
  return CLI_EXIT_USAGE;
}

cf_status cli_parse_image_memory(const char *text, unsigned long long *bytes, cf_error *err) {
  double gb = 0.0;
  cf_status s = cli_parse_number(text, "--max-image-memory", &gb, err);
  if (s == CF_OK && !(gb > 0.0 && gb <= 1e9))
    s = cf_error_set(err, CF_ERANGE, "--max-image-memory: %g GB is outside (0, 1e9]", gb);
  if (s == CF_OK) *bytes = (unsigned long long)(gb * 1e9) > 0 ? (unsigned long long)(gb * 1e9) : 1;
  return s;
}

void cli_progress(void *user, const char *stage, size_t done, size_t total) {
  /* on a terminal one line rewritten in place; in a log, a line at each
   * quarter */
  if (isatty(fileno(stderr))) {
    fprintf(stderr, "\rclayfit %s: %s %zu/%zu", (const char *)user, stage, done, total);
    if (done == total) fputc('\n', stderr);
  } else if (total > 0 && (done == total || done * 4 / total != (done - (done > 0)) * 4 / total)) {
    fprintf(stderr, "clayfit %s: %s %zu/%zu\n", (const char *)user, stage, done, total);
  }
  fflush(stderr);
}

static void usage(FILE *out) {
  fprintf(out,
          "usage: clayfit [--quiet] <command> [options]\n"
          "       clayfit <command> --help\n\n"
          "commands:\n");
  for (int k = 0; k < COMMAND_COUNT; ++k)
    fprintf(out, "  %-8s %s\n", commands[k].name, commands[k].summary);
  fprintf(out,
          "\noptions:\n"
          "  --quiet    no progress output on stderr\n"
          "  --version  print the version\n"
          "  --help     this text\n\n"
          "exit status: 0 success, 1 failure while running, 2 invalid "
          "command line or input\n");
}

int main(int argc, char **argv) {
  cli_context ctx = {0};
  int first = 1;
  for (; first < argc && argv[first][0] == '-'; ++first) {
    if (strcmp(argv[first], "--quiet") == 0 || strcmp(argv[first], "-q") == 0) {
      ctx.quiet = 1;
    } else if (strcmp(argv[first], "--version") == 0) {
      printf("clayfit %s\n", CLAYFIT_VERSION);
      return CLI_EXIT_OK;
    } else if (strcmp(argv[first], "--help") == 0 || strcmp(argv[first], "-h") == 0) {
      usage(stdout);
      return CLI_EXIT_OK;
    } else {
      fprintf(stderr, "clayfit: unknown option '%s'\n\n", argv[first]);
      usage(stderr);
      return CLI_EXIT_USAGE;
    }
  }
  if (first == argc) {
    usage(stderr);
    return CLI_EXIT_USAGE;
  }
  for (int k = 0; k < COMMAND_COUNT; ++k)
    if (strcmp(argv[first], commands[k].name) == 0)
      return commands[k].run(argc - first, argv + first, &ctx);
  fprintf(stderr, "clayfit: unknown command '%s'\n\n", argv[first]);
  usage(stderr);
  return CLI_EXIT_USAGE;
}
