/* The physics of the mapping from the models of docs/model.md §3 to the targets'
 * inputs, and what the writers share (export_internal.h). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/file.h"
#include "export_internal.h"
#include "model/tailed.h"

/* ---- text ---- */

void export_printf(export_text *t, const char *format, ...) {
  if (t->failed) return;
  for (;;) {
    va_list args;
    va_start(args, format);
    size_t room = t->capacity - t->size;
    int n = vsnprintf(t->data ? t->data + t->size : NULL, t->data ? room : 0, format, args);
    va_end(args);
    if (n < 0) {
      t->failed = 1;
      return;
    }
    if (t->data && (size_t)n < room) {
      t->size += (size_t)n;
      return;
    }
    size_t capacity = t->capacity ? t->capacity * 2 : 4096;
    while (capacity < t->size + (size_t)n + 1) capacity *= 2;
    char *grown = realloc(t->data, capacity);
    if (!grown) {
      t->failed = 1;
      return;
    }
    t->data = grown;
    t->capacity = capacity;
  }
}

void export_escaped(export_text *t, text_escape_fn escape, const char *text) {
  if (t->failed) return;
  char *escaped = text_escape_alloc(escape, text);
  if (!escaped) {
    t->failed = 1;
    return;
  }
  export_printf(t, "%s", escaped);
  free(escaped);
}

void export_text_free(export_text *t) {
  free(t->data);
  t->data = NULL;
  t->size = t->capacity = 0;
}

cf_status export_text_write(export_text *t, const char *path, cf_error *err) {
  cf_status s = t->failed ? cf_error_set(err, CF_ENOMEM, "%s: out of memory", path)
                          : cf_write_file(path, t->data ? t->data : "", t->size, err);
  export_text_free(t);
  return s;
}

/* ---- notes ---- */

void export_note(export_notes *n, export_note_kind kind, const char *format, ...) {
  char text[512];
  va_list args;
  va_start(args, format);
  vsnprintf(text, sizeof text, format, args);
  va_end(args);
  if (n->count < EXPORT_MAX_NOTES) {
    n->kind[n->count] = kind;
    memcpy(n->text[n->count], text, sizeof text);
    ++n->count;
  }
  if (kind == EXPORT_RANGE && n->warnings && n->warnings->count < CF_EXPORT_MAX_WARNINGS) {
    snprintf(n->warnings->text[n->warnings->count], sizeof n->warnings->text[0], "%s: %s",
             n->format_name ? n->format_name : "export", text);
    ++n->warnings->count;
  }
}

void export_notes_write(export_text *t, const export_notes *n, const char *prefix) {
  static const char *const heading[] = {"maps exactly", "maps approximately", "dropped",
                                        "outside the target's range"};
  for (int kind = 0; kind < 4; ++kind) {
    int any = 0;
    for (int i = 0; i < n->count; ++i) {
      if ((int)n->kind[i] != kind) continue;
      if (!any) export_printf(t, "%s%s:\n", prefix, heading[kind]);
      any = 1;
      /* wrap at about 90 columns */
      const char *s = n->text[i];
      int first = 1;
      while (*s) {
        size_t len = strlen(s), cut = len;
        if (len > 84) {
          cut = 84;
          while (cut > 20 && s[cut] != ' ') --cut;
        }
        export_printf(t, "%s%s%.*s\n", prefix, first ? "  - " : "    ", (int)cut, s);
        s += cut;
        while (*s == ' ') ++s;
        first = 0;
      }
    }
  }
}

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
    cf_status s =
        film ? export_ggx_from_tailed_film(*r, m->tail, *f0, film[0], film[1], &lobe->r_ggx,
                                           &lobe->f0_ggx, &lobe->rms_loss, err)
             : export_ggx_from_tailed(*r, m->tail, *f0, &lobe->r_ggx, &lobe->f0_ggx,
                                      &lobe->rms_loss, err);
    if (s != CF_OK) {
      cf_error_prefix(err, "%s", film ? "the base's lobe" : name);
      return s;
    }
  }
  *r = lobe->r_ggx;
  *f0 = lobe->f0_ggx;
  return CF_OK;
}

