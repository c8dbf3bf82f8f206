#include "ortho_scene.h"

#include <math.h>

void ortho_scene(cf_image *normals, cf_image *photo, const double l[3]) {
  for (int y = 0; y < ORTHO_SIZE; ++y)
    for (int x = 0; x < ORTHO_SIZE; ++x) {
      double nx = (x + 0.5 - 24.0) / 20.0, ny = -(y + 0.5 - 24.0) / 20.0;
      double r2 = nx * nx + ny * ny;
      if (r2 >= 1.0) continue;
      double n[3] = {nx, ny, sqrt(1.0 - r2)};
      float *p = normals->pixels + 3 * (y * ORTHO_SIZE + x);
      float *q = photo->pixels + 3 * (y * ORTHO_SIZE + x);
      double shade = 0.3 * fmax(0.0, n[0] * l[0] + n[1] * l[1] + n[2] * l[2]);
      for (int c = 0; c < 3; ++c) {
        p[c] = (float)n[c];
        q[c] = (float)(shade * (0.6 + 0.2 * c));
      }
    }
}
