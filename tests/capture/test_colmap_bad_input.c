/* COLMAP readers on bad input: every case gives the expected status and a
 * message that names the file and the record and field (and the line or
 * byte); valid binary files cut at every byte, and randomly corrupted,
 * give clean errors and never a crash (this test also runs under
 * AddressSanitizer and UBSan, where a stray read fails it). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clayfit/colmap.h"
#include "core/file.h"
#include "core/rng.h"
#include "support/check.h"

CHECK_MAIN_STATE;

enum { PATH_SIZE = 8192 };

/* status == want and the message holds every one of the NULL-terminated
 * needles. */
static void expect(const char *what, cf_status status, cf_status want, const cf_error *err, ...) {
  CHECK(status == want, "%s: status %s, expected %s (%s)", what, cf_status_name(status),
        cf_status_name(want), err->message);
  va_list args;
  va_start(args, err);
  for (const char *needle = va_arg(args, const char *); needle; needle = va_arg(args, const char *))
    CHECK(strstr(err->message, needle) != NULL, "%s: '%s' not in \"%s\"", what, needle,
          err->message);
  va_end(args);
  printf("  %-34s %s\n", what, status == CF_OK ? "read" : err->message);
}

/* ---- a small valid model ---- */

static char *copy_string(const char *s) {
  char *c = malloc(strlen(s) + 1);
  if (c) strcpy(c, s);
  return c;
}

static void build_model(cf_colmap_model *m) {
  m->num_cameras = 2;
  m->cameras = calloc(2, sizeof *m->cameras);
  m->cameras[0] = (cf_camera){
      1, CF_CAMERA_OPENCV, 640, 480, 8, {500, 501, 320, 240, -0.1, 0.01, 0.001, -0.002}};
  m->cameras[1] = (cf_camera){2, CF_CAMERA_PINHOLE, 800, 600, 4, {700, 700, 400, 300}};
  m->num_images = 2;
  m->images = calloc(2, sizeof *m->images);
  for (int i = 0; i < 2; ++i) {
    cf_colmap_image *im = &m->images[i];
    im->image_id = (uint32_t)(3 + i);
    im->qvec[0] = 1;
    memcpy(im->tvec, (double[3]){0.25 * i, -1, 2}, sizeof im->tvec);
    im->camera_id = (uint32_t)(1 + i);
    im->name = copy_string(i ? "b.jpg" : "a.jpg");
    im->num_points2d = 3;
    im->points2d = calloc(3, sizeof *im->points2d);
    for (int j = 0; j < 3; ++j)
      im->points2d[j] = (cf_point2d){10.5 + j, 20.25 + i, j == 1 ? -1 : (int64_t)(100 + j)};
  }
  m->num_points3d = 2;
  m->points3d = calloc(2, sizeof *m->points3d);
  for (int p = 0; p < 2; ++p) {
    cf_point3d *pt = &m->points3d[p];
    pt->point3d_id = (uint64_t)(100 + 2 * p);
    memcpy(pt->xyz, (double[3]){1, 2 + p, 3}, sizeof pt->xyz);
    memcpy(pt->rgb, (uint8_t[3]){10, 20, 30}, sizeof pt->rgb);
    pt->error = 0.5;
    pt->track_length = 2;
    pt->track = calloc(2, sizeof *pt->track);
    pt->track[0] = (cf_track_element){3, (uint32_t)(2 * p)};
    pt->track[1] = (cf_track_element){4, (uint32_t)(2 * p)};
  }
}

/* ---- files ---- */

typedef struct bytes {
  char *data;
  size_t size;
} bytes;

static void path_in(char *out, const char *dir, const char *name) {
  int n = snprintf(out, PATH_SIZE, "%s/%s", dir, name);
  CHECK(n > 0 && n < PATH_SIZE, "path too long");
}

static bytes load(const char *dir, const char *name) {
  char path[PATH_SIZE];
  bytes b = {NULL, 0};
  cf_error err = {0};
  path_in(path, dir, name);
  CHECK(cf_read_file(path, 1 << 20, &b.data, &b.size, &err) == CF_OK, "%s", err.message);
  return b;
}

static void save(const char *dir, const char *name, const void *data, size_t size) {
  char path[PATH_SIZE];
  cf_error err = {0};
  path_in(path, dir, name);
  CHECK(cf_write_file(path, data, size, &err) == CF_OK, "%s", err.message);
}

static void save_text(const char *dir, const char *name, const char *text) {
  save(dir, name, text, strlen(text));
}

