/* Per-image and per-light gains (fit_gains.h, cf_fit_check_gains). */
#include "fit_gains.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_multistart.h"
#include "fit_plan.h"
#include "fit_residuals.h"
#include "lsq/linalg.h"

/* sd(log g) of each gain of one kind (fit_kind_exposure: per group,
 * fit_kind_light: per light) into sd[slot] (count: the groups or lights),
 * the last one's from the sum of the others' covariance (its log is minus
 * their sum); returns 0 (sd untouched) when none is free. */
static int log_gain_sd(const fit_problem *p, const fit_kind *kind, const double *covariance,
                       size_t count, double *sd) {
  int n = fit_problem_unknown_count(p), any = 0;
  double last = 0.0;
  for (int u = 0; u < n; ++u) {
    fit_unknown unk = fit_problem_unknown(p, u);
    if (unk.kind != kind) continue;
    sd[unk.slot] = sqrt(fmax(0.0, covariance[u * n + u]));
    for (int v = 0; v < n; ++v)
      if (fit_problem_unknown(p, v).kind == kind) last += covariance[u * n + v];
    any = 1;
  }
  if (any) sd[count - 1] = sqrt(fmax(0.0, last));
  return any;
}

void fit_gains_sd(const fit_problem *p, const double *covariance, double *sd) {
  const fit_groups *g = fit_problem_groups(p);
  const double *log_exposures = fit_problem_read_values(p)->log_exposures;
  for (size_t k = 0; k < g->images; ++k) sd[k] = 0.0;
  /* first sd(log e) per group, in sd[group] */
  if (!log_gain_sd(p, &fit_kind_exposure, covariance, g->count, sd)) return;
  /* then per image (downward: an image's group is numbered at most its
   * own index, so sd[group] is still the group's when read) */
  for (size_t k = g->images; k-- > 0;) sd[k] = exp(log_exposures[k]) * sd[g->group[k]];
}

/* The name of light l (its first slot in the groups' slot_light) into text. */
static void light_name(const fit_problem *p, size_t l, char *text, size_t size) {
  const fit_groups *g = fit_problem_groups(p);
  size_t lights = (size_t)g->lights;
  for (size_t i = 0; i < g->images * lights; ++i)
    if (g->slot_light[i] == (long)l) {
      cf_capture_light_name(fit_problem_capture(p), i / lights, (int)(i % lights), text, size);
      return;
    }
  snprintf(text, size, "no light");
}

cf_status fit_light_gains_of(const fit_problem *p, const double *covariance, cf_fit_result *r,
                             cf_error *err) {
  size_t count = fit_problem_groups(p)->light_count;
  if (!fit_problem_has_kind(p, &fit_kind_light)) return CF_OK;
  r->light_gains = malloc(count * sizeof *r->light_gains);
  r->light_gains_sd = calloc(count, sizeof *r->light_gains_sd);
  r->light_names = malloc(count * sizeof *r->light_names);
  if (!r->light_gains || !r->light_gains_sd || !r->light_names)
    return cf_error_set(err, CF_ENOMEM, "out of memory for %zu lights' gains", count);
  r->light_count = count;
  log_gain_sd(p, &fit_kind_light, covariance, count, r->light_gains_sd);
  for (size_t l = 0; l < count; ++l) {
    r->light_gains[l] = exp(fit_problem_read_values(p)->log_light[l]);
    r->light_gains_sd[l] *= r->light_gains[l]; /* d g = g d log g */
    light_name(p, l, r->light_names[l], sizeof r->light_names[l]);
  }
  return CF_OK;
}

