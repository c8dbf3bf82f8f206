/* Chrome balls rendered for the tests of src/capture/include/capture/chrome_ball.h: a
 * mirror sphere reflecting small bright discs (distant lights, 2° across,
 * 4 times the clip level) in a dim sky, orthographic or through a pinhole
 * camera, 4 x 4 samples a pixel, stored as 8-bit values. */
#ifndef CLAYFIT_TESTS_CHROME_RENDER_H
#define CLAYFIT_TESTS_CHROME_RENDER_H

#include "clayfit/colmap.h"
#include "clayfit/image.h"

#define CHROME_MAX_SOURCES 4

typedef struct chrome_scene {
  int width, height;
  const cf_camera *camera;  /* NULL: orthographic; else PINHOLE */
  double cx, cy, r;         /* orthographic disc, px */
  double center[3], radius; /* pinhole: the ball, camera frame */
  int sources;
  double light[CHROME_MAX_SOURCES][3]; /* unit; orthographic: DiLiGenT frame,
                                          pinhole: camera frame */
  double sky;                          /* radiance of the dim surroundings */
  double source_radius_deg;            /* the lights' angular radius (0: 1 degree) */
} chrome_scene;

/* Set light k (normalised) and raise the count to k + 1. */
void chrome_set_light(chrome_scene *s, int k, double x, double y, double z);

/* The angle between two unit vectors, degrees. */
double chrome_angle_deg(const double a[3], const double b[3]);

/* Render the photo (RGB, 8-bit values) and the mask (one channel: pixel
 * centre on the ball); 0 when out of memory. */
int chrome_render(const chrome_scene *s, cf_image *photo, cf_image *mask);

#endif