/* M4T's lobes: the film's in air; the base's where the model sees it, at
 * the refracted directions under the fitted film (export_ggx_from_tailed_film,
 * τ the channels' mean): fitted as if in air instead, its GGX misses the
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

void export_provenance(export_text *t, const cf_fit_file *fit, const char *fit_path,
                       const char *prefix, text_escape_fn escape) {
  const cf_model_info *m = cf_model_info_get(fit->result.model);
  export_printf(t, "%sclayfit %s material preset: model %s (%s), fitted by clayfit ", prefix,
                CLAYFIT_EXPORT_VERSION, m->code, m->name);
  export_escaped(t, escape, fit->clayfit_version);
  export_printf(t, " on ");
  export_escaped(t, escape, fit->created);
  export_printf(t, "\n%sfit: ", prefix);
  export_escaped(t, escape, fit_path ? fit_path : "(not given)");
  export_printf(t, "; capture: ");
  export_escaped(t, escape, fit->capture_name);
  export_printf(t, " (");
  export_escaped(t, escape, fit->radiometry);
  export_printf(t, " radiometry, ");
  export_escaped(t, escape, fit->capture_path);
  export_printf(t, "); relative RMSE %.4g\n", fit->result.relative_rmse);
  export_printf(t,
                "%smodel: docs/model.md of clayfit %s, model version %d%s; mapping: "
                "docs/presets.md\n",
                prefix, CLAYFIT_EXPORT_VERSION, fit->model_version,
                fit->model_version < CF_MODEL_VERSION ? " (fitted with Schlick's Fresnel)" : "");
}

void export_common_notes(export_notes *n, const export_material *m) {
  export_note(n, EXPORT_EXACT,
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
    export_note(n, EXPORT_APPROX,
                "film optical depth tau %.6g, %.6g, %.6g -> coat colour exp(-2 tau) = %.6g, "
                "%.6g, %.6g, the film's round-trip transmittance at normal incidence; no target "
                "models absorption along the refracted paths exp(-tau (1/c_i' + 1/c_o')) nor "
                "the recycling K of light reflected back down by the film",
                m->tau[0], m->tau[1], m->tau[2], m->transmittance[0], m->transmittance[1],
                m->transmittance[2]);
  if (m->model == CF_MODEL_CLAY)
    export_note(n, EXPORT_APPROX,
                "base_f0 %.6g is the film-to-clay reflectance: relative IOR %.6g; the clay's "
                "IOR in air is film IOR x relative IOR = %.6g x %.6g = %.6g",
                m->base_f0, m->base_ior_rel, m->film_ior, m->base_ior_rel, m->base_ior_abs);
}

/* ---- a tailed lobe in GGX (docs/presets.md, "Tailed lobes in GGX-only formats") ----
 *
 * The metric: a camera sees a sphere lit by a distant point light from a
 * direction drawn uniformly over the sphere of directions. In the local frame
 * of a pixel, the view ω_o then has the density c_o dω_o (the sphere's
 * projected area) and the light ω_i the density dω_i over the upper
 * hemisphere; the pixel's radiance is f · c_i. So
 *   E(g) = ∫∫ (c_i (f_g − f_T))² dω_i c_o dω_o,   loss = √(E(g) / ∫∫ (c_i f_T)² dω_i c_o dω_o),
 * the relative RMS of those pixels over the lobe alone. The quadrature
 * (EXPORT_TAIL_QUADRATURE: 32 × 32 × 12 Gauss-Legendre points) runs over
 * the view's elevation ψ (c_o = sin ψ, tan ψ = r tan(π u / 2)) and, for
 * each view, over the half vector h (dω_i = 4 (o·h) dω_h): θ_h by
 * tan θ_h = α tan(π u / 2) (the nodes follow D's width α), φ_h over
 * [0, φ_max], where φ_max closes the region c_i > 0 (the integrand vanishes
 * there as c_i², so the rule stays spectral). */

