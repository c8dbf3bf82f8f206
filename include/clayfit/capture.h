/* clayfit: a capture (photos, camera poses, the sphere, the lights) turned
 * into observations: for each used pixel, the surface normal, the view
 * direction, every light's direction and irradiance, the measured linear
 * RGB and flags. This is what the fitter consumes.
 *
 * The capture file is described by data_schema/capture.schema.json. All
 * directions are unit vectors in the capture's world frame (COLMAP's, or
 * the orthographic camera's), pointing away from the surface, as
 * include/clayfit/model.h expects them. */
#ifndef CLAYFIT_CAPTURE_H
#define CLAYFIT_CAPTURE_H

#include <stddef.h>
#include <stdint.h>

#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Observation flags. */
enum {
  CF_OBS_CLIPPED_R = 1u << 0, /* the channel reached the clip level: the */
  CF_OBS_CLIPPED_G = 1u << 1, /* true value is at least what was measured */
  CF_OBS_CLIPPED_B = 1u << 2,
  CF_OBS_UNLIT = 1u << 3 /* no light reaches the point (c_i <= 0 for all) */
};
#define CF_OBS_CLIPPED (CF_OBS_CLIPPED_R | CF_OBS_CLIPPED_G | CF_OBS_CLIPPED_B)

/* Every used pixel of every image, structure of arrays. With L = lights
 * light slots per observation (the most any image has; unused slots carry
 * zero irradiance):
 *   normal[3 i + k], view[3 i + k]                  unit vectors
 *   light_dir[3 (L i + j) + k]                     unit, toward light j
 *   irradiance[3 (L i + j) + c]                    E of light j, channel c
 *   rgb[3 i + c]                                    linear radiance, divided by
 *                                                   the image's exposure e_k
 *   flags[i], image[i] (index into the capture's images), pixel[2 i + 0/1]
 *   (the pixel centre, COLMAP's continuous coordinates). */
typedef struct cf_observations {
  size_t count;
  int lights;
  double *normal, *view, *light_dir, *irradiance, *rgb;
  uint8_t *flags;
  uint32_t *image;
  float *pixel;
} cf_observations;

/* How near observation i's half vector comes to its normal, for any light
 * that reaches it: max_j n·normalize(l_j + v) over the lights with some
 * irradiance and n·l_j > 0; −1 when no light reaches it. (The cosine of
 * the half-angle: where the highlights are.) */
double cf_observation_specularity(const cf_observations *obs, size_t i);

/* More than 0.1 % of an image's pixels on the sphere: a region of the
 * photo, not stray pixels (a hot pixel, a filter's undershoot). */
#define CF_NOT_RADIANCE_TRACE 0.001

/* One image's part in the capture. */
typedef struct cf_capture_image {
  const char *name; /* as the capture file names it */
  const char *path; /* resolved */
  int width, height;
  double exposure;      /* e_k */
  double center[3];     /* camera centre, world (COLMAP cameras) */
  size_t observations;  /* used pixels */
  size_t clipped;       /* of which with a clipped channel */
  size_t not_radiance;  /* pixels left out: a value that cannot be radiance
                           (docs/captures.md), not among the observations;
                           a warning above CF_NOT_RADIANCE_TRACE of the
                           image's pixels (observations + these) */
  size_t sphere_pixels; /* pixels whose centre sees the sphere, before the
                           silhouette margin and the mask */
  int lights;           /* lights of this image */
  int jpeg;             /* 1: a JPEG file, whose lossy coding leaves errors correlated
                           within its blocks (docs/model.md, the noise) */
  int jpeg_quality;     /* a JPEG's coding (cf_jpeg_coding_read): libjpeg's quality
                           nearest its tables, 0 when its markers could not be read */
  int jpeg_exact;       /* 1: its tables are that quality's exactly */
  int jpeg_chroma;      /* its chroma subsampling, a cf_chroma */
  double adjacent_turn; /* the largest angle (radians) between the normals of
                           two horizontally adjacent observations */
} cf_capture_image;

/* Progress of a long load, for a progress line: stage is a short phrase
 * ("reading images"), done of total. */
