/* Light directions from a chrome ball (src/capture/include/capture/chrome_ball.h) on balls
 * rendered by chrome_render.c: a mirror sphere reflecting small bright
 * discs (distant lights, 2° across, 4 times the clip level) in a dim sky,
 * orthographic and through a pinhole, 4 × 4 samples a pixel, stored as
 * 8-bit. The directions
 * found must be within 0.5° of the lights; the 1-px sensitivities must match
 * their closed form (orthographic); bad balls must be errors or warnings. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture/chrome_ball.h"
#include "capture/chrome_render.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PI 3.14159265358979323846

/* The ball's lights found from its mask; CF_OK and the result, or the
 * status (err filled). */
static cf_status find(const chrome_scene *s, int lights, cf_chrome_result *result,
                      cf_ellipse *outline, cf_error *err) {
  cf_image photo = {0}, mask = {0};
  CHECK(chrome_render(s, &photo, &mask), "render");
  cf_chrome_options o;
  cf_chrome_default_options(&o);
  o.lights = lights;
  cf_status status = cf_chrome_outline(NULL, 0, &mask, "synthetic", outline, err);
  if (status == CF_OK)
    status = cf_chrome_lights(&photo, outline, s->camera, &o, "synthetic", result, err);
  cf_image_free(&photo);
  cf_image_free(&mask);
  return status;
}

/* Every light of the scene has one found within 0.5°. */
static void check_directions(const chrome_scene *s, const cf_chrome_result *r, const char *what) {
  CHECK(r->count == (size_t)s->sources, "%s: %zu lights found, %d rendered", what, r->count,
        s->sources);
  for (int k = 0; k < s->sources; ++k) {
    double best = 180.0;
    for (size_t j = 0; j < r->count; ++j)
      best = fmin(best, chrome_angle_deg(s->light[k], r->lights[j].direction));
    CHECK(best < 0.5, "%s: light %d (%.3f %.3f %.3f) found %.3f° off", what, k, s->light[k][0],
          s->light[k][1], s->light[k][2], best);
    printf("%s: light %d within %.3f°\n", what, k, best);
  }
}

static chrome_scene ortho_scene(void) {
  chrome_scene s;
  memset(&s, 0, sizeof s);
  s.width = 400, s.height = 300;
  s.cx = 201.3, s.cy = 148.7, s.r = 120.4;
  s.sky = 0.05;
  return s;
}

static void test_orthographic(void) {
  static const double lights[][3] = {
      {0, 0, 1}, {0.3, 0.4, 0.866}, {-0.6, 0.2, 0.77}, {0.1, -0.8, 0.6}, {0.9, 0.1, 0.3}};
  for (size_t k = 0; k < sizeof lights / sizeof lights[0]; ++k) {
    chrome_scene s = ortho_scene();
    chrome_set_light(&s, 0, lights[k][0], lights[k][1], lights[k][2]);
    cf_chrome_result r;
    cf_ellipse outline;
    cf_error err = {0};
    cf_status status = find(&s, 1, &r, &outline, &err);
    CHECK(status == CF_OK, "orthographic %zu: %s", k, err.message);
    if (status != CF_OK) continue;
    check_directions(&s, &r, "orthographic");
    const cf_chrome_light *L = &r.lights[0];
    CHECK(fabs(sqrt(L->direction[0] * L->direction[0] + L->direction[1] * L->direction[1] +
                    L->direction[2] * L->direction[2]) -
               1.0) < 1e-12,
          "unit");
    /* closed form: θ the normal's angle from the view, the light's is 2θ;
     * a pixel moves it by 2/(r cos θ) radially, 2ρ/(r cos θ) per px of
     * radius */
    double rr = 0.5 * (outline.a + outline.b), rho = L->rho, cos_t = sqrt(1.0 - rho * rho);
    double highlight = 2.0 / (rr * cos_t) * 180.0 / PI,
           radius = 2.0 * rho / (rr * cos_t) * 180.0 / PI;
    CHECK(fabs(L->per_px_highlight_deg - highlight) < 1e-3 * highlight, "highlight %g vs %g",
          L->per_px_highlight_deg, highlight);
    CHECK(fabs(L->per_px_center_deg - highlight) < 1e-3 * highlight, "centre %g vs %g",
          L->per_px_center_deg, highlight);
    CHECK(fabs(L->per_px_radius_deg - radius) < 1e-3 * highlight, "radius %g vs %g",
          L->per_px_radius_deg, radius);
    CHECK(L->warnings == 0, "orthographic %zu: warnings %u", k, L->warnings);
    printf("  per px: highlight %.3f°, centre %.3f°, radius %.3f°\n", L->per_px_highlight_deg,
           L->per_px_center_deg, L->per_px_radius_deg);
  }
}

