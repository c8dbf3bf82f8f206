/* The batch manifest (data_schema/manifest.schema.json), read as the
 * capture files are: every record checked, each error naming the file and
 * the JSON path. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "clayfit/batch.h"
#include "core/file.h"
#include "core/json_reader.h"

int cf_batch_name_valid(const char *name) {
  size_t n = strlen(name);
  if (n == 0 || n > CF_BATCH_NAME_MAX || name[0] == '.') return 0;
  for (size_t i = 0; i < n; ++i) {
    char c = name[i];
    int ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
             c == '.' || c == '_' || c == '-';
    if (!ok) return 0;
  }
  return 1;
}

/* The names the library folder uses for itself, which an entry's folder
 * would replace: library.json and index.html, and their temporaries while
 * they are written (cf_write_file's "<name>.tmp-<pid>"). Its other own
 * names (.lock, .lock.new.*, .tmp.*, .old.*, .slurm) start with '.', which
 * no entry name does. Compared ignoring case, as names are. */
static const char *reserved_name(const char *name) {
  static const char *const own[] = {"library.json", "index.html"};
  for (size_t i = 0; i < sizeof own / sizeof *own; ++i) {
    size_t n = strlen(own[i]);
    if (strncasecmp(name, own[i], n) == 0 &&
        (name[n] == '\0' || strncasecmp(name + n, ".tmp-", 5) == 0))
      return own[i];
  }
  return NULL;
}

/* "hold": {"param": number | [r, g, b]}. Names are checked against the
 * models later (cf_batch_fit_options), where the model is known. */
static cf_status read_holds(const json_t *hold, const json_at *at, cf_batch_entry *e,
                            cf_error *err) {
  const char *key;
  json_t *value;
  json_object_foreach((json_t *)hold, key, value) {
    json_at here = json_member_at(at, key);
    if (e->hold_count == CF_BATCH_MAX_HOLDS)
      return json_fail(at, err, CF_ERANGE, "more than %d holds", CF_BATCH_MAX_HOLDS);
    cf_fit_hold *h = &e->hold[e->hold_count++];
    h->name = key;
    if (json_is_array(value)) {
      if (json_array_size(value) != 3)
        return json_fail(&here, err, CF_EPARSE, "expected one number or 3 (r, g, b), got %zu",
                         json_array_size(value));
      h->count = 3;
      for (size_t c = 0; c < 3; ++c) {
        json_at element = json_element_at(&here, c);
        cf_status s = json_as_number(json_array_get(value, c), &element, -1e300, 1e300,
                                     &h->value[c], err);
        if (s != CF_OK) return s;
      }
      continue;
    }
    h->count = 1;
    cf_status s = json_as_number(value, &here, -1e300, 1e300, &h->value[0], err);
    if (s != CF_OK) return s;
  }
  return CF_OK;
}

/* "budget": N (100 to 2e9, as clayfit fit --budget) or "all". */
static cf_status read_budget(const json_t *options, const json_at *at, cf_batch_entry *e,
                             cf_error *err) {
  const json_t *value = json_object_get(options, "budget");
  if (!value) return CF_OK;
  json_at here = json_member_at(at, "budget");
  e->budget_given = 1;
  if (json_is_string(value)) {
    if (strcmp(json_string_value(value), "all") != 0)
      return json_fail(&here, err, CF_EPARSE, "expected a number of observations or \"all\"");
    e->budget = 0;
    return CF_OK;
  }
  long long n = 0;
  cf_status s = json_get_integer(options, at, "budget", 1, 100, 2000000000LL, &n, NULL, err);
  e->budget = (size_t)n;
  return s;
}

