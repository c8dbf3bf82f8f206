/* Environment maps reduced to directional lights by median cut (Debevec
 * 2005): a sun on a dim sky, rotation, a uniform map, negative and NaN
 * values (NaN and infinities refused), the analytic irradiance of a uniform upper hemisphere (π L),
 * and — when ../shared/data/hdri is there — the four real Poly Haven maps
 * with their timings. Usage: test_envmap [shared-data-dir] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "capture/envmap.h"
#include "support/check.h"

CHECK_MAIN_STATE;

#define PI 3.14159265358979323846
#define DEG (180.0 / PI)

static cf_directional_light lights[4096];

static double seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void make_map(cf_image *map, int width, int height, int channels, const float value[3]) {
  cf_error err = {0};
  if (cf_image_alloc(map, width, height, channels, &err) != CF_OK) {
    fprintf(stderr, "%s\n", err.message);
    exit(1);
  }
  for (size_t i = 0; i < (size_t)width * (size_t)height; ++i)
    for (int c = 0; c < channels; ++c)
      map->pixels[i * (size_t)channels + (size_t)c] = c < 3 ? value[c] : 1.0f;
}

static float *pixel(cf_image *map, int x, int y) {
  return map->pixels + ((size_t)y * (size_t)map->width + (size_t)x) * (size_t)map->channels;
}

/* Σ L dω per channel, computed here from envmap.h's convention, with
 * negative and non-finite values as 0. */
static void map_total(const cf_image *map, double total[3]) {
  total[0] = total[1] = total[2] = 0.0;
  for (int y = 0; y < map->height; ++y) {
    double d_omega =
        (2.0 * PI / map->width) * (PI / map->height) * sin(PI * (y + 0.5) / map->height);
    for (int x = 0; x < map->width; ++x)
      for (int c = 0; c < 3; ++c) {
        float v = map->pixels[((size_t)y * (size_t)map->width + (size_t)x) * (size_t)map->channels +
                              (size_t)c];
        if (isfinite(v) && v > 0.0f) total[c] += v * d_omega;
      }
  }
}

static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double angle_deg(const double a[3], const double b[3]) {
  double c = dot3(a, b) / sqrt(dot3(a, a) * dot3(b, b));
  return acos(fmax(-1.0, fmin(1.0, c))) * DEG;
}

static double lum(const double rgb[3]) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

/* The largest relative difference between the lights' total and the map's. */
static double total_error(const cf_directional_light *l, int k, const double total[3]) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    double sum = 0.0;
    for (int j = 0; j < k; ++j) sum += l[j].irradiance[c];
    worst = fmax(worst, fabs(sum - total[c]) / fabs(total[c]));
  }
  return worst;
}

static int run(const cf_image *map, const double rotation[9], int k, cf_envmap_report *report) {
  cf_error err = {0};
  cf_status s = cf_envmap_median_cut(map, rotation, k, lights, report, &err);
  CHECK(s == CF_OK, "median cut, k = %d: %s", k, err.message);
  for (int j = 0; s == CF_OK && j < k; ++j)
    CHECK(fabs(dot3(lights[j].direction, lights[j].direction) - 1.0) < 1e-12, "light %d not unit",
          j);
  return s == CF_OK;
}

/* (1) a small bright sun on a dim uniform sky */
static void test_sun(void) {
  const int w = 512, h = 256, sx = 100, sy = 61;
  const float sky[3] = {0.1f, 0.12f, 0.15f};
  cf_image map;
  make_map(&map, w, h, 3, sky);
  for (int y = sy - 1; y <= sy + 1; ++y)
    for (int x = sx - 1; x <= sx + 1; ++x) {
      float *p = pixel(&map, x, y);
      p[0] = 2.0e4f, p[1] = 1.8e4f, p[2] = 1.5e4f;
    }
  double sun[3], total[3];
  cf_envmap_direction(w, h, sx, sy, sun);
  map_total(&map, total);
  printf("sun at (%d, %d): direction %.4f %.4f %.4f; map total %.6g %.6g %.6g\n", sx, sy, sun[0],
         sun[1], sun[2], total[0], total[1], total[2]);
  static const int ks[] = {1, 2, 3, 8, 64, 255, 1000, 4096};
  for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i) {
    const int k = ks[i];
    cf_envmap_report report;
    double t0 = seconds();
    if (!run(&map, NULL, k, &report)) continue;
    double dt = seconds() - t0;
    int brightest = 0;
    for (int j = 1; j < k; ++j)
      if (lum(lights[j].irradiance) > lum(lights[brightest].irradiance)) brightest = j;
    double off = angle_deg(lights[brightest].direction, sun);
    double err_total = total_error(lights, k, total);
    printf(
        "k = %4d: brightest light %.3f deg from the sun carrying %.4g (luminance); total error "
        "%.2g; %.2f ms\n",
        k, off, lum(lights[brightest].irradiance), err_total, 1e3 * dt);
    CHECK(err_total < 1e-9, "k = %d: lights' total off by %g", k, err_total);
    /* the patch spans ±1 pixel (0.85 deg to its corners); for small k > 1
     * the sun's region also holds sky, which pulls its centroid */
    CHECK(off < (k == 1 ? 0.5 : 1.5), "k = %d: brightest light %g deg from the sun", k, off);
    for (int c = 0; c < 3; ++c)
      CHECK(fabs(report.total[c] - total[c]) < 1e-9 * total[c], "report total %d", c);
    CHECK(report.clamped == 0, "nothing to clamp: %zu", report.clamped);
    if (k == 1)
      for (int c = 0; c < 3; ++c)
        CHECK(fabs(lights[0].irradiance[c] - total[c]) < 1e-9 * total[c], "k = 1 carries all");
  }
  cf_image_free(&map);
}

