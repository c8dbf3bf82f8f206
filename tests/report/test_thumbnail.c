/* The fitted sphere under the standard light (include/clayfit/thumbnail.h):
 *   - a Lambertian material renders, at every pixel the silhouette does not
 *     cross, to the analytic (ρ/π)(0.8π max(0, n·l_key) + 0.2π max(0, n·l_fill))
 *     at the pixel centre's normal, to 1e-6 (the lights and the camera
 *     written here from the documentation, not taken from the code);
 *   - an albedo-1 Lambertian sphere peaks at 0.8 (facing the key);
 *   - the background is the view's colour; silhouette pixels lie between,
 *     each the share of its 3 × 3 samples on the sphere (a black sphere on
 *     white sums to the disc's area);
 *   - a highlight narrower than a pixel is integrated over the pixel (its
 *     sum near a 16 × 16-sample reference);
 *   - an M2, M3 and M4 render (glossy ones too: the highlight's footprint
 *     integration) is finite and non-negative;
 *   - a brighter albedo gives a brighter sphere (linear and PNG);
 *   - the view's own lights (the report's material view): the standard
 *     light given as its own lights renders the same image to the bit; a
 *     coloured light from the upper right, irradiance (2, 0.5, 0), renders
 *     each channel to its analytic Lambert value (1e-6); 33 lights, a
 *     negative irradiance or no directions are refused;
 *   - the PNG exists, 256 × 256, holds the tone-mapped sRGB values, and no
 *     temporary is left; a write into a missing folder fails (CF_EIO) and
 *     leaves nothing; bad views and parameters are refused.
 * Prints the time of a 256² render and write (not asserted).
 * usage: test_thumbnail WORKDIR */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clayfit/thumbnail.h"
#include "core/file.h"
#include "support/check.h"

#pragma GCC diagnostic ignored "-Wformat-truncation" /* paths in a test's folder */

CHECK_MAIN_STATE;

static const double pi = 3.14159265358979323846;

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static float pixel(const cf_image *im, int x, int y, int c) {
  return im->pixels[3 * ((size_t)y * (size_t)im->width + (size_t)x) + c];
}

/* The documented scene: centre N/2, radius 0.92 N/2 (the default view),
 * y up; key (−4, 4, 7)/9 at 0.8π, fill (6, −2, 3)/7 at 0.2π. */
static double lambert_expected(double albedo, int size, double radius, int x, int y) {
  double centre = 0.5 * size, r = radius * centre;
  double u = (x + 0.5 - centre) / r, w = (centre - (y + 0.5)) / r, z = sqrt(1.0 - u * u - w * w);
  double key = (-4.0 * u + 4.0 * w + 7.0 * z) / 9.0, fill = (6.0 * u - 2.0 * w + 3.0 * z) / 7.0;
  return albedo / pi * (0.8 * pi * fmax(0.0, key) + 0.2 * pi * fmax(0.0, fill));
}

/* -1 for a pixel wholly off the sphere, 1 wholly on it, 0 crossed. */
static int pixel_class(int size, double radius, int x, int y) {
  double centre = 0.5 * size, r = radius * centre;
  double d = hypot(x + 0.5 - centre, y + 0.5 - centre) - r;
  return d >= 0.7072 ? -1 : d <= -0.7072 ? 1 : 0;
}

