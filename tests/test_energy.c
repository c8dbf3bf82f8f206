/* Energy (docs/model.md §4.3, (33)): with ρ = 1 the
 * directional albedo ∫ f c_i dω is <= 1 + 1e-3 for M0, M2 and M4 and
 * <= 1.016 for M1 at 8 view angles down to c_o = 0.01, over extreme and
 * random in-range parameter sets; M3's maximum is printed, not asserted.
 *
 * The integral is estimated by multiple importance sampling (Veach 1997,
 * balance heuristic, deterministic sample allocation) of
 *   - the cosine and the uniform hemisphere (diffuse lobes; Oren-Nayar's
 *     angular factor grows like 1/max(c_i, c_o) toward grazing while f c_i
 *     stays bounded),
 *   - each GGX lobe by its visible normals (Heitz 2018); M4's base lobe is
 *     sampled in the film around the refracted view and refracted out,
 *     with pdf(l) = pdf(l') c_i / (η1² c_i') (Veach 1997, §5.2),
 *   - Burley's GTR1 lobe for M3 (Burley 2012, B.2).
 * Plain quadrature misses the narrow lobes at r = 0.03 (α = 9e-4).
 *
 * The estimator is itself checked: for every strategy, the MIS estimate of
 * ∫ pdf_k dω must equal the fraction of strategy-k samples that were valid
 * (above the horizon, not totally reflected in the film), which it only
 * does when each pdf matches its sampler. */
#include <math.h>
#include <string.h>

#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { RANDOM_SETS = 16, MAX_STRATEGIES = 4 };
static const double view_cosines[8] = {1.0, 0.8, 0.6, 0.4, 0.2, 0.1, 0.03, 0.01};
static const double max_standard_error = 2.5e-4;

typedef struct vec3 {
  double x, y, z;
} vec3;

