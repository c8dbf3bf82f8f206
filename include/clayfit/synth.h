/* clayfit: synthetic captures with known parameters, rendered by docs/model.md §5's
 * image formation with the evaluator: a clay sphere on a textured ground
 * inside a textured backdrop (so that COLMAP can match features), an orbit
 * of cameras each with its flash, photon and read noise. It writes the
 * images, the true COLMAP model (text), a capture file and truth.json: the
 * project's default demo capture and test fixture.
 *
 * World frame: z up, the sphere's centre at the origin, radius 1 (world
 * units); the ground is the plane z = -1; the backdrop a cylinder of radius
 * 6 about the z axis. */
#ifndef CLAYFIT_SYNTH_H
#define CLAYFIT_SYNTH_H

#include <stdint.h>

#include "clayfit/capture.h"
#include "clayfit/model.h"
#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_synth_format {
  CF_SYNTH_PNG8,  /* 8-bit sRGB PNG: what a camera gives */
  CF_SYNTH_PNG16, /* 16-bit linear PNG */
  CF_SYNTH_EXR,   /* 32-bit float linear OpenEXR */
  CF_SYNTH_JPEG   /* 8-bit JPEG (sRGB unless `response` says otherwise), 4:2:0 */
} cf_synth_format;

/* synth's default JPEG quality (libjpeg's 1..100 scale). */
#define CF_SYNTH_JPEG_QUALITY 90

/* With a reference card, the flash intensity the capture file gives is the
 * true one times this factor: only the card can set the scale right. */
#define CF_SYNTH_REFERENCE_FACTOR 0.37

/* The default environment rotation, row-major: d_world = (x, -z, y) of
 * d_map, a proper rotation (+90 degrees about x) taking the map's up (+y)
 * to the world's (+z). */
#define CF_SYNTH_ENVIRONMENT_ROTATION \
  { 1, 0, 0, 0, 0, -1, 0, 1, 0 }

typedef struct cf_synth_options {
  cf_model_id model;
  double params[CF_MAX_DIM]; /* the sphere's material, in range */
  int images;                /* cameras on the orbit, >= 1 */
  int width, height;         /* pixels */
  double focal_px;           /* pinhole focal length, pixels */
  double distance;           /* camera distance from the sphere's centre, world units */
  double flash_offset[3];    /* camera coordinates (x right, y down, z forward), world units */
  double flash_intensity;    /* radiant intensity (grey); 0 = choose: a white Lambert surface
                                facing the flash at `distance` has radiance 0.5 */
  double read_noise;         /* σ of the read noise, radiance units (0 = none) */
  double shot_noise;         /* photon noise: variance per unit radiance (0 = none) */
  int supersample;           /* S: S×S samples per pixel near and on the sphere */
  cf_synth_format format;
  int response;            /* the camera's response curve the photos are coded with: a
                              cf_response (include/clayfit/image.h), or -1 for the
                              format's own (png8, jpg: srgb; png16, exr: linear; exr takes
                              no other) */
  int jpeg_quality;        /* CF_SYNTH_JPEG: 1..100 */
  int exif_exposures;      /* 1 (CF_SYNTH_JPEG only): each image gets its own exposure
                              time, ISO and f-number in EXIF (a cycle of five settings,
                              their exposures within a factor of 2), the photo is scaled
                              by its exposure and the capture says "exposure": "exif" */
  int silhouette_geometry; /* 1: the capture file asks for the sphere from its
                              silhouettes instead of giving centre and radius */
  int write_masks;         /* 1: masks/ with the sphere's pixels */
  uint64_t seed;           /* texture layout and noise */
  double sphere_radius_m;  /* for the capture file's scale */
  double reference_albedo; /* 0: none. In (0, 1]: a grey card of this albedo
                              (Lambertian, 0.6 x 0.6 world units) lies on the
                              ground in front of the sphere as image 0 sees
                              it; the capture file then says "radiometry":
                              "relative", gives the flash's intensity times
                              CF_SYNTH_REFERENCE_FACTOR (wrong on purpose), and
                              names the card as its "reference" */
  /* NULL: each camera's flash. Else an equirectangular map (linear RGB
   * radiance, the capture format's `environment` convention) whose median
   * cut into environment_lights (K in [1, 4096]) directional lights
   * replaces the flash in every image (the sphere unshadowed, as the fit
   * sees it; the ground and backdrop shadowed by the sphere). flash_* are
   * then unused, reference_albedo must be 0. environment_rotation takes
   * the map's frame (y up) to the world (z up), row-major, orthonormal. */
  const char *environment;
  int environment_lights;
  double environment_rotation[9];
  cf_progress_fn progress; /* may be NULL */
  void *progress_user;
} cf_synth_options;

/* Defaults: M4 at its default parameters, 16 images of 640 x 480, focal
 * 1.2 x width, distance 5, flash 0.3 right and 0.3 up of the lens, read
 * noise 0.002, shot noise 0.0005, 3 x 3 samples, 8-bit PNG, seed 1, a 4 cm
 * sphere; no environment, and for one 1024 lights and the rotation
 * CF_SYNTH_ENVIRONMENT_ROTATION. */
void cf_synth_default_options(cf_synth_options *options);

/* Render into folder `dir` (created if missing): images/NNN.<ext>,
 * sparse/0/{cameras,images,points3D}.txt, capture.json, truth.json, and
 * masks/NNN.png when asked. */
cf_status cf_synth_write(const char *dir, const cf_synth_options *options, cf_error *err);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_SYNTH_H */