static cf_status read_options(const json_t *options, const json_at *at, cf_batch_entry *e,
                              cf_error *err) {
  static const char *const known[] = {"model", "hold", "budget", "fit_exposures", NULL};
  cf_status s = json_check_keys(options, at, known, err);
  int found = 0;
  if (s == CF_OK) s = json_get_string(options, at, "model", 0, &e->model, &found, err);
  if (s == CF_OK && strcmp(e->model, "auto") != 0) {
    cf_model_id id;
    cf_error why = {0};
    if (cf_model_find(e->model, &id, &why) != CF_OK) {
      json_at here = json_member_at(at, "model");
      return json_fail(&here, err, CF_EINVAL, "%s", why.message);
    }
  }
  const json_t *hold = NULL;
  if (s == CF_OK) s = json_get_object(options, at, "hold", 0, &hold, &found, err);
  if (s == CF_OK && hold) {
    json_at here = json_member_at(at, "hold");
    s = read_holds(hold, &here, e, err);
  }
  if (s == CF_OK) s = read_budget(options, at, e, err);
  if (s == CF_OK) s = json_get_bool(options, at, "fit_exposures", 0, &e->fit_exposures, &found, err);
  return s;
}

/* The options as the fit will take them (holds named by some model, in
 * range), so that a mistake stops the batch before any work. */
static cf_status check_options(const cf_batch_entry *e, const json_at *at, cf_error *err) {
  cf_fit_options ladder[CF_MODEL_COUNT];
  int automatic = 0;
  cf_model_id model;
  cf_error why = {0};
  if (cf_batch_fit_options(e, 1, &automatic, &model, ladder, &why) == CF_OK) return CF_OK;
  return json_fail(at, err, CF_EINVAL, "%s", why.message);
}

static cf_status read_tags(const json_t *tags, const json_at *at, cf_error *err) {
  if (json_object_size(tags) > CF_BATCH_MAX_TAGS)
    return json_fail(at, err, CF_ERANGE, "more than %d tags", CF_BATCH_MAX_TAGS);
  const char *key;
  json_t *value;
  json_object_foreach((json_t *)tags, key, value) {
    json_at here = json_member_at(at, key);
    const char *text = NULL;
    cf_status s = json_as_string(value, &here, &text, err);
    if (s != CF_OK) return s;
    if (strlen(key) == 0 || strlen(key) > CF_BATCH_TAG_MAX || strlen(text) > CF_BATCH_TAG_MAX)
      return json_fail(&here, err, CF_ERANGE, "a tag's key and value are 1 to %d bytes",
                       CF_BATCH_TAG_MAX);
  }
  return CF_OK;
}

/* The capture's path joined to the manifest's folder; the file must exist
 * and be a regular file (a symbolic link to one is). */
static cf_status read_capture(const json_t *record, const json_at *at, const char *dir,
                              cf_batch_entry *e, cf_error *err) {
  const char *given = NULL;
  cf_status s = json_get_string(record, at, "capture", 1, &given, NULL, err);
  if (s != CF_OK) return s;
  json_at here = json_member_at(at, "capture");
  char path[4096];
  if (given[0] == '\0' || cf_path_join(dir, given, path, sizeof path, err) != CF_OK)
    return json_fail(&here, err, CF_EINVAL, "not a usable path");
  struct stat st;
  if (stat(path, &st) != 0)
    return json_fail(&here, err, CF_ENOTFOUND, "%s: %s", path,
                     errno == ENOENT ? "no such file" : strerror(errno));
  if (!S_ISREG(st.st_mode)) /* a FIFO would block the batch, /dev/zero never end */
    return json_fail(&here, err, CF_EINVAL,
                     "%s: not a regular file (a folder, device or FIFO), as clayfit fit refuses",
                     path);
  if (!(e->capture = strdup(path))) return cf_error_set(err, CF_ENOMEM, "out of memory");
  return CF_OK;
}

