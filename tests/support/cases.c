#include "cases.h"

#include <math.h>
#include <string.h>

void random_params(cf_rng *rng, cf_model_id model, double p_bound, double *params) {
  const cf_model_info *m = cf_model_info_get(model);
  for (int j = 0; j < m->param_count; ++j) {
    const cf_param_info *p = cf_param_info_get(m->params[j]);
    for (int c = 0; c < p->components; ++c) {
      double x = cf_rng_range(rng, p->lower, p->upper);
      if (cf_rng_uniform(rng) < p_bound) x = cf_rng_uniform(rng) < 0.5 ? p->lower : p->upper;
      params[m->offsets[j] + c] = x;
    }
  }
}

void direction_from(double c, double phi, double out[3]) {
  double s = sqrt((1.0 - c) * (1.0 + c));
  out[0] = s * cos(phi);
  out[1] = s * sin(phi);
  out[2] = c;
}

/* Rotate a z-up vector into the frame whose z axis is unit n. */
static void to_frame(const double n[3], const double a[3], double out[3]) {
  double t[3] = {1.0, 0.0, 0.0};
  if (fabs(n[0]) > 0.9) t[0] = 0.0, t[1] = 1.0;
  double d = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
  for (int k = 0; k < 3; ++k) t[k] -= d * n[k];
  double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  for (int k = 0; k < 3; ++k) t[k] /= len;
  double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
  for (int k = 0; k < 3; ++k) out[k] = a[0] * t[k] + a[1] * b[k] + a[2] * n[k];
}

void random_directions(cf_rng *rng, double p_grazing, double p_equal, double n[3], double l[3],
                       double v[3]) {
  cf_rng_unit_vector(rng, n);
  double ci = cf_rng_uniform(rng), co = cf_rng_uniform(rng);
  if (cf_rng_uniform(rng) < p_grazing) {
    double u = cf_rng_uniform(rng);
    double tiny = pow(10.0, -1.0 - 11.0 * cf_rng_uniform(rng));
    if (u < 1.0 / 3.0)
      ci = tiny;
    else if (u < 2.0 / 3.0)
      co = tiny;
    else
      ci = co = tiny;
  }
  double a[3], b[3];
  double phi_i = 2.0 * M_PI * cf_rng_uniform(rng);
  double phi_o = 2.0 * M_PI * cf_rng_uniform(rng);
  direction_from(ci, phi_i, a);
  direction_from(co, phi_o, b);
  to_frame(n, a, l);
  if (cf_rng_uniform(rng) < p_equal)
    memcpy(v, l, sizeof a);
  else
    to_frame(n, b, v);
}

size_t hard_geometries(double (*n)[3], double (*l)[3], double (*v)[3], size_t max) {
  static const double cosines[] = {1.0, 0.5, 1e-3, 1e-8, 1e-150, 1e-300, 0.0};
  enum { NC = sizeof cosines / sizeof cosines[0] };
  static const double tilted[3] = {0.36, -0.48, 0.8};
  static const double up[3] = {0.0, 0.0, 1.0};
  size_t count = 0;
  for (int frame = 0; frame < 2; ++frame) {
    const double *normal = frame ? tilted : up;
    for (int i = 0; i < NC; ++i) {
      for (int o = 0; o < NC; ++o) {
        /* azimuth difference 0 (l = v when the cosines are equal),
         * π (l mirrored about n when equal), π/2, and a generic one */
        static const double dphi[] = {0.0, M_PI, 0.5 * M_PI, 2.0};
        for (int a = 0; a < 4 && count < max; ++a) {
          double li[3], vo[3];
          direction_from(cosines[i], 0.3, li);
          direction_from(cosines[o], 0.3 + dphi[a], vo);
          memcpy(n[count], normal, sizeof li);
          to_frame(normal, li, l[count]);
          to_frame(normal, vo, v[count]);
          ++count;
        }
      }
    }
    /* l + v = 0 exactly, at the horizon */
    if (count < max) {
      double li[3] = {1.0, 0.0, 0.0}, vo[3] = {-1.0, 0.0, 0.0};
      memcpy(n[count], normal, sizeof li);
      to_frame(normal, li, l[count]);
      to_frame(normal, vo, v[count]);
      ++count;
    }
  }
  return count;
}

