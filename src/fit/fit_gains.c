/* Per-image gains (fit_gains.h, cf_fit_check_gains). */
#include "fit_gains.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_budget.h"
#include "fit_multistart.h"
#include "fit_plan.h"
#include "fit_residuals.h"
#include "lsq/linalg.h"

void fit_gains_sd(const fit_problem *p, const double *covariance, double *sd) {
  int n = p->num_unknowns;
  double last = 0.0;
  int any = 0;
  for (size_t k = 0; k < p->images; ++k) sd[k] = 0.0;
  for (int u = 0; u < n; ++u) { /* first sd(log e) per group, in sd[group] */
    if (p->unknowns[u].kind != FIT_LOG_EXPOSURE) continue;
    sd[p->unknowns[u].slot] = sqrt(fmax(0.0, covariance[u * n + u]));
    for (int v = 0; v < n; ++v)
      if (p->unknowns[v].kind == FIT_LOG_EXPOSURE) last += covariance[u * n + v];
    any = 1;
  }
  if (!any) return;
  sd[p->gain_groups - 1] = sqrt(fmax(0.0, last));
  /* then per image (downward: an image's group is numbered at most its
   * own index, so sd[group] is still the group's when read) */
  for (size_t k = p->images; k-- > 0;) sd[k] = exp(p->log_exposures[k]) * sd[p->gain_group[k]];
}

cf_status fit_balance_of(const fit_problem *p, int fitted, const double *covariance,
                         cf_fit_result *r, cf_error *err) {
  size_t images = p->images, n = (size_t)p->num_unknowns;
  r->white_balance = malloc(3 * (images ? images : 1) * sizeof *r->white_balance);
  r->white_balance_sd = calloc(3 * (images ? images : 1), sizeof *r->white_balance_sd);
  if (!r->white_balance || !r->white_balance_sd)
    return cf_error_set(err, CF_ENOMEM, "out of memory for the white balance");
  r->white_balance_fitted = fitted;
  for (size_t i = 0; i < 3 * images; ++i) r->white_balance[i] = exp(p->log_balance[i]);
  double last[2] = {0.0, 0.0};
  for (size_t u = 0; fitted && u < n; ++u) {
    if (p->unknowns[u].kind != FIT_LOG_BALANCE) continue;
    size_t slot = (size_t)p->unknowns[u].slot, at = 3 * (slot / 2) + 2 * (slot % 2);
    r->white_balance_sd[at] = r->white_balance[at] * sqrt(fmax(0.0, covariance[u * n + u]));
    for (size_t v = 0; v < n; ++v)
      if (p->unknowns[v].kind == FIT_LOG_BALANCE && (size_t)p->unknowns[v].slot % 2 == slot % 2)
        last[slot % 2] += covariance[u * n + v];
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

/* The problem for the check: the options' model on the budget's sample
 * (each image at least FIT_GAIN_FLOOR), unweighted (the information the
 * fit's sample holds), at the base start, σ from the capture's noise model
 * or the start's residuals; the plan's unknowns declared. */
static cf_status check_problem(const cf_capture *capture, const cf_fit_options *o, fit_problem *p,
                               fit_sample *sample, fit_plan *plan, cf_error *err) {
  fit_population population;
  uint32_t *index;
  size_t images = cf_capture_image_count(capture);
  cf_status s = fit_population_of_images(capture, o->use_image, &population, &index, err);
  size_t budget = o->budget > 0 ? o->budget : population.count;
  if (s == CF_OK)
    s = fit_budget_draw_images(cf_capture_observations(capture), &population, images, budget,
                               FIT_GAIN_FLOOR, o->sampling, sample, err);
  free(index);
  if (s != CF_OK) return s;
  s = fit_problem_init(p, capture, o->model, sample->index, sample->count, o->threads, err);
  if (s != CF_OK) {
    fit_sample_free(sample);
    return s;
  }
  fit_plan_for(capture, o, plan);
  fit_base_start(p, plan, o, p->params, &p->log_scale);
  double sigma = 1.0;
  if (!fit_capture_has_noise(capture)) s = fit_estimate_sigma(p, &sigma, err);
  if (s == CF_OK) fit_problem_set_sigma(p, capture, sigma);
  if (s == CF_OK) s = fit_problem_reweight(p, capture, err);
  if (s == CF_OK) s = fit_declare(p, plan, err);
  if (s != CF_OK) {
    fit_problem_release(p);
    fit_sample_free(sample);
  }
  return s;
}

/* jtj (n², the problem's unknowns) with the gains' unknowns moved last,
 * into moved (n²); returns their count. */
static int gains_last(const fit_problem *p, const double *jtj, double *moved, int *order) {
  int n = p->num_unknowns, m = 0, g = 0;
  for (int pass = 0; pass < 2; ++pass)
    for (int u = 0; u < n; ++u)
      if ((p->unknowns[u].kind == FIT_LOG_EXPOSURE) == pass) order[m++] = u, g += pass;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) moved[a * n + b] = jtj[order[a] * n + order[b]];
  return g;
}

/* The refusal, from the normal equations with the gains last (jtj): the
 * gains' block singular (the images of its weakest
 * direction named), or the gains whose sd is above FIT_GAIN_SD_MOST. */
static cf_status judge_gains(const cf_capture *capture, const fit_problem *p, const double *jtj,
                             cf_error *err) {
  size_t images = p->images, groups = p->gain_groups;
  int n = p->num_unknowns, g = (int)groups - 1;
  double *covariance = malloc((size_t)g * (size_t)g * sizeof *covariance);
  double *weakest = malloc((size_t)g * sizeof *weakest), *part = malloc(groups * sizeof *part);
  unsigned char *flag = calloc(images + groups, 1), *group_flag = flag + images;
  char names[1024];
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
    for (size_t k = 0; k < images; ++k) flag[k] = fabs(part[p->gain_group[k]]) > 0.3 * most;
    image_names(capture, flag, names, sizeof names);
    s = cf_error_set(
        err, CF_EINVAL,
        "the gains (--fit-exposures, --fit-gains) of images %s cannot be told from the material "
        "(the gains' block of the normal equations, the material and the scale "
        "profiled out, is singular: their observations fix only their product with "
        "it); drop the gains or these images",
        names);
  } else {
    size_t over = 0;
    double worst = 0.0, total = 0.0;
    for (int a = 0; a < g; ++a) {
      double sd = sqrt(fmax(0.0, covariance[a * g + a]));
      group_flag[a] = sd > FIT_GAIN_SD_MOST;
      worst = fmax(worst, sd);
      for (int b = 0; b < g; ++b) total += covariance[a * g + b];
    }
    double last = sqrt(fmax(0.0, total)); /* log e_last = −Σ the others */
    group_flag[g] = last > FIT_GAIN_SD_MOST;
    worst = fmax(worst, last);
    for (size_t k = 0; k < images; ++k) over += flag[k] = group_flag[p->gain_group[k]];
    image_names(capture, flag, names, sizeof names);
    if (over)
      s = cf_error_set(
          err, CF_EINVAL,
          "the gains (--fit-exposures, --fit-gains) of %zu images are not told from the material "
          "(predicted sd above %g %%, up to %.3g %%): %s; drop the gains or these "
          "images",
          over, 100.0 * FIT_GAIN_SD_MOST, 100.0 * worst, names);
  }
  free(covariance), free(weakest), free(part), free(flag);
  return s;
}

