/* The layering probe (check_layering.py): compiled on a target that links
 * clayfit_export, so it sees every layer below export as export does. With
 * CLAYFIT_PROBE_PRIVATE it includes model's private terms.h, which must not
 * compile; without, core's interface header, which must. */
#ifdef CLAYFIT_PROBE_PRIVATE
#include "model/terms.h"
#else
#include "core/file.h"
#endif

int clayfit_layering_probe(void);
int clayfit_layering_probe(void) { return 0; }