static void remove_in(const char *dir, const char *name) {
  char path[PATH_SIZE];
  path_in(path, dir, name);
  remove(path);
}

static const char *const all_files[] = {"cameras.txt", "images.txt", "points3D.txt",
                                        "cameras.bin", "images.bin", "points3D.bin"};

static void clear_dir(const char *dir) {
  for (size_t k = 0; k < sizeof all_files / sizeof all_files[0]; ++k) remove_in(dir, all_files[k]);
}

/* ---- the parse cores on bytes ---- */

typedef enum file_kind { CAMERAS, IMAGES, POINTS } file_kind;
static const char *const binary_names[3] = {"cameras.bin", "images.bin", "points3D.bin"};
static const char *const text_names[3] = {"cameras.txt", "images.txt", "points3D.txt"};

/* Parse a private heap copy of exactly `size` bytes (so that AddressSanitizer
 * sees any read past them). */
static cf_status parse(file_kind kind, int binary, const void *data, size_t size,
                       cf_colmap_model *model, cf_error *err) {
  char *copy = malloc(size ? size : 1);
  if (size) memcpy(copy, data, size);
  const uint8_t *b = (const uint8_t *)copy;
  cf_status s;
  const char *name = binary ? binary_names[kind] : text_names[kind];
  if (kind == CAMERAS)
    s = binary ? cf_colmap_parse_cameras_binary(b, size, name, model, err)
               : cf_colmap_parse_cameras_text(copy, size, name, model, err);
  else if (kind == IMAGES)
    s = binary ? cf_colmap_parse_images_binary(b, size, name, model, err)
               : cf_colmap_parse_images_text(copy, size, name, model, err);
  else
    s = binary ? cf_colmap_parse_points3d_binary(b, size, name, model, err)
               : cf_colmap_parse_points3d_text(copy, size, name, model, err);
  free(copy);
  return s;
}

static size_t record_count(const cf_colmap_model *m, file_kind kind) {
  return kind == CAMERAS ? m->num_cameras : kind == IMAGES ? m->num_images : m->num_points3d;
}

/* The field a message names ("points2D[3].x" → "points2D.x"). */
static void field_of(const char *message, char *out, size_t size) {
  const char *f = strstr(message, ": field ");
  size_t n = 0;
  if (f) {
    for (f += 8; *f && *f != ':' && n + 1 < size; ++f) {
      if (*f == '[') {
        while (*f && *f != ']') ++f;
        continue;
      }
      out[n++] = *f;
    }
  }
  out[n] = '\0';
}

/* Cut a valid binary file at every byte: each cut a clean CF_EPARSE that
 * names the file, a byte offset within the cut and a field, with the model
 * left as it was; and every field of the record type is among those named
 * (so the cuts reach into every field, not only the record count). A cut
 * inside a points2D or track array is named at its count (num_points2D,
 * track_length): the elements have a fixed size, so the count check
 * against the bytes that remain is exact, and none is read. */
