/* The loaded capture (include/clayfit/capture.h), shared by the files that
 * build it: capture.c (orchestration), capture_views.c (cameras and
 * exposures), capture_lights.c, capture_surface.c (the sphere's surface),
 * observations.c (the pixel loop) and capture_screen.c (the screen).
 * Private to src/capture. */
#ifndef CLAYFIT_CAPTURE_INTERNAL_H
#define CLAYFIT_CAPTURE_INTERNAL_H

#include "capture_spec.h"
#include "clayfit/capture.h"
#include "clayfit/colmap.h"
#include "clayfit/image.h"
#include "lights.h"
#include "capture/sphere_silhouette.h"

/* One image's camera. */
typedef struct capture_view {
  const cf_camera *camera; /* COLMAP's (NULL for the orthographic camera) */
  double r[9];             /* world-to-camera rotation, row-major */
  double t[3];             /* world-to-camera translation */
  double c[3];             /* camera centre, world */
  double focal_px;         /* mean focal length, pixels (margins, reports) */
} capture_view;

struct cf_capture {
  cf_capture_spec spec;
  cf_colmap_model colmap;
  capture_view *views;      /* one per image */
  cf_capture_image *images; /* one per image */
  double *raw_exposures;    /* e_k before normalisation (exif) */

  /* lights: image k has light_counts[k] lights at lights[k * max_lights] */
  cf_light *lights;
  int *light_counts;
  int max_lights;

  /* the sphere's surface */
  double center[3], radius; /* COLMAP cameras */
  double rms_px;            /* of the triangulation, over the kept points */
  double silhouette_kept;   /* fraction of outline points kept */
  cf_ellipse circle;        /* orthographic + silhouettes */
  const char *circle_source; /* the mask or image it was fitted to (a spec path) */
  cf_image normal_map;      /* orthographic + normal map, normalised */
  uint8_t *map_class;       /* its pixels: a surface_hit each */
  int map_box[4];           /* the box of its pixels not SURFACE_MISS:
                               x0, y0, x1, y1 (exclusive) */

  cf_observations obs;

  char **warnings;
  size_t num_warnings;

  /* the scale from the reference target (capture_reference.c), applied to
   * every light and observation: the radiometry is then absolute */
  int from_reference;
  double reference_scale, reference_spread, reference_channel_scales[3];
  size_t reference_pixels;
};

/* Is a mask's value (its first channel) one of a usable pixel? */
static inline int capture_mask_usable(float value) {
  return value > 0.5f;
}