typedef void (*cf_progress_fn)(void *user, const char *stage, size_t done, size_t total);

/* The default cap on a capture's decoded image data (every image and mask,
 * as 32-bit floats, all together): 32 GB. 100 photos of 24 megapixels in
 * RGB are 28.8 GB; DiLiGenT's 96 images 0.36 GB. */
#define CF_CAPTURE_MAX_IMAGE_BYTES 32000000000ULL

/* Environment maps are reduced to directional lights by median cut: at
 * most CF_ENVMAP_MAX_LIGHTS of them for a rendering (clayfit synth: a
 * glossy M4 film under studio.exr is within 0.41 % of the map's exact
 * integral at 16384 lights, 2.7 % at 4096), at most
 * CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS in a capture file (its `count`): the
 * fit keeps every light of every observation. */
#define CF_ENVMAP_MAX_LIGHTS 65536
#define CF_CAPTURE_ENVIRONMENT_MAX_LIGHTS 4096

typedef struct cf_capture_options {
  cf_progress_fn progress; /* may be NULL */
  void *progress_user;
  /* The cap on the capture's decoded image data in bytes, checked from the
   * files' headers before any pixel is decoded; 0 for the default,
   * CF_CAPTURE_MAX_IMAGE_BYTES. */
  unsigned long long max_image_bytes;
} cf_capture_options;

typedef struct cf_capture cf_capture; /* opaque */

/* Load a capture file and everything it names, and build the observations.
 * Errors name the file and the field (capture file: JSON path; images:
 * file; COLMAP models: file, line or byte, record, field). Every image's
 * header is read before any pixel is decoded: its size against its camera
 * (or the normal map, or the first image), its mask's against it, the
 * total against max_image_bytes (CF_ERANGE); one file listed twice is
 * CF_EINVAL. Out of memory is CF_ENOMEM, never a bad input. */
cf_status cf_capture_load(const char *path, const cf_capture_options *options, cf_capture **capture,
                          cf_error *err);
void cf_capture_free(cf_capture *capture);

/* Every file loading the capture at path reads: the capture file, the
 * image list, images, masks, the COLMAP model's files, light files, the
 * environment map, the normal map (paths resolved as the loader does;
 * listed, not opened). From the capture file alone, so that the list lives
 * with its reader (clayfit batch keys its entries by these files). Errors
 * are the capture file's (cf_capture_load's). Free with
 * cf_capture_files_free. */
cf_status cf_capture_files(const char *path, char ***files, size_t *count, cf_error *err);
void cf_capture_files_free(char **files, size_t count);

const cf_observations *cf_capture_observations(const cf_capture *capture);
size_t cf_capture_image_count(const cf_capture *capture);
/* The capture file's lights as a gain per light sees them (clayfit fit
 * --fit-gains per-light, docs/fitting.md): ids (images × lights, lights =
 * cf_observations' lights; image k's slot j at k × lights + j) gets each
 * slot's light, 0 … count − 1 numbered as first met (image by image, slot
 * by slot), or −1 for a slot without light (zero irradiance). A light is
 * an entry of the capture file's "lights": a flash, point or directional
 * light (the same in every image), an environment (all its slots); a
 * directional_per_image light is one light per distinct row (direction
 * and intensity), shared by the images whose rows are the same. Returns
 * the count; allocates nothing. */
size_t cf_capture_light_ids(const cf_capture *capture, long *ids);
/* The name of image `image`'s light slot `slot` (as in ids) for messages
 * and fit.json: "light 2" (the capture file's second light), "light 1
 * (environment)", or a directional_per_image row's "light 1, row of
 * 003.png" (the first image with that row). */
void cf_capture_light_name(const cf_capture *capture, size_t image, int slot, char *text,
                           size_t size);
const cf_capture_image *cf_capture_image_at(const cf_capture *capture, size_t index);