cf_status fit_balance_of(const fit_problem *p, int fitted, const double *covariance,
                         cf_fit_result *r, cf_error *err) {
  size_t images = fit_problem_images(p), n = (size_t)fit_problem_unknown_count(p);
  const double *log_balance = fit_problem_read_values(p)->log_balance;
  r->white_balance = malloc(3 * (images ? images : 1) * sizeof *r->white_balance);
  r->white_balance_sd = calloc(3 * (images ? images : 1), sizeof *r->white_balance_sd);
  if (!r->white_balance || !r->white_balance_sd)
    return cf_error_set(err, CF_ENOMEM, "out of memory for the white balance");
  r->white_balance_fitted = fitted;
  for (size_t i = 0; i < 3 * images; ++i) r->white_balance[i] = exp(log_balance[i]);
  double last[2] = {0.0, 0.0};
  for (size_t u = 0; fitted && u < n; ++u) {
    fit_unknown unk = fit_problem_unknown(p, (int)u);
    if (unk.kind != &fit_kind_balance) continue;
    size_t slot = (size_t)unk.slot, at = 3 * (slot / 2) + 2 * (slot % 2);
    r->white_balance_sd[at] = r->white_balance[at] * sqrt(fmax(0.0, covariance[u * n + u]));
    for (size_t v = 0; v < n; ++v) {
      fit_unknown other = fit_problem_unknown(p, (int)v);
      if (other.kind == &fit_kind_balance && (size_t)other.slot % 2 == slot % 2)
        last[slot % 2] += covariance[u * n + v];
    }
  }
  for (int j = 0; fitted && images > 0 && j < 2; ++j) {
    size_t at = 3 * (images - 1) + 2 * (size_t)j;
    r->white_balance_sd[at] = r->white_balance[at] * sqrt(fmax(0.0, last[j]));
  }
  return CF_OK;
}

/* Group g's part of a direction over the free log gains (x, groups − 1:
 * the last group's is −Σ x), its uniform part removed (a change of every
 * gain alike is the scale's or the albedo's); into part (groups). */
static void gain_parts(const double *x, size_t groups, double *part) {
  double sum = 0.0, mean = 0.0;
  for (size_t g = 0; g + 1 < groups; ++g) sum += part[g] = x[g];
  part[groups - 1] = -sum;
  for (size_t g = 0; g < groups; ++g) mean += part[g] / (double)groups;
  for (size_t g = 0; g < groups; ++g) part[g] -= mean;
}

/* "name1, name2, ..." of the images with flag[k] into text (at most
 * `size`; "and N more" when they do not fit). */
static void image_names(const cf_capture *capture, const unsigned char *flag, char *text,
                        size_t size) {
  size_t used = 0, named = 0, left = 0;
  text[0] = '\0';
  for (size_t k = 0; k < cf_capture_image_count(capture); ++k) {
    if (!flag[k]) continue;
    const char *name = cf_capture_image_at(capture, k)->name;
    if (used + strlen(name) + 24 < size) {
      used += (size_t)snprintf(text + used, size - used, "%s%s", named ? ", " : "", name);
      ++named;
    } else {
      ++left;
    }
  }
  if (left) snprintf(text + used, size - used, " and %zu more", left);
}

/* The problem for the check: the options' model on the budget's
 * observations (its sample: each image at least FIT_GAIN_FLOOR),
 * unweighted (the information the fit's sample holds), at the base start,
 * σ from the capture's noise model or the start's residuals; the plan's
 * unknowns declared. On failure *p is NULL. */
static cf_status check_problem(const cf_capture *capture, const cf_fit_options *o,
                               const fit_budget *budget, fit_problem **p, fit_plan *plan,
                               cf_error *err) {
  const fit_population *population = &budget->population;
  cf_status s = fit_problem_new(p, capture, o->model, population->index, population->count,
                                o->threads, err);
  if (s != CF_OK) return s;
  fit_plan_for(capture, o, plan);
  fit_values *v = fit_problem_values(*p);
  fit_base_start(*p, plan, o, v->params, &v->log_scale);
  double sigma = 1.0;
  if (!fit_capture_has_noise(capture)) s = fit_estimate_sigma(*p, &sigma, err);
  if (s == CF_OK) fit_problem_set_sigma(*p, sigma);
  if (s == CF_OK) s = fit_problem_reweight(*p, err);
  if (s == CF_OK) s = fit_declare(*p, plan, err);
  if (s != CF_OK) {
    fit_problem_free(*p);
    *p = NULL;
  }
  return s;
}

static int is_gain(const fit_kind *kind) {
  return kind == &fit_kind_exposure || kind == &fit_kind_light;
}

/* jtj (n², the problem's unknowns) with the gains' unknowns (per group or
 * per light) moved last, into moved (n²); returns their count. */
