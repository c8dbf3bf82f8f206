/* The physics of the mapping from the models of docs/model.md §3 to the targets'
 * inputs (export_internal.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "export_internal.h"

/* ---- physics ---- */

double export_ior_from_f0(double f0) {
  double s = sqrt(f0);
  return (1.0 + s) / (1.0 - s);
}

double export_f0_from_ior(double ior) {
  double r = (ior - 1.0) / (ior + 1.0);
  return r * r;
}

double export_sigma_materialx_glsl(double sigma) {
  return sigma / CF_PI;
}

double export_sigma_fujii(double sigma) {
  double s2 = sigma * sigma;
  double a = 1.0 - 0.5 * s2 / (s2 + 0.33), b = 0.45 * s2 / (s2 + 0.09);
  return b / a;
}

double export_gtr1_width(double gloss) {
  return 0.1 + (0.001 - 0.1) * gloss;
}

/* A tailed lobe of the fit replaced by its GGX (r, F0 in place), in air or,
 * when film is not NULL ({F0_1, τ}), under M4's film. At γ = 2 the lobe is
 * GGX and the model equals its twin to the bit (test_tailed_rungs), so the
 * identity is written without a fit and its loss is 0. */
static cf_status material_tailed_lobe(export_material *m, const char *name, const double *film,
                                      double *r, double *f0, cf_error *err) {
  export_tailed_lobe *lobe = &m->lobes[m->lobe_count++];
  snprintf(lobe->name, sizeof lobe->name, "%s", name);
  lobe->r = lobe->r_ggx = *r;
  lobe->f0 = lobe->f0_ggx = *f0;
  lobe->rms_loss = 0.0;
  if (m->tail != 2.0) {
    cf_tailed_ggx ggx;
    cf_status s = cf_tailed_ggx_default(*r, m->tail, *f0, film, &ggx, err);
    if (s != CF_OK) {
      cf_error_prefix(err, "%s", film ? "the base's lobe" : name);
      return s;
    }
    lobe->r_ggx = ggx.r;
    lobe->f0_ggx = ggx.f0;
    lobe->rms_loss = ggx.rms_loss;
  }
  *r = lobe->r_ggx;
  *f0 = lobe->f0_ggx;
  return CF_OK;
}

/* M4T's lobes: the film's in air; the base's where the model sees it, at
 * the refracted directions under the fitted film (cf_tailed_ggx_default with
 * the film, τ the channels' mean): fitted as if in air instead, its GGX misses the
 * lobe under the film by 16-41 % RMS where this fit, the best GGX there,
 * misses it by 1-4 % (tests/export/test_tailed_base.c, docs/presets.md). */
static cf_status material_clay_lobes(export_material *m, cf_error *err) {
  if (m->info->tail_slot < 0) return CF_OK;
  const double film[2] = {m->film_f0, (m->tau[0] + m->tau[1] + m->tau[2]) / 3.0};
  double eta1 = export_ior_from_f0(film[0]);
  char base[192];
  snprintf(base, sizeof base,
           "the base's lobe (fitted where the model sees it: under the film, at the refracted "
           "directions c' >= %.3g, weighted by the film's transmission)",
           sqrt(1.0 - 1.0 / (eta1 * eta1)));
  cf_status s =
      material_tailed_lobe(m, "the film's lobe", NULL, &m->film_roughness, &m->film_f0, err);
  if (s != CF_OK) return s;
  return material_tailed_lobe(m, base, film, &m->base_roughness, &m->base_f0, err);
}