static cf_status read_entry(const json_t *record, const json_at *at, const char *dir,
                            cf_batch_entry *e, cf_error *err) {
  static const char *const known[] = {"name", "capture", "options", "tags", NULL};
  if (!json_is_object(record))
    return json_fail(at, err, CF_EPARSE, "expected an object, got %s", json_type_name(record));
  cf_status s = json_check_keys(record, at, known, err);
  const char *name = NULL;
  if (s == CF_OK) s = json_get_string(record, at, "name", 1, &name, NULL, err);
  if (s == CF_OK && !cf_batch_name_valid(name)) {
    json_at here = json_member_at(at, "name");
    return json_fail(&here, err, CF_EINVAL,
                     "'%s' is not a name: 1 to %d of A-Z a-z 0-9 . _ -, not starting with '.'",
                     name, CF_BATCH_NAME_MAX);
  }
  const char *own = s == CF_OK ? reserved_name(name) : NULL;
  if (own) {
    json_at here = json_member_at(at, "name");
    return json_fail(&here, err, CF_EINVAL,
                     "'%s' is a name the library folder uses for its own %s (library.json, "
                     "index.html and their temporaries are reserved, ignoring case)",
                     name, own);
  }
  if (s == CF_OK) strcpy(e->name, name);
  if (s == CF_OK) s = read_capture(record, at, dir, e, err);
  const json_t *options = NULL, *tags = NULL;
  if (s == CF_OK) s = json_get_object(record, at, "options", 0, &options, NULL, err);
  if (s == CF_OK) s = json_get_object(record, at, "tags", 0, &tags, NULL, err);
  e->options = options;
  e->tags = tags;
  e->model = "auto";
  json_at options_at = json_member_at(at, "options");
  json_at tags_at = json_member_at(at, "tags");
  if (s == CF_OK && options) s = read_options(options, &options_at, e, err);
  if (s == CF_OK && options) s = check_options(e, &options_at, err);
  if (s == CF_OK && tags) s = read_tags(tags, &tags_at, err);
  return s;
}

/* No two entries with one name (nor names equal but for case: they would
 * be one folder on a case-insensitive file system). */
static cf_status check_unique(const cf_batch_manifest *m, size_t i, const json_at *at,
                              cf_error *err) {
  for (size_t j = 0; j < i; ++j)
    if (strcasecmp(m->entries[j].name, m->entries[i].name) == 0) {
      json_at here = json_member_at(at, "name");
      return json_fail(&here, err, CF_EINVAL, "'%s' is also the name of captures[%zu]",
                       m->entries[i].name, j);
    }
  return CF_OK;
}

static cf_status read_captures(const json_t *list, const json_at *at, cf_batch_manifest *m,
                               cf_error *err) {
  size_t n = json_array_size(list);
  if (n == 0) return json_fail(at, err, CF_EINVAL, "no captures");
  if (n > CF_BATCH_MAX_ENTRIES)
    return json_fail(at, err, CF_ERANGE, "%zu captures, more than %d", n, CF_BATCH_MAX_ENTRIES);
  if (!(m->entries = calloc(n, sizeof *m->entries)))
    return cf_error_set(err, CF_ENOMEM, "out of memory");
  char dir[4096];
  cf_status s = cf_path_dirname(m->path, dir, sizeof dir, err);
  for (size_t i = 0; s == CF_OK && i < n; ++i) {
    json_at here = json_element_at(at, i);
    m->count = i + 1;
    s = read_entry(json_array_get(list, i), &here, dir, &m->entries[i], err);
    if (s == CF_OK) s = check_unique(m, i, &here, err);
  }
  return s;
}

cf_status cf_batch_manifest_read(const char *path, cf_batch_manifest *m, cf_error *err) {
  memset(m, 0, sizeof *m);
  if (!(m->path = strdup(path))) return cf_error_set(err, CF_ENOMEM, "out of memory");
  json_t *root = NULL;
  cf_status s = json_load_object(path, CF_BATCH_MANIFEST_MAX_SIZE, &root, err);
  m->document = root;
  json_at at = {path, NULL, NULL, 0};
  static const char *const known[] = {"clayfit_manifest", "captures", NULL};
  if (s == CF_OK) s = json_check_keys(root, &at, known, err);
  long long version = 0;
  if (s == CF_OK)
    s = json_get_integer(root, &at, "clayfit_manifest", 1, 1, 1, &version, NULL, err);
  const json_t *list = NULL;
  if (s == CF_OK) s = json_get_array(root, &at, "captures", 1, &list, NULL, err);
  json_at list_at = json_member_at(&at, "captures");
  if (s == CF_OK) s = read_captures(list, &list_at, m, err);
  if (s != CF_OK) cf_batch_manifest_free(m);
  return s;
}

void cf_batch_manifest_free(cf_batch_manifest *m) {
  for (size_t i = 0; i < m->count; ++i) free(m->entries[i].capture);
  free(m->entries);
  free(m->path);
  if (m->document) json_decref(m->document);
  memset(m, 0, sizeof *m);
}
