/* The STD masking's table at one γ, sliced from the grid over γ
 * (tailed_grid.c, written by tools/tailed_grid_gen.c; docs/model.md §2.8,
 * "The table"). */
#include "tailed.h"

/* The cubic Hermite in p on [p_j, p_j+1] of one entry column (0: h, 1: ∂h/∂w)
 * with its p-derivative (columns 2 and 3 are their ∂/∂p). */
static void hermite_p(const double *a, const double *b, int col, double t, double *value,
                      double *d_p) {
  const double h = CF_STD_GRID_STEP;
  double t2 = t * t, s = 1.0 - t;
  *value = (1.0 + 2.0 * t) * s * s * a[col] + t * s * s * h * a[col + 2] +
           t2 * (3.0 - 2.0 * t) * b[col] + t2 * (t - 1.0) * h * b[col + 2];
  *d_p = 6.0 * t * (t - 1.0) / h * (a[col] - b[col]) + (3.0 * t2 - 4.0 * t + 1.0) * a[col + 2] +
         t * (3.0 * t - 2.0) * b[col + 2];
}

void cf_std_table_build(cf_std_table *tb, double gamma) {
  tb->gamma = gamma;
  tb->built = gamma > CF_STD_GAMMA_MIN && gamma < CF_STD_GAMMA_BECKMANN;
  if (!tb->built) return;
  double p = 1.0 / (gamma - 1.0), x = (p - 1.0) / CF_STD_GRID_STEP + 16.0;
  int j = x > 0.0 ? (int)x : 0;
  if (j > CF_STD_GRID_GAMMAS - 2) j = CF_STD_GRID_GAMMAS - 2; /* γ < 1.5 + 2.5e-7: extrapolated */
  double t = x - j;
  /* g = h/f, and ∂/∂γ = −p² ∂/∂p of it, f = 1 − p/2 (∂f/∂p = −1/2), formed
   * as (2γ − 3)/(2γ − 2) without cancellation near γ = 1.5 */
  double f = std_grid_f(gamma), inv_f = 1.0 / f, d_p_d_gamma = -p * p;
  cf_std_node node[CF_STD_TABLE_NODES];
  for (int k = 0; k < CF_STD_TABLE_NODES; ++k) {
    const double *a = cf_std_grid[j][k], *b = cf_std_grid[j + 1][k];
    double h, h_p, hx, hx_p;
    hermite_p(a, b, 0, t, &h, &h_p);
    hermite_p(a, b, 1, t, &hx, &hx_p);
    cf_std_node *n = &node[k];
    n->g = h * inv_f;
    n->g_w = hx * inv_f;
    n->g_gamma = (h_p + 0.5 * n->g) * inv_f * d_p_d_gamma;
    n->g_w_gamma = (hx_p + 0.5 * n->g_w) * inv_f * d_p_d_gamma;
  }
  cf_std_table_from_nodes(tb, node);
}

void cf_std_lobe_prepare(cf_std_lobe_prep *p, double a2, double gamma) {
  p->tail = cf_std_tail_prepare(a2, gamma);
  cf_std_table_build(&p->table, gamma);
}