static void test_lambert(void) {
  const double albedo[3] = {0.3, 0.55, 1.0};
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  CHECK(view.size == 256 && view.radius == 0.92 && view.background[1] == 0.18, "default view");
  cf_image im;
  cf_error err = {0};
  cf_status s = cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &im, &err);
  CHECK(s == CF_OK, "lambert render: %s", err.message);
  if (s != CF_OK) return;
  CHECK(im.width == 256 && im.height == 256 && im.channels == 3, "size %dx%dx%d", im.width,
        im.height, im.channels);
  long inside = 0, bad = 0, background_bad = 0, edge_bad = 0;
  double worst = 0.0, peak = 0.0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      int k = pixel_class(view.size, view.radius, x, y);
      for (int c = 0; c < 3; ++c) {
        float v = pixel(&im, x, y, c);
        if (k == 1) {
          double e = fabs(v - lambert_expected(albedo[c], view.size, view.radius, x, y));
          worst = fmax(worst, e);
          bad += !(e <= 1e-6);
        } else if (k == -1) {
          background_bad += v != (float)view.background[c];
        } else {
          edge_bad += !(v >= 0.0f && v <= 0.8f + 1e-6f);
        }
        if (c == 2) peak = fmax(peak, v);
      }
      inside += k == 1;
    }
  printf("lambert: %ld pixels wholly on the sphere, largest error %.3g; albedo-1 peak %.6f\n",
         inside, worst, peak);
  CHECK(inside > 40000, "%ld pixels on the sphere", inside);
  CHECK(bad == 0, "%ld values off the analytic Lambert value by more than 1e-6 (worst %.3g)", bad,
        worst);
  CHECK(background_bad == 0, "%ld background values are not the background colour", background_bad);
  CHECK(edge_bad == 0, "%ld silhouette values outside [0, 0.8]", edge_bad);
  CHECK(peak >= 0.8 - 1e-3 && peak <= 0.8 + 1e-6, "an albedo-1 Lambertian sphere peaks at %.6f",
        peak);
  /* the centre pixel, by name */
  CHECK(fabs(pixel(&im, 128, 128, 0) - lambert_expected(0.3, 256, 0.92, 128, 128)) <= 1e-6,
        "centre %g", pixel(&im, 128, 128, 0));
  cf_image_free(&im);

  /* another background and size: the corners take it exactly */
  view.size = 64;
  view.background[0] = 0.1, view.background[1] = 0.2, view.background[2] = 0.3;
  s = cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &im, &err);
  CHECK(s == CF_OK, "%s", err.message);
  if (s != CF_OK) return;
  for (int c = 0; c < 3; ++c)
    CHECK(pixel(&im, 0, 0, c) == (float)view.background[c] &&
              pixel(&im, 63, 63, c) == (float)view.background[c],
          "corner channel %d: %g", c, pixel(&im, 0, 0, c));
  cf_image_free(&im);
}

/* The silhouette: a black sphere (albedo 0) on white. Each pixel is the
 * share of its 3 × 3 samples off the sphere, so the image's darkness sums
 * to the disc's area πR², and the pixels the edge crosses are partial. */
static void test_silhouette(void) {
  const double black[3] = {0.0, 0.0, 0.0};
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  for (int c = 0; c < 3; ++c) view.background[c] = 1.0;
  cf_image im;
  cf_error err = {0};
  cf_status s = cf_sphere_render(CF_MODEL_LAMBERT, black, &view, &im, &err);
  CHECK(s == CF_OK, "%s", err.message);
  if (s != CF_OK) return;
  double area = 0.0, r = view.radius * 0.5 * view.size;
  long partial = 0, off_grid = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      float v = pixel(&im, x, y, 0);
      area += 1.0 - v;
      partial += v > 0.0f && v < 1.0f;
      off_grid += fabs(9.0 * v - round(9.0 * v)) > 1e-5;
    }
  printf("silhouette: area %.1f px for pi R^2 = %.1f, %ld partial pixels\n", area, pi * r * r,
         partial);
  CHECK(fabs(area - pi * r * r) < 2e-3 * pi * r * r, "area %g for %g", area, pi * r * r);
  CHECK(partial > 400, "only %ld pixels on the silhouette are partial", partial);
  CHECK(off_grid == 0, "%ld pixels are not a share of 9 samples", off_grid);
  cf_image_free(&im);
}

static double image_sum(const cf_image *im) {
  double sum = 0.0;
  for (size_t i = 0; i < 3 * (size_t)im->width * (size_t)im->height; ++i) sum += im->pixels[i];
  return sum;
}

/* A highlight narrower than a pixel (M2, roughness 0.03: α = 9e-4 rad) is
 * integrated over the pixel: the image's sum is nearer a reference of 16 ×
 * 16 samples wherever needed than pixel centres are, by a factor of 3 at
 * least (measured: 101 against 1,108, 2026-11-26). */
static void test_highlight_footprint(void) {
  double p[CF_MAX_DIM];
  cf_model_default_params(CF_MODEL_DIELECTRIC, p);
  p[CF_DIELECTRIC_ROUGHNESS] = 0.03;
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  cf_image standard, centre, reference;
  cf_error err = {0};
  cf_status s = cf_sphere_render(CF_MODEL_DIELECTRIC, p, &view, &standard, &err);
  view.footprint_tolerance = 0.0;
  if (s == CF_OK) s = cf_sphere_render(CF_MODEL_DIELECTRIC, p, &view, &centre, &err);
  view.footprint_tolerance = 1e-6;
  view.footprint_max = 16;
  if (s == CF_OK) s = cf_sphere_render(CF_MODEL_DIELECTRIC, p, &view, &reference, &err);
  CHECK(s == CF_OK, "%s", err.message);
  if (s != CF_OK) return;
  double ref = image_sum(&reference), a = fabs(image_sum(&standard) - ref),
         b = fabs(image_sum(&centre) - ref);
  printf("highlight: the image's sum off the reference's by %.1f (pixel centres: %.1f)\n", a, b);
  CHECK(a < b / 3.0, "footprint %g, centres %g off the reference", a, b);
  cf_image_free(&standard);
  cf_image_free(&centre);
  cf_image_free(&reference);
}

