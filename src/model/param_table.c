/* The parameter and model tables, instantiated from CF_PARAM_MAP and
 * CF_MODEL_MAP (include/clayfit/model.h): the evaluator, the CLI's help,
 * the fitter and the exporters all read these, so nothing repeats them. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/model.h"

static const cf_param_info param_table[CF_PARAM_COUNT] = {
#define CF__PARAM_ROW(ID, name, symbol, ncomp, unit, def, lo, hi, meaning) \
  {CF_PARAM_##ID, name, symbol, ncomp, unit, def, lo, hi, meaning},
    CF_PARAM_MAP(CF__PARAM_ROW)
#undef CF__PARAM_ROW
};

/* Per model: its parameter ids and their first slots, in vector order. */
#define CF__LIST_ID(M, ID) CF_PARAM_##ID,
#define CF__LIST_SLOT(M, ID) CF_##M##_##ID,
#define CF__MODEL_LISTS(ID, code, name, PARAMS, twin, summary)        \
  static const cf_param_id ID##_params[] = {PARAMS(CF__LIST_ID, ID)}; \
  static const int ID##_offsets[] = {PARAMS(CF__LIST_SLOT, ID)};
CF_MODEL_MAP(CF__MODEL_LISTS)
#undef CF__MODEL_LISTS
#undef CF__LIST_ID
#undef CF__LIST_SLOT

