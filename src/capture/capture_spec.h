/* A capture file (data_schema/capture.schema.json) as read and checked:
 * every path resolved against the capture file's folder, every default
 * filled in. Reading it touches no image, model or light file; loading the
 * capture (capture.c) does. Private to src/capture. */
#ifndef CLAYFIT_CAPTURE_SPEC_H
#define CLAYFIT_CAPTURE_SPEC_H

#include <stddef.h>

#include "clayfit/image.h"
#include "clayfit/status.h"
#include "lights.h"

typedef enum cf_camera_kind { CF_CAMERA_KIND_COLMAP, CF_CAMERA_KIND_ORTHOGRAPHIC } cf_camera_kind;

typedef enum cf_geometry_kind {
  CF_GEOMETRY_SPHERE,
  CF_GEOMETRY_SPHERE_FROM_SILHOUETTES,
  CF_GEOMETRY_NORMAL_MAP
} cf_geometry_kind;

typedef enum cf_exposure_kind {
  CF_EXPOSURE_NONE,
  CF_EXPOSURE_GIVEN,
  CF_EXPOSURE_EXIF
} cf_exposure_kind;

typedef enum cf_light_spec_kind {
  CF_LIGHT_SPEC_SINGLE,     /* flash, point, directional: `light` */
  CF_LIGHT_SPEC_PER_IMAGE,  /* directional, one per image, from files */
  CF_LIGHT_SPEC_ENVIRONMENT /* an environment map, reduced to `count` */
} cf_light_spec_kind;

typedef struct cf_light_spec {
  cf_light_spec_kind kind;
  cf_light light;                 /* SINGLE */
  int offset_in_metres;           /* flash: light.position is in metres; it
                                     becomes world units once the sphere's
                                     world radius is known */
  char *directions, *intensities; /* PER_IMAGE: resolved paths; intensities
                                     NULL when intensities_equal */
  int intensities_equal;          /* PER_IMAGE: "intensities": "equal", unknown
                                     and equal (1 each, radiometry relative) */
  char *file;                     /* ENVIRONMENT: resolved path */
  double rotation[9], scale;
  int count;
} cf_light_spec;

/* A flat matte (Lambertian) target of known albedo seen in one image,
 * which sets the absolute scale of a capture with relative radiometry
 * (capture_reference.c). */
typedef struct cf_reference_spec {
  size_t image;     /* index into the capture's images */
  int region[4];    /* x0, y0, x1, y1: the pixels x0 <= x < x1, y0 <= y < y1 */
  double albedo[3]; /* in (0, 1] */
  double normal[3]; /* unit, world */
  double point[3];  /* on the target's plane, world (when has_point) */
  int has_point;
} cf_reference_spec;

typedef struct cf_capture_spec {
  char *path; /* the capture file */
  char *dir;  /* its folder: relative paths start here */
  char *name; /* "" if not given */

  cf_camera_kind camera;
  char *colmap_model; /* resolved folder (COLMAP) */
  double view[3];     /* unit, toward the camera (orthographic) */

  size_t num_images;
  char **image_names; /* as given (the COLMAP model's names) */
  char *image_list;   /* the resolved list file they came from, or NULL */
  char **image_paths; /* resolved */
  double *exposures;  /* given exposures, or NULL */
  char **mask_paths;  /* resolved per-image masks, or NULL */

  cf_transfer transfer;
  double gamma, black_level;
  double clip_level; /* NaN: the default for each image's format */
  cf_exposure_kind exposure;
  int tone_curve_unknown;
  int radiometry_relative;
  int radiometry_given; /* "radiometry" is in the file */
  int has_noise;
  double noise_read, noise_shot;

  cf_geometry_kind geometry;
  double center[3], radius; /* SPHERE */
  char *normal_map;         /* NORMAL_MAP: resolved path */
  double margin_px;

  double sphere_radius_m; /* NaN if not given */

  size_t num_lights;
  cf_light_spec *lights;

  int has_reference; /* only with radiometry "relative" */
  cf_reference_spec reference;
} cf_capture_spec;

/* Read and check a capture file. Errors name the file and the JSON path
 * (or line and column for malformed JSON). */
cf_status cf_capture_spec_read(const char *path, cf_capture_spec *spec, cf_error *err);
void cf_capture_spec_free(cf_capture_spec *spec);

#endif /* CLAYFIT_CAPTURE_SPEC_H */