static cf_camera pinhole(void) {
  cf_camera c;
  memset(&c, 0, sizeof c);
  c.model = CF_CAMERA_PINHOLE;
  c.width = 480, c.height = 360;
  c.num_params = 4;
  c.params[0] = 610.0, c.params[1] = 610.0, c.params[2] = 243.0, c.params[3] = 178.5;
  return c;
}

static void test_perspective(void) {
  cf_camera camera = pinhole();
  /* camera frame (x right, y down, z forward): lights toward the camera
   * side, one off to the side; the ball off the axis so that its outline
   * is an ellipse */
  static const double lights[][3] = {
      {0, 0, -1}, {0.3, -0.4, -0.866}, {-0.6, -0.2, -0.77}, {0.5, 0.6, -0.62}, {0.85, 0.1, -0.5}};
  for (size_t k = 0; k < sizeof lights / sizeof lights[0]; ++k) {
    chrome_scene s;
    memset(&s, 0, sizeof s);
    s.width = 480, s.height = 360, s.camera = &camera, s.sky = 0.05;
    s.center[0] = 0.5, s.center[1] = -0.3, s.center[2] = 5.5, s.radius = 1.0;
    chrome_set_light(&s, 0, lights[k][0], lights[k][1], lights[k][2]);
    cf_chrome_result r;
    cf_ellipse outline;
    cf_error err = {0};
    cf_status status = find(&s, 1, &r, &outline, &err);
    CHECK(status == CF_OK, "perspective %zu: %s", k, err.message);
    if (status != CF_OK) continue;
    check_directions(&s, &r, "perspective");
    const cf_chrome_light *L = &r.lights[0];
    CHECK(isfinite(L->per_px_highlight_deg) && L->per_px_highlight_deg > 0.5 &&
              L->per_px_highlight_deg < 10.0,
          "perspective per px %g", L->per_px_highlight_deg);
    CHECK(isfinite(L->per_px_center_deg) && isfinite(L->per_px_radius_deg), "finite");
  }
}

static void test_several_lights(void) {
  chrome_scene s = ortho_scene();
  chrome_set_light(&s, 0, 0.3, 0.4, 0.866);
  chrome_set_light(&s, 1, -0.5, -0.3, 0.81);
  chrome_set_light(&s, 2, 0.2, -0.6, 0.77);
  cf_chrome_result r;
  cf_ellipse outline;
  cf_error err = {0};
  cf_status status = find(&s, 3, &r, &outline, &err);
  CHECK(status == CF_OK, "three lights: %s", err.message);
  if (status == CF_OK) check_directions(&s, &r, "three lights");
  /* one expected: an error naming the count, never one of them */
  status = find(&s, 1, &r, &outline, &err);
  CHECK(status == CF_EINVAL && strstr(err.message, "3 highlights"), "one expected: %d %s",
        (int)status, err.message);
}

