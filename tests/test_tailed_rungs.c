/* The tailed rungs contain their GGX twins exactly (issue 18; docs/model.md
 * §4.5): M2T and M4T at tail 2 equal M2 and M4 to the bit, value and every
 * gradient entry the twin has; and the tail moves the value elsewhere. M4T's
 * batches against its per-observation path. */
#include <math.h>
#include <string.h>

#include "model/models.h"
#include "support/cases.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { CASES = 4000 };

/* The twin of `tailed`, at tail 2, against the twin: value and gradient. */
static void check_twin(cf_model_id tailed, int i, const double n[3], const double l[3],
                       const double v[3], cf_rng *rng, int *moved) {
  const cf_model_info *m = cf_model_info_get(tailed);
  const cf_model_info *twin = cf_model_info_get(m->ggx_twin);
  double p[CF_MAX_DIM], f_t[3], f_g[3];
  double grad_t[3 * CF_MAX_DIM], grad_g[3 * CF_MAX_DIM];
  random_params(rng, tailed, 0.1, p);
  p[m->tail_slot] = 2.0;
  cf_eval(tailed, p, n, l, v, f_t, grad_t);
  cf_eval(twin->id, p, n, l, v, f_g, grad_g); /* the twin's vector is the prefix */
  for (int c = 0; c < 3; ++c) {
    CHECK(f_t[c] == f_g[c], "case %d: %s(tail=2) %.17g != %s %.17g", i, m->code, f_t[c], twin->code,
          f_g[c]);
    for (int k = 0; k < twin->dim; ++k)
      CHECK(grad_t[c * m->dim + k] == grad_g[c * twin->dim + k],
            "case %d: %s(tail=2) d/d%d %.17g != %s's %.17g", i, m->code, k, grad_t[c * m->dim + k],
            twin->code, grad_g[c * twin->dim + k]);
    CHECK(isfinite(grad_t[c * m->dim + m->tail_slot]), "case %d: %s's d/dtail not finite", i,
          m->code);
  }
  /* away from 2 the tail changes the lobe */
  p[m->tail_slot] = 1.7;
  cf_eval(tailed, p, n, l, v, f_t, NULL);
  if (f_g[0] > 0.0 && f_t[0] != f_g[0]) ++*moved;
}

/* M4T's batches (clay.c, the lobes over blocks: the vector path where the
 * processor has one) against its per-observation evaluation (value_grad,
 * std_dv: the scalar path), on random and grazing observations with
 * unlit ones among them: each f within BATCH_TOLERANCE relative, each
 * gradient entry k within BATCH_TOLERANCE (|f| + |∂f/∂p_k| w_k) / w_k, w_k
 * the width of p_k's range (a change of the parameter across its range
 * moves f alike in both). And an observation's result does not depend on
 * its neighbours or the entry point: cf_eval of each, and
 * cf_eval_batch_directions, equal the batch to the bit. */
#define BATCH_TOLERANCE 1e-13
enum { BATCH = 1001 }; /* not a multiple of the block */