/* Values each parameter takes on the grid. */
static int extreme_values(const cf_param_info *p, cf_model_id model, double out[4]) {
  int k = 0;
  out[k++] = p->lower;
  out[k++] = p->upper;
  out[k++] = p->default_value;
  if (model == CF_MODEL_CLAY && p->id == CF_PARAM_OPTICAL_DEPTH) out[k++] = 1e3;
  return k;
}

long for_each_extreme_params(cf_model_id model, void (*visit)(const double *params, void *user),
                             void *user) {
  const cf_model_info *m = cf_model_info_get(model);
  int index[16] = {0}, size[16];
  double values[16][4];
  for (int j = 0; j < m->param_count; ++j)
    size[j] = extreme_values(cf_param_info_get(m->params[j]), model, values[j]);
  long visited = 0;
  for (;;) {
    double params[CF_MAX_DIM];
    for (int j = 0; j < m->param_count; ++j) {
      const cf_param_info *p = cf_param_info_get(m->params[j]);
      for (int c = 0; c < p->components; ++c) params[m->offsets[j] + c] = values[j][index[j]];
    }
    visit(params, user);
    ++visited;
    int j = 0;
    while (j < m->param_count && ++index[j] == size[j]) index[j++] = 0;
    if (j == m->param_count) break;
  }
  return visited;
}

static void eval_at(cf_model_id model, const double *params, int k, double x, const double n[3],
                    const double l[3], const double v[3], double f[3]) {
  double p[CF_MAX_DIM];
  memcpy(p, params, sizeof p);
  p[k] = x;
  cf_eval(model, p, n, l, v, f, NULL);
}

void finite_difference(cf_model_id model, const double *params, int k, const double n[3],
                       const double l[3], const double v[3], double g_fd[3], double quotient[3],
                       int *one_sided) {
  const cf_param_info *p = cf_model_slot_param(model, k, NULL);
  double x = params[k];
  double h = 1e-6 * fmax(fabs(x), 1.0);
  int in_range = x >= p->lower && x <= p->upper;
  /* stencil offsets (in steps) and weights (times 1/h) */
  double steps[2], weights[3];
  if (in_range && x - h < p->lower) {
    *one_sided = 1; /* forward: (−3 f(x) + 4 f(x + h) − f(x + 2h)) / 2h */
    steps[0] = 1.0, steps[1] = 2.0;
    weights[0] = -1.5, weights[1] = 2.0, weights[2] = -0.5;
  } else if (in_range && x + h > p->upper) {
    *one_sided = -1; /* backward: (3 f(x) − 4 f(x − h) + f(x − 2h)) / 2h */
    steps[0] = -1.0, steps[1] = -2.0;
    weights[0] = 1.5, weights[1] = -2.0, weights[2] = 0.5;
  } else {
    *one_sided = 0; /* central: (f(x + h) − f(x − h)) / 2h */
    steps[0] = 1.0, steps[1] = -1.0;
    weights[0] = 0.0, weights[1] = 0.5, weights[2] = -0.5;
  }
  double f0[3], f1[3], f2[3];
  eval_at(model, params, k, x, n, l, v, f0);
  eval_at(model, params, k, x + steps[0] * h, n, l, v, f1);
  eval_at(model, params, k, x + steps[1] * h, n, l, v, f2);
  for (int c = 0; c < 3; ++c) {
    g_fd[c] = (weights[0] * f0[c] + weights[1] * f1[c] + weights[2] * f2[c]) / h;
    quotient[c] = fmax(fabs(f1[c] - f0[c]), fabs(f2[c] - f0[c])) / h;
  }
}
