/* The single parameter table: consistent, complete, and its look-ups and
 * checks give the errors the CLI shows. */
#include <math.h>
#include <string.h>

#include "clayfit/model.h"
#include "support/check.h"

CHECK_MAIN_STATE;

int main(void) {
  for (int p = 0; p < CF_PARAM_COUNT; ++p) {
    const cf_param_info *info = cf_param_info_get((cf_param_id)p);
    CHECK(info && info->id == (cf_param_id)p, "param %d", p);
    CHECK(info->lower < info->upper, "%s: empty range", info->name);
    CHECK(info->default_value >= info->lower && info->default_value <= info->upper,
          "%s: default %g outside [%g, %g]", info->name, info->default_value, info->lower,
          info->upper);
    CHECK(info->components == 1 || info->components == 3, "%s", info->name);
    for (int q = 0; q < p; ++q)
      CHECK(strcmp(info->name, cf_param_info_get((cf_param_id)q)->name) != 0, "duplicate name %s",
            info->name);
  }
  CHECK(cf_param_info_get(CF_PARAM_COUNT) == NULL, "out-of-range id");

  /* docs/model.md §1.6's ranges, checked against the table */
  CHECK(cf_param_info_get(CF_PARAM_FILM_F0)->lower == 0.01, "F0_1 floor");
  CHECK(cf_param_info_get(CF_PARAM_ROUGHNESS)->lower == 0.03, "roughness floor");
  CHECK(cf_param_info_get(CF_PARAM_OPTICAL_DEPTH)->upper == 8.0, "tau bound");
  CHECK(cf_param_info_get(CF_PARAM_DIFFUSE_ROUGHNESS)->upper == 1.2, "sigma bound");

  static const int dims[CF_MODEL_COUNT] = {3, 4, 6, 8, 11, 7, 12};
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    const cf_model_info *model = cf_model_info_get((cf_model_id)m);
    CHECK(model->dim == dims[m], "%s dim %d", model->code, model->dim);
    int next = 0;
    for (int k = 0; k < model->param_count; ++k) {
      CHECK(model->offsets[k] == next, "%s: %s at slot %d, expected %d", model->code,
            cf_param_info_get(model->params[k])->name, model->offsets[k], next);
      next += cf_param_info_get(model->params[k])->components;
    }
    CHECK(next == model->dim, "%s: slots %d != dim %d", model->code, next, model->dim);
    cf_model_id found;
    CHECK(cf_model_find(model->code, &found, NULL) == CF_OK && found == model->id, "find %s",
          model->code);
    CHECK(cf_model_find(model->name, &found, NULL) == CF_OK && found == model->id, "find %s",
          model->name);
    double params[CF_MAX_DIM];
    cf_model_default_params(model->id, params);
    CHECK(cf_params_check(model->id, params, NULL) == CF_OK, "%s defaults", model->code);
  }

  cf_model_id id;
  cf_error err = {0};
  CHECK(cf_model_find("m4", &id, &err) == CF_OK && id == CF_MODEL_CLAY, "case-insensitive");
  CHECK(cf_model_find("M9", &id, &err) == CF_ENOTFOUND, "unknown model");
  CHECK(strstr(err.message, "M9") && strstr(err.message, "clay"), "message: %s", err.message);

  int slot = -1;
  const cf_param_info *info = NULL;
  CHECK(cf_model_param_find(CF_MODEL_CLAY, "base_f0", &slot, &info, &err) == CF_OK &&
            slot == CF_CLAY_BASE_F0 && info->id == CF_PARAM_BASE_F0,
        "base_f0 slot %d", slot);
  CHECK(cf_model_param_find(CF_MODEL_DIELECTRIC, "film_f0", &slot, &info, &err) == CF_ENOTFOUND,
        "M2 has no film_f0");
  CHECK(strstr(err.message, "film_f0") && strstr(err.message, "roughness"), "message: %s",
        err.message);

  double p[CF_CLAY_DIM];
  cf_model_default_params(CF_MODEL_CLAY, p);
  p[CF_CLAY_FILM_F0] = 0.005;
  CHECK(cf_params_check(CF_MODEL_CLAY, p, &err) == CF_ERANGE, "below range");
  CHECK(strstr(err.message, "film_f0") && strstr(err.message, "0.01"), "message: %s", err.message);
  cf_model_default_params(CF_MODEL_CLAY, p);
  p[CF_CLAY_OPTICAL_DEPTH + 1] = NAN;
  CHECK(cf_params_check(CF_MODEL_CLAY, p, &err) == CF_EINVAL, "NaN");
  CHECK(strstr(err.message, "optical_depth[g]") != NULL, "message: %s", err.message);

  /* a slot's error in units of max(|truth|, its range's width): optical
   * depth's range is [0, 8], film F0's [0.01, 0.25] */
  double e = cf_model_slot_error(CF_MODEL_CLAY, CF_CLAY_OPTICAL_DEPTH + 2, 0.5, 0.1);
  CHECK(fabs(e - 0.4 / 8.0) < 1e-15, "optical depth error %.17g", e);
  e = cf_model_slot_error(CF_MODEL_CLAY, CF_CLAY_FILM_F0, 0.02, 0.03);
  CHECK(fabs(e - 0.01 / 0.24) < 1e-15, "film F0 error %.17g", e);
  e = cf_model_slot_error(CF_MODEL_CLAY, CF_CLAY_OPTICAL_DEPTH, 30.0, 20.0);
  CHECK(fabs(e - 0.5) < 1e-15, "an error beyond the range's width: %.17g", e);
  CHECK(isnan(cf_model_slot_error(CF_MODEL_LAMBERT, 3, 0.0, 0.0)), "M0 has no slot 3");

  CHECK(strcmp(cf_status_name(CF_ERANGE), "ERANGE") == 0, "status name");
  CHECK(strcmp(cf_status_message(CF_ENOMEM), "out of memory") == 0, "status message");
  return check_finish("test_param_table");
}