static void truncations(const bytes *files) {
  static const char *const fields[3] = {
      " num_cameras camera_id model_id width height fx fy cx cy k1 k2 p1 p2 ",
      " num_images image_id qw qx qy qz tx ty tz camera_id name num_points2D ",
      " num_points3D point3D_id x y z r g b error track_length "};
  static const char *const never[3] = {"", " points2D.x points2D.y points2D.point3D_id ",
                                       " track.image_id track.point2D_idx "};
  for (int kind = 0; kind < 3; ++kind) {
    const bytes *f = &files[kind];
    long clean = 0, in_header = 0;
    char seen[512] = " ";
    for (size_t cut = 0; cut < f->size; ++cut) {
      cf_colmap_model model = {0};
      cf_error err = {0};
      cf_status s = parse((file_kind)kind, 1, f->data, cut, &model, &err);
      size_t at = (size_t)-1;
      const char *byte = strstr(err.message, ": byte ");
      if (byte) at = strtoull(byte + 7, NULL, 10);
      char field[64], padded[70];
      field_of(err.message, field, sizeof field);
      int ok = s == CF_EPARSE &&
               strncmp(err.message, binary_names[kind], strlen(binary_names[kind])) == 0 &&
               at <= cut && field[0] && record_count(&model, (file_kind)kind) == 0;
      CHECK(ok, "%s cut at %zu: %s %s", binary_names[kind], cut, cf_status_name(s), err.message);
      clean += ok;
      in_header += strstr(err.message, ": header: ") != NULL;
      snprintf(padded, sizeof padded, " %s ", field);
      if (field[0] && !strstr(seen, padded) && strlen(seen) + strlen(field) + 2 < sizeof seen)
        strcat(strcat(seen, field), " ");
      if (cut == f->size - 5) printf("  %s cut at %zu: %s\n", binary_names[kind], cut, err.message);
      cf_colmap_model_free(&model);
    }
    cf_colmap_model model = {0};
    cf_error err = {0};
    CHECK(parse((file_kind)kind, 1, f->data, f->size, &model, &err) == CF_OK, "%s whole: %s",
          binary_names[kind], err.message);
    cf_colmap_model_free(&model);
    printf(
        "%s: %ld of %zu cuts give a clean error (%ld caught by the record count); fields "
        "named:%s\n",
        binary_names[kind], clean, f->size, in_header, seen);
    for (const char *p = fields[kind] + 1; *p;) {
      size_t n = strcspn(p, " ");
      char padded[70];
      snprintf(padded, sizeof padded, " %.*s ", (int)n, p);
      CHECK(strstr(seen, padded), "%s: no cut is reported in field%s", binary_names[kind], padded);
      p += n + 1;
    }
    for (const char *p = never[kind]; *p == ' ' && p[1];) {
      size_t n = strcspn(p + 1, " ");
      char padded[70];
      snprintf(padded, sizeof padded, " %.*s ", (int)n, p + 1);
      CHECK(!strstr(seen, padded), "%s: a cut read into the array:%s", binary_names[kind], padded);
      p += n + 1;
    }
  }
}

/* Eight records of each kind, bigger than the smallest possible, so that
 * cuts pass the record-count check and land in every field. */
static void build_truncation_model(cf_colmap_model *m) {
  const int n = 8;
  m->num_cameras = m->num_images = m->num_points3d = (size_t)n;
  m->cameras = calloc((size_t)n, sizeof *m->cameras);
  m->images = calloc((size_t)n, sizeof *m->images);
  m->points3d = calloc((size_t)n, sizeof *m->points3d);
  for (int i = 0; i < n; ++i) {
    m->cameras[i] = (cf_camera){(uint32_t)(i + 1),
                                CF_CAMERA_OPENCV,
                                640,
                                480,
                                8,
                                {500, 501, 320, 240, -0.1, 0.01, 0.001, -0.002}};
    cf_colmap_image *im = &m->images[i];
    im->image_id = (uint32_t)(i + 1);
    im->qvec[0] = 1;
    im->camera_id = 1;
    im->name = copy_string("image_name.jpg");
    im->num_points2d = 3;
    im->points2d = calloc(3, sizeof *im->points2d);
    for (int j = 0; j < 3; ++j) im->points2d[j] = (cf_point2d){1.5, 2.5, j - 1};
    cf_point3d *pt = &m->points3d[i];
    pt->point3d_id = (uint64_t)i;
    pt->track_length = 4;
    pt->track = calloc(4, sizeof *pt->track);
  }
}

/* Text files cut anywhere: either a complete file or a clean error. */
static void text_truncations(const bytes *files) {
  for (int kind = 0; kind < 3; ++kind) {
    long ok = 0, errors = 0;
    for (size_t cut = 0; cut <= files[kind].size; ++cut) {
      cf_colmap_model model = {0};
      cf_error err = {0};
      cf_status s = parse((file_kind)kind, 0, files[kind].data, cut, &model, &err);
      if (s == CF_OK) {
        ++ok;
      } else {
        ++errors;
        CHECK(s == CF_EPARSE &&
                  strncmp(err.message, text_names[kind], strlen(text_names[kind])) == 0 &&
                  strstr(err.message, "field "),
              "%s cut at %zu: %s", text_names[kind], cut, err.message);
      }
      cf_colmap_model_free(&model);
    }
    printf("%s: %ld cuts read, %ld give a clean error\n", text_names[kind], ok, errors);
  }
}