/* export_internal.h */
void export_gauss_legendre01(int n, double *x, double *w) {
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = cos(CF_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p1 = 1.0, p2 = 0.0;
      for (int j = 1; j <= n; ++j) {
        double p3 = p2;
        p2 = p1;
        p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
      }
      dp = n * (z * p1 - p2) / (z * z - 1.0);
      double step = p1 / dp;
      z -= step;
      if (fabs(step) < 1e-15) break;
    }
    x[i] = 0.5 * (1.0 - z);
    x[n - 1 - i] = 0.5 * (1.0 + z);
    w[i] = w[n - 1 - i] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
}

/* The Fresnel of both lobes, the one switch: Schlick's or the exact
 * dielectric one of terms.h (docs/model.md (8)); F and ∂F/∂F0 at c_d. */
typedef struct tail_fresnel_prep {
  export_fresnel kind;
  cf_fresnel_eta eta; /* eta.f0: F0 for either kind */
} tail_fresnel_prep;

static tail_fresnel_prep tail_fresnel_prepare(export_fresnel kind, double f0) {
  tail_fresnel_prep p = {kind, fresnel_eta(f0)};
  return p;
}

static double tail_fresnel(const tail_fresnel_prep *p, double c_d, double *d_f0) {
  if (p->kind == EXPORT_FRESNEL_SCHLICK) {
    double w = schlick_weight(c_d);
    *d_f0 = 1.0 - w;
    return fresnel_schlick(p->eta.f0, w);
  }
  cf_fresnel f = fresnel_dielectric(&p->eta, c_d, fresnel_root(&p->eta, c_d));
  *d_f0 = f.d_f0;
  return f.value;
}

/* One quadrature node: its weight, the factor k of the residual (the
 * pixel's radiance is k·f: c_i in air), its geometry, the tailed lobe. */
typedef struct tail_node {
  double w, k, c_i, c_o, sin2_h, cos2_h, c_d, target;
} tail_node;

/* M4's base under the film (docs/model.md (23)-(26), (30)): the lobe's own
 * directions l', v' are the refracted ones, inside the cone c' >= c_min;
 * an outside pixel sees k·f with, changing variables (dω = η1² c'/c dω'),
 *   E = ∫∫ (k Δf)² dω_i' w_o dω_o',  k² = c_i c_i' T(c_i)² e^(−2τ/c_i'),
 *   w_o = c_o' T(c_o)² e^(−2τ/c_o'),
 * with c the outside cosine of c' and T = 1 − F(F0_1, c). The constants
 * a_tau's mean and 1/η1² drop out of the relative loss. */
typedef struct tail_film {
  cf_fresnel_eta eta1; /* the film's */
  double eta2, c_min, tau;
} tail_film;

static tail_film tail_film_prepare(double film_f0, double tau) {
  tail_film f = {fresnel_eta(film_f0), 0.0, 0.0, tau};
  f.eta2 = 1.0 + f.eta1.u;
  f.c_min = sqrt(f.eta1.u / f.eta2);
  return f;
}

/* c'·T(c)²·e^(−2τ/c') and, in *c_out, the outside cosine c; 0 outside the cone. */
static double tail_film_factor(const tail_film *f, double c_in, double *c_out) {
  double c2 = f->eta2 * c_in * c_in - f->eta1.u;
  *c_out = c2 > 0.0 ? sqrt(c2) : 0.0;
  if (!(*c_out > 0.0)) return 0.0;
  double t = 1.0 - fresnel_dielectric(&f->eta1, *c_out, fresnel_root(&f->eta1, *c_out)).value;
  return c_in * t * t * exp(-2.0 * f->tau / c_in);
}

typedef struct tail_problem {
  tail_node *nodes;
  size_t count;
  double energy; /* Σ w (c_i f_T)²: the loss's denominator */
  export_fresnel fresnel;
} tail_problem;