static void check_batch_paths(cf_rng *rng) {
  static double n[BATCH][3], l[BATCH][3], v[BATCH][3], f[3 * BATCH], f_dir[3 * BATCH];
  static double grad[3 * CF_MAX_DIM * BATCH], grad_dir[3 * CF_MAX_DIM * BATCH];
  static cf_geometry g[BATCH];
  const cf_model_id model = CF_MODEL_CLAY_TAILED;
  const cf_model_info *m = cf_model_info_get(model);
  const size_t row = 3 * (size_t)m->dim;
  static const double tails[] = {1.6, 1.75, 2.5, 3.0, 10.0, 63.0, 64.0, 100.0};
  double worst_f = 0.0, worst_g = 0.0;
  long differ = 0;
  for (int j = 0; j < 8; ++j) {
    double p[CF_MAX_DIM], width[CF_MAX_DIM];
    random_params(rng, model, 0.1, p);
    p[m->tail_slot] = tails[j];
    for (int k = 0; k < m->dim; ++k) {
      const cf_param_info *info = cf_model_slot_param(model, k, NULL);
      width[k] = info->upper - info->lower;
    }
    for (int i = 0; i < BATCH; ++i) {
      random_directions(rng, 0.2, 0.02, n[i], l[i], v[i]);
      if (i % 97 == 0) v[i][0] = -n[i][0], v[i][1] = -n[i][1], v[i][2] = -n[i][2]; /* unlit */
      g[i] = cf_geometry_from_directions(n[i], l[i], v[i]);
    }
    CHECK(cf_eval_batch(model, p, BATCH, g, f, grad) == CF_OK, "cf_eval_batch failed");
    CHECK(cf_eval_batch_directions(model, p, BATCH, &n[0][0], &l[0][0], &v[0][0], f_dir,
                                   grad_dir) == CF_OK,
          "cf_eval_batch_directions failed");
    differ +=
        memcmp(f, f_dir, sizeof f) != 0 || memcmp(grad, grad_dir, row * BATCH * sizeof *grad) != 0;
    cf_prepared prep;
    cf_clay_tailed_impl.prepare(p, &prep);
    for (int i = 0; i < BATCH; ++i) {
      double f1[3] = {0.0, 0.0, 0.0}, g1[3 * CF_MAX_DIM], f_one[3], g_one[3 * CF_MAX_DIM];
      memset(g1, 0, sizeof g1);
      if (cf_geometry_is_lit(&g[i])) cf_clay_tailed_impl.value_grad(&prep, &g[i], f1, g1);
      cf_eval(model, p, n[i], l[i], v[i], f_one, g_one);
      differ += memcmp(f_one, f + 3 * i, sizeof f_one) != 0 ||
                memcmp(g_one, grad + row * (size_t)i, row * sizeof *g_one) != 0;
      for (int c = 0; c < 3; ++c) {
        double fb = f[3 * i + c], e = fb == f1[c] ? 0.0 : fabs(fb - f1[c]) / fabs(f1[c]);
        CHECK(e <= BATCH_TOLERANCE, "tail %g obs %d: batch f %.17g, per observation %.17g",
              tails[j], i, fb, f1[c]);
        if (e > worst_f) worst_f = e;
        for (int k = 0; k < m->dim; ++k) {
          double gb = grad[row * (size_t)i + (size_t)(c * m->dim + k)], gs = g1[c * m->dim + k];
          double eg =
              gb == gs ? 0.0 : fabs(gb - gs) * width[k] / (fabs(f1[c]) + fabs(gs) * width[k]);
          CHECK(eg <= BATCH_TOLERANCE, "tail %g obs %d: batch d/dp%d %.17g, per observation %.17g",
                tails[j], i, k, gb, gs);
          if (eg > worst_g) worst_g = eg;
        }
      }
    }
  }
  CHECK(differ == 0, "%ld results depend on the entry point or the neighbours", differ);
  printf(
      "M4T batches against per observation (%s): worst f %.2g, gradient %.2g (tolerance %.0e); "
      "cf_eval, batches and directions bit-equal\n",
      cf_std_block_vector() ? "vector path" : "no vector path here", worst_f, worst_g,
      BATCH_TOLERANCE);
}

int main(void) {
  cf_rng rng = cf_rng_seed(1818);
  int moved[2] = {0, 0};
  long lit = 0;
  for (int i = 0; i < CASES; ++i) {
    double n[3], l[3], v[3];
    random_directions(&rng, 0.1, 0.02, n, l, v);
    cf_geometry g = cf_geometry_from_directions(n, l, v);
    lit += cf_geometry_is_lit(&g);
    check_twin(CF_MODEL_DIELECTRIC_TAILED, i, n, l, v, &rng, &moved[0]);
    check_twin(CF_MODEL_CLAY_TAILED, i, n, l, v, &rng, &moved[1]);
  }
  CHECK(moved[0] > lit / 2, "M2T at tail 1.7 equals M2 in %ld of %ld lit cases", lit - moved[0],
        lit);
  CHECK(moved[1] > lit / 2, "M4T at tail 1.7 equals M4 in %ld of %ld lit cases", lit - moved[1],
        lit);
  printf("%d cases (%ld lit): M2T and M4T at tail 2 equal M2 and M4 to the bit\n", CASES, lit);
  check_batch_paths(&rng);
  return check_finish("test_tailed_rungs");
}