static void test_bad_balls(void) {
  cf_chrome_result r;
  cf_ellipse outline;
  cf_error err = {0};
  /* no highlight: only the dim sky */
  chrome_scene s = ortho_scene();
  cf_status status = find(&s, 1, &r, &outline, &err);
  CHECK(status == CF_EINVAL && strstr(err.message, "no highlight"), "no highlight: %d %s",
        (int)status, err.message);
  /* no highlight on a dark ball: 8-bit noise of a few codes only */
  s = ortho_scene();
  s.sky = 0.004;
  {
    cf_image photo = {0}, mask = {0};
    CHECK(chrome_render(&s, &photo, &mask), "render");
    unsigned state = 12345u;
    for (size_t k = 0; k < (size_t)photo.width * (size_t)photo.height * 3; ++k) {
      state = state * 1664525u + 1013904223u;
      photo.pixels[k] += (float)((state >> 29) / 255.0); /* 0 to 7 codes */
    }
    CHECK(cf_chrome_outline(NULL, 0, &mask, "dark", &outline, &err) == CF_OK, "%s", err.message);
    status = cf_chrome_lights(&photo, &outline, NULL, NULL, "dark", &r, &err);
    CHECK(status == CF_EINVAL && strstr(err.message, "no highlight"), "dark ball: %d %s",
          (int)status, err.message);
    cf_image_free(&photo);
    cf_image_free(&mask);
  }
  /* a clipped ball: its mask runs off the left border */
  s = ortho_scene();
  s.cx = 60.0;
  chrome_set_light(&s, 0, 0.3, 0.4, 0.866);
  status = find(&s, 1, &r, &outline, &err);
  CHECK(status == CF_EINVAL && strstr(err.message, "border"), "clipped mask: %d %s", (int)status,
        err.message);
  /* and an outline given past the border */
  cf_image photo = {0}, mask = {0};
  CHECK(chrome_render(&s, &photo, &mask), "render");
  cf_ellipse past = {60.0, 118.7, 90.4, 90.4, 0.0};
  status = cf_chrome_lights(&photo, &past, NULL, NULL, "clipped", &r, &err);
  CHECK(status == CF_EINVAL && strstr(err.message, "clipped"), "clipped outline: %s", err.message);
  cf_image_free(&photo);
  cf_image_free(&mask);
  /* grazing: a light 150° from the view shows at the rim: a warning, and
   * a pixel there moves the direction by several degrees */
  s = ortho_scene();
  chrome_set_light(&s, 0, sin(150.0 * PI / 180.0), 0.0, cos(150.0 * PI / 180.0));
  status = find(&s, 1, &r, &outline, &err);
  CHECK(status == CF_OK, "grazing: %s", err.message);
  if (status == CF_OK) {
    CHECK(r.lights[0].warnings & CF_CHROME_GRAZING, "grazing not flagged (rho %g)",
          r.lights[0].rho);
    CHECK(r.lights[0].per_px_highlight_deg > 3.0, "grazing per px %g",
          r.lights[0].per_px_highlight_deg);
  }
  /* an extended source (a light 50° across): a warning */
  s = ortho_scene();
  s.source_radius_deg = 25.0;
  chrome_set_light(&s, 0, 0.3, 0.4, 0.866);
  status = find(&s, 1, &r, &outline, &err);
  CHECK(status == CF_OK && (r.lights[0].warnings & CF_CHROME_EXTENDED), "extended: %d %s %u",
        (int)status, err.message, r.lights[0].warnings);
  /* an unusable option */
  cf_chrome_options o;
  cf_chrome_default_options(&o);
  o.lights = 0;
  cf_image one = {0};
  CHECK(cf_image_alloc(&one, 320, 240, 3, NULL) == CF_OK, "alloc");
  cf_ellipse inside = {160, 120, 50, 50, 0};
  CHECK(cf_chrome_lights(&one, &inside, NULL, &o, "x", &r, &err) == CF_EINVAL, "lights 0");
  cf_image_free(&one);
}

static void test_direction_basics(void) {
  cf_ellipse circle = {100.0, 80.0, 50.0, 50.0, 0.0};
  double l[3];
  CHECK(cf_chrome_direction(&circle, NULL, 100.0, 80.0, l) && fabs(l[2] - 1.0) < 1e-15,
        "centre reflects the view");
  /* a normal 45° to the right: the light is 90° to the right */
  double x = 100.0 + 50.0 * sin(PI / 4);
  CHECK(cf_chrome_direction(&circle, NULL, x, 80.0, l) && fabs(l[0] - 1.0) < 1e-12 &&
            fabs(l[2]) < 1e-12,
        "45° normal: %g %g %g", l[0], l[1], l[2]);
  /* up in the image is +y */
  CHECK(cf_chrome_direction(&circle, NULL, 100.0, 60.0, l) && l[1] > 0.0, "up is +y");
  CHECK(!cf_chrome_direction(&circle, NULL, 151.0, 80.0, l), "off the ball");
}

/* 40 lights up to 95° from the view, the ball moved by sub-pixel steps
 * between them: the worst and the mean error. */
static void test_sweep(void) {
  double worst = 0.0, sum = 0.0;
  int n = 0;
  for (int k = 0; k < 40; ++k) {
    chrome_scene s = ortho_scene();
    s.cx += 0.037 * k, s.cy += 0.061 * k;
    double theta = (0.05 + 0.9 * (k % 10) / 10.0), phi = k * 2.4;
    chrome_set_light(&s, 0, sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
    cf_chrome_result r;
    cf_ellipse outline;
    cf_error err = {0};
    cf_status status = find(&s, 1, &r, &outline, &err);
    CHECK(status == CF_OK, "sweep %d: %s", k, err.message);
    if (status != CF_OK) continue;
    double e = chrome_angle_deg(s.light[0], r.lights[0].direction);
    worst = fmax(worst, e), sum += e, ++n;
  }
  CHECK(n == 40 && worst < 0.5, "sweep: worst %.3f°", worst);
  printf("sweep of 40 lights: worst %.3f°, mean %.3f°\n", worst, sum / (n ? n : 1));
}

int main(void) {
  test_sweep();
  test_direction_basics();
  test_orthographic();
  test_perspective();
  test_several_lights();
  test_bad_balls();
  return check_finish("test_chrome_ball");
}
