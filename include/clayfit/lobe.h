/* clayfit: the specular lobe alone, D·V without the Fresnel, for its
 * benchmark (clayfit bench eval; docs/model.md §2.8): GGX's, the STD lobe's
 * with its exact masking, and the STD lobe's with the masking tabulated
 * once per tail (the models' hot path), over a batch of geometries; and the
 * table's build, the cost a model's prepare adds. Each evaluation is the
 * model's own out-of-line function (src/model/lobe.c). */
#ifndef CLAYFIT_LOBE_H
#define CLAYFIT_LOBE_H

#include <stddef.h>

#include "clayfit/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_lobe_kind {
  CF_LOBE_GGX,       /* GGX's D·V (the tail ignored) */
  CF_LOBE_STD_EXACT, /* STD's D·V with the exact masking (its lobe at F = 1) */
  CF_LOBE_STD_TABLE, /* STD's D·V with the masking from the tail's table */
  CF_LOBE_KIND_COUNT
} cf_lobe_kind;

/* A lobe prepared once for its roughness r (α = r²) and tail γ: its tail's
 * constants and masking table (a few kB). */
typedef struct cf_lobe cf_lobe;

/* NULL when out of memory. */
cf_lobe *cf_lobe_new(double roughness, double gamma);
void cf_lobe_free(cf_lobe *lobe);

/* One pass over `count` geometries (cf_geometry_from_directions): the sum of
 * the lobe's values and, with grad, of 1e-30 times every partial derivative
 * it returns, so that none of them is left uncomputed. */
double cf_lobe_sum(const cf_lobe *lobe, cf_lobe_kind kind, size_t count,
                   const cf_geometry *geometry, int grad);

/* The lobe's table built again at γ: from the precomputed grid over γ, as
 * every prepare does, or (exact != 0) from the exact masking at every node.
 * Returns an entry of the table, for the caller to keep. */
double cf_lobe_tabulate(cf_lobe *lobe, double gamma, int exact);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_LOBE_H */
