/* Light probes (src/capture/include/capture/light_probe.h). A chrome ball is rendered in
 * each real HDRI of ../shared/data/hdri (orthographic, view (0, 0, 1); the
 * renderer below reflects view rays off the sphere and reads the map with
 * its own equirectangular formulas, negatives clamped at 0), written as a
 * float EXR photo, read back and unwrapped; the unwrapped map's irradiance,
 * its order-2 spherical harmonics (Ramamoorthi & Hanrahan 2001: 9
 * coefficients per channel, Â = π, 2π/3, π/4), must match the original's
 * within 5 %. Then the same photo cut into three 8-bit sRGB brackets at
 * exposures 1, 4, 16, merged back. Without the data: the synthetic checks
 * (the inverse of cf_envmap_direction, a single bright spot found where
 * the `environment` light's median cut puts it, the merge's errors) run,
 * the HDRI part is skipped; with no data at all the test exits 77 after
 * them. Usage: test_light_probe SHARED_DATA [FIXTURE_DIR]: FIXTURE_DIR
 * receives a ball photo, its brackets and a capture for the CLI tests. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "capture/envmap.h"
#include "capture/light_probe.h"
#include "core/file.h"
#include "ortho_scene.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PI 3.14159265358979323846

enum { PHOTO = 768, RENDER_SS = 4, MAP_W = 512 };
static const double BALL_CX = 384.0, BALL_CY = 384.0, BALL_R = 360.0;

static void die(const cf_error *err) {
  fprintf(stderr, "%s\n", err->message);
  exit(1);
}

/* ---- the renderer: a chrome ball in an equirectangular map ---- */

/* The map's radiance toward d, bilinear, negatives as 0; the map's
 * convention written out again here (envmap.h): θ = acos(d_y) from +y,
 * φ = atan2(−d_z, −d_x), u = φ/2π, v = θ/π, pixel centres at +0.5. */
static void map_lookup(const cf_image *map, const double d[3], double rgb[3]) {
  double theta = acos(fmax(-1.0, fmin(1.0, d[1]))), phi = atan2(-d[2], -d[0]);
  if (phi < 0) phi += 2 * PI;
  double fx = phi / (2 * PI) * map->width - 0.5, fy = theta / PI * map->height - 0.5;
  int x0 = (int)floor(fx), y0 = (int)floor(fy);
  double ax = fx - x0, ay = fy - y0;
  rgb[0] = rgb[1] = rgb[2] = 0.0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      int x = ((x0 + i) % map->width + map->width) % map->width;
      int y = y0 + j < 0 ? 0 : y0 + j >= map->height ? map->height - 1 : y0 + j;
      double w = (i ? ax : 1 - ax) * (j ? ay : 1 - ay);
      const float *p = map->pixels + ((size_t)y * map->width + x) * map->channels;
      for (int c = 0; c < 3; ++c) rgb[c] += w * (p[c] > 0.0f ? p[c] : 0.0);
    }
}

/* A PHOTO² orthographic photo of a perfect mirror ball, RENDER_SS²
 * samples per pixel, the background a constant. */
static void render_ball_on(const cf_image *map, double background, cf_image *photo) {
  cf_error err = {0};
  if (cf_image_alloc(photo, PHOTO, PHOTO, 3, &err) != CF_OK) die(&err);
  for (int y = 0; y < PHOTO; ++y)
    for (int x = 0; x < PHOTO; ++x) {
      double sum[3] = {0, 0, 0};
      for (int j = 0; j < RENDER_SS; ++j)
        for (int i = 0; i < RENDER_SS; ++i) {
          double nx = (x + (i + 0.5) / RENDER_SS - BALL_CX) / BALL_R;
          double ny = -(y + (j + 0.5) / RENDER_SS - BALL_CY) / BALL_R;
          double rr = nx * nx + ny * ny, rgb[3];
          if (rr >= 1.0) {
            for (int c = 0; c < 3; ++c) sum[c] += background;
            continue;
          }
          double nz = sqrt(1.0 - rr);
          double d[3] = {2 * nz * nx, 2 * nz * ny, 2 * nz * nz - 1}; /* 2(n·v)n − v */
          map_lookup(map, d, rgb);
          for (int c = 0; c < 3; ++c) sum[c] += rgb[c];
        }
      for (int c = 0; c < 3; ++c)
        photo->pixels[3 * ((size_t)y * PHOTO + x) + c] = (float)(sum[c] / (RENDER_SS * RENDER_SS));
    }
}