static int gains_last(const fit_problem *p, const double *jtj, double *moved, int *order) {
  int n = fit_problem_unknown_count(p), m = 0, g = 0;
  for (int pass = 0; pass < 2; ++pass)
    for (int u = 0; u < n; ++u)
      if (is_gain(fit_problem_unknown(p, u).kind) == pass) order[m++] = u, g += pass;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) moved[a * n + b] = jtj[order[a] * n + order[b]];
  return g;
}

/* What the flagged gains (gain_flag: per group, or per light) are, into
 * text: "images a, b", or "light 1; light 2 (in images a, b)"; image_flag
 * (images) is scratch. */
static void gain_subject(const fit_problem *p, int per_light, const unsigned char *gain_flag,
                         unsigned char *image_flag, char *text, size_t size) {
  char images[1024];
  const fit_groups *g = fit_problem_groups(p);
  size_t lights = (size_t)g->lights, used = 0;
  for (size_t k = 0; k < g->images; ++k) {
    image_flag[k] = per_light ? 0 : gain_flag[g->group[k]];
    for (size_t j = 0; per_light && j < lights; ++j) {
      long l = g->slot_light[k * lights + j];
      image_flag[k] |= l >= 0 && gain_flag[l];
    }
  }
  image_names(fit_problem_capture(p), image_flag, images, sizeof images);
  if (!per_light) {
    snprintf(text, size, "images %s", images);
    return;
  }
  text[0] = '\0';
  for (size_t l = 0; l < g->light_count && used + CF_FIT_LIGHT_NAME + 4 < size / 2; ++l) {
    if (!gain_flag[l]) continue;
    char name[CF_FIT_LIGHT_NAME];
    light_name(p, l, name, sizeof name);
    used += (size_t)snprintf(text + used, size - used, "%s%s", used ? "; " : "", name);
  }
  snprintf(text + used, size - used, " (in images %s)", images);
}

/* The refusal, from the normal equations with the gains last (jtj; per
 * group of images, or per light): the gains' block singular (the gains of
 * its weakest direction named), or the gains whose sd is above
 * FIT_GAIN_SD_MOST. */
static cf_status judge_gains(const fit_problem *p, int per_light, const double *jtj,
                             cf_error *err) {
  const fit_groups *gr = fit_problem_groups(p);
  size_t images = gr->images, groups = per_light ? gr->light_count : gr->count;
  int n = fit_problem_unknown_count(p), g = (int)groups - 1;
  double *covariance = malloc((size_t)g * (size_t)g * sizeof *covariance);
  double *weakest = malloc((size_t)g * sizeof *weakest), *part = malloc(groups * sizeof *part);
  unsigned char *flag = calloc(images + groups, 1), *group_flag = flag + images;
  char names[2048];
  if (!covariance || !weakest || !part || !flag) {
    free(covariance), free(weakest), free(part), free(flag);
    return cf_error_set(err, CF_ENOMEM, "out of memory for the gains' check");
  }
  int regular = cf_schur_covariance(n, g, jtj, covariance, weakest);
  cf_status s = CF_OK;
  if (regular < 0) {
    s = cf_error_set(err, CF_ENUMERIC, "the gains' normal equations are not finite at the start");
  } else if (regular == 0) {
    gain_parts(weakest, groups, part);
    double most = 0.0;
    for (size_t q = 0; q < groups; ++q) most = fmax(most, fabs(part[q]));
    /* 30 % of the largest part: named in the message only (69a8156, not measured) */
    for (size_t q = 0; q < groups; ++q) group_flag[q] = fabs(part[q]) > 0.3 * most;
    gain_subject(p, per_light, group_flag, flag, names, sizeof names);
    s = cf_error_set(
        err, CF_EINVAL,
        "the gains (--fit-exposures, --fit-gains) of %s cannot be told from the material "
        "(the gains' block of the normal equations, the material and the scale "
        "profiled out, is singular: their observations fix only their product with "
        "it); drop the gains or these %s",
        names, per_light ? "lights" : "images");
  } else {
    size_t over = 0;
    double worst = 0.0, total = 0.0;
    for (int a = 0; a < g; ++a) {
      double sd = sqrt(fmax(0.0, covariance[a * g + a]));
      over += group_flag[a] = sd > FIT_GAIN_SD_MOST;
      worst = fmax(worst, sd);
      for (int b = 0; b < g; ++b) total += covariance[a * g + b];
    }
    double last = sqrt(fmax(0.0, total)); /* log e_last = −Σ the others */
    over += group_flag[g] = last > FIT_GAIN_SD_MOST;
    worst = fmax(worst, last);
    gain_subject(p, per_light, group_flag, flag, names, sizeof names);
    if (over)
      s = cf_error_set(err, CF_EINVAL,
                       "the gains (--fit-exposures, --fit-gains) of %s are not told from the "
                       "material (predicted sd above %g %%, up to %.3g %%); drop the gains or "
                       "these %s",
                       names, 100.0 * FIT_GAIN_SD_MOST, 100.0 * worst,
                       per_light ? "lights" : "images");
  }
  free(covariance), free(weakest), free(part), free(flag);
  return s;
}

