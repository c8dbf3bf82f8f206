/* The report's parts (include/clayfit/report.h): the residuals and angles
 * of every observation (report_data.c), the per-image pictures
 * (report_images.c), the plots (report_plots.c over the SVG writer
 * svg.c), report.json (report_json.c) and the page (report_html.c).
 * Private to src/report. */
#ifndef CLAYFIT_REPORT_INTERNAL_H
#define CLAYFIT_REPORT_INTERNAL_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "clayfit/report.h"
#include "clayfit/thumbnail.h"
#include "core/text_escape.h"
#include "svg.h"

enum { REPORT_CENSORED = 1u << 0, REPORT_REJECTED = 1u << 1 };

/* The 8-bit sRGB code of a linear value (report_images.c): the code the
 * PNG writer stores for cf_linear_to_srgb of the value clamped to [0, 1],
 * read from the encoding's steps instead of computed. */
enum { REPORT_SRGB_BINS = 4096 };
typedef struct report_srgb {
  float threshold[256];                /* the least value of each code */
  uint8_t start[REPORT_SRGB_BINS + 1]; /* the code of b / REPORT_SRGB_BINS */
} report_srgb;
void report_srgb_init(report_srgb *t);
int report_srgb_encode(const report_srgb *t, float linear);

typedef struct report_data {
  const cf_capture *capture;
  const cf_fit_file *fit;
  const cf_observations *obs;
  size_t count, images;
  double *prediction, *sigma; /* 3 × count */
  float *residual;            /* count: Σ_c (prediction − y)/σ over the m channels not
                                 censored, over √m (N(0, 1) for noise alone); NaN
                                 where all are */
  uint8_t *mark;              /* count: REPORT_CENSORED, REPORT_REJECTED (beyond the loss) */
  float *half_angle;          /* count: degrees between n and the nearest half vector */
  float *view_angle;          /* count: degrees between n and v */
  double loss_scale;          /* in σ */
  /* per image */
  size_t *censored, *rejected, *observations;
  size_t *first, *last;       /* the range of observations holding image k's
                                 (the capture lists them image by image) */
  double *rms_sigma;          /* RMS of residual, σ units */
  size_t *rejected_region;    /* the observations in the image's largest 8-connected
                                 region (in its pixel grid) of REPORT_REJECTED ones */
  size_t *rejected_clustered; /* those in its regions of REPORT_CLUSTER_PX or more */
  const char *capture_path;   /* the capture re-rendered */
  const char *capture_check;  /* how it was checked to be the fit's (cf_report_options) */
  report_srgb srgb;           /* the pictures' encoding */
  int threads;                /* the pictures' and the prediction's */
  const json_t *doc;          /* fit.json as cf_fit_file_read parsed it (the fit's; for the
                                 choice, solver, timings); may be NULL */
} report_data;

/* A region of rejected observations this large is a cluster, not chance:
 * with independent rejections (a Lambertian capture fitted with M0, the
 * loss's scale at 2 σ, 13 % of the pixels rejected) 4 % of them lie in
 * regions this large (test report_regions). */
#define REPORT_CLUSTER_PX 9
/* At least this share of the rejected observations in clusters reads as a
 * systematic misfit rather than outliers: a glossy capture fitted with M0
 * gives 0.77 (its highlights and its rim, in several regions: the largest
 * holds 0.35), independent rejections 0.04, DiLiGenT's M4 0.89. */
#define REPORT_SYSTEMATIC_SHARE 0.5

/* Σ_k rejected_region[k] / Σ_k rejected[k], or with clustered
 * Σ_k rejected_clustered[k] / Σ_k rejected[k] (NaN: nothing rejected). */
double report_rejected_share(const report_data *d, int clustered);

cf_status report_data_build(report_data *d, const cf_capture *capture, const cf_fit_file *fit,
                            const char *fit_path, cf_error *err);
void report_data_free(report_data *d);

