/* Reading whole files and joining paths, with the checks every reader of
 * untrusted input needs. Pure C. */
#ifndef CLAYFIT_CORE_FILE_H
#define CLAYFIT_CORE_FILE_H

#include <stddef.h>
#include <stdio.h>

#include "clayfit/status.h"

/* Open the regular file at `path` for reading (*file, closed with fclose())
 * and give its *size in bytes. CF_ENOTFOUND if it does not exist (naming
 * any character in the path that prints as nothing), CF_EIO if it cannot
 * be opened or is not a regular file: a FIFO or a device is refused, never
 * waited on (it is opened without blocking, then checked). */
cf_status cf_open_regular_file(const char *path, FILE **file, long long *size, cf_error *err);

/* Read the whole file at `path` into a new buffer (*data, freed with free())
 * of *size bytes plus a terminating NUL (not counted), so text parsers may
 * treat it as a string. CF_ENOTFOUND if it does not exist, CF_EIO if it
 * cannot be read, CF_ERANGE if it is larger than max_size bytes (checked
 * before anything is allocated). Messages name the file. */
cf_status cf_read_file(const char *path, size_t max_size, char **data, size_t *size, cf_error *err);

/* cf_read_file for a text file: CF_EPARSE naming the line and byte offset
 * of a NUL byte (a text file holds none: UTF-16 or a binary file), and a
 * leading UTF-8 byte-order mark removed (an encoding marker, not text). */
cf_status cf_read_text_file(const char *path, size_t max_size, char **data, size_t *size,
                            cf_error *err);

/* For messages about a path that was not found: " (the name holds a
 * UTF-8 byte-order mark (U+FEFF, bytes EF BB BF) at byte 7)" when it holds
 * a character that prints as nothing (a byte-order mark, a control
 * character, a no-break or zero-width space, a space at either end of a
 * name); else "". Into out (size bytes). */
void cf_path_hidden_characters(const char *path, char *out, size_t size);

/* Write `size` bytes to `path` (created or replaced) so that a reader never
 * sees it half-written: into a temporary file beside it, every write, the
 * flush to the disk and the close checked, then renamed into place; on an
 * error the temporary is removed and `path` left as it was. A path that
 * exists and is not a regular file (/dev/stdout, a FIFO) is written
 * directly; a FIFO that no process reads is CF_EINVAL, not waited for.
 * Else CF_EIO with the path and the system's reason. */
cf_status cf_write_file(const char *path, const void *data, size_t size, cf_error *err);

/* `dir`/`name` into out (size bytes); `name` as it is when absolute or when
 * dir is NULL or empty. CF_ERANGE if it does not fit. */
cf_status cf_path_join(const char *dir, const char *name, char *out, size_t size, cf_error *err);

/* The folder part of a path ("a/b/c.json" → "a/b", "c.json" → "."). */
cf_status cf_path_dirname(const char *path, char *out, size_t size, cf_error *err);

/* `target` as a path relative to the folder `from` (each relative to the
 * current folder, or absolute), computed between their real paths
 * (symbolic links resolved), so that from/out names target wherever the
 * two are read from. The folder `from` and the folder of `target` must
 * exist (CF_ENOTFOUND otherwise); `target` itself need not. */
cf_status cf_path_relative(const char *from, const char *target, char *out, size_t size,
                           cf_error *err);

/* 1 if a file or folder exists at path. */
int cf_path_exists(const char *path);

/* Create a folder and its parents (like mkdir -p). */
cf_status cf_make_dirs(const char *path, cf_error *err);

#endif /* CLAYFIT_CORE_FILE_H */
