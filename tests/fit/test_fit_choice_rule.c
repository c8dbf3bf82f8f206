/* The model choice's decision on figures made by hand (fit_choice_decide;
 * include/clayfit/fit.h states the rule, docs/model.md §6.8):
 *   - the walk up the ladder needs a richer model clearly better on both
 *     scores;
 *   - the guard: no choice whose held-out error is more than 10 % above
 *     another's, unless its BIC is lower by more than the margin, and then
 *     its note says why (before issue 18 the walk alone kept M0 at 1.9 σ
 *     against M2's 1.2 σ when M2's BIC was lower by only 5);
 *   - the physical reading: a model whose film is a second lobe gives way
 *     to a candidate marked as the simpler reading when that one does as
 *     well within the margins, and not otherwise;
 *   - which films are not films (fit_choice_stacked_lobes), and the table
 *     of rungs. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fit_choice.h"
#include "support/check.h"

CHECK_MAIN_STATE;

typedef struct figure {
  cf_model_id model;
  double bic, heldout;
} figure;

/* A choice of `count` candidates with these figures (all fitted). */
static void make_choice(cf_fit_choice *choice, const figure *f, int count) {
  memset(choice, 0, sizeof *choice);
  choice->automatic = 1;
  choice->bic_margin = CF_FIT_CHOICE_BIC_MARGIN;
  choice->heldout_margin = CF_FIT_CHOICE_HELDOUT_MARGIN;
  choice->heldout_guard = CF_FIT_CHOICE_HELDOUT_GUARD;
  choice->count = count;
  for (int i = 0; i < count; ++i) {
    cf_fit_candidate *c = &choice->candidate[i];
    c->model = c->fit.model = f[i].model;
    c->ok = 1;
    c->bic = f[i].bic;
    c->heldout_score = f[i].heldout;
  }
}

static const char *code(cf_model_id m) {
  return cf_model_info_get(m)->code;
}

static void check_chosen(const cf_fit_choice *choice, cf_model_id expect, const char *what) {
  CHECK(choice->chosen == expect, "%s: chose %s, expected %s", what, code(choice->chosen),
        code(expect));
  int marked = 0;
  for (int i = 0; i < choice->count; ++i) marked += choice->candidate[i].chosen;
  const cf_fit_candidate *c = cf_fit_choice_chosen(choice);
  CHECK(marked == 1 && c && c->model == expect, "%s: %d candidates marked chosen", what, marked);
}

/* The walk alone (the rule before issue 18) and the guard. */
static void check_guard(void) {
  cf_fit_choice choice;
  /* clearly better on both: the walk goes up, the guard has nothing to do */
  const figure up[] = {{CF_MODEL_LAMBERT, 1000, 2.0}, {CF_MODEL_DIELECTRIC, 900, 1.2}};
  make_choice(&choice, up, 2);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_DIELECTRIC, "clearly better");
  CHECK(strstr(choice.candidate[1].note, "clearly better than M0"), "note: %s",
        choice.candidate[1].note);

  /* M2's held-out error 37 % below M0's, its BIC lower by only 5: the walk
   * keeps M0 (held-out 58 % above M2's), the guard takes M2 */
  const figure weak_bic[] = {{CF_MODEL_LAMBERT, 1000, 1.9}, {CF_MODEL_DIELECTRIC, 995, 1.2}};
  make_choice(&choice, weak_bic, 2);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_DIELECTRIC, "guard");
  CHECK(strstr(choice.candidate[1].note, "chosen over M0") &&
            strstr(choice.candidate[1].note, "58.3 % above"),
        "guard note: %s", choice.candidate[1].note);

  /* the same held-out errors, M0's BIC lower by 200: the BIC says so, M0
   * is kept and its note says why */
  const figure strong_bic[] = {{CF_MODEL_LAMBERT, 1000, 1.9}, {CF_MODEL_DIELECTRIC, 1200, 1.2}};
  make_choice(&choice, strong_bic, 2);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_LAMBERT, "BIC says so");
  CHECK(strstr(choice.candidate[0].note, "kept although") &&
            strstr(choice.candidate[0].note, "BIC is lower by 200"),
        "kept note: %s", choice.candidate[0].note);

  /* within 10 %: the walk's simpler choice stands (M2 is 8 % below) */
  const figure close[] = {{CF_MODEL_LAMBERT, 1000, 1.30}, {CF_MODEL_DIELECTRIC, 995, 1.20}};
  make_choice(&choice, close, 2);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_LAMBERT, "within the guard");

  /* the guard takes the simplest within 10 % of the lowest, not the
   * lowest: M2 (1.25) rather than M4 (1.2) */
  const figure ladder[] = {{CF_MODEL_LAMBERT, 1000, 2.0},
                           {CF_MODEL_OREN_NAYAR, 1001, 2.0},
                           {CF_MODEL_DIELECTRIC, 998, 1.25},
                           {CF_MODEL_CLEARCOAT, 1003, 1.22},
                           {CF_MODEL_CLAY, 997, 1.2}};
  make_choice(&choice, ladder, 5);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_DIELECTRIC, "simplest within the guard");

  /* a failed candidate is skipped by every step */
  make_choice(&choice, ladder, 5);
  choice.candidate[2].ok = 0;
  choice.candidate[2].heldout_score = 0.1;
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_CLEARCOAT, "failed candidate skipped");
}