/* Add a warning (printf-style). Out of memory loses the warning only. */
void capture_warn(cf_capture *capture, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* A JPEG's default clip level (stored units; code 237 of 255). On
 * synthetic M2 captures at quality 90, 4:2:0, 1.0 left the roughness 0.01
 * high (30 sd); 0.95 still 0.003 (4 sd); 0.90 pulled it 0.004 low
 * (tests/fit/test_fit_jpeg.c, docs/model.md's noise). */
#define CAPTURE_JPEG_CLIP_LEVEL 0.93

/* capture.c: how image k's stored values become radiance divided by its
 * exposure e_k (the spec's encoding, black and clip levels). */
cf_decode capture_image_decode(const cf_capture *capture, const cf_image_info *info,
                               double exposure);

/* capture_views.c: read the COLMAP model and match every image to it (or
 * set up the orthographic camera); fill views and images' names, paths. */
cf_status capture_load_views(cf_capture *capture, cf_error *err);

/* capture_views.c: check an image's size against its camera (and, for the
 * orthographic camera, against the first image's). */
cf_status capture_check_size(cf_capture *capture, size_t k, const cf_image *image, cf_error *err);

/* capture_views.c: the exposure e_k of image k from the spec or EXIF
 * (before normalisation); an EXIF field outside what cameras record is
 * refused (CF_EINVAL, naming the field and its range). */
cf_status capture_raw_exposure(const cf_capture *capture, size_t k, const cf_image_info *info,
                               double *exposure, cf_error *err);

/* capture_views.c: CF_EINVAL when an image's EXIF exposure
 * (raw_exposures) is more than 2^16 times above or below the capture's
 * median. */
cf_status capture_check_exposure_spread(const cf_capture *capture, cf_error *err);

/* capture_lights.c: every image's lights (needs the sphere's radius for
 * flash offsets given in metres). */
cf_status capture_load_lights(cf_capture *capture, cf_error *err);

/* capture_surface.c: the sphere (given, or triangulated from silhouettes),
 * or the orthographic circle, or the normal map. */
cf_status capture_load_surface(cf_capture *capture, const cf_capture_options *options,
                               cf_error *err);

/* capture_surface.c: what pixel (x, y) of image k sees of the sphere. */
typedef enum surface_hit { SURFACE_MISS, SURFACE_MARGIN, SURFACE_HIT } surface_hit;
typedef struct surface_point {
  double position[3]; /* world (COLMAP cameras; 0 for orthographic) */
  double normal[3], view[3];
} surface_point;
surface_hit capture_surface_at(const cf_capture *capture, size_t k, int x, int y,
                               surface_point *point);

/* capture_surface.c: the same at continuous pixel coordinates (u, v)
 * (pixel centres at +0.5); a normal map's normals are interpolated
 * bilinearly between pixel centres. */
surface_hit capture_surface_at_uv(const cf_capture *capture, size_t k, double u, double v,
                                  surface_point *point);

/* capture_surface.c: the pixel rectangle [x0, x1) × [y0, y1) of image k
 * that can see the sphere. */
void capture_surface_bounds(const cf_capture *capture, size_t k, int width, int height,
                            int bounds[4]);

/* observations.c: the arrays of n observations (o->lights set); shrunk
 * to o->count; freed; observations [first, first + count) of `from` moved
 * to [at, at + count) of `to` (the same arrays: at <= first). */
cf_status capture_allocate_observations(cf_observations *o, size_t n, cf_error *err);
void capture_shrink_observations(cf_observations *o);
void capture_free_observations(cf_observations *o);
void capture_move_observations(cf_observations *to, size_t at, const cf_observations *from,
                               size_t first, size_t count);

/* What one image adds (its cf_capture_image counts). */
typedef struct image_observations {
  size_t observations, clipped, sphere_pixels;
} image_observations;

/* observations.c: decode image k and append its observations to o
 * (room for its capture_surface_bounds' pixels after o->count); eight_bit:
 * its samples are image_scale_u8's. */
void capture_add_observations(const cf_capture *capture, size_t k, const cf_image *image,
                              const cf_image *mask, const cf_decode *decode, int eight_bit,
                              cf_observations *o, image_observations *out);

/* capture_screen.c: leave out the values that cannot be radiance (counted
 * per image, a warning beyond a trace), then refuse a capture with no lit,
 * positive observation or mostly such values (CF_EINVAL, saying why). */
cf_status capture_screen_observations(cf_capture *capture, cf_error *err);
/* Every image's adjacent_turn from the final observations (capture_turn.c). */
void capture_measure_adjacent_turn(cf_capture *capture);

/* capture_images.c: every map's, image's and mask's header read before
 * any of them is decoded: sizes against the cameras, masks and normal map
 * (whose header's size it records in capture->normal_map, pixels NULL),
 * the decoded bytes against the cap (CF_ERANGE), duplicates. */
cf_status capture_read_headers(cf_capture *capture, const cf_capture_options *options,
                               cf_error *err);

/* capture_screen.c: the brightest radiance any material of the ladder, with
 * any parameters inside docs/model.md §1.6's ranges, reflects per unit
 * irradiance (f·c_i at its largest over the light's direction) seen at
 * cos_o = n·v (infinite for cos_o <= 0). */
double capture_radiance_bound(double cos_o);

/* Read every image (and its mask) and add its observations, in image
 * order, decoding ahead on other threads (capture_images.c), after
 * capture_read_headers. */
cf_status capture_read_images(cf_capture *capture, const cf_capture_options *options,
                              cf_error *err);

/* capture_reference.c: the absolute scale from the capture's reference
 * target (spec.reference), measured in its image (which must have been
 * loaded: its exposure is known) and applied to every light and every
 * observation's irradiance. Call once, after every image is loaded. */
cf_status capture_apply_reference(cf_capture *capture, cf_error *err);

#endif /* CLAYFIT_CAPTURE_INTERNAL_H */