/* The half vectors of one view (c_o, weight w_o): appends the nodes where c_i > 0. */
static void tail_view_nodes(tail_problem *p, const cf_std_tail *t, const tail_fresnel_prep *fresnel,
                            const tail_film *film, double c_o, double w_o,
                            const export_tail_quadrature *q, const double *xu, const double *wu,
                            const double *xp, const double *wp) {
  double s_o = sqrt((1.0 - c_o) * (1.0 + c_o)), alpha = sqrt(t->a2);
  double l_o = cf_std_masking_eval(t, c_o, 0).value;
  /* under a film both directions are in the cone c' >= c_min, and so is h:
   * θ_h's nodes end there (u <= u_max). r 1 under η1 3 (F0_1 0.25): doubling
   * the quadrature moved the loss by 1.9 % with nodes up to 90°, 4e-5 so */
  double u_max = 1.0;
  if (film)
    u_max = 2.0 / CF_PI * atan(sqrt(1.0 - film->c_min * film->c_min) / (film->c_min * alpha));
  for (int a = 0; a < q->thetas; ++a) {
    double tu = tan(0.5 * CF_PI * u_max * xu[a]), tan_h = alpha * tu, tan2 = tan_h * tan_h;
    double dtheta = u_max * alpha * 0.5 * CF_PI * (1.0 + tu * tu) / (1.0 + tan2);
    double cos2_h = 1.0 / (1.0 + tan2), sin2_h = tan2 * cos2_h;
    double c_h = sqrt(cos2_h), s_h = tan_h * c_h;
    /* c_i > 0  <=>  cos φ > −c_o cos 2θ_h / (s_o sin 2θ_h) = num / den */
    double num = -c_o * (cos2_h - sin2_h), den = 2.0 * s_o * s_h * c_h;
    if (num >= den) continue; /* no φ lights this h */
    double phi_max = num <= -den ? CF_PI : acos(num / den);
    for (int b = 0; b < q->phis; ++b) {
      double phi = phi_max * xp[b];
      double c_d = s_o * s_h * cos(phi) + c_o * c_h, c_i = 2.0 * c_d * c_h - c_o;
      if (!(c_i > 0.0) || !(c_d > 0.0)) continue;
      double k = c_i, c_out;
      if (film) {
        k = tail_film_factor(film, c_i, &c_out);
        if (!(k > 0.0)) continue; /* outside the cone: no outside light reaches it */
        k = sqrt(k * c_out);
      }
      tail_node *n = &p->nodes[p->count++];
      n->k = k;
      /* view · θ_h (dθ/du, sin θ_h) · φ (both signs) · dω_i/dω_h */
      n->w = w_o * wu[a] * dtheta * s_h * 2.0 * phi_max * wp[b] * 4.0 * c_d;
      n->c_i = c_i;
      n->c_o = c_o;
      n->sin2_h = sin2_h;
      n->cos2_h = cos2_h;
      n->c_d = c_d;
      /* V of (T6), 0.5 / (c_o L_i + c_i L_o), with L_o once per view: the
       * masking's continued fraction is half the cost of a call */
      double vis = 0.5 / (c_o * cf_std_masking_eval(t, c_i, 0).value + c_i * l_o), d_f0;
      double dv = std_d(t, sin2_h, cos2_h).value * vis;
      n->target = tail_fresnel(fresnel, c_d, &d_f0) * dv;
      double e = k * n->target;
      p->energy += n->w * e * e;
    }
  }
}