cf_status export_material_from_fit(const cf_fit_file *fit, export_material *m, cf_error *err) {
  memset(m, 0, sizeof *m);
  const double *p = fit->result.params;
  m->info = cf_model_info_get(fit->result.model);
  /* a tailed twin's vector is its GGX twin's plus the tail: the twin's
   * slot constants read it */
  m->model = m->info->ggx_twin;
  m->tail = m->info->tail_slot >= 0 ? p[m->info->tail_slot] : 2.0;
  for (int c = 0; c < 3; ++c) m->albedo[c] = p[c]; /* albedo is slot 0 of every model */
  m->sigma = m->model == CF_MODEL_LAMBERT ? 0.0 : p[CF_OREN_NAYAR_DIFFUSE_ROUGHNESS];
  cf_status s = CF_OK;
  if (m->model == CF_MODEL_DIELECTRIC || m->model == CF_MODEL_CLEARCOAT) {
    m->roughness = p[CF_DIELECTRIC_ROUGHNESS];
    m->f0 = p[CF_DIELECTRIC_F0];
    if (m->info->tail_slot >= 0)
      s = material_tailed_lobe(m, "the specular lobe", NULL, &m->roughness, &m->f0, err);
    m->ior = export_ior_from_f0(m->f0);
  }
  if (m->model == CF_MODEL_CLEARCOAT) {
    m->coat_weight = p[CF_CLEARCOAT_COAT_WEIGHT];
    m->coat_gloss = p[CF_CLEARCOAT_COAT_GLOSS];
    m->gtr1_a = export_gtr1_width(m->coat_gloss);
    m->ggx_coat_weight = 0.25 * m->coat_weight;
    m->ggx_coat_roughness = sqrt(m->gtr1_a);
  }
  if (m->model == CF_MODEL_CLAY) {
    m->film_roughness = p[CF_CLAY_FILM_ROUGHNESS];
    m->film_f0 = p[CF_CLAY_FILM_F0];
    for (int c = 0; c < 3; ++c) {
      m->tau[c] = p[CF_CLAY_OPTICAL_DEPTH + c];
      m->transmittance[c] = exp(-2.0 * m->tau[c]);
    }
    m->base_roughness = p[CF_CLAY_BASE_ROUGHNESS];
    m->base_f0 = p[CF_CLAY_BASE_F0];
    s = material_clay_lobes(m, err);
    m->film_ior = export_ior_from_f0(m->film_f0);
    m->base_ior_rel = export_ior_from_f0(m->base_f0);
    m->base_ior_abs = m->film_ior * m->base_ior_rel;
  }
  return s;
}

void export_common_notes(preset_notes *n, const export_material *m) {
  preset_note(n, PRESET_EXACT,
              "albedo %.6g, %.6g, %.6g (linear RGB) -> the diffuse colour; clayfit's "
              "roughness is perceptual (GGX alpha = r^2): each target's convention is given "
              "with its input below",
              m->albedo[0], m->albedo[1], m->albedo[2]);
  /* the tailed lobes first: every value below is their GGX's */
  for (int k = 0; k < m->lobe_count; ++k) {
    const export_tailed_lobe *lobe = &m->lobes[k];
    export_note_tailed(n, lobe->name, lobe->r, m->tail, lobe->f0, lobe->r_ggx, lobe->f0_ggx,
                       lobe->rms_loss);
  }
  if (m->model == CF_MODEL_CLAY)
    preset_note(n, PRESET_APPROX,
                "film optical depth tau %.6g, %.6g, %.6g -> coat colour exp(-2 tau) = %.6g, "
                "%.6g, %.6g, the film's round-trip transmittance at normal incidence; no target "
                "models absorption along the refracted paths exp(-tau (1/c_i' + 1/c_o')) nor "
                "the recycling K of light reflected back down by the film",
                m->tau[0], m->tau[1], m->tau[2], m->transmittance[0], m->transmittance[1],
                m->transmittance[2]);
  if (m->model == CF_MODEL_CLAY)
    preset_note(n, PRESET_APPROX,
                "base_f0 %.6g is the film-to-clay reflectance: relative IOR %.6g; the clay's "
                "IOR in air is film IOR x relative IOR = %.6g x %.6g = %.6g",
                m->base_f0, m->base_ior_rel, m->film_ior, m->base_ior_rel, m->base_ior_abs);
}

/* ---- a tailed lobe in GGX (clayfit/tailed_ggx.h; docs/presets.md, "Tailed lobes in
 * GGX-only formats"): its note ---- */

void export_ggx_loss_text(double rms_loss, char *text, size_t size) {
  if (rms_loss == 0.0) /* GGX itself (tail 2), or no lobe (F0 0) */
    snprintf(text, size, "GGX approximation: 0 %% RMS over the lobe");
  else if (rms_loss < 0.0005)
    snprintf(text, size, "GGX approximation: < 0.1 %% RMS over the lobe");
  else
    snprintf(text, size, "GGX approximation: %.1f %% RMS over the lobe", 100.0 * rms_loss);
}

void export_note_tailed(preset_notes *n, const char *lobe, double r, double gamma, double f0,
                        double r_ggx, double f0_ggx, double rms_loss) {
  char loss[96];
  export_ggx_loss_text(rms_loss, loss, sizeof loss);
  if (gamma == 2.0) {
    preset_note(n, PRESET_EXACT,
                "%s: tail gamma 2 is GGX: roughness %.6g, F0 %.6g written as they are; %s", lobe, r,
                f0, loss);
    return;
  }
  preset_note(n, PRESET_APPROX,
              "%s: tailed (roughness %.6g, tail gamma %.6g, F0 %.6g) -> the GGX of least "
              "squares as a renderer sees it (docs/presets.md): roughness %.6g, F0 %.6g; %s",
              lobe, r, gamma, f0, r_ggx, f0_ggx, loss);
}

