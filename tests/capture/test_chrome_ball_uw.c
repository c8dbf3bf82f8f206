/* Light directions from a real chrome ball: ../shared/data/uw_chrome (12
 * photos, 8-bit, one light each, with a mask; skipped when absent). Its
 * ground truth is unknown, so the test is of consistency:
 * - every direction is a unit vector toward the camera's side;
 * - the circle fitted to the mask and the one fitted to the photos'
 *   silhouette give the same directions, to within what the difference of
 *   the two circles explains through the computed 1-px sensitivities
 *   (|Δcentre| × per_px_center + |Δradius| × per_px_radius, first order,
 *   plus 0.05° for the second order), the two circles within 2 px of each
 *   other in centre and radius (measured: 1.06 px and 0.94 px; a silhouette
 *   from the photos' maximum instead of their median was 19 px off);
 * - a synthetic ball rendered from the directions found, with the mask's
 *   circle, puts each highlight within 0.5 px of the photo's. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "capture/chrome_ball.h"
#include "capture/chrome_render.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PHOTOS 12

static int read_all(const char *dir, cf_image photos[PHOTOS], cf_image *mask) {
  char path[4200];
  cf_error err = {0};
  snprintf(path, sizeof path, "%s/chrome.mask.png", dir);
  if (cf_image_read(path, mask, NULL, &err) != CF_OK) {
    CHECK(0, "%s", err.message);
    return 0;
  }
  for (int k = 0; k < PHOTOS; ++k) {
    snprintf(path, sizeof path, "%s/chrome.%d.png", dir, k);
    if (cf_image_read(path, &photos[k], NULL, &err) != CF_OK) {
      CHECK(0, "%s", err.message);
      return 0;
    }
  }
  return 1;
}

/* The photo's highlight found again on a ball rendered from its direction
 * (the mask's circle, orthographic). */
static void check_rerender(const cf_image *photo, const cf_ellipse *circle,
                           const cf_chrome_light *found, int k) {
  chrome_scene s;
  memset(&s, 0, sizeof s);
  s.width = photo->width, s.height = photo->height;
  s.cx = circle->cx, s.cy = circle->cy, s.r = 0.5 * (circle->a + circle->b);
  s.sky = 0.05;
  chrome_set_light(&s, 0, found->direction[0], found->direction[1], found->direction[2]);
  cf_image render = {0}, mask = {0};
  cf_chrome_result again;
  cf_error err = {0};
  CHECK(chrome_render(&s, &render, &mask), "render");
  cf_status status = cf_chrome_lights(&render, circle, NULL, NULL, "rendered", &again, &err);
  CHECK(status == CF_OK, "photo %d rendered: %s", k, err.message);
  if (status == CF_OK) {
    double dx = again.lights[0].pixel[0] - found->pixel[0],
           dy = again.lights[0].pixel[1] - found->pixel[1];
    CHECK(hypot(dx, dy) < 0.5, "photo %d: rendered highlight %.2f px from the photo's", k,
          hypot(dx, dy));
    printf("  rendered highlight %.3f px from the photo's\n", hypot(dx, dy));
  }
  cf_image_free(&render);
  cf_image_free(&mask);
}

int main(int argc, char **argv) {
  char dir[4096];
  snprintf(dir, sizeof dir, "%s/uw_chrome", argc > 1 ? argv[1] : "../shared/data");
  char probe[4200];
  snprintf(probe, sizeof probe, "%s/chrome.mask.png", dir);
  FILE *f = fopen(probe, "rb");
  if (!f) {
    printf("skipped: %s is absent\n", probe);
    return CHECK_SKIPPED;
  }
  fclose(f);
  cf_image photos[PHOTOS] = {{0}}, mask = {0};
  if (!read_all(dir, photos, &mask)) return check_finish("test_chrome_ball_uw");
  cf_ellipse from_mask, from_photos;
  cf_error err = {0};
  CHECK(cf_chrome_outline(NULL, 0, &mask, "mask", &from_mask, &err) == CF_OK, "%s", err.message);
  CHECK(cf_chrome_outline(photos, PHOTOS, NULL, "photos", &from_photos, &err) == CF_OK, "%s",
        err.message);
  double r_mask = 0.5 * (from_mask.a + from_mask.b),
         r_photos = 0.5 * (from_photos.a + from_photos.b);
  double d_center = hypot(from_mask.cx - from_photos.cx, from_mask.cy - from_photos.cy);
  double d_radius = fabs(r_mask - r_photos);
  printf("mask circle: centre %.2f %.2f radius %.2f (a %.2f b %.2f)\n", from_mask.cx, from_mask.cy,
         r_mask, from_mask.a, from_mask.b);
  printf("silhouette circle: centre %.2f %.2f radius %.2f (a %.2f b %.2f)\n", from_photos.cx,
         from_photos.cy, r_photos, from_photos.a, from_photos.b);
  CHECK(d_center < 2.0 && d_radius < 2.0,
        "the circles differ by %.2f px (centre), %.2f px (radius)", d_center, d_radius);
  for (int k = 0; k < PHOTOS; ++k) {
    cf_chrome_result a, b;
    char name[32];
    snprintf(name, sizeof name, "chrome.%d.png", k);
    cf_status sa = cf_chrome_lights(&photos[k], &from_mask, NULL, NULL, name, &a, &err);
    CHECK(sa == CF_OK, "%s (mask): %s", name, err.message);
    cf_status sb = cf_chrome_lights(&photos[k], &from_photos, NULL, NULL, name, &b, &err);
    CHECK(sb == CF_OK, "%s (silhouette): %s", name, err.message);
    if (sa != CF_OK || sb != CF_OK) continue;
    const cf_chrome_light *L = &a.lights[0];
    double length = sqrt(L->direction[0] * L->direction[0] + L->direction[1] * L->direction[1] +
                         L->direction[2] * L->direction[2]);
    CHECK(fabs(length - 1.0) < 1e-12 && L->direction[2] > 0.0, "%s: |l| = %.17g, z %g", name,
          length, L->direction[2]);
    double angle = chrome_angle_deg(L->direction, b.lights[0].direction);
    double bound = d_center * L->per_px_center_deg + d_radius * L->per_px_radius_deg + 0.05;
    CHECK(angle <= bound, "%s: mask and silhouette circles %.3f° apart (bound %.3f°)", name, angle,
          bound);
    printf(
        "%s: highlight %.2f %.2f (%zu px) l = %.4f %.4f %.4f, %.1f° from the view; per px "
        "%.2f° highlight, %.2f° centre, %.2f° radius; mask vs silhouette %.3f° (bound %.3f°) "
        "warnings %u\n",
        name, L->pixel[0], L->pixel[1], L->area, L->direction[0], L->direction[1], L->direction[2],
        L->view_angle_deg, L->per_px_highlight_deg, L->per_px_center_deg, L->per_px_radius_deg,
        angle, bound, L->warnings);
    check_rerender(&photos[k], &from_mask, L, k);
  }
  for (int k = 0; k < PHOTOS; ++k) cf_image_free(&photos[k]);
  cf_image_free(&mask);
  return check_finish("test_chrome_ball_uw");
}
