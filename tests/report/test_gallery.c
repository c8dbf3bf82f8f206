/* The gallery page (include/clayfit/gallery.h), written for the checks of
 * check_gallery.py: four entries, one failed, with hostile names, tags and
 * folder names (`</script>`, quotes, `-->`, `#`, `?`, `%`, a `javascript:`
 * folder), three thumbnails rendered by cf_report_write_thumbnail, and
 * DIR/expected.tsv (name, thumbnail path, relative RMSE per line) for the
 * checker. Here: the refusals (a NULL name, an absolute path, a value not
 * finite, a missing folder: CF_EIO and no page) and that a failed write
 * leaves the earlier page as it was.
 * usage: test_gallery DIR */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clayfit/gallery.h"
#include "clayfit/thumbnail.h"
#include "core/file.h"
#include "support/check.h"

#pragma GCC diagnostic ignored "-Wformat-truncation" /* paths in a test's folder */

CHECK_MAIN_STATE;

enum { ENTRIES = 4 };

static const char *const names[ENTRIES] = {
    "Stoneware </script><script>alert(1)</script> \"B-Mix\"",
    "porcelain --> <!-- 'single' \"double\" & more",
    "javascript:alert(2)",
    "broken <b>bold</b>",
};
/* the entries' folders (file names: no '/') */
static const char *const folders[ENTRIES] = {
    "it's \"q\" #1 ?x %41 --> &amp;",
    "porcelain",
    "javascript:alert(2)",
    "broken",
};
static const double rmse[ENTRIES] = {0.021, 0.005, 0.04, NAN};

static cf_fit_result fit_of(cf_model_id model, double albedo) {
  cf_fit_result r;
  memset(&r, 0, sizeof r);
  r.model = model;
  cf_model_default_params(model, r.params);
  for (int c = 0; c < 3; ++c) r.params[c] = albedo * (1.0 - 0.2 * c); /* albedo first */
  const cf_model_info *m = cf_model_info_get(model);
  for (int k = 0; k < m->dim; ++k) r.sd[k] = k == 1 ? 0.0 : 0.001 * (k + 1);
  return r;
}