/* ---- the diffuse colour a target's diffuse needs ---- */

enum { DIFFUSE_QUADRATURE = 16, DIFFUSE_MAX_VARIANTS = 32 };

/* Accumulates sum w t^2, sum w t beta_k and sum w beta_k^2 (t the model's
 * diffuse times c_i, beta_k the target's per unit colour) over the metric. */
typedef struct diffuse_sums {
  double t2[3], tb[DIFFUSE_MAX_VARIANTS][3], bb[DIFFUSE_MAX_VARIANTS];
} diffuse_sums;

static cf_status diffuse_accumulate(const cf_fit_file *fit, export_diffuse_basis basis,
                                    const void *ctx, int variants, diffuse_sums *s) {
  enum { Q = DIFFUSE_QUADRATURE };
  cf_model_id model = fit->result.model;
  double lobe_params[CF_MAX_DIM];
  memcpy(lobe_params, fit->result.params, sizeof lobe_params);
  lobe_params[0] = lobe_params[1] = lobe_params[2] = 0.0; /* albedo: slot 0 of every model */
  double x[Q], w[Q];
  cf_gauss_legendre01(Q, x, w);
  const double n[3] = {0.0, 0.0, 1.0};
  for (int a = 0; a < Q; ++a) {
    double co = x[a], v[3] = {sqrt(1.0 - co * co), 0.0, co};
    for (int b = 0; b < Q; ++b) {
      double ci = x[b], si = sqrt(1.0 - ci * ci);
      for (int c = 0; c < Q; ++c) {
        double phi = CF_PI * x[c], l[3] = {si * cos(phi), si * sin(phi), ci};
        double weight = co * w[a] * w[b] * w[c], f[3], lobes[3];
        cf_status st = cf_eval(model, fit->result.params, n, l, v, f, NULL);
        if (st == CF_OK) st = cf_eval(model, lobe_params, n, l, v, lobes, NULL);
        if (st != CF_OK) return st;
        for (int k = 0; k < variants; ++k) {
          double beta = ci * basis(ctx, k, l, v);
          s->bb[k] += weight * beta * beta;
          for (int ch = 0; ch < 3; ++ch) s->tb[k][ch] += weight * beta * ci * (f[ch] - lobes[ch]);
        }
        for (int ch = 0; ch < 3; ++ch) {
          double t = ci * (f[ch] - lobes[ch]);
          s->t2[ch] += weight * t * t;
        }
      }
    }
  }
  return CF_OK;
}

/* The model's diffuse is what remains of f when the albedo is 0 removed:
 * every model's diffuse vanishes there and its lobes do not depend on the
 * albedo, so a lobe's misfit (a tail's GGX) stays out of the colour. */
cf_status export_fit_diffuse_colour(const cf_fit_file *fit, export_diffuse_basis basis,
                                    const void *ctx, int variants, const char *what,
                                    export_diffuse_colour *out, cf_error *err) {
  if (variants < 1 || variants > DIFFUSE_MAX_VARIANTS)
    return cf_error_set(err, CF_ERANGE, "%s: %d variants, at most %d", what, variants,
                        DIFFUSE_MAX_VARIANTS);
  diffuse_sums *s = calloc(1, sizeof *s);
  if (!s) return cf_error_set(err, CF_ENOMEM, "%s: out of memory", what);
  cf_status st = diffuse_accumulate(fit, basis, ctx, variants, s);
  if (st != CF_OK) {
    free(s);
    cf_error_set(err, st, "%s: the model's evaluation failed", what);
    return st;
  }
  /* the residual of the best colour of variant k: sum t^2 - (t.b)^2 / b.b */
  int best = 0;
  double best_e = INFINITY;
  for (int k = 0; k < variants; ++k) {
    double e = 0.0;
    for (int ch = 0; ch < 3; ++ch) e += s->t2[ch] - s->tb[k][ch] * s->tb[k][ch] / s->bb[k];
    if (e < best_e) best_e = e, best = k;
  }
  out->variant = best;
  for (int ch = 0; ch < 3; ++ch)
    out->colour[ch] = fmin(1.0, fmax(0.0, s->tb[best][ch] / s->bb[best]));
  double total = s->t2[0] + s->t2[1] + s->t2[2];
  out->loss = total > 0.0 ? sqrt(fmax(0.0, best_e) / total) : 0.0;
  free(s);
  return CF_OK;
}

/* ---- M3's clear coat (Burley's GTR1) as a GGX coat ---- */

enum { COAT_VIEWS = 24, COAT_THETAS = 64, COAT_PHIS = 32, COAT_STEPS = 40 };
#define COAT_THETA_SCALE 0.05 /* tan θ_h = s tan(π u / 2): nodes dense near the peak */