/* Random bytes overwritten in valid binary files: OK or a clean error. */
static void corruptions(const bytes *files, cf_rng *rng) {
  long errors = 0, total = 0;
  for (int kind = 0; kind < 3; ++kind) {
    for (int n = 0; n < 3000; ++n) {
      char *copy = malloc(files[kind].size);
      memcpy(copy, files[kind].data, files[kind].size);
      int flips = 1 + (int)(cf_rng_next(rng) % 4);
      for (int k = 0; k < flips; ++k)
        copy[cf_rng_next(rng) % files[kind].size] = (char)(cf_rng_next(rng) >> 56);
      cf_colmap_model model = {0};
      cf_error err = {0};
      cf_status s = parse((file_kind)kind, 1, copy, files[kind].size, &model, &err);
      CHECK(
          s == CF_OK || (s == CF_EPARSE && strstr(err.message, binary_names[kind]) == err.message),
          "corrupt %s: %s %s", binary_names[kind], cf_status_name(s), err.message);
      errors += s != CF_OK;
      ++total;
      cf_colmap_model_free(&model);
      free(copy);
    }
  }
  printf("random corruptions: %ld of %ld rejected, the others read, none crashed\n", errors, total);
}

/* ---- binary cases ---- */

static void put_u64(char *p, uint64_t v) {
  for (int k = 0; k < 8; ++k) p[k] = (char)(v >> (8 * k));
}
static void put_u32(char *p, uint32_t v) {
  for (int k = 0; k < 4; ++k) p[k] = (char)(v >> (8 * k));
}

static cf_status parse_edited(file_kind kind, const bytes *f, size_t at, uint64_t value, int width,
                              cf_error *err) {
  char *copy = malloc(f->size);
  memcpy(copy, f->data, f->size);
  if (width == 8)
    put_u64(copy + at, value);
  else
    put_u32(copy + at, (uint32_t)value);
  cf_colmap_model model = {0};
  cf_status s = parse(kind, 1, copy, f->size, &model, err);
  cf_colmap_model_free(&model);
  free(copy);
  return s;
}