static cf_status tail_problem_build(tail_problem *p, double r, double gamma, double f0,
                                    export_fresnel fresnel, const tail_film *film,
                                    const export_tail_quadrature *q, cf_error *err) {
  size_t max_nodes = (size_t)q->views * (size_t)q->thetas * (size_t)q->phis;
  int max_rule = q->views > q->thetas ? q->views : q->thetas;
  max_rule = max_rule > q->phis ? max_rule : q->phis;
  memset(p, 0, sizeof *p);
  p->fresnel = fresnel;
  p->nodes = malloc(max_nodes * sizeof *p->nodes);
  double *rules = malloc(6 * (size_t)max_rule * sizeof *rules);
  if (!p->nodes || !rules) {
    free(p->nodes);
    free(rules);
    p->nodes = NULL;
    return cf_error_set(err, CF_ENOMEM, "GGX fit of a tailed lobe: out of memory");
  }
  double *xo = rules, *wo = xo + max_rule, *xu = wo + max_rule, *wu = xu + max_rule;
  double *xp = wu + max_rule, *wp = xp + max_rule;
  export_gauss_legendre01(q->views, xo, wo);
  export_gauss_legendre01(q->thetas, xu, wu);
  export_gauss_legendre01(q->phis, xp, wp);
  cf_std_tail t = cf_std_tail_prepare(r * r * r * r, gamma);
  tail_fresnel_prep fr = tail_fresnel_prepare(fresnel, f0);
  /* views by their elevation ψ (c_o = sin ψ): tan ψ = r tan(π u / 2). A
   * sharp lobe changes over c_o ~ α at grazing and is flat above; the scale
   * r = √α, between the two, needs 32 views where uniform c_o needs 100
   * and the scale α misses the normal views (the doubling test). Under a
   * film, c_o' in [c_min, 1], no grazing view: uniform in c_o'. */
  for (int v = 0; v < q->views && film; ++v) {
    double c_o = film->c_min + (1.0 - film->c_min) * xo[v], c_out;
    double w_o = 2.0 * CF_PI * (1.0 - film->c_min) * wo[v] * tail_film_factor(film, c_o, &c_out);
    if (w_o > 0.0) tail_view_nodes(p, &t, &fr, film, c_o, w_o, q, xu, wu, xp, wp);
  }
  for (int v = 0; v < q->views && !film; ++v) {
    double tu = tan(0.5 * CF_PI * xo[v]), tan_psi = r * tu;
    double dpsi = r * 0.5 * CF_PI * (1.0 + tu * tu) / (1.0 + tan_psi * tan_psi);
    double cos_psi = 1.0 / sqrt(1.0 + tan_psi * tan_psi), c_o = tan_psi * cos_psi;
    /* c_o dω_o = 2π c_o dc_o, dc_o = cos ψ dψ */
    double w_o = 2.0 * CF_PI * c_o * cos_psi * dpsi * wo[v];
    tail_view_nodes(p, &t, &fr, NULL, c_o, w_o, q, xu, wu, xp, wp);
  }
  free(rules);
  return CF_OK;
}

/* E(g) / energy at GGX (r, f0), with its gradient and Gauss-Newton Hessian
 * (JᵀJ) in (r, f0) when grad is not NULL. */
static double tail_cost(const tail_problem *p, double r, double f0, double *grad, double *hess) {
  double a2 = r * r * r * r, inv_a2 = 1.0 / a2, da2_dr = 4.0 * r * r * r;
  double sum = 0.0, g0 = 0.0, g1 = 0.0, h00 = 0.0, h01 = 0.0, h11 = 0.0;
  tail_fresnel_prep fresnel = tail_fresnel_prepare(p->fresnel, f0);
  for (size_t k = 0; k < p->count; ++k) {
    const tail_node *n = &p->nodes[k];
    cf_ggx_d d = ggx_d(a2, inv_a2, n->sin2_h, n->cos2_h);
    cf_smith_v v = smith_ggx_v(a2, n->c_i, n->c_o);
    double df, fr = tail_fresnel(&fresnel, n->c_d, &df);
    double res = n->k * (fr * (d.value * v.value) - n->target); /* target's order */
    sum += n->w * res * res;
    if (!grad) continue;
    double j0 = n->k * fr * (d.d_a2 * v.value + d.value * v.d_a2) * da2_dr;
    double j1 = n->k * df * d.value * v.value;
    g0 += n->w * j0 * res;
    g1 += n->w * j1 * res;
    h00 += n->w * j0 * j0;
    h01 += n->w * j0 * j1;
    h11 += n->w * j1 * j1;
  }
  double inv_e = 1.0 / p->energy;
  if (grad) {
    grad[0] = g0 * inv_e;
    grad[1] = g1 * inv_e;
    hess[0] = h00 * inv_e;
    hess[1] = h01 * inv_e;
    hess[2] = h11 * inv_e;
  }
  return sum * inv_e;
}

