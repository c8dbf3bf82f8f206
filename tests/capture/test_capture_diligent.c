/* The real DiLiGenT ball (Shi et al. 2016) through the capture loader, with
 * its ground-truth normal map (tests/diligent_ball.capture.json) and with
 * normals from the circle fitted to its mask (diligent_ball_circle): every
 * image used, the observations where they belong, the clipped highlight
 * flagged, and the two sets of normals agreeing within a stated mean angle.
 * usage: test_capture_diligent TESTS_DIR SHARED_DATA_DIR (exit 77: skipped
 * when the data is absent). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "clayfit/capture.h"
#include "core/file.h"
#include "support/check.h"

CHECK_MAIN_STATE;

static const double max_mean_angle_deg = 1.0, max_angle_deg = 5.0;

static cf_capture *load(const char *tests, const char *name) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", tests, name);
  cf_capture *capture = NULL;
  cf_error err = {0};
  CHECK(cf_capture_load(path, NULL, &capture, &err) == CF_OK, "%s: %s", name, err.message);
  return capture;
}

int main(int argc, char **argv) {
  if (argc != 3) return 2;
  char ball[4096];
  snprintf(ball, sizeof ball, "%s/diligent_ball/001.png", argv[2]);
  if (!cf_path_exists(ball)) {
    printf("skipped: %s is absent (the DiLiGenT ball is in ../shared/data)\n", ball);
    return CHECK_SKIPPED;
  }
  cf_capture *truth = load(argv[1], "diligent_ball.capture.json");
  cf_capture *circle = load(argv[1], "diligent_ball_circle.capture.json");
  if (!truth || !circle) return check_finish("test_capture_diligent");

  const cf_observations *a = cf_capture_observations(truth), *b = cf_capture_observations(circle);
  size_t images = cf_capture_image_count(truth), clipped = 0, unlit = 0;
  CHECK(images == 96, "96 images, got %zu", images);
  for (size_t k = 0; k < images; ++k) {
    const cf_capture_image *im = cf_capture_image_at(truth, k);
    CHECK(im->width == 612 && im->height == 512, "image %zu size", k);
    /* the mask has 15791 pixels; 3 px of margin leave about 92 % */
    CHECK(im->sphere_pixels == 15791 && im->observations > 14000 && im->observations < 15000,
          "image %zu: %zu sphere pixels, %zu used", k, im->sphere_pixels, im->observations);
    CHECK(im->clipped <= 30, "image %zu: %zu clipped", k, im->clipped);
    clipped += im->clipped;
  }
  for (size_t i = 0; i < a->count; ++i) unlit += (a->flags[i] & CF_OBS_UNLIT) != 0;
  printf(
      "normal map: %zu observations in %zu images, %zu with a clipped channel (README: 3 to "
      "14 pixels an image at 65535), %zu unlit\n",
      a->count, images, clipped, unlit);
  CHECK(clipped >= 3 * images, "the clipped highlights are flagged (%zu)", clipped);
  CHECK(a->lights == 1 && fabs(a->view[2] - 1.0) < 1e-15, "one directional light, v = +z");

  /* same pixel in both captures: compare the normals */
  size_t j = 0, common = 0;
  double sum = 0.0, worst = 0.0;
  for (size_t i = 0; i < a->count && a->image[i] == 0; ++i) {
    while (j < b->count && b->image[j] == 0 &&
           (b->pixel[2 * j + 1] < a->pixel[2 * i + 1] ||
            (b->pixel[2 * j + 1] == a->pixel[2 * i + 1] && b->pixel[2 * j] < a->pixel[2 * i])))
      ++j;
    if (j >= b->count || b->image[j] != 0 || b->pixel[2 * j] != a->pixel[2 * i] ||
        b->pixel[2 * j + 1] != a->pixel[2 * i + 1])
      continue;
    const double *n1 = a->normal + 3 * i, *n2 = b->normal + 3 * j;
    double c = fmin(1.0, n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]);
    double angle = acos(c) * 180.0 / 3.14159265358979;
    sum += angle;
    worst = fmax(worst, angle);
    ++common;
  }
  double mean = common ? sum / (double)common : 180.0;
  printf(
      "normals from the mask's circle against the ground truth, %zu pixels: mean %.3g, worst "
      "%.3g degrees (tolerances %.3g and %.3g)\n",
      common, mean, worst, max_mean_angle_deg, max_angle_deg);
  CHECK(common > 14000, "pixels in both captures: %zu", common);
  CHECK(mean < max_mean_angle_deg && worst < max_angle_deg, "normals agree");
  cf_capture_free(truth);
  cf_capture_free(circle);
  return check_finish("test_capture_diligent");
}
