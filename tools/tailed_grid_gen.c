/* The STD masking's grid over γ (src/model/tailed.h, cf_std_grid;
 * docs/model.md §2.8, "The table"): the exact nodes at the grid's γ, as
 * h = g f and its derivatives in w and p = 1/(γ − 1), f = 1 − p/2.
 *   tailed_grid_gen OUT.c   writes the grid as C source,
 * at every build (src/model/CMakeLists.txt; tests/fuzz/fuzz.mk): the grid
 * is never stale and never in the tree. A program, not the library: out of
 * src/model, whose every .c file tests/fuzz/fuzz.mk compiles into the model. */
#include <stdio.h>
#include <string.h>

#include "tailed.h" /* src/model: the generator is the model's own */

/* The grid's entries at γ node j: h, ∂h/∂w, ∂h/∂p, ∂²h/∂w∂p per node. */
static void grid_row(int j, double row[CF_STD_TABLE_NODES][4]) {
  static cf_std_node node[CF_STD_TABLE_NODES];
  double p = std_grid_p(j), gamma = 1.0 + 1.0 / p, f = std_grid_f(gamma), dg_dp = -1.0 / (p * p);
  cf_std_table_nodes_exact(node, gamma);
  for (int k = 0; k < CF_STD_TABLE_NODES; ++k) {
    const cf_std_node *n = &node[k];
    row[k][0] = n->g * f;
    row[k][1] = n->g_w * f;
    row[k][2] = n->g_gamma * dg_dp * f - 0.5 * n->g;
    row[k][3] = n->g_w_gamma * dg_dp * f - 0.5 * n->g_w;
  }
}

/* Written to PATH.tmp and renamed: a killed build leaves no truncated grid
 * that the next build would take for current. */
static int write_grid(const char *path) {
  char tmp[4096];
  if (snprintf(tmp, sizeof tmp, "%s.tmp", path) >= (int)sizeof tmp) {
    fprintf(stderr, "tailed_grid_gen: path too long\n");
    return 1;
  }
  FILE *out = fopen(tmp, "w");
  if (!out) {
    perror(tmp);
    return 1;
  }
  static double row[CF_STD_TABLE_NODES][4];
  fprintf(out,
          "/* Generated at build time by tools/tailed_grid_gen.c. The STD\n"
          " * masking's grid over gamma (tailed.h, docs/model.md 2.8 \"The table\"). */\n"
          "/* clang-format off */\n"
          "#include \"tailed.h\"\n\n"
          "const double cf_std_grid[CF_STD_GRID_GAMMAS][CF_STD_TABLE_NODES][4] = {\n");
  int bad = 0;
  for (int j = 0; j < CF_STD_GRID_GAMMAS; ++j) {
    grid_row(j, row);
    fprintf(out, "{ /* p = %.17g */\n", std_grid_p(j));
    for (int k = 0; k < CF_STD_TABLE_NODES; ++k) {
      for (int i = 0; i < 4; ++i) bad += !isfinite(row[k][i]);
      fprintf(out, "{%.17g, %.17g, %.17g, %.17g},\n", row[k][0], row[k][1], row[k][2], row[k][3]);
    }
    fprintf(out, "},\n");
  }
  fprintf(out, "};\n");
  if (fclose(out) != 0 || bad) {
    fprintf(stderr, "tailed_grid_gen: %s\n", bad ? "a node is not finite" : "write failed");
    remove(tmp);
    return 1;
  }
  if (rename(tmp, path) != 0) {
    perror(path);
    remove(tmp);
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc == 2 && argv[1][0] != '-') return write_grid(argv[1]);
  fprintf(stderr, "usage: tailed_grid_gen OUT.c\n");
  return 2;
}