static void render_ball(const cf_image *map, cf_image *photo) {
  render_ball_on(map, 0.25, photo);
}

/* ---- irradiance in spherical harmonics ---- */

static void sh9(const double d[3], double y[9]) {
  const double x = d[0], yy = d[1], z = d[2];
  y[0] = 0.282095;
  y[1] = 0.488603 * yy;
  y[2] = 0.488603 * z;
  y[3] = 0.488603 * x;
  y[4] = 1.092548 * x * yy;
  y[5] = 1.092548 * yy * z;
  y[6] = 0.315392 * (3 * z * z - 1);
  y[7] = 1.092548 * x * z;
  y[8] = 0.546274 * (x * x - yy * yy);
}

/* The irradiance coefficients E_lm = Â_l Σ L Y_lm dω of a map, negatives
 * as 0, each value times its alpha (4th channel) if it has one; with
 * max_angle_deg > 0 only directions within that angle of v = (0, 0, 1). */
static void irradiance_sh(const cf_image *map, double max_angle_deg, double e[3][9]) {
  static const double a_hat[9] = {PI,     2 * PI / 3, 2 * PI / 3, 2 * PI / 3, PI / 4,
                                  PI / 4, PI / 4,     PI / 4,     PI / 4};
  const double cos_max = cos(max_angle_deg * PI / 180.0);
  memset(e, 0, sizeof(double) * 27);
  for (int y = 0; y < map->height; ++y) {
    double d_omega = (2 * PI / map->width) * (PI / map->height) * sin(PI * (y + 0.5) / map->height);
    for (int x = 0; x < map->width; ++x) {
      double d[3], basis[9];
      cf_envmap_direction(map->width, map->height, x, y, d);
      if (max_angle_deg > 0 && d[2] < cos_max) continue;
      sh9(d, basis);
      const float *p = map->pixels + ((size_t)y * map->width + x) * map->channels;
      double alpha = map->channels == 4 ? p[3] : 1.0;
      for (int c = 0; c < 3; ++c) {
        double value = p[c] > 0.0f ? p[c] * alpha * d_omega : 0.0;
        for (int k = 0; k < 9; ++k) e[c][k] += value * basis[k];
      }
    }
  }
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 9; ++k) e[c][k] *= a_hat[k];
}

/* The largest over channels of |E − E_ref| / |E_ref| (the 9 coefficients'
 * norms: the RMS of the irradiance difference over all normals, relative
 * to the RMS irradiance, the basis being orthonormal); `scale` divides E. */
static double sh_error(double e[3][9], double ref[3][9], double scale) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    double diff = 0, norm = 0;
    for (int k = 0; k < 9; ++k) {
      diff += pow(e[c][k] / scale - ref[c][k], 2);
      norm += ref[c][k] * ref[c][k];
    }
    worst = fmax(worst, sqrt(diff / norm));
  }
  return worst;
}

/* ---- synthetic checks (no data needed) ---- */

static void check_inverse(void) {
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    double x = fmod(i * 0.6180339887 * 98.0, 98.0) - 0.5, y = fmod(i * 0.377, 48.0) - 0.5;
    double d[3], back[3], px, py;
    cf_envmap_direction(98, 48, x, y, d);
    cf_envmap_pixel(98, 48, d, &px, &py);
    cf_envmap_direction(98, 48, px, py, back);
    worst = fmax(worst, fabs(back[0] - d[0]) + fabs(back[1] - d[1]) + fabs(back[2] - d[2]));
  }
  printf("cf_envmap_pixel inverts cf_envmap_direction: worst |Δd|₁ %.3g\n", worst);
  CHECK(worst < 1e-12, "round trip %g", worst);
}

/* A dim map with one bright patch toward `toward`: rendered, unwrapped,
 * and reduced to one light by the `environment` light's median cut, the
 * light points within 2° of the patch (the map's convention and frames
 * agree with envmap.c's). */
