/* The real DiLiGenT ball (Shi, Wu, Tan, Matsushita, Zickler, "A Benchmark
 * Dataset and Evaluation for Non-Lambertian and Uncalibrated Photometric
 * Stereo", CVPR 2016 / TPAMI 2019), read from <shared data>/diligent_ball:
 * the circle found from its mask gives orthographic normals that must
 * agree with the benchmark's ground truth (Normal_gt.pfm); the circle found
 * in its photos without the mask must agree with the mask's. Skipped
 * (exit 77) when the data is absent. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/sphere_silhouette.h"
#include "support/check.h"

CHECK_MAIN_STATE;

/* tests/capture/sphere_diligent_cv.cpp */
int sphere_test_read_png(const char *path, cf_image *out, char *why, size_t why_size);

/* A 3-channel little-endian PFM ("PF\n<w> <h>\n<negative scale>\n", then
 * rows bottom to top) into a top-row-first cf_image. 0 on failure. */
static int read_pfm(const char *path, cf_image *out, char *why, size_t why_size) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    snprintf(why, why_size, "%s: cannot open it", path);
    return 0;
  }
  char magic[3] = {0};
  int width = 0, height = 0;
  double scale = 0.0;
  if (fscanf(f, "%2s %d %d %lf", magic, &width, &height, &scale) != 4 || strcmp(magic, "PF") != 0 ||
      width <= 0 || height <= 0 || width > 100000 || height > 100000 || fgetc(f) != '\n') {
    snprintf(why, why_size, "%s: not a 3-channel PFM header", path);
    fclose(f);
    return 0;
  }
  if (!(scale < 0.0)) {
    snprintf(why, why_size, "%s: big-endian PFM (scale %g) is not handled here", path, scale);
    fclose(f);
    return 0;
  }
  size_t row = (size_t)width * 3;
  float *pixels = malloc(row * (size_t)height * sizeof(float));
  unsigned char *bytes = malloc(row * 4);
  int ok = pixels && bytes;
  for (int r = 0; ok && r < height; ++r) {
    if (fread(bytes, 4, row, f) != row) {
      ok = 0;
      break;
    }
    float *dst = pixels + row * (size_t)(height - 1 - r); /* bottom row first in the file */
    for (size_t k = 0; k < row; ++k) {
      uint32_t u = (uint32_t)bytes[4 * k] | (uint32_t)bytes[4 * k + 1] << 8 |
                   (uint32_t)bytes[4 * k + 2] << 16 | (uint32_t)bytes[4 * k + 3] << 24;
      memcpy(&dst[k], &u, sizeof u);
    }
  }
  free(bytes);
  fclose(f);
  if (!ok) {
    snprintf(why, why_size, "%s: truncated or out of memory", path);
    free(pixels);
    return 0;
  }
  out->width = width;
  out->height = height;
  out->channels = 3;
  out->pixels = pixels;
  return 1;
}

#define RAD_TO_DEG (180.0 / 3.14159265358979323846)
#define MAX_POINTS 2048