/* The pictures of image k: DIR/images/NNN_{photo,render,residual}.png;
 * names receives the three file names relative to DIR (64 bytes each). */
cf_status report_image(const report_data *d, size_t k, const char *dir, char names[3][64],
                       cf_error *err);
/* Every image's pictures (report_image), on d->threads; names: 3 per
 * image. progress (may be NULL) is called as each image is done, one call
 * at a time, from any of the threads. On failure, the first failing
 * image's error. */
cf_status report_images(const report_data *d, const char *dir, char (*names)[3][64],
                        cf_progress_fn progress, void *user, cf_error *err);

/* The heat map's colour of a residual r (σ units): blue at
 * −CF_REPORT_SIGMA_RANGE, white at 0, red at +CF_REPORT_SIGMA_RANGE
 * (linear RGB; beyond the range, the range's ends). */
void report_residual_colour(double r, float rgb[3]);

/* The plots, into DIR/plots/; names (NULL-terminated pairs of key and
 * relative path) for the page and report.json. */
enum { REPORT_PLOT_COUNT = 6 };
typedef struct report_plot {
  const char *key, *title, *file;
} report_plot;
extern const report_plot report_plots[REPORT_PLOT_COUNT];
/* Every plot's size in the page, in pixels. */
enum { REPORT_PLOT_WIDTH = 560, REPORT_PLOT_HEIGHT = 340 };
/* Begin plot `info` in DIR (svg_begin at that size), its path into path. */
cf_status report_plot_begin(svg_plot *plot, const char *dir, const report_plot *info, char *path,
                            size_t size, cf_error *err);
cf_status report_write_plots(const report_data *d, const char *dir, cf_error *err);
/* The fitted camera response curve with its ±2 sd band
 * (report_response.c): written, and listed in report.json and on the page,
 * only when the fit recovered a response (an unknown tone curve). */
extern const report_plot report_response_plot_info;
cf_status report_response_plot(const report_data *d, const char *dir, cf_error *err);

/* The fitted material's view (report_viewer.c): the capture's lighting at
 * one image's observation facing the camera, as at most
 * CF_SPHERE_MAX_LIGHTS directional lights in that camera's frame, exposed
 * for display. */
enum { REPORT_VIEW_SIZE = 256 }; /* pixels per side, both renderings */
typedef struct report_view {
  size_t image;    /* the image whose camera and lights are taken */
  int slots;       /* its light slots with irradiance */
  int light_count; /* the strongest of them, at most CF_SPHERE_MAX_LIGHTS */
  /* the lights in the camera frame; irradiance × exposure */
  double direction[3 * CF_SPHERE_MAX_LIGHTS], irradiance[3 * CF_SPHERE_MAX_LIGHTS];
  double exposure;   /* puts a white Lambertian sphere's peak at CF_SPHERE_KNEE */
  char absent[1100]; /* why the interactive view is absent ("" when present) */
} report_view;
cf_status report_view_scene(const report_data *d, report_view *v, cf_error *err);
/* DIR/viewer/: clayfit.png (clayfit's rendering), material.mjs (the glsl
 * export), material.js (it as a classic script), three_viewer.js (a copy of
 * `bundle`; when it cannot be read, v->absent says why and the page says
 * so). */
cf_status report_view_write(const report_data *d, const char *dir, const char *fit_path,
                            const char *bundle, report_view *v, cf_error *err);
void report_view_html(FILE *f, const report_data *d, const report_view *v);

/* report.json and index.html. image_files: 3 names per image. */
cf_status report_write_json(const report_data *d, const char *dir, const char *fit_path,
                            const char *version, char (*image_files)[3][64], cf_error *err);
cf_status report_write_html(const report_data *d, const char *dir, const char *fit_path,
                            const char *version, char (*image_files)[3][64],
                            const report_view *view, cf_error *err);

#endif /* CLAYFIT_REPORT_INTERNAL_H */