static void binary_cases(const bytes *files) {
  printf("binary cases:\n");
  cf_error err = {0};
  const bytes *cameras = &files[CAMERAS], *images = &files[IMAGES], *points = &files[POINTS];
  /* offsets from the layout: camera 1 starts at 8, image 1 at 8, its name
   * "a.jpg" at 8 + 4 + 56 + 4 = 72, num_points2D at 78, points at 86 */
  expect("huge camera count", parse_edited(CAMERAS, cameras, 0, (uint64_t)1 << 62, 8, &err),
         CF_EPARSE, &err, "cameras.bin: byte 0", "num_cameras", "4611686018427387904", "remain",
         NULL);
  expect("huge image count", parse_edited(IMAGES, images, 0, UINT64_MAX, 8, &err), CF_EPARSE, &err,
         "images.bin: byte 0", "num_images", "remain", NULL);
  expect("huge num_points2D", parse_edited(IMAGES, images, 78, 1000000000000ull, 8, &err),
         CF_EPARSE, &err, "images.bin: byte 78", "image record 1 of 2 (image_id 3)",
         "field num_points2D", "1000000000000", "remain", NULL);
  /* point 1: id at 8, xyz, rgb, error, track_length at 8 + 8 + 24 + 3 + 8 = 51 */
  expect("huge track_length", parse_edited(POINTS, points, 51, (uint64_t)1 << 40, 8, &err),
         CF_EPARSE, &err, "points3D.bin: byte 51", "point record 1 of 2 (point3D_id 100)",
         "field track_length", "1099511627776", "remain", NULL);
  expect("huge point count", parse_edited(POINTS, points, 0, 123456789012ull, 8, &err), CF_EPARSE,
         &err, "points3D.bin: byte 0", "num_points3D", NULL);
  expect("unknown model id", parse_edited(CAMERAS, cameras, 12, 42, 4, &err), CF_EPARSE, &err,
         "cameras.bin: byte 12", "camera record 1 of 2 (camera_id 1)", "field model_id",
         "unknown camera model id 42", "10 (THIN_PRISM_FISHEYE)", NULL);
  expect("negative model id", parse_edited(CAMERAS, cameras, 12, UINT32_MAX, 4, &err), CF_EPARSE,
         &err, "field model_id", "id -1", NULL);
  double nan = NAN;
  uint64_t nan_bits;
  memcpy(&nan_bits, &nan, 8);
  expect("NaN in a quaternion", parse_edited(IMAGES, images, 20, nan_bits, 8, &err), CF_EPARSE,
         &err, "images.bin: byte 20", "image_id 3", "field qx", "nan", "finite", NULL);
  expect("NaN in a parameter", parse_edited(CAMERAS, cameras, 8 + 24 + 4 * 8, nan_bits, 8, &err),
         CF_EPARSE, &err, "cameras.bin: byte 64", "camera_id 1", "field k1", "finite", NULL);
  uint64_t inf_bits;
  double inf = INFINITY;
  memcpy(&inf_bits, &inf, 8);
  expect("Inf in a point", parse_edited(POINTS, points, 16, inf_bits, 8, &err), CF_EPARSE, &err,
         "points3D.bin: byte 16", "point3D_id 100", "field x", "inf", NULL);
  expect("keypoint x NaN", parse_edited(IMAGES, images, 86 + 24, nan_bits, 8, &err), CF_EPARSE,
         &err, "images.bin: byte 110", "field points2D[1].x", NULL);
  expect("point3D_id above INT64_MAX",
         parse_edited(IMAGES, images, 86 + 16, (uint64_t)INT64_MAX + 5, 8, &err), CF_EPARSE, &err,
         "images.bin: byte 102", "field points2D[0].point3D_id", "9223372036854775812", NULL);
  expect("duplicate camera id", parse_edited(CAMERAS, cameras, 8 + 88, 1, 4, &err), CF_EPARSE, &err,
         "cameras.bin: byte 96", "camera record 2", "camera_id 1 is used twice",
         "camera record 1 at byte 8", NULL);

  /* a name that runs to the end of the file, and one beyond 4096 bytes */
  cf_colmap_model model = {0};
  char unterminated[8 + 64 + 20];
  memcpy(unterminated, images->data, 72);
  put_u64(unterminated, 1);
  memset(unterminated + 72, 'n', 20);
  expect("name without NUL", parse(IMAGES, 1, unterminated, sizeof unterminated, &model, &err),
         CF_EPARSE, &err, "images.bin: byte 72", "image_id 3", "field name",
         "no terminating NUL before the end of the file (20 bytes)", NULL);
  size_t long_size = 8 + 4 + 56 + 4 + 5000 + 1 + 8;
  char *long_name = calloc(1, long_size);
  put_u64(long_name, 1);
  put_u32(long_name + 8, 9);
  put_u64(long_name + 12, 0x3ff0000000000000ull); /* qw = 1 */
  memset(long_name + 72, 'x', 5000);
  expect("name over 4096 bytes", parse(IMAGES, 1, long_name, long_size, &model, &err), CF_EPARSE,
         &err, "images.bin: byte 72", "image_id 9", "field name", "longer than 4096", NULL);
  memset(long_name + 72 + 4096, 0, 9); /* exactly 4096 bytes, NUL, no points: fine */
  expect("name of exactly 4096 bytes",
         parse(IMAGES, 1, long_name, 8 + 4 + 56 + 4 + 4097 + 8, &model, &err), CF_OK, &err, NULL);
  CHECK(model.num_images == 1 && strlen(model.images[0].name) == 4096, "4096-byte name");
  cf_colmap_model_free(&model);
  free(long_name);

  char *longer = malloc(cameras->size + 3);
  memcpy(longer, cameras->data, cameras->size);
  memset(longer + cameras->size, 0, 3);
  expect("trailing bytes", parse(CAMERAS, 1, longer, cameras->size + 3, &model, &err), CF_EPARSE,
         &err, "cameras.bin: byte 152", "3 bytes follow the last camera", NULL);
  free(longer);

  /* appending: a point id already in the model */
  CHECK(parse(POINTS, 1, points->data, points->size, &model, &err) == CF_OK, "%s", err.message);
  expect("id already in the model", parse(POINTS, 1, points->data, points->size, &model, &err),
         CF_EPARSE, &err, "points3D.bin: byte 8", "point3D_id 100 is already in the model", NULL);
  CHECK(model.num_points3d == 2, "a failed parse changed the model: %zu points",
        model.num_points3d);
  cf_colmap_model_free(&model);
}

/* ---- text cases ---- */

static void text_case(const char *what, file_kind kind, const char *text, cf_status want, ...) {
  cf_colmap_model model = {0};
  cf_error err = {0};
  cf_status s = parse(kind, 0, text, strlen(text), &model, &err);
  CHECK(s == want, "%s: status %s, expected %s (%s)", what, cf_status_name(s), cf_status_name(want),
        err.message);
  va_list args;
  va_start(args, want);
  for (const char *needle = va_arg(args, const char *); needle; needle = va_arg(args, const char *))
    CHECK(strstr(err.message, needle) != NULL, "%s: '%s' not in \"%s\"", what, needle, err.message);
  va_end(args);
  CHECK(s == CF_OK || record_count(&model, kind) == 0, "%s: a failed parse added records", what);
  printf("  %-34s %s\n", what, s == CF_OK ? "read" : err.message);
  cf_colmap_model_free(&model);
}

