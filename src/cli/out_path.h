/* The output location of a command (-o), checked before any loading or
 * fitting: a folder or file that cannot be written is otherwise found only
 * at the end of the work. */
#ifndef CLAYFIT_CLI_OUT_PATH_H
#define CLAYFIT_CLI_OUT_PATH_H

#include "clayfit/status.h"

typedef enum cli_out_kind {
  /* a folder written into: it exists and is writable, or it is created
   * with its missing parents inside the nearest folder that is */
  CLI_OUT_FOLDER,
  /* a folder replaced as a whole (clayfit report): as a folder, and when
   * it exists, the folder it is in must be writable too */
  CLI_OUT_FOLDER_REPLACED,
  /* a file created or replaced: not a folder, and its folder exists and is
   * writable (an existing device or FIFO needs only to be writable) */
  CLI_OUT_FILE
} cli_out_kind;

/* CF_EINVAL, with a message naming the option, the path and the reason
 * (the system's, when there is one), if `path` cannot be used as `kind`.
 * Writability is tried by creating and removing a file in the folder, so
 * that it holds for root and on read-only mounts too. */
cf_status cli_check_output(const char *option, const char *path, cli_out_kind kind, cf_error *err);

/* The folder `dir` checked as CLI_OUT_FOLDER and, when it exists, the file
 * `name` to be written in it as CLI_OUT_FILE (clayfit fit's fit.json). */
cf_status cli_check_output_in(const char *option, const char *dir, const char *name, cf_error *err);

#endif /* CLAYFIT_CLI_OUT_PATH_H */