static void check_spot(const double toward[3]) {
  cf_image map = {0}, photo = {0}, probe = {0};
  cf_error err = {0};
  if (cf_image_alloc(&map, 128, 64, 3, &err) != CF_OK) die(&err);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) {
      double d[3];
      cf_envmap_direction(128, 64, x, y, d);
      double c = d[0] * toward[0] + d[1] * toward[1] + d[2] * toward[2];
      for (int k = 0; k < 3; ++k) map.pixels[3 * (y * 128 + x) + k] = c > 0.995 ? 100.0f : 0.0f;
    }
  render_ball(&map, &photo);
  const cf_probe_ball ball = {BALL_CX, BALL_CY, BALL_R};
  const cf_probe_options o = {128, 2.0, 1.0, NULL};
  cf_probe_report report;
  CHECK(cf_probe_unwrap(&photo, &ball, &o, &probe, &report, &err) == CF_OK, "%s", err.message);
  cf_directional_light light;
  CHECK(cf_envmap_median_cut(&probe, NULL, 1, &light, NULL, &err) == CF_OK, "%s", err.message);
  double c = light.direction[0] * toward[0] + light.direction[1] * toward[1] +
             light.direction[2] * toward[2];
  double angle = acos(fmin(1.0, c)) * 180.0 / PI;
  printf("spot toward (%.2f, %.2f, %.2f): the probe's median-cut light is %.2f° off\n", toward[0],
         toward[1], toward[2], angle);
  CHECK(angle < 2.0, "spot %.2f° off", angle);
  cf_image_free(&map);
  cf_image_free(&photo);
  cf_image_free(&probe);
}

static void check_merge_errors(void) {
  cf_image b[3] = {{0}};
  cf_error err = {0};
  for (int k = 0; k < 3; ++k)
    if (cf_image_alloc(&b[k], 8, 6, 3, &err) != CF_OK) die(&err);
  const char *names[3] = {"a.png", "b.png", "c.png"};
  const cf_bracket_options o = {CF_TRANSFER_SRGB, 0.0, 0.5 / 255, 254.5 / 255};
  cf_image out = {0};
  const double not_increasing[3] = {1, 16, 4}, duplicate[3] = {1, 4, 4}, good[3] = {1, 4, 16};
  CHECK(cf_brackets_merge(b, not_increasing, 3, names, &o, &out, NULL, &err) == CF_EINVAL &&
            strstr(err.message, "c.png (bracket 3) has 4 after 16"),
        "not increasing: %s", err.message);
  CHECK(cf_brackets_merge(b, duplicate, 3, names, &o, &out, NULL, &err) == CF_EINVAL &&
            strstr(err.message, "increase strictly"),
        "duplicate: %s", err.message);
  cf_image small = {0};
  if (cf_image_alloc(&small, 8, 5, 3, &err) != CF_OK) die(&err);
  cf_image mixed[3] = {b[0], small, b[2]};
  CHECK(cf_brackets_merge(mixed, good, 3, names, &o, &out, NULL, &err) == CF_EINVAL &&
            strstr(err.message, "b.png (bracket 2) is 8 x 5, but a.png (bracket 1) is 8 x 6"),
        "sizes: %s", err.message);
  /* one pixel saturated in every bracket, one dark in every bracket, one
   * mid-grey: the merge gives the lower bound, the counts and the value */
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) {
      b[k].pixels[c] = 1.0f;
      b[k].pixels[3 + c] = 0.0f;
      b[k].pixels[6 + c] = (float)cf_linear_to_srgb(0.01 * good[k]);
    }
  }
  cf_bracket_report report;
  CHECK(cf_brackets_merge(b, good, 3, names, &o, &out, &report, &err) == CF_OK, "%s", err.message);
  printf("merge: %zu saturated everywhere, %zu dark everywhere, mid pixel %.6f\n",
         report.saturated_everywhere, report.dark_everywhere, out.pixels[6]);
  CHECK(report.saturated_everywhere == 1, "saturated count %zu", report.saturated_everywhere);
  CHECK(report.dark_everywhere == 46, "dark count %zu", report.dark_everywhere);
  CHECK(fabs(out.pixels[6] - 0.01) < 1e-6, "merged %g, expected 0.01", out.pixels[6]);
  CHECK(fabs(out.pixels[0] - cf_srgb_to_linear(254.5 / 255)) < 1e-6, "lower bound %g",
        out.pixels[0]);
  cf_image_free(&out);
  cf_image_free(&small);
  for (int k = 0; k < 3; ++k) cf_image_free(&b[k]);
}

/* ---- the real maps ---- */

static const double EXPOSURES[3] = {1.0, 4.0, 16.0};

/* Cut the photo into three 8-bit sRGB brackets at EXPOSURES, scaled so
 * that the shortest puts the brightest ball pixel at 0.9; returns that
 * scale. The brackets go through PNG files in `dir` and are read back;
 * with `exif`, also as 16-bit TIFFs with EXIF exposure times 1/60, 4/60,
 * 16/60 s. */
