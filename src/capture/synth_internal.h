/* A synthetic capture being made (include/clayfit/synth.h), shared by the
 * files that make it: synth.c (options, cameras, exposures, the
 * environment, cf_synth_write), synth_render.c (the images and the
 * reference card's region) and synth_files.c (the COLMAP model, the
 * capture file and truth.json). Private to src/capture. */
#ifndef CLAYFIT_CAPTURE_SYNTH_INTERNAL_H
#define CLAYFIT_CAPTURE_SYNTH_INTERNAL_H

#include <pthread.h>

#include "clayfit/colmap.h"
#include "clayfit/image.h"
#include "clayfit/status.h"
#include "clayfit/synth.h"
#include "envmap.h"
#include "lights.h"
#include "synth_scene.h"

/* The reference card (--reference): a square on the ground, centre (x, y)
 * and half its side (world units; synth_render.c). */
extern const double synth_card_center[2], synth_card_half;

typedef struct synth_camera {
  double r[9], t[3], c[3]; /* world-to-camera rotation, translation; centre */
  double q[4];             /* r as a quaternion (qw, qx, qy, qz) */
} synth_camera;

enum { SYNTH_THREADS = 2 };

typedef struct render_job {
  const cf_synth_options *options;
  const char *dir;
  cf_camera camera;
  synth_camera *cameras;
  double intensity;
  cf_light *environment;       /* the map's lights (options->environment_lights), or NULL */
  char environment_file[4096]; /* the map relative to the capture's folder */
  cf_envmap_report environment_report;
  cf_response response;
  double *exposures;   /* e_k per image (geometric mean 1) */
  cf_image_info *exif; /* per image with exif_exposures, else NULL */
  int card_region[4];  /* the reference card's pixels in image 0 */
  /* over done, status, error and the progress */
  pthread_mutex_t lock;
  int done;
  cf_status status;
  cf_error error;
} render_job;

/* The images' file extension ("png", "jpg", "exr"; synth.c). */
const char *synth_extension(cf_synth_format format);

/* Image k rendered and written with its mask, unless an image has failed
 * (the first failure is kept in job->status and job->error): a
 * cf_parallel_for body over the images (synth_render.c). */
void synth_render_one(void *user, int k);

/* The region [x0, x1) x [y0, y1) of image 0 inside the reference card,
 * clear of its edges and lit by flash 0 (synth_render.c). */
cf_status synth_card_region(const render_job *job, int region[4], cf_error *err);

/* The COLMAP model (sparse/0), capture.json and truth.json into dir
 * (synth_files.c). */
cf_status synth_write_files(const char *dir, const render_job *job, cf_error *err);

#endif /* CLAYFIT_CAPTURE_SYNTH_INTERNAL_H */