/* (2) a rotation turns every direction and changes nothing else */
static void test_rotation(void) {
  const float sky[3] = {0.2f, 0.2f, 0.2f};
  cf_image map;
  make_map(&map, 256, 128, 3, sky);
  for (int y = 20; y < 30; ++y)
    for (int x = 40; x < 60; ++x) pixel(&map, x, y)[1] = 50.0f;
  /* 40 degrees about (1, 2, 3)/|.| (Rodrigues) */
  double axis[3] = {1, 2, 3}, n = sqrt(14.0), a = 40.0 / DEG, r[9];
  for (int i = 0; i < 3; ++i) axis[i] /= n;
  const double c = cos(a), s = sin(a),
               k3[9] = {0, -axis[2], axis[1], axis[2], 0, -axis[0], -axis[1], axis[0], 0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double kk = 0.0;
      for (int m = 0; m < 3; ++m) kk += k3[3 * i + m] * k3[3 * m + j];
      r[3 * i + j] = (i == j) + s * k3[3 * i + j] + (1 - c) * kk;
    }
  const int k = 12;
  static cf_directional_light plain[12];
  if (!run(&map, NULL, k, NULL)) return;
  memcpy(plain, lights, sizeof plain);
  if (!run(&map, r, k, NULL)) return;
  double worst = 0.0, turned = 0.0;
  int same_light = 1;
  for (int j = 0; j < k; ++j) {
    double expected[3];
    for (int i = 0; i < 3; ++i)
      expected[i] = r[3 * i] * plain[j].direction[0] + r[3 * i + 1] * plain[j].direction[1] +
                    r[3 * i + 2] * plain[j].direction[2];
    for (int i = 0; i < 3; ++i) worst = fmax(worst, fabs(expected[i] - lights[j].direction[i]));
    turned = fmax(turned, angle_deg(plain[j].direction, lights[j].direction));
    for (int ch = 0; ch < 3; ++ch)
      same_light &= plain[j].irradiance[ch] == lights[j].irradiance[ch];
  }
  printf("rotation by 40 deg: |R d - d_rotated| <= %.2g, directions turned up to %.2f deg\n", worst,
         turned);
  CHECK(worst < 1e-12, "rotated directions off by %g", worst);
  CHECK(turned > 1.0, "the rotation did nothing");
  CHECK(same_light, "irradiance changed under rotation");
  /* not a rotation */
  double bad[9] = {1, 0, 0, 0, 2, 0, 0, 0, 1};
  cf_error err = {0};
  CHECK(cf_envmap_median_cut(&map, bad, 4, lights, NULL, &err) == CF_EINVAL,
        "a scaling accepted as rotation");
  printf("scaled rotation: %s\n", err.message);
  /* a mirror (the old convention needed one to match a renderer) */
  double mirror[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1};
  CHECK(cf_envmap_median_cut(&map, mirror, 4, lights, NULL, &err) == CF_EINVAL &&
            strstr(err.message, "a mirror"),
        "a mirror accepted as rotation: %s", err.message);
  printf("mirror: %s\n", err.message);
  /* the convention is three.js' equirectUv: u = atan2(d_z, d_x)/2π + ½,
   * the row from the top acos(d_y)/π (so Cycles' too, after (x, −z, y)) */
  double worst_uv = 0.0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      double d[3];
      cf_envmap_direction(64, 32, x, y, d);
      double u = atan2(d[2], d[0]) / (2.0 * PI) + 0.5, v = acos(d[1]) / PI;
      double du = fabs(u - (x + 0.5) / 64.0);
      du = fmin(du, fabs(du - 1.0));
      worst_uv = fmax(worst_uv, fmax(du, fabs(v - (y + 0.5) / 32.0)));
    }
  printf("three.js' equirectUv of cf_envmap_direction: off the texel centres by %.2g\n", worst_uv);
  CHECK(worst_uv < 1e-12, "not three.js' equirectangular lookup: off by %g", worst_uv);
  CHECK(cf_envmap_median_cut(&map, NULL, 0, lights, NULL, &err) == CF_EINVAL, "k = 0");
  CHECK(
      cf_envmap_median_cut(&map, NULL, CF_ENVMAP_MAX_LIGHTS + 1, lights, NULL, &err) == CF_EINVAL &&
          strstr(err.message, "give 1 to"),
      "k = %d: %s", CF_ENVMAP_MAX_LIGHTS + 1, err.message);
  cf_image tiny;
  make_map(&tiny, 4, 2, 3, sky);
  CHECK(cf_envmap_median_cut(&tiny, NULL, 8, lights, NULL, &err) == CF_OK, "8 lights of 8 px");
  CHECK(cf_envmap_median_cut(&tiny, NULL, 9, lights, NULL, &err) == CF_EINVAL, "9 of 8 px");
  printf("9 lights from 8 pixels: %s\n", err.message);
  cf_image_free(&tiny);
  cf_image_free(&map);
}