static double make_brackets(const cf_image *photo, const char *dir, int exif,
                            cf_image brackets[3]) {
  cf_error err = {0};
  double peak = 0;
  for (size_t i = 0; i < (size_t)photo->width * photo->height * 3; ++i)
    peak = fmax(peak, photo->pixels[i]);
  const double scale = 0.9 / peak;
  for (int k = 0; k < 3; ++k) {
    cf_image b = {0};
    if (cf_image_alloc(&b, photo->width, photo->height, 3, &err) != CF_OK) die(&err);
    for (size_t i = 0; i < (size_t)photo->width * photo->height * 3; ++i)
      b.pixels[i] = (float)cf_linear_to_srgb(fmin(1.0, photo->pixels[i] * scale * EXPOSURES[k]));
    char path[4096];
    if (exif) { /* 16-bit TIFF with EXIF exposure times k/60 s, for the CLI */
      cf_image_info info = {.exposure_time = EXPOSURES[k] / 60.0, .f_number = NAN, .iso = NAN};
      snprintf(path, sizeof path, "%s/bracket%d.tif", dir, k + 1);
      if (cf_image_write_with_info(path, &b, 16, &info, &err) != CF_OK) die(&err);
    }
    snprintf(path, sizeof path, "%s/bracket%d.png", dir, k + 1);
    if (cf_image_write(path, &b, 8, &err) != CF_OK) die(&err);
    cf_image_free(&b);
    if (cf_image_read(path, &brackets[k], NULL, &err) != CF_OK) die(&err);
  }
  return scale;
}

/* The outline's margin pays: before a bright background (5, 11 times
 * sunset's mean radiance) and with the outline 1 px too large,
 * the default 2 px keeps the observable error under 5 %, and a margin of
 * 0 (the rim's pixels, half background, unwrapped) does worse. */
static void check_margin(const cf_image *map, const char *name, double ref_whole[3][9],
                         double ref_obs[3][9]) {
  cf_image photo = {0}, probe = {0};
  cf_error err = {0};
  render_ball_on(map, 5.0, &photo);
  const cf_probe_ball ball = {BALL_CX, BALL_CY, BALL_R + 1.0};
  double error[2], got[3][9];
  for (int m = 0; m < 2; ++m) {
    const cf_probe_options o = {MAP_W, m ? 2.0 : 0.0, 1.0, NULL};
    CHECK(cf_probe_unwrap(&photo, &ball, &o, &probe, NULL, &err) == CF_OK, "%s", err.message);
    irradiance_sh(&probe, 0.0, got);
    error[m] = sh_error(got, m ? ref_obs : ref_whole, 1.0); /* margin 0 sees all */
    cf_image_free(&probe);
  }
  /* the map's mean radiance: L_00 / (Y_00 4π), L_00 = E_00 / π */
  const double mean = ref_whole[1][0] / PI / (0.282095 * 4 * PI);
  printf(
      "%-7s background 5 (the map's mean radiance is %.3g), outline 1 px too large: SH-2 "
      "error %.2f %% with margin 0, %.2f %% with 2 px\n",
      name, mean, 100 * error[0], 100 * error[1]);
  CHECK(error[1] < 0.05 && error[1] < error[0], "%s: margin %.4f vs %.4f", name, error[1],
        error[0]);
  cf_image_free(&photo);
}

typedef struct probe_numbers {
  double observable, whole, brackets_observable, invalid, max_angle;
} probe_numbers;