/* A gain per light needs each image lit by one light, and two lights. */
static cf_status check_lights(const cf_capture *capture, cf_error *err) {
  size_t images = cf_capture_image_count(capture), lights = 0;
  for (size_t k = 0; k < images; ++k) {
    long light = cf_capture_image_light_id(capture, k);
    if (light < 0)
      return cf_error_set(err, CF_EINVAL,
                          "--fit-gains per-light: image %s has several lights (the capture "
                          "file's lights), and a gain per light among them is not supported; "
                          "use --fit-gains per-image",
                          cf_capture_image_at(capture, k)->name);
    lights += (size_t)light == k;
  }
  if (lights < 2)
    return cf_error_set(err, CF_EINVAL,
                        "--fit-gains per-light: one light lights every image, so its gain is "
                        "the capture's overall scale, not a gain to fit (their mean log is 0); "
                        "use --fit-gains per-image for a gain per photo");
  return CF_OK;
}

cf_status cf_fit_check_gains(const cf_capture *capture, const cf_fit_options *o, cf_error *err) {
  if (!o->fit_exposures || cf_capture_image_count(capture) < 2) return CF_OK;
  if (o->fit_exposures != CF_GAINS_PER_IMAGE && o->fit_exposures != CF_GAINS_PER_LIGHT &&
      o->fit_exposures != CF_GAINS_PER_IMAGE_RGB)
    return cf_error_set(err, CF_EINVAL, "invalid gains mode %d", o->fit_exposures);
  if (cf_capture_observations(capture)->count == 0)
    return cf_error_set(err, CF_EINVAL, "the capture has no observations to fit");
  if (o->fit_exposures == CF_GAINS_PER_LIGHT) {
    cf_status lights = check_lights(capture, err);
    if (lights != CF_OK) return lights;
  }
  fit_problem p;
  fit_sample sample;
  fit_plan plan;
  cf_status s = check_problem(capture, o, &p, &sample, &plan, err);
  if (s != CF_OK) return s; /* (check_problem released what it made) */
  size_t n = (size_t)p.num_unknowns;
  double *jtj = malloc(n * n * sizeof *jtj), *moved = malloc(n * n * sizeof *moved);
  int *order = malloc(n * sizeof *order);
  s = jtj && moved && order ? fit_normal_equations(&p, fit_threads(o), jtj, NULL, NULL, err)
                            : cf_error_set(err, CF_ENOMEM, "out of memory for the gains' check");
  if (s == CF_OK && gains_last(&p, jtj, moved, order) != (int)p.gain_groups - 1)
    s = cf_error_set(err, CF_EINVAL, "internal: the gains are not all free");
  if (s == CF_OK) s = judge_gains(capture, &p, moved, err);
  free(jtj);
  free(moved);
  free(order);
  fit_problem_release(&p);
  fit_sample_free(&sample);
  return s;
}