int main(int argc, char **argv) {
  if (argc < 2) {
    printf("skipped: no shared data folder given on the command line\n");
    return CHECK_SKIPPED;
  }
  char dir[4096], path[4200], why[4400];
  snprintf(dir, sizeof dir, "%s/diligent_ball", argv[1]);
  snprintf(path, sizeof path, "%s/mask.png", dir);
  FILE *probe = fopen(path, "rb");
  if (!probe) {
    printf("skipped: %s is absent (the DiLiGenT ball is not in the shared data here)\n", path);
    return CHECK_SKIPPED;
  }
  fclose(probe);

  cf_image mask = {0, 0, 0, NULL}, normals = {0, 0, 0, NULL};
  int ok = sphere_test_read_png(path, &mask, why, sizeof why);
  CHECK(ok, "%s", why);
  snprintf(path, sizeof path, "%s/Normal_gt.pfm", dir);
  int ok_normals = read_pfm(path, &normals, why, sizeof why);
  CHECK(ok_normals, "%s", why);
  if (!ok || !ok_normals) return check_finish("test_sphere_diligent");
  CHECK(mask.width == 612 && mask.height == 512, "mask %d × %d", mask.width, mask.height);
  CHECK(normals.width == mask.width && normals.height == mask.height, "normals %d × %d",
        normals.width, normals.height);

  /* the circle from the mask */
  static double boundary[2 * MAX_POINTS];
  size_t count = 0;
  cf_ellipse circle;
  cf_error err = {0};
  cf_silhouette_hint hint = {&mask, {308.0, 264.0}, 71.0};
  cf_status st = cf_detect_sphere_silhouette(NULL, &hint, "diligent_ball/mask.png", &circle,
                                             boundary, MAX_POINTS, &count, &err);
  CHECK(st == CF_OK, "%s", err.message);
  printf("mask: centre (%.3f, %.3f), axes %.3f, %.3f px, %zu boundary points\n", circle.cx,
         circle.cy, circle.a, circle.b, count);
  CHECK(fabs(circle.cx - 308.0) < 3.0 && fabs(circle.cy - 264.0) < 3.0 &&
            fabs(circle.a - 71.0) < 2.0 && circle.a - circle.b < 1.0,
        "the README's ball: centre near (308, 264), radius about 71");

  /* its normals against the ground truth, 3 px or more inside the outline */
  double radius = 0.5 * (circle.a + circle.b);
  double sum = 0.0, worst = 0.0;
  long used = 0, mask_pixels = 0;
  int worst_x = -1, worst_y = -1;
  for (int y = 0; y < mask.height && st == CF_OK; ++y)
    for (int x = 0; x < mask.width; ++x) {
      size_t i = (size_t)y * (size_t)mask.width + (size_t)x;
      if (mask.pixels[i * (size_t)mask.channels] == 0.0f) continue;
      ++mask_pixels;
      double px = x + 0.5, py = y + 0.5;
      if (hypot(px - circle.cx, py - circle.cy) > radius - 3.0) continue;
      double n[3];
      if (!cf_sphere_normal_orthographic(&circle, px, py, n)) continue;
      const float *g = normals.pixels + 3 * i;
      double len = sqrt((double)g[0] * g[0] + (double)g[1] * g[1] + (double)g[2] * g[2]);
      if (!(len > 0.5)) continue;
      double c = (n[0] * g[0] + n[1] * g[1] + n[2] * g[2]) / len;
      double angle = acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c) * RAD_TO_DEG;
      sum += angle;
      ++used;
      if (angle > worst) {
        worst = angle;
        worst_x = x;
        worst_y = y;
      }
    }
  double mean = used ? sum / (double)used : INFINITY;
  printf(
      "normals: %ld of the mask's %ld pixels at least 3 px inside; angle to Normal_gt: mean "
      "%.3f°, max %.3f° (at column %d, row %d)\n",
      used, mask_pixels, mean, worst, worst_x, worst_y);
  CHECK(mask_pixels == 15791, "the README says 15,791 mask pixels, counted %ld", mask_pixels);
  CHECK(used > 12000, "only %ld pixels compared", used);
  /* threshold: 1.5° mean; the ground truth is itself a fitted sphere */
  CHECK(mean < 1.5, "mean normal angle %.3f° >= 1.5°", mean);
  CHECK(worst < 6.0, "max normal angle %.3f° >= 6°", worst);

  /* the photos without the mask (hint only): the same circle */
  static const char *photos[] = {"001.png", "025.png", "048.png", "072.png", "096.png"};
  cf_silhouette_hint near = {NULL, {308.0, 264.0}, 71.0};
  for (size_t k = 0; k < sizeof photos / sizeof photos[0]; ++k) {
    snprintf(path, sizeof path, "%s/%s", dir, photos[k]);
    cf_image photo = {0, 0, 0, NULL};
    if (!sphere_test_read_png(path, &photo, why, sizeof why)) {
      CHECK(0, "%s", why);
      continue;
    }
    for (int hinted = 0; hinted < 2; ++hinted) {
      cf_ellipse found;
      size_t n = 0;
      st = cf_detect_sphere_silhouette(&photo, hinted ? &near : NULL, photos[k], &found, boundary,
                                       MAX_POINTS, &n, &err);
      CHECK(st == CF_OK, "%s", err.message);
      if (st != CF_OK) continue;
      double dc = hypot(found.cx - circle.cx, found.cy - circle.cy);
      double dr = 0.5 * (found.a + found.b) - radius;
      printf(
          "%s%s: centre (%.3f, %.3f), axes %.3f, %.3f px, %zu points; vs the mask's circle: "
          "centre %.3f px, radius %+.3f px\n",
          photos[k], hinted ? " (hint)" : "", found.cx, found.cy, found.a, found.b, n, dc, dr);
      CHECK(dc < 1.5 && fabs(dr) < 1.5, "%s: centre off by %.3f px, radius by %.3f px", photos[k],
            dc, dr);
    }
    free(photo.pixels);
  }

  free(mask.pixels);
  free(normals.pixels);
  return check_finish("test_sphere_diligent");
}
