/* clayfit: COLMAP 3.8 sparse models (cameras, images, points3D) in the
 * text and the binary format, and the camera models that turn a pixel into
 * a ray and back.
 *
 * Conventions (COLMAP's, kept as they are):
 * - An image's pose is world-to-camera: x_cam = R(q) x_world + t, with the
 *   unit quaternion q = (qw, qx, qy, qz) and t = (tx, ty, tz). The camera
 *   centre is C = −R(q)ᵀ t. Camera axes: x right, y down, z forward.
 * - Pixel coordinates (u, v) are continuous with the centre of the top-left
 *   pixel at (0.5, 0.5): pixel (column i, row j) has its centre at
 *   (i + 0.5, j + 0.5).
 * - Camera parameters are in COLMAP's order for each model (below).
 *
 * Everything read from files is untrusted: every count is checked against
 * the bytes that remain before anything is allocated, every number must be
 * finite where it has to be, and an error names the file, the line (text)
 * or byte offset (binary), the record and the field. */
#ifndef CLAYFIT_COLMAP_H
#define CLAYFIT_COLMAP_H

#include <stddef.h>
#include <stdint.h>

#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* COLMAP's camera models, with COLMAP's numeric ids (used in cameras.bin)
 * and parameter lists: X(ID, number, "NAME", parameter count, "params").
 * The distortion of each is undone exactly (by iteration) in
 * cf_camera_unproject. */
/* clang-format off */
#define CF_CAMERA_MODEL_MAP(X)                                                          \
  X(SIMPLE_PINHOLE, 0, "SIMPLE_PINHOLE", 3, "f, cx, cy")                                \
  X(PINHOLE, 1, "PINHOLE", 4, "fx, fy, cx, cy")                                         \
  X(SIMPLE_RADIAL, 2, "SIMPLE_RADIAL", 4, "f, cx, cy, k")                               \
  X(RADIAL, 3, "RADIAL", 5, "f, cx, cy, k1, k2")                                        \
  X(OPENCV, 4, "OPENCV", 8, "fx, fy, cx, cy, k1, k2, p1, p2")                           \
  X(OPENCV_FISHEYE, 5, "OPENCV_FISHEYE", 8, "fx, fy, cx, cy, k1, k2, k3, k4")           \
  X(FULL_OPENCV, 6, "FULL_OPENCV", 12,                                                  \
    "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6")                                   \
  X(FOV, 7, "FOV", 5, "fx, fy, cx, cy, omega")                                          \
  X(SIMPLE_RADIAL_FISHEYE, 8, "SIMPLE_RADIAL_FISHEYE", 4, "f, cx, cy, k")               \
  X(RADIAL_FISHEYE, 9, "RADIAL_FISHEYE", 5, "f, cx, cy, k1, k2")                        \
  X(THIN_PRISM_FISHEYE, 10, "THIN_PRISM_FISHEYE", 12,                                   \
    "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1")
/* clang-format on */

typedef enum cf_camera_model {
#define CF__CAMERA_ENUM(ID, number, name, count, params) CF_CAMERA_##ID = number,
  CF_CAMERA_MODEL_MAP(CF__CAMERA_ENUM)
#undef CF__CAMERA_ENUM
      CF_CAMERA_MODEL_COUNT
} cf_camera_model;

enum { CF_CAMERA_MAX_PARAMS = 12 };

typedef struct cf_camera {
  uint32_t camera_id;
  cf_camera_model model;
  uint64_t width, height; /* pixels */
  int num_params;         /* as the model requires */
  double params[CF_CAMERA_MAX_PARAMS];
} cf_camera;

typedef struct cf_point2d {
  double x, y;        /* pixel coordinates, COLMAP's convention */
  int64_t point3d_id; /* −1 where the keypoint has no 3D point */
} cf_point2d;

typedef struct cf_colmap_image {
  uint32_t image_id;
  double qvec[4]; /* qw, qx, qy, qz: world-to-camera rotation */
  double tvec[3]; /* world-to-camera translation */
  uint32_t camera_id;
  char *name; /* the image's file name, relative to COLMAP's image folder */
  size_t num_points2d;
  cf_point2d *points2d;
} cf_colmap_image;

typedef struct cf_track_element {
  uint32_t image_id;
  uint32_t point2d_idx;
} cf_track_element;

typedef struct cf_point3d {
  uint64_t point3d_id;
  double xyz[3];
  uint8_t rgb[3];
  double error; /* mean reprojection error, pixels */
  size_t track_length;
  cf_track_element *track;
} cf_point3d;

/* A whole sparse model; owned by the caller, released by
 * cf_colmap_model_free. Records are kept in file order. */
typedef struct cf_colmap_model {
  size_t num_cameras;
  cf_camera *cameras;
  size_t num_images;
  cf_colmap_image *images;
  size_t num_points3d;
  cf_point3d *points3d;
} cf_colmap_model;

void cf_colmap_model_free(cf_colmap_model *model);