static const cf_model_info model_table[CF_MODEL_COUNT] = {
#define CF__MODEL_ROW(ID, code, name, PARAMS, twin, summary) \
  {CF_MODEL_##ID,                                            \
   code,                                                     \
   name,                                                     \
   summary,                                                  \
   (int)(sizeof ID##_params / sizeof ID##_params[0]),        \
   ID##_params,                                              \
   ID##_offsets,                                             \
   CF_##ID##_DIM,                                            \
   CF_MODEL_##twin,                                          \
   CF_MODEL_##ID == CF_MODEL_##twin ? -1 : (int)CF_##twin##_DIM},
    CF_MODEL_MAP(CF__MODEL_ROW)
#undef CF__MODEL_ROW
};

/* A tailed twin extends its GGX twin's vector by the tail, at its end. */
#define CF__TWIN_CHECK(ID, code, name, PARAMS, twin, summary)                             \
  _Static_assert(                                                                         \
      CF_MODEL_##ID == CF_MODEL_##twin || (int)CF_##ID##_DIM == (int)CF_##twin##_DIM + 1, \
      code " is its twin's vector plus the tail");
CF_MODEL_MAP(CF__TWIN_CHECK)
#undef CF__TWIN_CHECK
_Static_assert((int)CF_DIELECTRIC_TAILED_TAIL == (int)CF_DIELECTRIC_DIM &&
                   (int)CF_DIELECTRIC_TAILED_F0 == (int)CF_DIELECTRIC_F0 &&
                   (int)CF_DIELECTRIC_TAILED_ROUGHNESS == (int)CF_DIELECTRIC_ROUGHNESS,
               "M2T extends M2's vector");
_Static_assert((int)CF_CLAY_TAILED_TAIL == (int)CF_CLAY_DIM &&
                   (int)CF_CLAY_TAILED_BASE_F0 == (int)CF_CLAY_BASE_F0 &&
                   (int)CF_CLAY_TAILED_OPTICAL_DEPTH == (int)CF_CLAY_OPTICAL_DEPTH,
               "M4T extends M4's vector");

/* The codes and names in id order, NULL-terminated (for readers' choices). */
static const char *const model_codes[CF_MODEL_COUNT + 1] = {
#define CF__MODEL_CODE(ID, code, ...) code,
    CF_MODEL_MAP(CF__MODEL_CODE)
#undef CF__MODEL_CODE
        NULL};
static const char *const model_names[CF_MODEL_COUNT + 1] = {
#define CF__MODEL_NAME(ID, code, name, ...) name,
    CF_MODEL_MAP(CF__MODEL_NAME)
#undef CF__MODEL_NAME
        NULL};

const char *const *cf_model_codes(void) {
  return model_codes;
}

const char *const *cf_model_names(void) {
  return model_names;
}

const cf_param_info *cf_param_info_get(cf_param_id id) {
  if ((int)id < 0 || id >= CF_PARAM_COUNT) return NULL;
  return &param_table[id];
}

const cf_model_info *cf_model_info_get(cf_model_id id) {
  if ((int)id < 0 || id >= CF_MODEL_COUNT) return NULL;
  return &model_table[id];
}

/* ASCII case-insensitive equality (locale-independent). */
static int same_word(const char *a, const char *b) {
  for (; *a && *b; ++a, ++b) {
    char x = (*a >= 'A' && *a <= 'Z') ? (char)(*a - 'A' + 'a') : *a;
    char y = (*b >= 'A' && *b <= 'Z') ? (char)(*b - 'A' + 'a') : *b;
    if (x != y) return 0;
  }
  return *a == *b;
}

cf_status cf_model_find(const char *code_or_name, cf_model_id *id, cf_error *err) {
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    if (same_word(code_or_name, model_table[m].code) ||
        same_word(code_or_name, model_table[m].name)) {
      *id = (cf_model_id)m;
      return CF_OK;
    }
  }
  char known[256] = "";
  size_t used = 0;
  for (int m = 0; m < CF_MODEL_COUNT && used < sizeof known; ++m) {
    int n = snprintf(known + used, sizeof known - used, "%s%s (%s)", m ? ", " : "",
                     model_table[m].code, model_table[m].name);
    if (n > 0) used += (size_t)n;
  }
  return cf_error_set(err, CF_ENOTFOUND, "unknown model '%s'; the models are %s", code_or_name,
                      known);
}

cf_status cf_model_param_find(cf_model_id model, const char *name, int *slot,
                              const cf_param_info **info, cf_error *err) {
  const cf_model_info *m = cf_model_info_get(model);
  if (!m) return cf_error_set(err, CF_EINVAL, "invalid model id %d", (int)model);
  for (int k = 0; k < m->param_count; ++k) {
    const cf_param_info *p = &param_table[m->params[k]];
    if (strcmp(name, p->name) == 0) {
      if (slot) *slot = m->offsets[k];
      if (info) *info = p;
      return CF_OK;
    }
  }
  char known[512] = "";
  size_t used = 0;
  for (int k = 0; k < m->param_count && used < sizeof known; ++k) {
    int n = snprintf(known + used, sizeof known - used, "%s%s", k ? ", " : "",
                     param_table[m->params[k]].name);
    if (n > 0) used += (size_t)n;
  }
  return cf_error_set(err, CF_ENOTFOUND,
                      "model %s (%s) has no parameter '%s'; its parameters are %s", m->code,
                      m->name, name, known);
}

const cf_param_info *cf_model_slot_param(cf_model_id model, int k, int *component) {
  const cf_model_info *m = cf_model_info_get(model);
  if (!m || k < 0 || k >= m->dim) return NULL;
  int j = m->param_count - 1;
  while (j > 0 && k < m->offsets[j]) --j; /* the last parameter starting at or before k */
  if (component) *component = k - m->offsets[j];
  return &param_table[m->params[j]];
}

const char *cf_model_slot_name(cf_model_id model, int k, char *buf, size_t size) {
  int channel = 0;
  const cf_param_info *p = cf_model_slot_param(model, k, &channel);
  if (!p)
    snprintf(buf, size, "#%d", k);
  else if (p->components == 3)
    snprintf(buf, size, "%s[%c]", p->name, "rgb"[channel]);
  else
    snprintf(buf, size, "%s", p->name);
  return buf;
}

double cf_model_slot_error(cf_model_id model, int k, double fitted, double truth) {
  const cf_param_info *p = cf_model_slot_param(model, k, NULL);
  if (!p) return NAN;
  return fabs(fitted - truth) / fmax(fabs(truth), p->upper - p->lower);
}

void cf_model_default_params(cf_model_id model, double *params) {
  const cf_model_info *m = cf_model_info_get(model);
  if (!m) return;
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *p = &param_table[m->params[j]];
    for (int c = 0; c < p->components; ++c) params[m->offsets[j] + c] = p->default_value;
  }
}

cf_status cf_params_check(cf_model_id model, const double *params, cf_error *err) {
  const cf_model_info *m = cf_model_info_get(model);
  if (!m) return cf_error_set(err, CF_EINVAL, "invalid model id %d", (int)model);
  for (int k = 0; k < m->dim; ++k) {
    const cf_param_info *p = cf_model_slot_param(model, k, NULL);
    char name[64];
    cf_model_slot_name(model, k, name, sizeof name);
    if (!isfinite(params[k]))
      return cf_error_set(err, CF_EINVAL, "parameter %s of model %s is %g; it must be finite", name,
                          m->name, params[k]);
    if (params[k] < p->lower || params[k] > p->upper)
      return cf_error_set(err, CF_ERANGE,
                          "parameter %s of model %s is %.17g, outside its range [%g, %g] (%s)",
                          name, m->name, params[k], p->lower, p->upper,
                          p->unit[0] == '1' ? "dimensionless" : p->unit);
  }
  return CF_OK;
}
