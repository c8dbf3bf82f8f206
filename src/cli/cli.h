/* The clayfit command's subcommands. Each gets argv starting at its own
 * name and returns the process exit status:
 *   0 success, 1 failure while running, 2 invalid command line or input. */
#ifndef CLAYFIT_CLI_CLI_H
#define CLAYFIT_CLI_CLI_H

#include <stdio.h>

#include "clayfit/status.h"

enum { CLI_EXIT_OK = 0, CLI_EXIT_FAILURE = 1, CLI_EXIT_USAGE = 2 };

typedef struct cli_context {
  int quiet; /* --quiet: no progress on stderr */
} cli_context;

int cmd_eval(int argc, char **argv, cli_context *ctx);
int cmd_models(int argc, char **argv, cli_context *ctx);
int cmd_bench(int argc, char **argv, cli_context *ctx);
int cmd_bench_fit(int argc, char **argv, cli_context *ctx); /* clayfit bench fit */
int cmd_synth(int argc, char **argv, cli_context *ctx);
int cmd_inspect(int argc, char **argv, cli_context *ctx);
int cmd_fit(int argc, char **argv, cli_context *ctx);
int cmd_report(int argc, char **argv, cli_context *ctx);
int cmd_export(int argc, char **argv, cli_context *ctx);
int cmd_batch(int argc, char **argv, cli_context *ctx);
int cmd_library(int argc, char **argv, cli_context *ctx); /* clayfit library compare */
int cmd_lights(int argc, char **argv, cli_context *ctx);  /* clayfit lights (chrome ball) */

/* The path of the report's three.js bundle, built beside the clayfit binary
 * (src/report/viewer/viewer.cmake); "" when the binary's path is unknown
 * (the report then says why its interactive view is absent). For
 * cf_report_options.viewer_bundle (clayfit report, clayfit batch's tasks). */
void cli_viewer_bundle(char *path, size_t size);
/* clayfit lights --probe (cmd_lights_probe.c), called by cmd_lights when
 * --probe is among its arguments; argv[0] is "lights". */
int cli_lights_probe(int argc, char **argv);
/* The photos' and masks' headers of clayfit lights and lights --probe, read
 * before any pixel is decoded (cmd_lights.c): a small compressed file may
 * declare gigabytes. cap: the most decoded bytes (32-bit floats) of all the
 * files together, 0 for CF_CAPTURE_MAX_IMAGE_BYTES; bytes: the sum so far. */
typedef struct cli_headers {
  unsigned long long cap, bytes;
} cli_headers;
/* path's header into *h; its decoded bytes added to the sum, which must
 * stay within the cap (CF_ERANGE naming the file, the sum and the cap). */
struct cf_image_header;
cf_status cli_read_header(cli_headers *t, const char *path, struct cf_image_header *h,
                          cf_error *err);

/* A progress line on stderr ("clayfit synth: rendering images 5/16"),
 * rewritten in place; user is the command's name. Ends the line when
 * done == total. Use only when not --quiet. */
void cli_progress(void *user, const char *stage, size_t done, size_t total);

/* The model ladder and every parameter (name, unit, default, range,
 * meaning), from the single table in clayfit/model.h. */
void cli_print_model_table(FILE *out);

/* --max-image-memory GB (fit, inspect, report): the cap on a capture's
 * decoded image data (cf_capture_options.max_image_bytes), GB = 10^9
 * bytes, in (0, 1e9]. */
#define CLI_IMAGE_MEMORY_USAGE                                                     \
  "  --max-image-memory GB  the most decoded image data a capture may hold, all\n" \
  "                     images together (default 32; checked from the files'\n"    \
  "                     headers before decoding)\n"
cf_status cli_parse_image_memory(const char *text, unsigned long long *bytes, cf_error *err);

/* Report an error on stderr as "clayfit <command>: <message>". */
void cli_report(const char *command, const char *message);

/* Report the option getopt_long rejected (call with opterr = 0 after it
 * returned '?'); returns CLI_EXIT_USAGE. */
int cli_bad_option(const char *command, char **argv);

#endif /* CLAYFIT_CLI_CLI_H */
