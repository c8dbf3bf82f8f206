/* What the batch layer's files share. Private to src/batch. */
#ifndef CLAYFIT_BATCH_INTERNAL_H
#define CLAYFIT_BATCH_INTERNAL_H

#include <stddef.h>
#include <sys/types.h>

#include "clayfit/batch.h"
#include "clayfit/export.h"

/* The preset file of each export format, in an entry's presets/ folder. */
const char *batch_preset_file(cf_export_format format);

/* Remove a folder and everything in it (symbolic links not followed);
 * nothing when it does not exist. 0 on success. */
int batch_remove_tree(const char *path);

/* LIBRARY/.tmp.<name>.<pid>: a task's folder, on the same file system and
 * at the same depth as LIBRARY/<name> (fit.json records the capture's
 * path relative to its own folder, which must stay right after the
 * rename). */
cf_status batch_tmp_path(const char *library, const char *name, pid_t pid, char *out,
                         size_t size, cf_error *err);

/* Make `tmp` LIBRARY/<name>: the old entry renamed to
 * LIBRARY/.old.<name>.<pid>, the new one into place, the old one deleted.
 * A kill between the renames leaves the old entry aside, which
 * cf_batch_clean moves back. */
cf_status batch_replace_entry(const char *library, const char *name, const char *tmp,
                              cf_error *err);

/* A new reference to object, or a new empty object when it is NULL (for
 * json_pack's "o"). */
struct json_t *batch_object_or_empty(const struct json_t *object);

/* The host's name ("" when unknown). */
void batch_host_name(char *out, size_t size);

#endif /* CLAYFIT_BATCH_INTERNAL_H */