/* The geometry of a point of observation i's pixel footprint: the surface
 * point seen through pixel coordinates (pixel centre + (du, dv)), du and
 * dv in pixels (the pixel's footprint is |du|, |dv| <= 1/2): its normal,
 * its view direction, and every light slot's direction and irradiance
 * (lights × 3 each, laid out as one observation's in cf_observations;
 * zero for unused slots). For a normal map, normals between pixel centres
 * are interpolated bilinearly. Returns 1, or 0 where that point does not
 * see the sphere (or i is not an observation). What the fitter uses to
 * integrate a lobe narrower than a pixel over the pixel (docs/model.md
 * §5.6). */
int cf_capture_footprint_at(const cf_capture *capture, size_t i, double du, double dv,
                            double normal[3], double view[3], double *light_dir,
                            double *irradiance);

/* What a capture says about itself, for the fitter and reports. */
typedef struct cf_capture_summary {
  const char *name;
  const char *camera;      /* "colmap" or "orthographic" */
  const char *geometry;    /* "sphere", "sphere_from_silhouettes", "normal_map" */
  double sphere_center[3]; /* world (when the camera is COLMAP's) */
  double sphere_radius;    /* world units; 0 for an orthographic camera */
  double sphere_rms_px;    /* silhouette reprojection error when triangulated, else 0 */
  double silhouette_kept;  /* fraction of the silhouettes' points that fit the sphere */
  int radiometry_relative; /* lights known only up to one common factor */
  int tone_curve_unknown;
  int transfer;          /* the declared encoding, a cf_transfer (image.h) */
  double transfer_gamma; /* its gamma (CF_TRANSFER_GAMMA) */
  int has_noise;
  double noise_read, noise_shot; /* variance = read² + shot · radiance */
  size_t warnings;
  /* relative radiometry made absolute by a reference target of known
   * albedo (capture file: "reference"); radiometry_relative is then 0 and
   * every light's irradiance has been multiplied by reference_scale */
  int radiometry_from_reference;
  double reference_scale;             /* s: median of measured / predicted radiance */
  double reference_spread;            /* 1.4826 MAD / median of those ratios */
  double reference_channel_scales[3]; /* the median ratio per channel */
  size_t reference_pixels;            /* the target's pixels used */
  /* orthographic camera + sphere_from_silhouettes: the sphere's outline,
   * one ellipse fitted to the first mask (or image) and used for every
   * image; pixels, x right, y down. The normals take the circle of radius
   * (a + b) / 2 about the centre. has_circle is 0 otherwise. */
  int has_circle;
  double circle_center_px[2];
  double circle_axes_px[2]; /* semi-axes a >= b */
  double circle_angle;      /* of the a axis from +x toward +y, radians */
  const char *circle_source;
} cf_capture_summary;

void cf_capture_summarize(const cf_capture *capture, cf_capture_summary *summary);

/* Write an 8-bit sRGB PNG of image `index` showing which pixels became
 * observations: the photo (scaled so that its 99.5th percentile is white),
 * the pixels used tinted green, those with a clipped channel red. */
cf_status cf_capture_write_overlay(const cf_capture *capture, size_t index, const char *path,
                                   cf_error *err);

/* Image `index` decoded as the observations are: linear radiance divided
 * by the image's exposure e_k, 3 channels (include/clayfit/image.h; free
 * with cf_image_free), and, when clipped is not NULL (width × height
 * bytes), each pixel's clip mask (bit c: channel c clipped). For reports
 * that show the photo beside the fit's rendering. */
struct cf_image;
struct cf_decode;
cf_status cf_capture_read_radiance(const cf_capture *capture, size_t index,
                                   struct cf_image *radiance, uint8_t *clipped, cf_error *err);

/* Image `index` as stored (3 channels, a grey image's one in all three;
 * free with cf_image_free) and how the observations decoded it
 * (cf_decode_pixel; its inverse cf_encode_value): for the fit's model of
 * a JPEG's coding, which works on stored values. */
cf_status cf_capture_read_stored(const cf_capture *capture, size_t index, struct cf_image *stored,
                                 struct cf_decode *decode, cf_error *err);

/* Warnings raised while loading (for example, environment-map values
 * clamped to 0, an image that does not see the sphere). */
const char *cf_capture_warning(const cf_capture *capture, size_t index);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_CAPTURE_H */