/* Levenberg-Marquardt over (r, F0) in the box [lo, hi] (Marquardt's
 * diagonal scaling; a parameter at a bound that the gradient pushes out is
 * held for that step). x: the start, then the minimum; returns the cost. */
static double tail_lm(const tail_problem *p, const double lo[2], const double hi[2], double x[2],
                      int *iterations, double *start_cost) {
  double g[2], h[3], lambda = 1e-3;
  double cost = tail_cost(p, x[0], x[1], g, h);
  *start_cost = cost;
  int it = 0;
  for (; it < 200 && cost > 0.0; ++it) {
    int free0 = !((x[0] <= lo[0] && g[0] > 0.0) || (x[0] >= hi[0] && g[0] < 0.0));
    int free1 = !((x[1] <= lo[1] && g[1] > 0.0) || (x[1] >= hi[1] && g[1] < 0.0));
    double a = h[0] * (1.0 + lambda) + 1e-300, d = h[2] * (1.0 + lambda) + 1e-300;
    double step[2] = {0.0, 0.0};
    if (free0 && free1) {
      double det = a * d - h[1] * h[1];
      step[0] = (-g[0] * d + g[1] * h[1]) / det;
      step[1] = (-g[1] * a + g[0] * h[1]) / det;
    } else if (free0) {
      step[0] = -g[0] / a;
    } else if (free1) {
      step[1] = -g[1] / d;
    } else {
      break; /* a corner that holds the minimum */
    }
    double trial[2], gt[2], ht[3];
    for (int k = 0; k < 2; ++k) {
      trial[k] = x[k] + step[k];
      trial[k] = trial[k] < lo[k] ? lo[k] : trial[k] > hi[k] ? hi[k] : trial[k];
    }
    /* F0 goes at most 90 % of the way to 0 in a step: the dielectric
     * Fresnel's ∂F/∂F0 grows like 1/c⁴ at F0 = 0, so a step that lands
     * there stalls (r 0.3, γ 1.51 stopped at F0 0, loss 100 %) */
    if (trial[1] < 0.1 * x[1]) trial[1] = 0.1 * x[1];
    double c = tail_cost(p, trial[0], trial[1], gt, ht);
    if (!(c < cost)) {
      lambda *= 10.0;
      if (lambda > 1e12) break; /* no descent left at machine precision */
      continue;
    }
    double decrease = cost - c;
    /* Gauss-Newton converges linearly here (the residual is not 0, ratio
     * about 0.3 a step): stop once a step moves both parameters by < 1e-5
     * relative, below the quadrature's own error (3e-5), when the step was
     * Gauss-Newton's (λ small, not shortened by rejections) */
    int small = lambda <= 1e-2 && fabs(trial[0] - x[0]) <= 1e-5 * x[0] &&
                fabs(trial[1] - x[1]) <= 1e-5 * (x[1] > 1e-3 ? x[1] : 1e-3);
    memcpy(x, trial, sizeof trial);
    memcpy(g, gt, sizeof gt);
    memcpy(h, ht, sizeof ht);
    cost = c;
    lambda = lambda > 1e-9 ? 0.1 * lambda : lambda;
    if (small || decrease <= 1e-12 * cost) break;
  }
  *iterations = it;
  return cost;
}