static void text_cases(void) {
  printf("text cases:\n");
  text_case("unknown model name", CAMERAS, "# c\n1 OPENCVX 100 100 1 2 3\n", CF_EPARSE,
            "cameras.txt:2: camera 1: field MODEL: 'OPENCVX' is not a camera model",
            "SIMPLE_PINHOLE, PINHOLE", "THIN_PRISM_FISHEYE", NULL);
  text_case("wrong parameter count", CAMERAS, "1 OPENCV 640 480 500 500 320 240 0.1\n", CF_EPARSE,
            "cameras.txt:1: camera 1: field PARAMS", "takes 8 parameters",
            "fx, fy, cx, cy, k1, k2, p1, p2", "has 5", NULL);
  text_case("missing field", CAMERAS, "\n\n7 PINHOLE 100\n", CF_EPARSE,
            "cameras.txt:3: camera 7: field HEIGHT is missing", NULL);
  text_case("parameter not a number", CAMERAS, "1 PINHOLE 10 10 1 1x 5 5\n", CF_EPARSE,
            "cameras.txt:1: camera 1: field fy: '1x' is not a number", NULL);
  text_case("infinite parameter", CAMERAS, "1 SIMPLE_RADIAL 10 10 1 5 5 1e999\n", CF_EPARSE,
            "field k: '1e999' is not a finite number", NULL);
  text_case("camera id too large", CAMERAS, "4294967296 PINHOLE 10 10 1 1 5 5\n", CF_EPARSE,
            "cameras.txt:1: camera record 1: field CAMERA_ID: '4294967296' is out of range", NULL);
  text_case("negative width", CAMERAS, "1 PINHOLE -10 10 1 1 5 5\n", CF_EPARSE,
            "field WIDTH: '-10' is not a whole number", NULL);
  text_case("duplicate camera id", CAMERAS,
            "1 PINHOLE 10 10 1 1 5 5\n# comment\n1 PINHOLE 10 10 1 1 5 5\n", CF_EPARSE,
            "cameras.txt:3: camera 1: CAMERA_ID 1 is used twice (first on line 1)", NULL);
  text_case("CRLF and blanks", CAMERAS, "# c\r\n  1 PINHOLE\t10 10 1 1 5 5 \r\n\r\n", CF_OK, NULL);

  text_case("QW not a number", IMAGES,
            "# i\n# i\n3 1 0 0 0 0 0 0 1 a.jpg\n1 2 -1\n4 abc 0 0 0 0 0 0 1 b.jpg\n\n", CF_EPARSE,
            "images.txt:5: image 4: field QW: 'abc' is not a number", NULL);
  text_case("NaN in a quaternion", IMAGES, "3 1 nan 0 0 0 0 0 1 a.jpg\n\n", CF_EPARSE,
            "images.txt:1: image 3: field QX: 'nan' is not a finite number", NULL);
  text_case("missing name", IMAGES, "3 1 0 0 0 0 0 0 1\n\n", CF_EPARSE,
            "images.txt:1: image 3: field NAME is missing",
            "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME", NULL);
  text_case("points2D not in threes", IMAGES, "3 1 0 0 0 0 0 0 1 a.jpg\n1 2 -1 3 4\n", CF_EPARSE,
            "images.txt:2: image 3: field POINTS2D: 5 numbers, not a multiple of 3", NULL);
  text_case("POINT3D_ID -2", IMAGES, "3 1 0 0 0 0 0 0 1 a.jpg\n1 2 -1 3 4 -2\n", CF_EPARSE,
            "images.txt:2: image 3: field POINTS2D[1].POINT3D_ID: '-2' is neither -1 nor", NULL);
  text_case("keypoint y not a number", IMAGES, "3 1 0 0 0 0 0 0 1 a.jpg\n1 y 7\n", CF_EPARSE,
            "images.txt:2: image 3: field POINTS2D[0].Y: 'y' is not a number", NULL);
  text_case("duplicate image id", IMAGES, "3 1 0 0 0 0 0 0 1 a.jpg\n\n3 1 0 0 0 0 0 0 1 b.jpg\n\n",
            CF_EPARSE, "images.txt:3: image 3: IMAGE_ID 3 is used twice (first on line 1)", NULL);
  text_case("empty points line, last image", IMAGES,
            "3 1 0 0 0 0 0 0 1 a.jpg\n\n4 1 0 0 0 0 0 0 1 b c.jpg", CF_OK, NULL);

  text_case("colour above 255", POINTS, "100 1 2 3 10 256 30 0.5 3 0\n", CF_EPARSE,
            "points3D.txt:1: point 100: field G: '256' is out of range [0, 255]", NULL);
  text_case("odd track", POINTS, "100 1 2 3 10 20 30 0.5 3 0 4\n", CF_EPARSE,
            "points3D.txt:1: point 100: field TRACK: 3 numbers, not a multiple of 2", NULL);
  text_case("track image id", POINTS, "100 1 2 3 10 20 30 0.5 3 0 x 1\n", CF_EPARSE,
            "field TRACK[1].IMAGE_ID: 'x' is not a whole number", NULL);
  text_case("ERROR missing", POINTS, "100 1 2 3 10 20 30\n", CF_EPARSE,
            "points3D.txt:1: point 100: field ERROR is missing", NULL);
  text_case("point id too large", POINTS, "9223372036854775808 1 2 3 10 20 30 0.5\n", CF_EPARSE,
            "field POINT3D_ID: '9223372036854775808' is out of range", NULL);

  /* a NUL byte inside a number (the cores take sizes, not C strings) */
  static const char with_nul[] = "100 1 2\0003 3 10 20 30 0.5\n";
  cf_colmap_model model = {0};
  cf_error err = {0};
  expect("NUL inside a number", parse(POINTS, 0, with_nul, sizeof with_nul - 1, &model, &err),
         CF_EPARSE, &err, "points3D.txt:1: point 100: field Y: '2?3' is not a number", NULL);
  cf_colmap_model_free(&model);
}