static probe_numbers check_map(const char *hdri, const char *name, const char *dir) {
  probe_numbers n = {0};
  cf_image map = {0}, photo = {0}, read = {0}, probe = {0};
  cf_error err = {0};
  if (cf_image_read(hdri, &map, NULL, &err) != CF_OK) die(&err);
  render_ball(&map, &photo);
  char path[4096];
  snprintf(path, sizeof path, "%s/%s_ball.exr", dir, name);
  if (cf_image_write(path, &photo, 32, &err) != CF_OK) die(&err);
  if (cf_image_read(path, &read, NULL, &err) != CF_OK) die(&err);
  const cf_probe_ball ball = {BALL_CX, BALL_CY, BALL_R};
  const cf_probe_options o = {MAP_W, 2.0, 1.0, NULL};
  cf_probe_report report;
  CHECK(cf_probe_unwrap(&read, &ball, &o, &probe, &report, &err) == CF_OK, "%s", err.message);
  double ref_whole[3][9], ref_obs[3][9], got[3][9];
  irradiance_sh(&map, 0.0, ref_whole);
  irradiance_sh(&map, report.max_reflection_deg, ref_obs);
  irradiance_sh(&probe, 0.0, got);
  n.observable = sh_error(got, ref_obs, 1.0);
  n.whole = sh_error(got, ref_whole, 1.0);
  n.invalid = report.invalid_fraction;
  n.max_angle = report.max_reflection_deg;
  /* the cap beyond max_reflection_deg around −v: (1 + cos 2α_max)/2 of 4π */
  const double cap = (1.0 + cos(report.max_reflection_deg * PI / 180.0)) / 2.0;
  CHECK(fabs(n.invalid - cap) < 0.1 * cap + 1e-3, "%s: invalid %.5f, the cap %.5f", name, n.invalid,
        cap);
  if (!strcmp(name, "sunset")) check_margin(&map, name, ref_whole, ref_obs);
  cf_image brackets[3] = {{0}}, merged = {0}, probe2 = {0};
  const double scale = make_brackets(&photo, dir, 0, brackets);
  const cf_bracket_options bo = {CF_TRANSFER_SRGB, 0.0, 0.5 / 255, 254.5 / 255};
  cf_bracket_report br;
  CHECK(cf_brackets_merge(brackets, EXPOSURES, 3, NULL, &bo, &merged, &br, &err) == CF_OK, "%s",
        err.message);
  CHECK(br.saturated_everywhere == 0, "%s: %zu saturated", name, br.saturated_everywhere);
  for (int k = 0; k < 2; ++k)
    CHECK(fabs(br.measured_ratio[k] / 4.0 - 1.0) < 0.05, "%s: brackets %d/%d measure %g, not 4",
          name, k + 2, k + 1, br.measured_ratio[k]);
  /* a bracket missing (the 1st and 3rd, declared 1 and 4), and the three
   * out of order: refused, naming the brackets */
  {
    const char *gap_names[2] = {"b1.png", "b3.png"},
               *swap_names[3] = {"b2.png", "b1.png", "b3.png"};
    cf_image gap[2] = {brackets[0], brackets[2]},
             swapped[3] = {brackets[1], brackets[0], brackets[2]};
    cf_image none = {0};
    CHECK(cf_brackets_merge(gap, EXPOSURES, 2, gap_names, &bo, &none, NULL, &err) == CF_EINVAL &&
              strstr(err.message, "b3.png (bracket 2) measures 1") &&
              strstr(err.message, "times as bright as b1.png (bracket 1), but its exposure says 4"),
          "%s: missing bracket: %s", name, err.message);
    CHECK(
        cf_brackets_merge(swapped, EXPOSURES, 3, swap_names, &bo, &none, NULL, &err) == CF_EINVAL &&
            strstr(err.message, "b1.png (bracket 2) measures 0.2") &&
            strstr(err.message, "as bright as b2.png (bracket 1)"),
        "%s: swapped brackets: %s", name, err.message);
    CHECK(none.pixels == NULL, "nothing allocated on error");
  }
  CHECK(cf_probe_unwrap(&merged, &ball, &o, &probe2, NULL, &err) == CF_OK, "%s", err.message);
  irradiance_sh(&probe2, 0.0, got);
  n.brackets_observable = sh_error(got, ref_obs, scale);
  printf(
      "%-7s SH-2 irradiance error: observable %.2f %%, whole sphere %.2f %%, from 8-bit "
      "brackets %.2f %% (%zu px dark in all); invalid %.3f %% of 4π (beyond %.1f° from v), "
      "S = %d\n",
      name, 100 * n.observable, 100 * n.whole, 100 * n.brackets_observable, br.dark_everywhere,
      100 * n.invalid, n.max_angle, report.supersample);
  CHECK(n.observable < 0.05, "%s: observable %.4f", name, n.observable);
  CHECK(n.whole < 0.05, "%s: whole sphere %.4f", name, n.whole);
  CHECK(n.brackets_observable < 0.05, "%s: brackets %.4f", name, n.brackets_observable);
  for (int k = 0; k < 3; ++k) cf_image_free(&brackets[k]);
  cf_image_free(&merged);
  cf_image_free(&probe2);
  cf_image_free(&map);
  cf_image_free(&photo);
  cf_image_free(&read);
  cf_image_free(&probe);
  return n;
}

/* For the CLI tests: the studio ball as a float EXR, its three brackets
 * (PNG), and a capture (ortho_scene's photo and normals) whose light is
 * the environment map probe.exr that the CLI will write beside it. */
