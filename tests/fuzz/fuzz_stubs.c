/* For scripts/fuzz.sh's builds only: capture_warn without capture.c, which
 * would bring the whole loader (COLMAP, the sphere, Ceres) into fuzz_text.
 * The environment maps that warn are not fuzzed there (fuzz_text's capture
 * has per-image lights only); the ctest build links the real one. */
#include <stdlib.h>

#include "capture/capture_internal.h"

void capture_warn(cf_capture *capture, const char *format, ...) {
  (void)capture;
  (void)format;
  abort(); /* not reached from fuzz_text: a warning would mean an environment map */
}