/* ---- whole folders ---- */

static void folder_cases(const char *root, cf_colmap_model *model) {
  printf("folder cases:\n");
  char dir[PATH_SIZE];
  path_in(dir, root, "model");
  CHECK(mkdir(dir, 0700) == 0, "mkdir %s", dir);
  cf_colmap_model got = {0};
  cf_error err = {0};

  expect("missing folder", cf_colmap_read("/nonexistent/clayfit/sparse", 1, &got, &err),
         CF_ENOTFOUND, &err, "/nonexistent/clayfit/sparse: no such folder", NULL);
  expect("empty folder", cf_colmap_read(dir, 1, &got, &err), CF_ENOTFOUND, &err, dir,
         "no COLMAP sparse model", "cameras.bin", "points3D.txt", NULL);

  CHECK(cf_colmap_write_text(dir, model, &err) == CF_OK, "%s", err.message);
  remove_in(dir, "points3D.txt");
  expect("missing points3D.txt", cf_colmap_read(dir, 1, &got, &err), CF_ENOTFOUND, &err,
         "points3D.txt: no such file", NULL);
  CHECK(got.num_cameras == 0 && got.cameras == NULL, "a failed read leaves an empty model");
  CHECK(cf_colmap_read(dir, 0, &got, &err) == CF_OK && got.num_images == 2,
        "poses only, without points3D.txt: %s", err.message);
  cf_colmap_model_free(&got);

  /* an image whose camera does not exist */
  clear_dir(dir);
  model->images[1].camera_id = 99;
  CHECK(cf_colmap_write_binary(dir, model, &err) == CF_OK, "%s", err.message);
  expect("image without its camera", cf_colmap_read(dir, 1, &got, &err), CF_EPARSE, &err,
         "images.bin: image 4 (b.jpg): camera_id 99 names no camera", "cameras.bin", NULL);
  model->images[1].camera_id = 2;

  /* a zero quaternion; one far from unit length is normalised */
  clear_dir(dir);
  model->images[0].qvec[0] = 0;
  CHECK(cf_colmap_write_text(dir, model, &err) == CF_OK, "%s", err.message);
  expect("zero quaternion", cf_colmap_read(dir, 1, &got, &err), CF_EPARSE, &err,
         "images.txt: image 3 (a.jpg): quaternion (0, 0, 0, 0) has zero length", NULL);
  model->images[0].qvec[0] = 2;
  model->images[0].qvec[3] = 2;
  CHECK(cf_colmap_write_text(dir, model, &err) == CF_OK, "%s", err.message);
  CHECK(cf_colmap_read(dir, 1, &got, &err) == CF_OK, "%s", err.message);
  const cf_colmap_image *a = cf_colmap_find_image_by_name(&got, "a.jpg");
  CHECK(a && fabs(a->qvec[0] - sqrt(0.5)) < 2e-16 && fabs(a->qvec[3] - sqrt(0.5)) < 2e-16,
        "quaternion (2, 0, 0, 2) normalised");
  cf_colmap_model_free(&got);
  model->images[0].qvec[0] = 1;
  model->images[0].qvec[3] = 0;

  /* a camera that fails cf_camera_check, duplicate names */
  clear_dir(dir);
  model->cameras[1].params[1] = 0;
  CHECK(cf_colmap_write_text(dir, model, &err) == CF_OK, "%s", err.message);
  expect("zero focal length", cf_colmap_read(dir, 1, &got, &err), CF_ERANGE, &err, "cameras.txt",
         "camera 2 (PINHOLE): focal length fy is 0", NULL);
  model->cameras[1].params[1] = 700;
  model->images[1].name[0] = 'a';
  CHECK(cf_colmap_write_binary(dir, model, &err) == CF_OK, "%s", err.message);
  expect("two images of one name", cf_colmap_read(dir, 1, &got, &err), CF_EPARSE, &err,
         "images.bin: images 3 and 4 have the same name 'a.jpg'", NULL);
  model->images[1].name[0] = 'b';

  /* a text file with a wrong field, through the folder reader */
  clear_dir(dir);
  CHECK(cf_colmap_write_text(dir, model, &err) == CF_OK, "%s", err.message);
  save_text(dir, "points3D.txt", "# p\n100 1 2 3 10 20 30 0.5 3 0 4 0\n102 1 2 3 red 20 30 0.5\n");
  expect("wrong field in points3D.txt", cf_colmap_read(dir, 1, &got, &err), CF_EPARSE, &err,
         "points3D.txt:3: point 102: field R: 'red' is not a whole number", NULL);
  /* the writer refuses what the text format cannot hold */
  char *name = model->images[0].name, broken[] = "two\nlines";
  model->images[0].name = broken;
  expect("name with a line break", cf_colmap_write_text(dir, model, &err), CF_EINVAL, &err,
         "image 3", "cannot be written", NULL);
  model->images[0].name = name;
  clear_dir(dir);
  rmdir(dir);
}