static int write_file(const char *path, const char *text) {
  cf_error err = {0};
  return cf_write_file(path, text, strlen(text), &err) == CF_OK ? 0 : -1;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: test_gallery DIR\n");
    return 2;
  }
  const char *dir = argv[1];
  cf_error err = {0};
  static const cf_model_id models[ENTRIES] = {CF_MODEL_DIELECTRIC, CF_MODEL_CLAY, CF_MODEL_LAMBERT,
                                              CF_MODEL_LAMBERT};
  static const double albedo[ENTRIES] = {0.6, 0.85, 0.3, 0.5};
  cf_fit_result fits[ENTRIES];
  cf_gallery_param params[ENTRIES][CF_MAX_DIM];
  size_t param_count[ENTRIES];
  char thumbs[ENTRIES][512], reports[ENTRIES][512], path[2048];
  const cf_gallery_tag tags[ENTRIES][3] = {
      {{"clay body", "stoneware \"B-Mix\""}, {"state", "dry"}, {"</script><script>x", "'y'"}},
      {{"clay body", "porcelain -->"}, {"state", "wet </script>"}},
      {{"clay body", "earthenware"}},
      {{"state", "dry"}},
  };
  static const size_t tag_count[ENTRIES] = {3, 2, 1, 1};
  cf_gallery_entry entries[ENTRIES];
  FILE *expected = NULL;
  snprintf(path, sizeof path, "%s/expected.tsv", dir);
  if (cf_make_dirs(dir, &err) != CF_OK || !(expected = fopen(path, "w"))) {
    fprintf(stderr, "%s: cannot prepare: %s\n", dir, err.message);
    return 1;
  }
  for (int i = 0; i < ENTRIES; ++i) {
    int failed = i == 3;
    fits[i] = fit_of(models[i], albedo[i]);
    cf_gallery_params_from_result(&fits[i], params[i], &param_count[i]);
    snprintf(path, sizeof path, "%s/%s", dir, folders[i]);
    CHECK(cf_make_dirs(path, &err) == CF_OK, "%s", err.message);
    snprintf(thumbs[i], sizeof thumbs[i], "%s/thumbnail.png", folders[i]);
    snprintf(reports[i], sizeof reports[i], "%s/%s", folders[i],
             failed ? "failed.json" : "report.html");
    snprintf(path, sizeof path, "%s/%s", dir, reports[i]);
    CHECK(write_file(path, failed ? "{\"reason\": \"test\"}\n" : "<p>report</p>\n") == 0, "%s",
          path);
    if (!failed) {
      snprintf(path, sizeof path, "%s/%s", dir, thumbs[i]);
      cf_status s = cf_report_write_thumbnail(&fits[i], NULL, path, &err);
      CHECK(s == CF_OK, "thumbnail %d: %s", i, err.message);
    }
    entries[i] = (cf_gallery_entry){
        .name = names[i],
        .tags = tags[i],
        .tag_count = tag_count[i],
        .state = failed ? CF_GALLERY_FAILED : CF_GALLERY_FITTED,
        .model = failed ? NULL : cf_model_info_get(models[i])->code,
        .params = failed ? NULL : params[i],
        .param_count = failed ? 0 : param_count[i],
        .relative_rmse = rmse[i],
        .thumbnail = failed ? NULL : thumbs[i],
        .report = reports[i],
        .reason = failed ? "capture.json:3: images[0].path: </script><script>alert(3)</script> "
                           "\"not\" found -->"
                         : NULL,
    };
    fprintf(expected, "%s\t%s\t%.17g\n", names[i], failed ? "" : thumbs[i], rmse[i]);
  }
  CHECK(fclose(expected) == 0, "expected.tsv");
  CHECK(param_count[1] == 7 && strcmp(params[1][0].name, "albedo") == 0 &&
            params[1][0].components == 3 && isnan(params[1][0].sd[1]) &&
            params[1][2].sd[0] == 0.001 * (CF_CLAY_FILM_ROUGHNESS + 1),
        "params from the M4 result: %zu, %s", param_count[1], params[1][0].name);

  char page[1100];
  snprintf(page, sizeof page, "%s/index.html", dir);
  cf_status s =
      cf_report_write_gallery(entries, ENTRIES, "Library </title><script>t</script>", page, &err);
  CHECK(s == CF_OK, "gallery: %s", err.message);
  char *before = NULL;
  size_t before_size = 0;
  CHECK(cf_read_file(page, 1 << 24, &before, &before_size, &err) == CF_OK, "%s", err.message);

  /* refusals: each leaves the page as it was */
  cf_gallery_entry bad[ENTRIES];
  memcpy(bad, entries, sizeof bad);
  bad[2].name = NULL;
  s = cf_report_write_gallery(bad, ENTRIES, "x", page, &err);
  CHECK(s == CF_EINVAL && strstr(err.message, "entry 2"), "NULL name: %d %s", s, err.message);
  memcpy(bad, entries, sizeof bad);
  bad[1].thumbnail = "/etc/passwd";
  s = cf_report_write_gallery(bad, ENTRIES, "x", page, &err);
  CHECK(s == CF_EINVAL && strstr(err.message, "relative"), "absolute path: %d %s", s, err.message);
  memcpy(bad, entries, sizeof bad);
  bad[0].report = "//example.com/x";
  CHECK(cf_report_write_gallery(bad, ENTRIES, "x", page, &err) == CF_EINVAL, "'//' accepted");
  cf_gallery_param nan_params[CF_MAX_DIM];
  memcpy(nan_params, params[0], sizeof nan_params);
  nan_params[0].value[1] = NAN;
  memcpy(bad, entries, sizeof bad);
  bad[0].params = nan_params;
  s = cf_report_write_gallery(bad, ENTRIES, "x", page, &err);
  CHECK(s == CF_EINVAL && strstr(err.message, "albedo[1]"), "NaN: %d %s", s, err.message);
  CHECK(cf_report_write_gallery(NULL, 2, "x", page, &err) == CF_EINVAL, "NULL entries");
  snprintf(path, sizeof path, "%s/no-such-folder/index.html", dir);
  s = cf_report_write_gallery(entries, ENTRIES, "x", path, &err);
  CHECK(s == CF_EIO && strstr(err.message, "no-such-folder"), "missing folder: %d %s", s,
        err.message);
  CHECK(!cf_path_exists(path), "%s written", path);

  char *after = NULL;
  size_t after_size = 0;
  CHECK(cf_read_file(page, 1 << 24, &after, &after_size, &err) == CF_OK, "%s", err.message);
  CHECK(before && after && before_size == after_size && memcmp(before, after, after_size) == 0,
        "a refused gallery changed %s", page);
  free(before);
  free(after);

  /* an empty library is a page too */
  snprintf(path, sizeof path, "%s/empty.html", dir);
  CHECK(cf_report_write_gallery(NULL, 0, NULL, path, &err) == CF_OK, "empty: %s", err.message);
  return check_finish("test_gallery");
}