/* (3) a uniform map: the lights spread over the sphere with equal shares */
static void test_uniform(void) {
  const float one[3] = {1.0f, 1.0f, 1.0f};
  cf_image map;
  make_map(&map, 512, 256, 3, one);
  const int k = 16;
  if (!run(&map, NULL, k, NULL)) return;
  double min_angle = 180.0, e_min = INFINITY, e_max = 0.0, e_sum = 0.0, resultant[3] = {0, 0, 0};
  for (int i = 0; i < k; ++i) {
    double e = lights[i].irradiance[1];
    e_min = fmin(e_min, e), e_max = fmax(e_max, e), e_sum += e;
    for (int c = 0; c < 3; ++c) resultant[c] += e * lights[i].direction[c];
    for (int j = 0; j < i; ++j)
      min_angle = fmin(min_angle, angle_deg(lights[i].direction, lights[j].direction));
  }
  double balance = sqrt(dot3(resultant, resultant)) / e_sum;
  printf(
      "uniform map, k = 16: closest pair %.1f deg apart; irradiance %.4f .. %.4f (4 pi / 16 = "
      "%.4f); |sum E l| / sum E = %.3g\n",
      min_angle, e_min, e_max, 4.0 * PI / 16.0, balance);
  CHECK(min_angle > 20.0, "two lights %g deg apart", min_angle);
  CHECK(e_max / e_min < 1.1, "unequal shares: %g .. %g", e_min, e_max);
  CHECK(fabs(e_sum - 4.0 * PI) < 1e-4 * 4.0 * PI, "total %g, 4 pi = %g", e_sum, 4.0 * PI);
  CHECK(balance < 0.02, "the lights do not balance: %g", balance);
  /* k = 1 of a uniform map: no mean direction; the light sits at the centre */
  if (run(&map, NULL, 1, NULL))
    CHECK(fabs(lights[0].irradiance[0] - e_sum) < 1e-9 * e_sum, "k = 1 total %g",
          lights[0].irradiance[0]);
  cf_image_free(&map);
}

/* (4) negative values count as 0 and are reported; a NaN or an infinity
 * in the first three channels is refused, naming the first one's texel
 * and channel (a 4th channel is ignored, NaN or not) */