/* Read the model in folder `dir`: cameras.bin, images.bin and points3D.bin
 * if all three exist, else cameras.txt, images.txt and points3D.txt.
 * points3D may be skipped (with_points = 0) when only poses are needed;
 * then cameras.bin and images.bin suffice for the binary format. Files
 * larger than 4 GiB are refused.
 * Checks every image's camera_id names a camera, every quaternion is
 * finite and of non-zero length (it is normalised, unless its squared
 * length is already 1 to within 8 ulp: then it is kept bit for bit, so
 * that what cf_colmap_write_* wrote reads back exactly), each camera
 * passes cf_camera_check, and no two images have the same name.
 * *model is overwritten (not freed first); on failure it is left empty.
 * CF_ENOTFOUND when the folder or a file is missing, CF_EPARSE for a
 * malformed file or a failed check (CF_EINVAL/CF_ERANGE from
 * cf_camera_check), CF_EIO, CF_ENOMEM. */
cf_status cf_colmap_read(const char *dir, int with_points, cf_colmap_model *model, cf_error *err);

/* The stream/memory cores behind cf_colmap_read: parse one file's bytes
 * (`size` of them; text need not be NUL-terminated). `name` is used in
 * messages only (for example "sparse/0/images.bin"). They append to
 * `model` (whose other arrays are left untouched); on failure (CF_EPARSE,
 * or CF_ENOMEM) the model is left exactly as it was. Ids must be unique
 * within the file and against the records already in the model; names are
 * 1 to 4096 bytes; point3D ids are at most INT64_MAX; binary files must
 * end where their last record does. Text: COLMAP's lines, '#' comments and
 * empty lines skipped between records; an image's NAME is the rest of its
 * line. */
cf_status cf_colmap_parse_cameras_text(const char *text, size_t size, const char *name,
                                       cf_colmap_model *model, cf_error *err);
cf_status cf_colmap_parse_images_text(const char *text, size_t size, const char *name,
                                      cf_colmap_model *model, cf_error *err);
cf_status cf_colmap_parse_points3d_text(const char *text, size_t size, const char *name,
                                        cf_colmap_model *model, cf_error *err);
cf_status cf_colmap_parse_cameras_binary(const uint8_t *data, size_t size, const char *name,
                                         cf_colmap_model *model, cf_error *err);
cf_status cf_colmap_parse_images_binary(const uint8_t *data, size_t size, const char *name,
                                        cf_colmap_model *model, cf_error *err);
cf_status cf_colmap_parse_points3d_binary(const uint8_t *data, size_t size, const char *name,
                                          cf_colmap_model *model, cf_error *err);

/* Write the model into folder `dir` (which must exist) in COLMAP's text or
 * binary format, with 17 significant digits in text so that a round trip
 * is exact; records in the model's order, quaternions as they are.
 * CF_EINVAL (nothing written) for what the files cannot hold: an unknown
 * camera model or a wrong parameter count, an empty name or one longer
 * than 4096 bytes, with a line break or with blanks at either end, a
 * point3d_id below −1; CF_EIO when a file cannot be written. */
cf_status cf_colmap_write_text(const char *dir, const cf_colmap_model *model, cf_error *err);
cf_status cf_colmap_write_binary(const char *dir, const cf_colmap_model *model, cf_error *err);

/* Look-ups (NULL when absent). */
const cf_camera *cf_colmap_find_camera(const cf_colmap_model *model, uint32_t camera_id);
const cf_colmap_image *cf_colmap_find_image_by_name(const cf_colmap_model *model, const char *name);

/* ---- cameras ---- */

/* "OPENCV" → CF_CAMERA_OPENCV (exact, case-sensitive, as COLMAP);
 * CF_ENOTFOUND (message lists the models). */
cf_status cf_camera_model_find(const char *name, cf_camera_model *model, cf_error *err);
const char *cf_camera_model_name(cf_camera_model model);        /* NULL if unknown */
int cf_camera_model_param_count(cf_camera_model model);         /* −1 if unknown */
const char *cf_camera_model_param_names(cf_camera_model model); /* "fx, fy, cx, cy" */

/* CF_OK if the model is known, num_params matches it, every parameter is
 * finite (else CF_EINVAL), focal lengths are > 0, and width and height are
 * in [1, 2^20] (else CF_ERANGE). Messages name the camera and parameter. */
cf_status cf_camera_check(const cf_camera *camera, cf_error *err);

/* Project a point in camera coordinates (z > 0) to pixel coordinates,
 * applying the model's distortion (COLMAP's WorldToImage, operation for
 * operation). Returns 0 if z <= 0, the camera's model or parameter count
 * is wrong, or the result is not finite (uv untouched). */
int cf_camera_project(const cf_camera *camera, const double xyz[3], double uv[2]);

/* The unit ray, in camera coordinates, of pixel coordinates (u, v): the
 * inverse of cf_camera_project, with the distortion undone by Newton
 * iteration to 1e-12 in normalised coordinates (on the equidistant plane
 * θ p/|p| for the fisheye models). Returns 0 (ray untouched) where the
 * iteration does not converge, where the only solution lies past a fold of
 * the distortion (where the Jacobian's determinant is <= 0: not the
 * physical ray), and for the fisheye models where the pixel is 90° or more
 * off axis (no direction with z > 0). */
int cf_camera_unproject(const cf_camera *camera, const double uv[2], double ray[3]);

/* ---- poses ---- */

/* The row-major rotation matrix of a unit quaternion (qw, qx, qy, qz). */
void cf_quaternion_to_matrix(const double q[4], double r[9]);

/* The camera centre C = −Rᵀ t of an image, in world coordinates. */
void cf_colmap_image_center(const cf_colmap_image *image, double center[3]);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_COLMAP_H */