static cf_status tail_check(double r, double gamma, double f0, cf_error *err) {
  const cf_param_info *rr = cf_param_info_get(CF_PARAM_ROUGHNESS);
  const cf_param_info *ff = cf_param_info_get(CF_PARAM_F0);
  if (!(r >= rr->lower && r <= rr->upper))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe: roughness %g is outside [%g, %g] (the "
                        "parameter table's range of r)",
                        r, rr->lower, rr->upper);
  if (!(f0 >= ff->lower && f0 <= ff->upper))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe: F0 %g is outside [%g, %g] (the parameter "
                        "table's range of F0)",
                        f0, ff->lower, ff->upper);
  if (!isfinite(gamma))
    return cf_error_set(err, CF_ERANGE, "GGX fit of a tailed lobe: tail gamma %g is not finite",
                        gamma);
  if (!(gamma > CF_STD_GAMMA_MIN))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe: tail gamma %g must be above %g (at and below "
                        "it the STD lobe has no finite masking)",
                        gamma, CF_STD_GAMMA_MIN);
  return CF_OK;
}

static cf_status tail_fit(double r, double gamma, double f0, export_fresnel fresnel,
                          const tail_film *film, const export_tail_quadrature *q,
                          const double start[2], export_tail_fit *out, cf_error *err) {
  memset(out, 0, sizeof *out);
  cf_status s = tail_check(r, gamma, f0, err);
  if (s != CF_OK) return s;
  if (q->views < 1 || q->thetas < 1 || q->phis < 1 || q->views > 256 || q->thetas > 256 ||
      q->phis > 256) /* 256³ points: 0.9 GB */
    return cf_error_set(err, CF_EINVAL,
                        "GGX fit of a tailed lobe: quadrature %d x %d x %d outside [1, 256]",
                        q->views, q->thetas, q->phis);
  double x[2] = {start ? start[0] : r, start ? start[1] : f0};
  if (tail_check(x[0], 2.0, x[1], err) != CF_OK) {
    cf_error_prefix(err, "the start");
    return CF_ERANGE;
  }
  tail_problem p;
  if ((s = tail_problem_build(&p, r, gamma, f0, fresnel, film, q, err)) != CF_OK) return s;
  out->nodes = p.count;
  if (!(p.energy > 0.0)) { /* F ≡ 0 (the dielectric Fresnel at F0 = 0): nothing to fit */
    out->r = r;
    out->f0 = f0;
    free(p.nodes);
    return CF_OK;
  }
  const double lo[2] = {cf_param_info_get(CF_PARAM_ROUGHNESS)->lower,
                        cf_param_info_get(CF_PARAM_F0)->lower};
  const double hi[2] = {cf_param_info_get(CF_PARAM_ROUGHNESS)->upper,
                        cf_param_info_get(CF_PARAM_F0)->upper};
  int naive_start = x[0] == r && x[1] == f0;
  double start_cost;
  double cost = tail_lm(&p, lo, hi, x, &out->iterations, &start_cost);
  /* F0 = 0 itself, which tail_lm's steps only approach: near γ = 1.5 the
   * lobe is almost 0 and so is the best GGX (r 1, γ 1.5000001: loss 1
   * there, 204 at the F0 of 4e-10 where the steps stopped) */
  double at_zero = tail_cost(&p, x[0], lo[1], NULL, NULL);
  if (at_zero < cost) {
    x[1] = lo[1];
    cost = at_zero;
  }
  out->rms_loss = sqrt(cost);
  out->naive_loss = sqrt(naive_start ? start_cost : tail_cost(&p, r, f0, NULL, NULL));
  out->r = x[0];
  out->f0 = x[1];
  free(p.nodes);
  if (!isfinite(out->rms_loss))
    return cf_error_set(err, CF_ENUMERIC,
                        "GGX fit of a tailed lobe (r %g, gamma %g, F0 %g): the loss is not finite",
                        r, gamma, f0);
  return CF_OK;
}