static vec3 v3(double x, double y, double z) {
  return (vec3){x, y, z};
}
static double dot(vec3 a, vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
static vec3 scale(vec3 a, double s) {
  return v3(a.x * s, a.y * s, a.z * s);
}
static vec3 add(vec3 a, vec3 b) {
  return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static vec3 normalize(vec3 a) {
  return scale(a, 1.0 / sqrt(dot(a, a)));
}
static vec3 cross(vec3 a, vec3 b) {
  return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static vec3 reflect(vec3 v, vec3 h) {
  return add(scale(h, 2.0 * dot(v, h)), scale(v, -1.0));
}

/* ---- the lobes' densities (z-up frame, n = (0, 0, 1)) ---- */

static double ggx_d(double a2, vec3 h) {
  double s2 = h.x * h.x + h.y * h.y, c2 = h.z * h.z;
  double q = s2 + a2 * c2;
  return a2 / (M_PI * q * q);
}

static double ggx_g1(double a2, double c) {
  return 2.0 * c / (c + sqrt(a2 + c * c * (1.0 - a2)));
}

/* Heitz 2018, "Sampling the GGX Distribution of Visible Normals", listing 1. */
static vec3 ggx_sample_visible_normal(double alpha, vec3 v, double u1, double u2) {
  vec3 vh = normalize(v3(alpha * v.x, alpha * v.y, v.z));
  double lensq = vh.x * vh.x + vh.y * vh.y;
  vec3 t1 = lensq > 0.0 ? scale(v3(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq)) : v3(1, 0, 0);
  vec3 t2 = cross(vh, t1);
  double r = sqrt(u1), phi = 2.0 * M_PI * u2;
  double p1 = r * cos(phi), p2 = r * sin(phi);
  double s = 0.5 * (1.0 + vh.z);
  p2 = (1.0 - s) * sqrt(1.0 - p1 * p1) + s * p2;
  vec3 nh =
      add(add(scale(t1, p1), scale(t2, p2)), scale(vh, sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2))));
  return normalize(v3(alpha * nh.x, alpha * nh.y, fmax(0.0, nh.z)));
}

/* pdf over l of reflecting v about a visible normal: G1(v) D(h) / (4 c_o). */
static double ggx_reflection_pdf(double a2, vec3 v, vec3 l) {
  if (l.z <= 0.0) return 0.0;
  vec3 h = normalize(add(l, v));
  return ggx_g1(a2, v.z) * ggx_d(a2, h) / (4.0 * v.z);
}

static double gtr1_d(double a2, vec3 h) {
  return (a2 - 1.0) / (M_PI * log(a2) * (1.0 + (a2 - 1.0) * h.z * h.z));
}

/* ---- refraction through the film of M4 (η >= 1: every outside direction
 * enters; inside, only directions with |l'_t| <= 1/η leave) ---- */

static vec3 refract_in(vec3 w, double eta) {
  double c = sqrt((eta * eta - 1.0) + w.z * w.z) / eta;
  return v3(w.x / eta, w.y / eta, c);
}

/* ---- the strategies ---- */

typedef enum strategy_kind { COSINE, UNIFORM, GGX_AIR, GGX_FILM, GTR1 } strategy_kind;

typedef struct strategy {
  strategy_kind kind;
  double a2, alpha; /* the lobe's α², α (a² for GTR1) */
} strategy;

typedef struct setup {
  cf_model_id model;
  const double *params;
  strategy strategies[MAX_STRATEGIES + 1];
  int count;
  double eta; /* M4's film */
} setup;

static double strategy_pdf(const setup *s, const strategy *k, vec3 v, vec3 l) {
  if (l.z <= 0.0) return 0.0;
  switch (k->kind) {
    case COSINE:
      return l.z / M_PI;
    case UNIFORM:
      return 0.5 / M_PI;
    case GGX_AIR:
      return ggx_reflection_pdf(k->a2, v, l);
    case GGX_FILM: {
      vec3 vf = refract_in(v, s->eta), lf = refract_in(l, s->eta);
      return ggx_reflection_pdf(k->a2, vf, lf) * l.z / (s->eta * s->eta * lf.z);
    }
    case GTR1: {
      vec3 h = normalize(add(l, v));
      return gtr1_d(k->a2, h) * h.z / (4.0 * dot(v, h));
    }
  }
  return 0.0;
}

/* Map (u1, u2) in [0, 1)² to l by strategy k; returns 0 when the draw
 * gives no valid direction. */
static int strategy_sample(const setup *s, const strategy *k, vec3 v, double u1, double u2,
                           vec3 *l) {
  switch (k->kind) {
    case COSINE: {
      double r = sqrt(u1), phi = 2.0 * M_PI * u2;
      *l = v3(r * cos(phi), r * sin(phi), sqrt(fmax(0.0, 1.0 - u1)));
      return l->z > 0.0;
    }
    case UNIFORM: {
      double sn = sqrt(fmax(0.0, 1.0 - u1 * u1)), phi = 2.0 * M_PI * u2;
      *l = v3(sn * cos(phi), sn * sin(phi), u1);
      return l->z > 0.0;
    }
    case GGX_AIR:
      *l = reflect(v, ggx_sample_visible_normal(k->alpha, v, u1, u2));
      return l->z > 0.0;
    case GGX_FILM: {
      vec3 vf = refract_in(v, s->eta);
      vec3 lf = reflect(vf, ggx_sample_visible_normal(k->alpha, vf, u1, u2));
      if (lf.z <= 0.0) return 0;
      double tx = s->eta * lf.x, ty = s->eta * lf.y, t2 = tx * tx + ty * ty;
      if (t2 >= 1.0) return 0; /* totally reflected at the film's top */
      *l = v3(tx, ty, sqrt(1.0 - t2));
      return 1;
    }
    case GTR1: {
      double c2 = (1.0 - pow(k->a2, 1.0 - u1)) / (1.0 - k->a2);
      double sn = sqrt(fmax(0.0, 1.0 - c2)), phi = 2.0 * M_PI * u2;
      vec3 h = v3(sn * cos(phi), sn * sin(phi), sqrt(c2));
      *l = reflect(v, h);
      return l->z > 0.0;
    }
  }
  return 0;
}

static void setup_strategies(setup *s) {
  const double *p = s->params;
  s->count = 0;
  s->strategies[s->count++] = (strategy){COSINE, 0, 0};
  /* Oren-Nayar's angular factor grows like 1/max(c_i, c_o) toward grazing;
   * f c_i stays bounded, so uniform sampling bounds its weight */
  if (s->model != CF_MODEL_LAMBERT) s->strategies[s->count++] = (strategy){UNIFORM, 0, 0};
  double r;
  switch (s->model) {
    case CF_MODEL_DIELECTRIC:
    case CF_MODEL_CLEARCOAT:
      r = p[CF_DIELECTRIC_ROUGHNESS];
      s->strategies[s->count++] = (strategy){GGX_AIR, r * r * r * r, r * r};
      if (s->model == CF_MODEL_CLEARCOAT) {
        double a = 0.1 + (0.001 - 0.1) * p[CF_CLEARCOAT_COAT_GLOSS];
        s->strategies[s->count++] = (strategy){GTR1, a * a, a};
      }
      break;
    case CF_MODEL_CLAY: {
      r = p[CF_CLAY_FILM_ROUGHNESS];
      s->strategies[s->count++] = (strategy){GGX_AIR, r * r * r * r, r * r};
      r = p[CF_CLAY_BASE_ROUGHNESS];
      s->strategies[s->count++] = (strategy){GGX_FILM, r * r * r * r, r * r};
      double sq = sqrt(p[CF_CLAY_FILM_F0]);
      s->eta = (1.0 + sq) / (1.0 - sq);
      break;
    }
    default:
      break;
  }
}

typedef struct estimate {
  double albedo[3], standard_error[3];
  double pdf_z[MAX_STRATEGIES + 1]; /* |∫ pdf_k − P(valid_k)| / its error */
} estimate;

/* MIS estimate of ∫ f c_i dω for view cosine c_o, with every strategy
 * drawing GRID² jittered-stratified samples in each of REPLICATES
 * independent replicates; the standard error comes from the spread of the
 * replicates, which stays honest under stratification. */
enum { GRID = 32, REPLICATES = 16, MAX_REPLICATES = 256 };

static estimate directional_albedo(const setup *s, double c_o, int replicates, cf_rng *rng) {
  const double n[3] = {0.0, 0.0, 1.0};
  vec3 v = v3(sqrt((1.0 - c_o) * (1.0 + c_o)), 0.0, c_o);
  const double weight = 1.0 / s->count;
  const double per_replicate = (double)s->count * GRID * GRID;
  static double rep[MAX_REPLICATES][3 + MAX_STRATEGIES + 1];
  memset(rep, 0, sizeof rep);
  for (int r = 0; r < replicates; ++r) {
    for (int k = 0; k < s->count; ++k) {
      for (int cell = 0; cell < GRID * GRID; ++cell) {
        double u1 = ((cell / GRID) + cf_rng_uniform(rng)) / GRID;
        double u2 = ((cell % GRID) + cf_rng_uniform(rng)) / GRID;
        vec3 l;
        if (!strategy_sample(s, &s->strategies[k], v, u1, u2, &l)) continue;
        /* the valid draw counts against strategy k's ∫ pdf_k estimate */
        rep[r][3 + k] -= (double)s->count / per_replicate;
        double mixture = 0.0, pdf[MAX_STRATEGIES + 1];
        for (int j = 0; j < s->count; ++j) {
          pdf[j] = strategy_pdf(s, &s->strategies[j], v, l);
          mixture += weight * pdf[j];
        }
        if (!(mixture > 0.0)) continue;
        double f[3], lv[3] = {l.x, l.y, l.z}, vv[3] = {v.x, v.y, v.z};
        cf_eval(s->model, s->params, n, lv, vv, f, NULL);
        for (int c = 0; c < 3; ++c) rep[r][c] += f[c] * l.z / mixture / per_replicate;
        for (int j = 0; j < s->count; ++j) rep[r][3 + j] += pdf[j] / mixture / per_replicate;
      }
    }
  }
  estimate e;
  memset(&e, 0, sizeof e);
  for (int c = 0; c < 3 + s->count; ++c) {
    double mean = 0.0, var = 0.0;
    for (int r = 0; r < replicates; ++r) mean += rep[r][c] / replicates;
    for (int r = 0; r < replicates; ++r)
      var += (rep[r][c] - mean) * (rep[r][c] - mean) / (replicates - 1);
    double standard_error = sqrt(var / replicates);
    if (c < 3) {
      e.albedo[c] = mean;
      e.standard_error[c] = standard_error;
    } else {
      e.pdf_z[c - 3] = fabs(mean) / (standard_error + 1e-9);
    }
  }
  return e;
}

typedef struct model_summary {
  double max_albedo, max_albedo_error, max_error, worst_pdf_z;
  double max_params[CF_MAX_DIM], max_view;
  long estimates, refined;
} model_summary;

static int needs_refinement(const estimate *e, double bound) {
  for (int c = 0; c < 3; ++c)
    if (e->standard_error[c] > max_standard_error &&
        e->albedo[c] + 6.0 * e->standard_error[c] >= bound)
      return 1;
  return 0;
}

static void check_params(cf_model_id model, const double *params, cf_rng *rng,
                         model_summary *summary) {
  double p[CF_MAX_DIM];
  memcpy(p, params, sizeof p);
  for (int c = 0; c < 3; ++c) p[c] = 1.0; /* albedo is slot 0..2 in every model */
  setup s = {.model = model, .params = p};
  setup_strategies(&s);
  const double bound = model == CF_MODEL_OREN_NAYAR ? 1.016 : 1.0 + 1e-3;
  const char *code = cf_model_info_get(model)->code;
  for (int j = 0; j < 8; ++j) {
    /* Where an estimate comes within 6 standard errors of the bound, refine
     * it with 4x the replicates until its error is at most
     * max_standard_error: the bound is then decided with an error well
     * under 1e-3. Far below the bound the first estimate settles it. */
    int replicates = REPLICATES;
    estimate e = directional_albedo(&s, view_cosines[j], replicates, rng);
    while (model != CF_MODEL_CLEARCOAT && replicates < MAX_REPLICATES &&
           needs_refinement(&e, bound)) {
      replicates *= 4;
      e = directional_albedo(&s, view_cosines[j], replicates, rng);
      ++summary->refined;
    }
    ++summary->estimates;
    for (int c = 0; c < 3; ++c) {
      if (e.albedo[c] > summary->max_albedo) {
        summary->max_albedo = e.albedo[c];
        summary->max_albedo_error = e.standard_error[c];
        memcpy(summary->max_params, p, sizeof p);
        summary->max_view = view_cosines[j];
      }
      summary->max_error = fmax(summary->max_error, e.standard_error[c]);
      if (model != CF_MODEL_CLEARCOAT)
        CHECK(e.albedo[c] + 6.0 * e.standard_error[c] < bound ||
                  e.standard_error[c] <= max_standard_error,
              "%s c_o %g: albedo %.5f near the bound with standard error %.2g", code,
              view_cosines[j], e.albedo[c], e.standard_error[c]);
      if (model != CF_MODEL_CLEARCOAT)
        CHECK(e.albedo[c] <= bound, "%s c_o %g channel %d: albedo %.6f (+- %.1e) > %g", code,
              view_cosines[j], c, e.albedo[c], e.standard_error[c], bound);
    }
    for (int k = 0; k < s.count; ++k) {
      summary->worst_pdf_z = fmax(summary->worst_pdf_z, e.pdf_z[k]);
      CHECK(e.pdf_z[k] < 8.0,
            "%s c_o %g strategy %d: the integral of its pdf differs "
            "from the fraction of its valid samples by %.1f standard errors",
            code, view_cosines[j], k, e.pdf_z[k]);
    }
  }
}

/* Corners: every non-albedo parameter at its lower or upper bound. */
static void corner_params(cf_model_id model, unsigned mask, double *p) {
  const cf_model_info *m = cf_model_info_get(model);
  for (int j = 1; j < m->param_count; ++j) {
    const cf_param_info *info = cf_param_info_get(m->params[j]);
    double x = (mask >> (j - 1)) & 1u ? info->upper : info->lower;
    for (int c = 0; c < info->components; ++c) p[m->offsets[j] + c] = x;
  }
}

int main(void) {
  printf(
      "directional albedo with rho = 1 by MIS: %d replicates x %d jittered samples "
      "per strategy, views c_o = 1 .. 0.01\n",
      REPLICATES, GRID * GRID);
  for (int m = 0; m < CF_MODEL_COUNT; ++m) {
    cf_model_id model = (cf_model_id)m;
    const cf_model_info *info = cf_model_info_get(model);
    /* The tailed twins' STD lobe is heavier-tailed than the GGX proposals
     * here (standard errors up to 0.4 at tail 1.6): its white furnace is
     * test_tailed_lobe's (D·V with F = 1 at most 1 + 1e-3), and the twins
     * combine it as M2 and M4 combine GGX's. */
    if (info->tail_slot >= 0) continue;
    cf_rng rng = cf_rng_seed(31337 + (uint64_t)m);
    model_summary summary = {0};
    double p[CF_MAX_DIM];
    unsigned corners = 1u << (info->param_count - 1);
    for (unsigned mask = 0; mask < corners; ++mask) {
      corner_params(model, mask, p);
      check_params(model, p, &rng, &summary);
    }
    if (model == CF_MODEL_OREN_NAYAR) /* the qualitative model's peak, σ near 0.2 */
      for (double sigma = 0.1; sigma < 0.45; sigma += 0.05) {
        p[CF_OREN_NAYAR_DIFFUSE_ROUGHNESS] = sigma;
        check_params(model, p, &rng, &summary);
      }
    for (int i = 0; i < RANDOM_SETS; ++i) {
      random_params(&rng, model, 0.0, p);
      check_params(model, p, &rng, &summary);
    }
    char params_text[512] = "";
    for (int k = 3, used = 0; k < info->dim; ++k) {
      char name[48];
      used += snprintf(params_text + used, sizeof params_text - (size_t)used, " %s=%g",
                       cf_model_slot_name(model, k, name, sizeof name), summary.max_params[k]);
    }
    printf(
        "%s %-10s: %ld estimates (%ld refined), max albedo %.5f +- %.1e at c_o = %g "
        "(%s ), largest standard error %.1e, worst pdf-integral z %.2f%s\n",
        info->code, info->name, summary.estimates, summary.refined, summary.max_albedo,
        summary.max_albedo_error, summary.max_view, params_text, summary.max_error,
        summary.worst_pdf_z, model == CF_MODEL_CLEARCOAT ? " (reported, not asserted)" : "");
  }
  return check_finish("test_energy");
}