static double sphere_mean(const cf_image *im) {
  double sum = 0.0;
  long n = 0;
  for (int y = 0; y < im->height; ++y)
    for (int x = 0; x < im->width; ++x)
      if (pixel_class(im->width, 0.92, x, y) == 1) {
        for (int c = 0; c < 3; ++c) sum += pixel(im, x, y, c);
        ++n;
      }
  return n ? sum / (3.0 * (double)n) : NAN;
}

/* Every model at its defaults and at a glossy setting: finite, >= 0. */
static void test_models(void) {
  for (int m = 0; m < CF_MODEL_COUNT; ++m)
    for (int glossy = 0; glossy < 2; ++glossy) {
      double p[CF_MAX_DIM];
      cf_model_default_params((cf_model_id)m, p);
      int slot;
      cf_error err = {0};
      const char *rough[] = {"roughness", "film_roughness", "base_roughness"};
      for (int k = 0; glossy && k < 3; ++k)
        if (cf_model_param_find((cf_model_id)m, rough[k], &slot, NULL, NULL) == CF_OK)
          p[slot] = 0.03;
      cf_image im;
      const cf_sphere_view zero = {0};
      cf_status s = cf_sphere_render((cf_model_id)m, p, &zero, &im, &err);
      CHECK(s == CF_EINVAL, "a zero view is refused");
      cf_sphere_view view;
      cf_sphere_view_default(&view);
      s = cf_sphere_render((cf_model_id)m, p, &view, &im, &err);
      CHECK(s == CF_OK, "model %d: %s", m, err.message);
      if (s != CF_OK) continue;
      long bad = 0;
      float top = 0.0f;
      for (size_t i = 0; i < 3 * (size_t)im.width * (size_t)im.height; ++i) {
        bad += !(isfinite(im.pixels[i]) && im.pixels[i] >= 0.0f);
        top = fmaxf(top, im.pixels[i]);
      }
      CHECK(bad == 0, "model %d glossy %d: %ld values not finite or negative", m, glossy, bad);
      printf("%s%s: mean on the sphere %.4f, brightest %.4f\n",
             cf_model_info_get((cf_model_id)m)->code, glossy ? " glossy" : "", sphere_mean(&im),
             top);
      cf_image_free(&im);
    }
}

/* A brighter albedo gives a brighter sphere, for a Lambertian and a clay
 * (M4) material, in the linear render and in the PNG. */
static void test_albedo_order(const char *work) {
  cf_fit_result dark, light;
  memset(&dark, 0, sizeof dark);
  dark.model = CF_MODEL_CLAY;
  cf_model_default_params(CF_MODEL_CLAY, dark.params);
  light = dark;
  for (int c = 0; c < 3; ++c) dark.params[CF_CLAY_ALBEDO + c] = 0.25;
  for (int c = 0; c < 3; ++c) light.params[CF_CLAY_ALBEDO + c] = 0.6;
  cf_image a, b;
  cf_error err = {0};
  cf_status s = cf_report_render_sphere(&dark, NULL, &a, &err);
  if (s == CF_OK) s = cf_report_render_sphere(&light, NULL, &b, &err);
  CHECK(s == CF_OK, "%s", err.message);
  if (s != CF_OK) return;
  long darker = 0;
  for (size_t i = 0; i < 3 * (size_t)a.width * (size_t)a.height; ++i)
    darker += a.pixels[i] > b.pixels[i] + 1e-7f;
  CHECK(darker == 0, "%ld values of albedo 0.25 brighter than albedo 0.6's", darker);
  CHECK(sphere_mean(&a) < sphere_mean(&b) - 0.05, "means %g, %g", sphere_mean(&a), sphere_mean(&b));
  cf_image_free(&a);
  cf_image_free(&b);

  char pa[1024], pb[1024];
  snprintf(pa, sizeof pa, "%s/dark.png", work);
  snprintf(pb, sizeof pb, "%s/light.png", work);
  s = cf_report_write_thumbnail(&dark, NULL, pa, &err);
  if (s == CF_OK) s = cf_report_write_thumbnail(&light, NULL, pb, &err);
  CHECK(s == CF_OK, "%s", err.message);
  s = cf_image_read(pa, &a, NULL, &err);
  if (s == CF_OK) s = cf_image_read(pb, &b, NULL, &err);
  CHECK(s == CF_OK, "%s", err.message);
  if (s != CF_OK) return;
  CHECK(sphere_mean(&a) < sphere_mean(&b) - 0.05, "PNG means %g, %g", sphere_mean(&a),
        sphere_mean(&b));
  cf_image_free(&a);
  cf_image_free(&b);
}

