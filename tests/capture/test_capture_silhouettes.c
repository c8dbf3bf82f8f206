/* The sphere found from the photos of a synthetic capture (clayfit synth
 * --silhouettes: 8-bit photos with noise, the sphere resting on the ground
 * and casting its flash shadow next to a dark limb): centre and radius
 * recovered to a stated fraction of the true radius. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "clayfit/capture.h"
#include "clayfit/synth.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static const double max_center_error = 0.01, max_radius_error = 0.01; /* of the radius */

int main(void) {
  char dir[] = "/tmp/clayfit-silhouettes-XXXXXX";
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  cf_synth_options o;
  cf_synth_default_options(&o);
  o.images = 12;
  o.silhouette_geometry = 1;
  o.seed = 5;
  cf_error err = {0};
  CHECK(cf_synth_write(dir, &o, &err) == CF_OK, "synth: %s", err.message);
  char path[512];
  snprintf(path, sizeof path, "%s/capture.json", dir);
  cf_capture *capture = NULL;
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_OK, "load: %s", err.message);
  if (capture) {
    cf_capture_summary s;
    cf_capture_summarize(capture, &s);
    double center_error =
        sqrt(s.sphere_center[0] * s.sphere_center[0] + s.sphere_center[1] * s.sphere_center[1] +
             s.sphere_center[2] * s.sphere_center[2]);
    double radius_error = fabs(s.sphere_radius - 1.0);
    printf(
        "sphere from %d silhouettes: centre off by %.3g R, radius off by %.3g %% (tolerances "
        "%.3g R, %.3g %%); RMS %.3g px over the %.3g %% of the outline points kept\n",
        o.images, center_error, 100.0 * radius_error, max_center_error, 100.0 * max_radius_error,
        s.sphere_rms_px, 100.0 * s.silhouette_kept);
    CHECK(center_error < max_center_error, "centre error %.3g", center_error);
    CHECK(radius_error < max_radius_error, "radius error %.3g", radius_error);
    CHECK(s.sphere_rms_px < 1.5 && s.silhouette_kept > 0.4, "silhouettes fit");
    CHECK(cf_capture_observations(capture)->count > 0, "observations");
    cf_capture_free(capture);
  }
  char command[600];
  snprintf(command, sizeof command, "rm -rf '%s'", dir);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_finish("test_capture_silhouettes");
}