cf_status export_tail_fit_ggx(double r, double gamma, double f0, export_fresnel fresnel,
                              const export_tail_quadrature *q, const double start[2],
                              export_tail_fit *out, cf_error *err) {
  return tail_fit(r, gamma, f0, fresnel, NULL, q, start, out, err);
}

cf_status export_tail_fit_ggx_film(double r, double gamma, double f0, double film_f0, double tau,
                                   export_fresnel fresnel, const export_tail_quadrature *q,
                                   const double start[2], export_tail_fit *out, cf_error *err) {
  const cf_param_info *ff = cf_param_info_get(CF_PARAM_FILM_F0);
  const cf_param_info *tt = cf_param_info_get(CF_PARAM_OPTICAL_DEPTH);
  memset(out, 0, sizeof *out);
  if (!(film_f0 >= ff->lower && film_f0 <= ff->upper) || !(tau >= tt->lower && tau <= tt->upper))
    return cf_error_set(err, CF_ERANGE,
                        "GGX fit of a tailed lobe under a film: film F0 %g or optical depth %g "
                        "outside [%g, %g], [%g, %g] (the parameter table's ranges)",
                        film_f0, tau, ff->lower, ff->upper, tt->lower, tt->upper);
  tail_film film = tail_film_prepare(film_f0, tau);
  return tail_fit(r, gamma, f0, fresnel, &film, q, start, out, err);
}

cf_status export_ggx_from_tailed_film(double r, double gamma, double f0, double film_f0, double tau,
                                      double *r_ggx, double *f0_ggx, double *rms_loss,
                                      cf_error *err) {
  export_tail_fit fit;
  const export_tail_quadrature q = EXPORT_TAIL_QUADRATURE;
  cf_status s = export_tail_fit_ggx_film(r, gamma, f0, film_f0, tau, EXPORT_FRESNEL_MODELS, &q,
                                         NULL, &fit, err);
  if (s != CF_OK) return s;
  *r_ggx = fit.r;
  *f0_ggx = fit.f0;
  *rms_loss = fit.rms_loss;
  return CF_OK;
}

cf_status export_ggx_from_tailed(double r, double gamma, double f0, double *r_ggx, double *f0_ggx,
                                 double *rms_loss, cf_error *err) {
  export_tail_fit fit;
  const export_tail_quadrature q = EXPORT_TAIL_QUADRATURE;
  cf_status s = export_tail_fit_ggx(r, gamma, f0, EXPORT_FRESNEL_MODELS, &q, NULL, &fit, err);
  if (s != CF_OK) return s;
  *r_ggx = fit.r;
  *f0_ggx = fit.f0;
  *rms_loss = fit.rms_loss;
  return CF_OK;
}

void export_ggx_loss_text(double rms_loss, char *text, size_t size) {
  if (rms_loss == 0.0) /* GGX itself (tail 2), or no lobe (F0 0) */
    snprintf(text, size, "GGX approximation: 0 %% RMS over the lobe");
  else if (rms_loss < 0.0005)
    snprintf(text, size, "GGX approximation: < 0.1 %% RMS over the lobe");
  else
    snprintf(text, size, "GGX approximation: %.1f %% RMS over the lobe", 100.0 * rms_loss);
}

void export_note_tailed(export_notes *n, const char *lobe, double r, double gamma, double f0,
                        double r_ggx, double f0_ggx, double rms_loss) {
  char loss[96];
  export_ggx_loss_text(rms_loss, loss, sizeof loss);
  if (gamma == 2.0) {
    export_note(n, EXPORT_EXACT,
                "%s: tail gamma 2 is GGX: roughness %.6g, F0 %.6g written as they are; %s", lobe, r,
                f0, loss);
    return;
  }
  export_note(n, EXPORT_APPROX,
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
  export_gauss_legendre01(Q, x, w);
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
  export_gauss_legendre01(COAT_VIEWS, xv, wv);
  export_gauss_legendre01(COAT_THETAS, xt, wt);
  export_gauss_legendre01(COAT_PHIS, xp, wp);
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