static int leftovers(const char *dir) {
  DIR *d = opendir(dir);
  int n = 0;
  for (struct dirent *e; d && (e = readdir(d));) n += strstr(e->d_name, ".tmp-") != NULL;
  if (d) closedir(d);
  return n;
}

static void test_png(const char *work) {
  const double albedo[3] = {0.2, 0.4, 0.8};
  char path[1024];
  snprintf(path, sizeof path, "%s/lambert.png", work);
  cf_image linear, read;
  cf_error err = {0};
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  cf_status s = cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &linear, &err);
  if (s == CF_OK) s = cf_sphere_write_png(&linear, path, &err);
  CHECK(s == CF_OK, "%s", err.message);
  cf_image_header h;
  s = cf_image_read_header(path, &h, &err);
  CHECK(s == CF_OK && h.width == 256 && h.height == 256 && h.channels == 3 &&
            strcmp(h.info.format, "png") == 0 && h.info.bits_per_sample == 8,
        "PNG header: %s %dx%dx%d %s %d bits", err.message, h.width, h.height, h.channels,
        h.info.format, h.info.bits_per_sample);
  CHECK(leftovers(work) == 0, "a temporary is left in %s", work);
  s = cf_image_read(path, &read, NULL, &err);
  CHECK(s == CF_OK, "%s", err.message);
  if (s == CF_OK) {
    long bad = 0;
    for (size_t i = 0; i < 3 * (size_t)read.width * (size_t)read.height; ++i) {
      double want = cf_linear_to_srgb(cf_sphere_tone(linear.pixels[i]));
      bad += fabs(read.pixels[i] - want) > 0.5 / 255.0 + 1e-6;
    }
    CHECK(bad == 0, "%ld PNG values are not the tone-mapped sRGB of the render", bad);
    cf_image_free(&read);
  }

  /* a missing folder: CF_EIO naming the file, nothing written */
  char missing[1100];
  snprintf(missing, sizeof missing, "%s/no-such-folder/t.png", work);
  cf_error e2 = {0};
  s = cf_sphere_write_png(&linear, missing, &e2);
  CHECK(s == CF_EIO && strstr(e2.message, "no-such-folder"), "missing folder: %d %s", s,
        e2.message);
  CHECK(!cf_path_exists(missing), "%s was written", missing);
  cf_image_free(&linear);

  /* the tone curve: identity to the knee, continuous, rising, below 1 */
  CHECK(cf_sphere_tone(0.5) == 0.5 && cf_sphere_tone(CF_SPHERE_KNEE) == CF_SPHERE_KNEE &&
            fabs(cf_sphere_tone(0.8 + 1e-9) - 0.8) < 1e-8 && cf_sphere_tone(2.0) < 1.0 &&
            cf_sphere_tone(2.0) > cf_sphere_tone(1.0) && cf_sphere_tone(-1.0) == 0.0 &&
            cf_sphere_tone(NAN) == 0.0,
        "tone curve");
}

static void test_own_lights(void) {
  const double albedo[3] = {0.5, 0.5, 0.5};
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  view.size = 64;
  cf_image standard = {0}, own = {0}, coloured = {0};
  cf_error err = {0};
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &standard, &err) == CF_OK, "%s",
        err.message);
  double direction[6], irradiance[6];
  for (int k = 0; k < 2; ++k)
    for (int c = 0; c < 3; ++c) {
      direction[3 * k + c] = cf_sphere_lights()[k].direction[c];
      irradiance[3 * k + c] = cf_sphere_lights()[k].irradiance;
    }
  view.light_count = 2;
  view.light_direction = direction;
  view.light_irradiance = irradiance;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &own, &err) == CF_OK, "%s", err.message);
  CHECK(standard.pixels && own.pixels &&
            memcmp(standard.pixels, own.pixels, 3 * 64 * 64 * sizeof(float)) == 0,
        "the standard light given as the view's lights renders another image");
  const double l[3] = {0.6, 0.0, 0.8}, e[3] = {2.0, 0.5, 0.0};
  view.light_count = 1;
  view.light_direction = l;
  view.light_irradiance = e;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &coloured, &err) == CF_OK, "%s",
        err.message);
  double worst = 0.0;
  for (int y = 0; coloured.pixels && y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      if (pixel_class(64, view.radius, x, y) != 1) continue;
      double centre = 32.0, r = view.radius * centre;
      double u = (x + 0.5 - centre) / r, w = (centre - (y + 0.5)) / r;
      double cos_i = fmax(0.0, 0.6 * u + 0.8 * sqrt(1.0 - u * u - w * w));
      for (int c = 0; c < 3; ++c)
        worst = fmax(worst, fabs(pixel(&coloured, x, y, c) - 0.5 / pi * e[c] * cos_i));
    }
  CHECK(coloured.pixels && worst < 1e-6, "a coloured light: %g off the analytic Lambert", worst);
  cf_image_free(&standard);
  cf_image_free(&own);
  cf_image_free(&coloured);
  cf_image none = {0};
  view.light_count = CF_SPHERE_MAX_LIGHTS + 1;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &none, &err) == CF_EINVAL,
        "33 lights accepted");
  const double negative[3] = {1.0, -1.0, 1.0};
  view.light_count = 1;
  view.light_irradiance = negative;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &none, &err) == CF_EINVAL,
        "a negative irradiance accepted");
  view.light_irradiance = e;
  view.light_direction = NULL;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, albedo, &view, &none, &err) == CF_EINVAL,
        "lights without directions accepted");
}