static void write_fixture(const char *hdri, const char *out) {
  cf_error err = {0};
  if (cf_make_dirs(out, &err) != CF_OK) die(&err);
  cf_image map = {0}, photo = {0}, brackets[3] = {{0}};
  if (cf_image_read(hdri, &map, NULL, &err) != CF_OK) die(&err);
  render_ball(&map, &photo);
  char path[4096];
  snprintf(path, sizeof path, "%s/ball.exr", out);
  if (cf_image_write(path, &photo, 32, &err) != CF_OK) die(&err);
  make_brackets(&photo, out, 1, brackets);
  cf_image mask = {0}; /* the ball's pixels: centre inside the outline */
  if (cf_image_alloc(&mask, PHOTO, PHOTO, 1, &err) != CF_OK) die(&err);
  for (int y = 0; y < PHOTO; ++y)
    for (int x = 0; x < PHOTO; ++x)
      mask.pixels[y * PHOTO + x] =
          hypot(x + 0.5 - BALL_CX, y + 0.5 - BALL_CY) < BALL_R ? 1.0f : 0.0f;
  snprintf(path, sizeof path, "%s/mask.png", out);
  if (cf_image_write(path, &mask, 8, &err) != CF_OK) die(&err);
  cf_image_free(&mask);
  cf_image normals = {0}, shaded = {0};
  const double up[3] = {0.0, 0.0, 1.0};
  if (cf_image_alloc(&normals, ORTHO_SIZE, ORTHO_SIZE, 3, &err) != CF_OK ||
      cf_image_alloc(&shaded, ORTHO_SIZE, ORTHO_SIZE, 3, &err) != CF_OK)
    die(&err);
  ortho_scene(&normals, &shaded, up);
  snprintf(path, sizeof path, "%s/normals.exr", out);
  if (cf_image_write(path, &normals, 32, &err) != CF_OK) die(&err);
  snprintf(path, sizeof path, "%s/photo.exr", out);
  if (cf_image_write(path, &shaded, 32, &err) != CF_OK) die(&err);
  snprintf(path, sizeof path, "%s/capture.json", out);
  static const char capture[] =
      "{\"clayfit_capture\": 1, \"camera\": {\"type\": \"orthographic\"},\n"
      " \"images\": {\"files\": [\"photo.exr\"]}, \"colour\": {\"encoding\": \"linear\"},\n"
      " \"geometry\": {\"type\": \"normal_map\", \"file\": \"normals.exr\"},\n"
      " \"lights\": [{\"type\": \"environment\", \"file\": \"probe.exr\", \"count\": 16}]}\n";
  if (cf_write_file(path, capture, strlen(capture), &err) != CF_OK) die(&err);
  printf("fixture for the CLI tests in %s\n", out);
  for (int k = 0; k < 3; ++k) cf_image_free(&brackets[k]);
  cf_image_free(&normals);
  cf_image_free(&shaded);
  cf_image_free(&map);
  cf_image_free(&photo);
}

int main(int argc, char **argv) {
  check_inverse();
  const double spots[3][3] = {{0.6, 0.0, 0.8}, {0.0, 0.8, -0.6}, {-0.48, -0.6, 0.64}};
  for (int i = 0; i < 3; ++i) check_spot(spots[i]);
  check_merge_errors();

  const char *shared = argc > 1 ? argv[1] : "/absent";
  char hdri[4096];
  snprintf(hdri, sizeof hdri, "%s/hdri/studio.exr", shared);
  if (!cf_path_exists(hdri)) {
    printf("skipped: %s is absent (../shared/data/hdri)\n", hdri);
    check_finish("test_light_probe");
    return check_global.failures ? 1 : CHECK_SKIPPED;
  }
  if (argc > 2) write_fixture(hdri, argv[2]);
  char dir[] = "/tmp/clayfit-light-probe-XXXXXX";
  if (!mkdtemp(dir)) {
    perror("mkdtemp");
    return 1;
  }
  static const char *const names[] = {"studio", "city", "sunset", "forest"};
  for (int i = 0; i < 4; ++i) {
    snprintf(hdri, sizeof hdri, "%s/hdri/%s.exr", shared, names[i]);
    check_map(hdri, names[i], dir);
  }
  char command[4200];
  snprintf(command, sizeof command, "rm -rf '%s'", dir);
  if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
  return check_finish("test_light_probe");
}