static void test_bad_values(void) {
  const float sky[3] = {0.5f, 0.4f, 0.3f};
  for (int channels = 3; channels <= 4; ++channels) {
    cf_image map, clean;
    make_map(&map, 64, 32, channels, sky);
    make_map(&clean, 64, 32, channels, sky);
    pixel(&map, 3, 4)[0] = -3.0f;
    pixel(&map, 63, 31)[0] = -1e30f;
    pixel(&map, 7, 7)[1] = -0.0f; /* zero, not negative */
    pixel(&clean, 3, 4)[0] = 0.0f;
    pixel(&clean, 63, 31)[0] = 0.0f;
    pixel(&clean, 7, 7)[1] = 0.0f;
    if (channels == 4)
      for (size_t i = 0; i < 64 * 32; ++i) map.pixels[i * 4 + 3] = NAN; /* ignored */
    static cf_directional_light expected[5];
    cf_envmap_report report, clean_report;
    if (!run(&clean, NULL, 5, &clean_report)) continue;
    memcpy(expected, lights, sizeof expected);
    if (!run(&map, NULL, 5, &report)) continue;
    int same = 1, finite = 1;
    for (int j = 0; j < 5; ++j)
      for (int c = 0; c < 3; ++c) {
        same &= lights[j].irradiance[c] == expected[j].irradiance[c] &&
                lights[j].direction[c] == expected[j].direction[c];
        finite &= isfinite(lights[j].irradiance[c]) && isfinite(lights[j].direction[c]);
      }
    printf("%d channels with -3, -1e30 (and -0): %zu clamped; lights as with zeros: %s\n",
           channels, report.clamped, same ? "yes" : "no");
    CHECK(report.clamped == 2, "clamped %zu, expected 2", report.clamped);
    CHECK(clean_report.clamped == 0, "clean map clamped %zu", clean_report.clamped);
    CHECK(same && finite, "negative values not treated as 0");
    for (int c = 0; c < 3; ++c)
      CHECK(report.total[c] == clean_report.total[c], "report total %d", c);
    /* non-finite: refused, the first in row-major order named */
    static const struct {
      int x, y, channel;
      float value;
      const char *says;
    } bad[] = {{10, 20, 1, NAN, "1 non-finite value (NaN or infinity); the first is NaN at texel "
                                "(10, 20) (column, row from the top-left), channel 1 (G)"},
               {30, 5, 2, INFINITY, "the first is an infinity at texel (30, 5)"},
               {63, 31, 0, -INFINITY, "an infinity at texel (63, 31) (column, row from the "
                                      "top-left), channel 0 (R)"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
      pixel(&map, bad[i].x, bad[i].y)[bad[i].channel] = bad[i].value;
      cf_error err = {0};
      cf_status s = cf_envmap_median_cut(&map, NULL, 5, lights, &report, &err);
      printf("  %g: %s\n", (double)bad[i].value, err.message);
      CHECK(s == CF_EINVAL && strstr(err.message, bad[i].says), "refused: %s", err.message);
      pixel(&map, bad[i].x, bad[i].y)[bad[i].channel] = sky[bad[i].channel];
    }
    cf_image_free(&map);
    cf_image_free(&clean);
  }
}

/* (5) a uniform sky of radiance L over the upper hemisphere: an upward
 * surface receives ∫ L cos θ dω = π L; one tilted by α receives
 * π L (1 + cos α) / 2 */
static void test_hemisphere(void) {
  const int w = 512, h = 256;
  const float zero[3] = {0.0f, 0.0f, 0.0f};
  const double radiance = 1.0;
  cf_image map;
  make_map(&map, w, h, 3, zero);
  double discrete = 0.0;
  for (int y = 0; y < h / 2; ++y) {
    double theta = PI * (y + 0.5) / h;
    discrete += w * (2.0 * PI / w) * (PI / h) * sin(theta) * cos(theta) * radiance;
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) pixel(&map, x, y)[c] = (float)radiance;
  }
  const int k = 256;
  double t0 = seconds();
  if (!run(&map, NULL, k, NULL)) return;
  double dt = seconds() - t0;
  const double alpha = 60.0 / DEG;
  const double up[3] = {0, 1, 0}, tilted[3] = {sin(alpha), cos(alpha), 0};
  double e_up = 0.0, e_tilted = 0.0, below = 0.0;
  for (int j = 0; j < k; ++j) {
    e_up += lights[j].irradiance[0] * fmax(0.0, dot3(up, lights[j].direction));
    e_tilted += lights[j].irradiance[0] * fmax(0.0, dot3(tilted, lights[j].direction));
    if (lights[j].direction[1] < 0.0) below += lights[j].irradiance[0];
  }
  const double exact_up = PI * radiance, exact_tilted = PI * radiance * (1 + cos(alpha)) / 2;
  printf(
      "upper hemisphere, k = %d (%.2f ms): sum E max(0, n.l) = %.6f, pi L = %.6f (rel. %.2g; "
      "the map itself %.6f); tilted 60 deg %.6f vs %.6f (rel. %.2g); light below the "
      "horizon %.3g\n",
      k, 1e3 * dt, e_up, exact_up, e_up / exact_up - 1, discrete, e_tilted, exact_tilted,
      e_tilted / exact_tilted - 1, below);
  CHECK(fabs(e_up / exact_up - 1) < 0.005, "upward irradiance %g vs %g", e_up, exact_up);
  CHECK(fabs(e_tilted / exact_tilted - 1) < 0.01, "tilted irradiance %g vs %g", e_tilted,
        exact_tilted);
  CHECK(below == 0.0, "light below the horizon: %g", below);
  cf_image_free(&map);
}