static double coat_schlick(double c) {
  double m = 1.0 - c;
  return 0.04 + 0.96 * m * m * m * m * m;
}

/* glTF's GGX coat per unit clearcoatFactor (three.js' BRDF_GGX_Clearcoat):
 * F_Schlick(0.04, 1, v.h) D V, height-correlated Smith, alpha = r^2. */
static double coat_ggx(double r, double ci, double co, double ch, double vh) {
  double a2 = r * r * r * r, d = ch * ch * (a2 - 1.0) + 1.0;
  double gv = ci * sqrt(co * co * (1.0 - a2) + a2), gl = co * sqrt(ci * ci * (1.0 - a2) + a2);
  return coat_schlick(vh) * a2 / (CF_PI * d * d) * 0.5 / (gv + gl);
}

static double coat_roughness(int k) {
  return 0.05 + 0.95 * k / (COAT_STEPS - 1);
}

/* Least squares over the sphere metric of docs/presets.md (a view of density
 * c_o, the light uniform over the hemisphere, pixels f c_i) with the light
 * reached through the half vector (dω_i = 4 (v.h) dω_h) so that the sharp
 * lobes are resolved: the model's coat (its f minus its f at coat_weight 0,
 * mean of the channels) against the GGX coat of roughness r_k times a weight
 * by closed form; the best r_k. */
cf_status export_coat_ggx_fit(const cf_fit_file *fit, double *weight, double *roughness,
                              double *loss, cf_error *err) {
  double xv[COAT_VIEWS], wv[COAT_VIEWS], xt[COAT_THETAS], wt[COAT_THETAS], xp[COAT_PHIS],
      wp[COAT_PHIS];
  cf_gauss_legendre01(COAT_VIEWS, xv, wv);
  cf_gauss_legendre01(COAT_THETAS, xt, wt);
  cf_gauss_legendre01(COAT_PHIS, xp, wp);
  double no_coat[CF_MAX_DIM], tt = 0.0, tb[COAT_STEPS] = {0}, bb[COAT_STEPS] = {0};
  memcpy(no_coat, fit->result.params, sizeof no_coat);
  no_coat[CF_CLEARCOAT_COAT_WEIGHT] = 0.0;
  const double n[3] = {0.0, 0.0, 1.0};
  for (int a = 0; a < COAT_VIEWS; ++a) {
    double co = xv[a], v[3] = {sqrt(1.0 - co * co), 0.0, co};
    for (int b = 0; b < COAT_THETAS; ++b) {
      double q = 0.5 * CF_PI * xt[b], tq = tan(q);
      double th = atan(COAT_THETA_SCALE * tq);
      double dth = COAT_THETA_SCALE * 0.5 * CF_PI / (cos(q) * cos(q)) /
                   (1.0 + COAT_THETA_SCALE * COAT_THETA_SCALE * tq * tq);
      for (int c = 0; c < COAT_PHIS; ++c) {
        double phi = CF_PI * xp[c]; /* [0, π]: the lobe is even in φ_h */
        double h[3] = {sin(th) * cos(phi), sin(th) * sin(phi), cos(th)};
        double vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
        double l[3] = {2.0 * vh * h[0] - v[0], 2.0 * vh * h[1] - v[1], 2.0 * vh * h[2] - v[2]};
        if (vh <= 0.0 || l[2] <= 1e-9) continue;
        double ci = l[2], f[3], base[3];
        double w = co * wv[a] * wt[b] * dth * sin(th) * CF_PI * wp[c] * 4.0 * vh;
        cf_status s = cf_eval(fit->result.model, fit->result.params, n, l, v, f, NULL);
        if (s == CF_OK) s = cf_eval(fit->result.model, no_coat, n, l, v, base, NULL);
        if (s != CF_OK)
          return cf_error_set(err, s, "the GGX coat fit: the model's evaluation failed");
        double t = ci * (f[0] + f[1] + f[2] - base[0] - base[1] - base[2]) / 3.0;
        tt += w * t * t;
        for (int k = 0; k < COAT_STEPS; ++k) {
          double g = ci * coat_ggx(coat_roughness(k), ci, co, h[2], vh);
          tb[k] += w * t * g;
          bb[k] += w * g * g;
        }
      }
    }
  }
  int best = 0;
  for (int k = 1; k < COAT_STEPS; ++k)
    if (tb[k] * tb[k] / bb[k] > tb[best] * tb[best] / bb[best]) best = k;
  *roughness = coat_roughness(best);
  *weight = fmax(0.0, tb[best] / bb[best]);
  *loss = tt > 0.0 ? sqrt(fmax(0.0, tt - tb[best] * tb[best] / bb[best]) / tt) : 0.0;
  return CF_OK;
}