int main(void) {
  const char *tmp = getenv("TMPDIR");
  char root[4096];
  snprintf(root, sizeof root, "%s/clayfit_colmap_bad_XXXXXX", tmp && *tmp ? tmp : "/tmp");
  if (!mkdtemp(root)) {
    printf("cannot create a temporary folder\n");
    return 1;
  }
  cf_colmap_model model = {0};
  build_model(&model);
  cf_error err = {0};
  CHECK(cf_colmap_write_binary(root, &model, &err) == CF_OK, "%s", err.message);
  CHECK(cf_colmap_write_text(root, &model, &err) == CF_OK, "%s", err.message);
  bytes binary[3], text[3];
  for (int k = 0; k < 3; ++k) {
    binary[k] = load(root, binary_names[k]);
    text[k] = load(root, text_names[k]);
  }
  CHECK(binary[CAMERAS].size == 152 && binary[IMAGES].size == 8 + 2 * 150 &&
            binary[POINTS].size == 8 + 2 * 67,
        "layout sizes %zu %zu %zu", binary[CAMERAS].size, binary[IMAGES].size, binary[POINTS].size);

  cf_colmap_model big = {0};
  char big_dir[PATH_SIZE];
  path_in(big_dir, root, "truncation");
  CHECK(mkdir(big_dir, 0700) == 0, "mkdir %s", big_dir);
  build_truncation_model(&big);
  CHECK(cf_colmap_write_binary(big_dir, &big, &err) == CF_OK, "%s", err.message);
  bytes big_files[3];
  for (int k = 0; k < 3; ++k) big_files[k] = load(big_dir, binary_names[k]);
  truncations(big_files);
  for (int k = 0; k < 3; ++k) free(big_files[k].data);
  cf_colmap_model_free(&big);
  clear_dir(big_dir);
  rmdir(big_dir);
  text_truncations(text);
  cf_rng rng = cf_rng_seed(99);
  corruptions(binary, &rng);
  binary_cases(binary);
  text_cases();
  folder_cases(root, &model);

  for (int k = 0; k < 3; ++k) {
    free(binary[k].data);
    free(text[k].data);
  }
  cf_colmap_model_free(&model);
  clear_dir(root);
  rmdir(root);
  return check_finish("test_colmap_bad_input");
}