/* (6) the real maps, and a 2048 × 1024 one for time */
static int test_real(const char *data) {
  static const char *names[] = {"studio", "city", "sunset", "forest"};
  char folder[512];
  snprintf(folder, sizeof folder, "%s/hdri", data ? data : "");
  struct stat st;
  if (!data || stat(folder, &st) != 0 || !S_ISDIR(st.st_mode)) {
    printf("skipped: no HDRIs at %s\n", data ? folder : "(no shared data folder given)");
    return 0;
  }
  int ran = 0;
  cf_image big = {0, 0, 0, NULL};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
    char path[600];
    snprintf(path, sizeof path, "%s/%s.exr", folder, names[i]);
    if (stat(path, &st) != 0) {
      printf("skipped: %s is absent\n", path);
      continue;
    }
    cf_image map;
    cf_image_info info;
    cf_error err = {0};
    CHECK(cf_image_read(path, &map, &info, &err) == CF_OK, "%s", err.message);
    if (!map.pixels) continue;
    ++ran;
    double total[3];
    map_total(&map, total);
    size_t negative = 0;
    float lowest = 0.0f;
    for (size_t v = 0; v < (size_t)map.width * map.height * (size_t)map.channels; ++v)
      if (map.pixels[v] < 0.0f) ++negative, lowest = fminf(lowest, map.pixels[v]);
    printf(
        "%s: %d x %d x %d %s (%d bits); %zu negative values (lowest %.1f); total %.4g %.4g "
        "%.4g\n",
        names[i], map.width, map.height, map.channels, info.format, info.bits_per_sample, negative,
        lowest, total[0], total[1], total[2]);
    static const int ks[] = {1, 8, 64};
    for (size_t j = 0; j < 3; ++j) {
      cf_envmap_report report;
      double t0 = seconds();
      if (!run(&map, NULL, ks[j], &report)) continue;
      double dt = seconds() - t0, e = total_error(lights, ks[j], total);
      int brightest = 0;
      for (int m = 1; m < ks[j]; ++m)
        if (lum(lights[m].irradiance) > lum(lights[brightest].irradiance)) brightest = m;
      const double *d = lights[brightest].direction;
      printf(
          "  k = %2d: %.2f ms, %zu clamped, total error %.2g, brightest light (%.3f, %.3f, "
          "%.3f) with %.4g\n",
          ks[j], 1e3 * dt, report.clamped, e, d[0], d[1], d[2], lum(lights[brightest].irradiance));
      CHECK(report.clamped >= negative, "%s: %zu clamped < %zu negative", names[i], report.clamped,
            negative);
      CHECK(e < 1e-9, "%s, k = %d: total off by %g", names[i], ks[j], e);
    }
    if (!big.pixels) { /* the first map, blown up 4× by nearest neighbour */
      if (cf_image_alloc(&big, 4 * map.width, 4 * map.height, 3, &err) == CF_OK)
        for (int y = 0; y < big.height; ++y)
          for (int x = 0; x < big.width; ++x)
            memcpy(pixel(&big, x, y), pixel(&map, x / 4, y / 4), 3 * sizeof(float));
    }
    cf_image_free(&map);
  }
  if (big.pixels) {
    double total[3];
    map_total(&big, total);
    static const int ks[] = {1, 64, 4096};
    for (size_t j = 0; j < 3; ++j) {
      cf_envmap_report report;
      double t0 = seconds();
      if (!run(&big, NULL, ks[j], &report)) continue;
      double dt = seconds() - t0, e = total_error(lights, ks[j], total);
      printf("%d x %d (the first map, 4x): k = %4d in %.1f ms, total error %.2g\n", big.width,
             big.height, ks[j], 1e3 * dt, e);
      CHECK(e < 1e-9, "2048 x 1024, k = %d: total off by %g", ks[j], e);
      CHECK(dt < 10.0, "2048 x 1024, k = %d took %.1f s", ks[j], dt);
    }
    cf_image_free(&big);
  }
  return ran;
}

int main(int argc, char **argv) {
  test_sun();
  test_rotation();
  test_uniform();
  test_bad_values();
  test_hemisphere();
  test_real(argc > 1 ? argv[1] : NULL);
  return check_finish("test_envmap");
}