static void set_film(cf_fit_candidate *c, double roughness, double f0, cf_param_status f0_status) {
  c->fit.params[CF_CLAY_FILM_ROUGHNESS] = roughness;
  c->fit.params[CF_CLAY_FILM_F0] = f0;
  c->fit.status[CF_CLAY_FILM_F0] = f0_status;
}

static void check_stacked_lobes(void) {
  cf_fit_result r;
  memset(&r, 0, sizeof r);
  char why[160] = "";
  r.model = CF_MODEL_CLAY;
  r.params[CF_CLAY_FILM_ROUGHNESS] = 0.3;
  r.params[CF_CLAY_FILM_F0] = 0.02;
  CHECK(!fit_choice_stacked_lobes(&r, why, sizeof why), "a water film is a film");
  r.params[CF_CLAY_FILM_ROUGHNESS] = 0.87;
  CHECK(fit_choice_stacked_lobes(&r, why, sizeof why) && strstr(why, "film roughness 0.87 > 0.7"),
        "r 0.87: %s", why);
  r.params[CF_CLAY_FILM_ROUGHNESS] = 0.3;
  r.params[CF_CLAY_FILM_F0] = 0.12;
  CHECK(fit_choice_stacked_lobes(&r, why, sizeof why) && strstr(why, "film F0 0.12 > 0.07"),
        "F0 0.12: %s", why);
  r.status[CF_CLAY_FILM_F0] = CF_PARAM_HELD_FOR_SCALE; /* held: not the data's claim */
  CHECK(!fit_choice_stacked_lobes(&r, why, sizeof why), "a held F0 says nothing");
  memset(&r, 0, sizeof r);
  r.model = CF_MODEL_DIELECTRIC;
  r.params[CF_DIELECTRIC_ROUGHNESS] = 0.9;
  CHECK(!fit_choice_stacked_lobes(&r, NULL, 0), "M2 has no film");
}

/* Rule 3 with M2 standing in for a rung marked as the physical reading
 * (M2T once it exists). */
static void check_physical_reading(void) {
  /* the walk: M2 not clearly better than M0 (BIC lower by 5), M4 clearly
   * better (BIC lower by 13, held-out error by 6.3 %); M2 within the
   * margins of M4 (held-out +0.67 %, BIC +8) */
  const figure f[] = {
      {CF_MODEL_LAMBERT, 2008, 1.6}, {CF_MODEL_DIELECTRIC, 2003, 1.51}, {CF_MODEL_CLAY, 1995, 1.5}};
  cf_fit_choice choice;
  make_choice(&choice, f, 3);
  set_film(&choice.candidate[2], 0.87, 0.04, CF_PARAM_HELD_FOR_SCALE);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_CLAY, "a lobe for a film, nothing marked physical");

  make_choice(&choice, f, 3);
  choice.candidate[1].physical = 1;
  set_film(&choice.candidate[2], 0.87, 0.04, CF_PARAM_HELD_FOR_SCALE);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_DIELECTRIC, "the physical reading");
  CHECK(strstr(choice.candidate[1].note, "the simpler physical reading") &&
            strstr(choice.candidate[1].note, "film roughness 0.87"),
        "physical note: %s", choice.candidate[1].note);

  /* the same with a real film (r 0.3, F0 0.02): M4 stays */
  make_choice(&choice, f, 3);
  choice.candidate[1].physical = 1;
  set_film(&choice.candidate[2], 0.3, 0.02, CF_PARAM_FITTED);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_CLAY, "a real film");

  /* a lobe, but the physical reading 3 % worse on held-out: M4 stays */
  make_choice(&choice, f, 3);
  choice.candidate[1].physical = 1;
  choice.candidate[1].heldout_score = 1.545;
  set_film(&choice.candidate[2], 0.87, 0.04, CF_PARAM_HELD_FOR_SCALE);
  fit_choice_decide(&choice);
  check_chosen(&choice, CF_MODEL_CLAY, "the physical reading not within the margins");
}

static void check_rungs(void) {
  int count;
  const fit_choice_rung *r = fit_choice_rungs(&count);
  CHECK(count >= 1 && count <= CF_FIT_MAX_CANDIDATES, "%d rungs", count);
  CHECK(r[0].model == CF_MODEL_LAMBERT, "the walk starts at M0");
  for (int i = 0; i < count; ++i)
    for (int j = 0; j < i; ++j)
      CHECK(r[i].model != r[j].model, "%s twice in the rungs", code(r[i].model));
}

int main(void) {
  check_guard();
  check_stacked_lobes();
  check_physical_reading();
  check_rungs();
  return check_finish("test_fit_choice_rule");
}
