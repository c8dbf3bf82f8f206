/* A small orthographic test scene shared by the capture tests: a sphere's
 * normal map seen along +z (DiLiGenT's frame: x right, y up), and a shaded
 * photo of it. */
#ifndef CLAYFIT_TEST_ORTHO_SCENE_H
#define CLAYFIT_TEST_ORTHO_SCENE_H

#include "clayfit/image.h"

enum { ORTHO_SIZE = 48 };

/* Fill `normals` (3 channels, ORTHO_SIZE², zero outside the disc of radius
 * 20 px about the centre) and `photo` (3 channels: grey Lambert shading
 * 0.3 max(0, n·l) tinted per channel). Both must be allocated. */
void ortho_scene(cf_image *normals, cf_image *photo, const double l[3]);

#endif /* CLAYFIT_TEST_ORTHO_SCENE_H */
