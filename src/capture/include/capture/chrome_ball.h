/* Light directions from photos of a chrome (mirror) ball: the ball's
 * outline, its highlights, and the direction each one reflects, with how far
 * a one-pixel error moves it. Pure C; the outline comes from the sphere
 * component (sphere_silhouette.h, OpenCV). Capture's interface to the
 * layers above (src/capture/include): `clayfit lights` is its user
 * (docs/lights.md).
 *
 * Frames. Orthographic (camera NULL): DiLiGenT's, x right, y up, z toward
 * the camera, view v = (0, 0, 1) everywhere. A COLMAP camera: its own frame,
 * x right, y down, z forward (the caller rotates into the world with the
 * image's pose). Directions point from the ball toward the light. Pixel
 * coordinates are COLMAP's continuous ones (pixel (x, y) has its centre at
 * (x + 0.5, y + 0.5)). */
#ifndef CLAYFIT_CAPTURE_CHROME_BALL_H
#define CLAYFIT_CAPTURE_CHROME_BALL_H

#include <stddef.h>

#include "clayfit/colmap.h"
#include "clayfit/image.h"
#include "clayfit/status.h"
#include "capture/sphere_silhouette.h"

enum { CF_CHROME_MAX_LIGHTS = 16 };

/* Warnings on one highlight (bits of cf_chrome_light.warnings). */
enum {
  /* the blob reaches within 1.5 px of the outline or its centroid is past
   * 0.95 of the radius: the light is behind the ball (over 143° from the
   * view), where a pixel moves the direction by several degrees */
  CF_CHROME_GRAZING = 1u << 0,
  /* more than 2% of the ball's pixels: a lamp seen close up or a window,
   * not a distant point light; its centroid is only the area's centre */
  CF_CHROME_EXTENDED = 1u << 1,
  /* no pixel of it at the photo's clip level: the brightest pixels may be a
   * reflection of something else (a wall, a second bounce) */
  CF_CHROME_UNSATURATED = 1u << 2
};

/* One line of text for one warning bit ("" for an unknown one). */
const char *cf_chrome_warning_text(unsigned bit);

typedef struct cf_chrome_options {
  int lights;          /* highlights each photo must have (default 1) */
  double threshold;    /* a highlight's pixels: at least this fraction of the
                          ball's brightest value (default 0.5) */
  double min_contrast; /* the brightest value on the ball over its
                          background, the 90th percentile (default 8):
                          below it there is no highlight */
  double speck;        /* blobs with less than this fraction of the largest
                          one's weight are ignored, and counted (default 0.01) */
  double clip_level;   /* stored grey at or above which a pixel is clipped
                          (default 0.99: 8-bit 253) */
} cf_chrome_options;

void cf_chrome_default_options(cf_chrome_options *options);

typedef struct cf_chrome_light {
  double pixel[2];       /* sub-pixel centroid, weighted by value − threshold */
  size_t area;           /* pixels in the blob */
  size_t clipped;        /* of them, at the clip level */
  double peak;           /* its brightest grey value */
  double rho;            /* distance from the outline's centre / its radius */
  double direction[3];   /* unit, toward the light (frame above) */
  double view_angle_deg; /* between the direction and the view (toward the camera) */
  /* Angles, degrees, by which a one-pixel error moves the direction
   * (derivatives by central differences of the same computation): the
   * highlight moved 1 px the worst way, the outline's centre moved 1 px the
   * worst way, its radius 1 px larger. */
  double per_px_highlight_deg, per_px_center_deg, per_px_radius_deg;
  unsigned warnings; /* CF_CHROME_* */
} cf_chrome_light;

typedef struct cf_chrome_result {
  size_t count; /* highlights found: options.lights of them on success */
  cf_chrome_light lights[CF_CHROME_MAX_LIGHTS];
  size_t specks;           /* blobs ignored as specks */
  double peak, background; /* grey on the ball: the brightest, the 90th percentile */
  size_t ball_pixels;
} cf_chrome_result;

/* The unit direction toward the light whose mirror reflection is seen at
 * pixel (x, y) of a ball with outline `outline` (camera NULL: orthographic,
 * the circle r = (a + b)/2; else the ellipse back-projected through the
 * camera into the cone tangent to the ball). 0 (l untouched) if the pixel
 * is off the ball or the outline or camera is not usable. */
int cf_chrome_direction(const cf_ellipse *outline, const cf_camera *camera, double x, double y,
                        double l[3]);

/* The outline from a mask (non-zero = ball, first channel) or, with mask
 * NULL, from the photos' silhouette: cf_detect_sphere_silhouette on the
 * per-pixel median of the `count` photos (one camera pose). A chrome ball
 * is dark but for its reflections; the median keeps what every photo shows
 * (the ball against its surroundings) and drops the highlights, which move
 * from photo to photo: on uw_chrome the maximum's outline was 19 px off the
 * mask's, the median's 1 px. Then checked: CF_EINVAL when the mask touches
 * the image border or the outline comes within 1 px of it (a clipped ball:
 * its circle is not measurable), CF_ENOTFOUND when there is no ball.
 * `name` is for messages. */
cf_status cf_chrome_outline(const cf_image *photos, size_t count, const cf_image *mask,
                            const char *name, cf_ellipse *outline, cf_error *err);

/* The highlights of one photo and their directions. Errors (CF_EINVAL,
 * naming `name`, never a guess): no highlight (the ball's brightest value
 * under min_contrast × its background), more or fewer highlights than
 * options->lights, more than CF_CHROME_MAX_LIGHTS, a photo of another size
 * than the outline allows, an outline that is not usable. options may be
 * NULL (defaults). Highlights are sorted by weight, largest first. */
cf_status cf_chrome_lights(const cf_image *photo, const cf_ellipse *outline,
                           const cf_camera *camera, const cf_chrome_options *options,
                           const char *name, cf_chrome_result *result, cf_error *err);

#endif /* CLAYFIT_CAPTURE_CHROME_BALL_H */