/* A gain per light needs two lights, and at most FIT_IMAGE_LIGHTS in an
 * image. */
static cf_status check_lights(const fit_problem *p, cf_error *err) {
  const fit_groups *g = fit_problem_groups(p);
  if (g->light_count < 2)
    return cf_error_set(err, CF_EINVAL,
                        "--fit-gains per-light: one light lights every image, so its gain is "
                        "the capture's overall scale, not a gain to fit (their mean log is 0); "
                        "use --fit-gains per-image for a gain per photo");
  if (g->image_lights > FIT_IMAGE_LIGHTS)
    return cf_error_set(err, CF_EINVAL,
                        "--fit-gains per-light: an image has %d lights, more than the %d that a "
                        "gain per light supports; use --fit-gains per-image",
                        g->image_lights, FIT_IMAGE_LIGHTS);
  return CF_OK;
}

cf_status fit_check_gains(const cf_capture *capture, const cf_fit_options *o,
                          const fit_budget *budget, cf_error *err) {
  if (!o->fit_exposures || cf_capture_image_count(capture) < 2) return CF_OK;
  if (o->fit_exposures != CF_GAINS_PER_IMAGE && o->fit_exposures != CF_GAINS_PER_LIGHT &&
      o->fit_exposures != CF_GAINS_PER_IMAGE_RGB)
    return cf_error_set(err, CF_EINVAL, "invalid gains mode %d", o->fit_exposures);
  if (cf_capture_observations(capture)->count == 0)
    return cf_error_set(err, CF_EINVAL, "the capture has no observations to fit");
  fit_problem *p;
  fit_plan plan;
  cf_status s = check_problem(capture, o, budget, &p, &plan, err);
  if (s != CF_OK) return s;
  int per_light = fit_problem_has_kind(p, &fit_kind_light);
  const fit_groups *g = fit_problem_groups(p);
  size_t n = (size_t)fit_problem_unknown_count(p), gains = per_light ? g->light_count : g->count;
  double *jtj = malloc(n * n * sizeof *jtj), *moved = malloc(n * n * sizeof *moved);
  int *order = malloc(n * sizeof *order);
  if (o->fit_exposures == CF_GAINS_PER_LIGHT) s = check_lights(p, err);
  if (s == CF_OK)
    s = jtj && moved && order ? fit_normal_equations(p, fit_threads(o), jtj, NULL, NULL, err)
                              : cf_error_set(err, CF_ENOMEM, "out of memory for the gains' check");
  if (s == CF_OK && gains_last(p, jtj, moved, order) != (int)gains - 1)
    s = cf_error_set(err, CF_EINVAL, "internal: the gains are not all free");
  if (s == CF_OK) s = judge_gains(p, per_light, moved, err);
  free(jtj);
  free(moved);
  free(order);
  fit_problem_free(p);
  return s;
}

cf_status cf_fit_check_gains(const cf_capture *capture, const cf_fit_options *o, cf_error *err) {
  if (!o->fit_exposures || cf_capture_image_count(capture) < 2) return CF_OK;
  fit_budget budget;
  cf_status s = fit_budget_for(capture, o, &budget, err);
  if (s == CF_OK) s = fit_check_gains(capture, o, &budget, err);
  fit_budget_free(&budget);
  return s;
}