static void test_refusals(void) {
  cf_sphere_view view;
  cf_sphere_view_default(&view);
  const double out_of_range[3] = {1.5, 0.5, 0.5}, nan_albedo[3] = {NAN, 0.5, 0.5};
  const double ok[3] = {0.5, 0.5, 0.5};
  cf_image im;
  cf_error err = {0};
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, out_of_range, &view, &im, &err) != CF_OK &&
            im.pixels == NULL,
        "albedo 1.5 accepted");
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, nan_albedo, &view, &im, &err) != CF_OK, "NaN accepted");
  CHECK(cf_sphere_render((cf_model_id)99, ok, &view, &im, &err) == CF_EINVAL, "model 99");
  view.size = CF_SPHERE_MAX_SIZE + 1;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, ok, &view, &im, &err) == CF_EINVAL, "size");
  cf_sphere_view_default(&view);
  view.radius = 1.5;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, ok, &view, &im, &err) == CF_EINVAL, "radius");
  cf_sphere_view_default(&view);
  view.background[2] = INFINITY;
  CHECK(cf_sphere_render(CF_MODEL_LAMBERT, ok, &view, &im, &err) == CF_EINVAL, "background");
}

static int compare_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The time of a 256² thumbnail of M4 (render; render and PNG), median of 5. */
static void timing(const char *work) {
  cf_fit_result r;
  memset(&r, 0, sizeof r);
  r.model = CF_MODEL_CLAY;
  cf_model_default_params(CF_MODEL_CLAY, r.params);
  r.params[CF_CLAY_FILM_ROUGHNESS] = 0.1; /* a sharp highlight: footprint samples */
  char path[1024];
  snprintf(path, sizeof path, "%s/timing.png", work);
  double render[5], whole[5];
  for (int i = 0; i < 5; ++i) {
    cf_image im;
    double t0 = now();
    cf_status s = cf_report_render_sphere(&r, NULL, &im, NULL);
    double t1 = now();
    if (s == CF_OK) s = cf_sphere_write_png(&im, path, NULL);
    double t2 = now();
    CHECK(s == CF_OK, "timing run %d", i);
    cf_image_free(&im);
    render[i] = t1 - t0;
    whole[i] = t2 - t0;
  }
  qsort(render, 5, sizeof *render, compare_double);
  qsort(whole, 5, sizeof *whole, compare_double);
  printf("M4 256x256 thumbnail: render %.1f ms, render and PNG %.1f ms (medians of 5)\n",
         1e3 * render[2], 1e3 * whole[2]);
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: test_thumbnail WORKDIR\n");
    return 2;
  }
  cf_error err = {0};
  if (cf_make_dirs(argv[1], &err) != CF_OK) {
    fprintf(stderr, "%s\n", err.message);
    return 1;
  }
  const cf_sphere_light *lights = cf_sphere_lights();
  CHECK(lights[0].direction[0] == -4.0 / 9.0 && lights[0].direction[2] == 7.0 / 9.0 &&
            fabs(lights[0].irradiance - 0.8 * pi) < 1e-15 && lights[1].direction[0] == 6.0 / 7.0 &&
            fabs(lights[1].irradiance - 0.2 * pi) < 1e-15,
        "the standard light differs from its documentation");
  test_lambert();
  test_silhouette();
  test_highlight_footprint();
  test_models();
  test_albedo_order(argv[1]);
  test_png(argv[1]);
  test_own_lights();
  test_refusals();
  timing(argv[1]);
  return check_finish("test_thumbnail");
}
