/* COLMAP sparse models written and read back: a model built in memory
 * (cameras of several models, images with keypoints with and without 3D
 * points, points with tracks, full-precision doubles) survives our text and
 * binary writers and readers bit for bit. Then the independent check: the
 * real COLMAP (`colmap model_converter`) reads what we wrote and writes it
 * in both formats, and what it wrote reads back equal to the original; its
 * text files hold the same lines as ours. Exit status 77 (skipped) when
 * `colmap` is not on PATH and everything else passed. */
#include <math.h>
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

/* ---- the model ---- */

static int same_bits(double a, double b) {
  return memcmp(&a, &b, sizeof a) == 0;
}

/* A random unit quaternion whose squared length is exactly 1 whatever the
 * order of summation, so that COLMAP's normalisation leaves it bit for bit. */
static void exact_unit_quaternion(cf_rng *rng, double q[4]) {
  for (;;) {
    double n2 = 0;
    for (int k = 0; k < 4; ++k) {
      q[k] = cf_rng_range(rng, -1, 1);
      n2 += q[k] * q[k];
    }
    double n = sqrt(n2);
    for (int k = 0; k < 4; ++k) q[k] /= n;
    double a = q[0] * q[0], b = q[1] * q[1], c = q[2] * q[2], d = q[3] * q[3];
    if (((a + b) + c) + d == 1.0 && (a + c) + (b + d) == 1.0 && (a + b) + (c + d) == 1.0 &&
        ((d + c) + b) + a == 1.0 && (a + d) + (b + c) == 1.0)
      return;
  }
}

static char *copy_string(const char *s) {
  char *c = malloc(strlen(s) + 1);
  if (c) strcpy(c, s);
  return c;
}

/* Cameras of six models, images (one without keypoints), points with
 * tracks that match the images' keypoints, one point without a track. */
static void build_model(cf_colmap_model *m, cf_rng *rng) {
  static const cf_camera_model models[] = {CF_CAMERA_PINHOLE,
                                           CF_CAMERA_OPENCV,
                                           CF_CAMERA_SIMPLE_RADIAL,
                                           CF_CAMERA_FULL_OPENCV,
                                           CF_CAMERA_THIN_PRISM_FISHEYE,
                                           CF_CAMERA_FOV};
  static const uint32_t camera_ids[] = {3, 1, 17, 8, 4000000000u, 5};
  m->num_cameras = 6;
  m->cameras = calloc(m->num_cameras, sizeof *m->cameras);
  for (size_t i = 0; i < m->num_cameras; ++i) {
    cf_camera *c = &m->cameras[i];
    c->camera_id = camera_ids[i];
    c->model = models[i];
    c->width = 1000 + 37 * i;
    c->height = 700 + 11 * i;
    c->num_params = cf_camera_model_param_count(c->model);
    int focal = c->model == CF_CAMERA_SIMPLE_RADIAL ? 1 : 2;
    for (int k = 0; k < c->num_params; ++k)
      c->params[k] = k < focal       ? cf_rng_range(rng, 800, 1500)
                     : k < focal + 2 ? cf_rng_range(rng, 300, 600)
                                     : cf_rng_range(rng, -0.05, 0.05);
  }

  static const char *const names[] = {"IMG_0010.JPG", "sub/dir/b.png", "\xc3\xbcnicode.jpg",
                                      "empty.jpg", "last.tif"};
  static const uint32_t image_ids[] = {10, 2, 7, 99, 4294967294u};
  m->num_points3d = 30;
  m->points3d = calloc(m->num_points3d, sizeof *m->points3d);
  for (size_t p = 0; p < m->num_points3d; ++p) {
    cf_point3d *pt = &m->points3d[p];
    pt->point3d_id = p == 0 ? (uint64_t)INT64_MAX - 1 : (uint64_t)(p * 7919 + 1);
    for (int k = 0; k < 3; ++k) pt->xyz[k] = cf_rng_range(rng, -50, 50);
    for (int k = 0; k < 3; ++k) pt->rgb[k] = (uint8_t)(cf_rng_next(rng) >> 56);
    pt->error = p == 1 ? -1.0 : cf_rng_range(rng, 0, 2);
    pt->track = calloc(64, sizeof *pt->track);
  }
  m->points3d[2].xyz[0] = -0.0;
  m->points3d[2].xyz[1] = 1e300;
  m->points3d[2].xyz[2] = 1e-300;

  m->num_images = 5;
  m->images = calloc(m->num_images, sizeof *m->images);
  for (size_t i = 0; i < m->num_images; ++i) {
    cf_colmap_image *im = &m->images[i];
    im->image_id = image_ids[i];
    if (i == 0) {
      im->qvec[0] = 1; /* the identity and a dyadic one, exact */
    } else if (i == 1) {
      memcpy(im->qvec, (double[4]){0.5, -0.5, 0.5, -0.5}, sizeof im->qvec);
    } else {
      exact_unit_quaternion(rng, im->qvec);
    }
    for (int k = 0; k < 3; ++k) im->tvec[k] = cf_rng_range(rng, -10, 10);
    im->camera_id = camera_ids[i % m->num_cameras];
    im->name = copy_string(names[i]);
    im->num_points2d = i == 3 ? 0 : 20 + 5 * i;
    im->points2d = calloc(im->num_points2d + 1, sizeof *im->points2d);
    for (size_t j = 0; j < im->num_points2d; ++j) {
      cf_point2d *pt = &im->points2d[j];
      pt->x = cf_rng_range(rng, 0, 1000);
      pt->y = cf_rng_range(rng, 0, 700);
      size_t p = (size_t)(cf_rng_next(rng) % 40); /* about a quarter without a point */
      if (p >= m->num_points3d - 1) {             /* the last point keeps an empty track */
        pt->point3d_id = -1;
        continue;
      }
      cf_point3d *owner = &m->points3d[p];
      pt->point3d_id = (int64_t)owner->point3d_id;
      owner->track[owner->track_length++] = (cf_track_element){im->image_id, (uint32_t)j};
    }
  }
  m->images[2].tvec[1] = -0.0;
}

/* ---- comparison ---- */

static const cf_colmap_image *image_by_id(const cf_colmap_model *m, uint32_t id) {
  for (size_t i = 0; i < m->num_images; ++i)
    if (m->images[i].image_id == id) return &m->images[i];
  return NULL;
}

static const cf_point3d *point_by_id(const cf_colmap_model *m, uint64_t id) {
  for (size_t i = 0; i < m->num_points3d; ++i)
    if (m->points3d[i].point3d_id == id) return &m->points3d[i];
  return NULL;
}

/* Every record of `want` in `got`, bit for bit; in the same order unless
 * by_id (COLMAP keeps records in hash maps and writes them in its order). */
static long compare_models(const char *what, const cf_colmap_model *want,
                           const cf_colmap_model *got, int by_id, int with_points) {
  long before = check_global.failures;
  CHECK(got->num_cameras == want->num_cameras && got->num_images == want->num_images &&
            got->num_points3d == (with_points ? want->num_points3d : 0),
        "%s: %zu cameras, %zu images, %zu points", what, got->num_cameras, got->num_images,
        got->num_points3d);
  if (check_global.failures != before) return check_global.failures - before;
  for (size_t i = 0; i < want->num_cameras; ++i) {
    const cf_camera *a = &want->cameras[i];
    const cf_camera *b = by_id ? cf_colmap_find_camera(got, a->camera_id) : &got->cameras[i];
    CHECK(b && b->camera_id == a->camera_id && b->model == a->model && b->width == a->width &&
              b->height == a->height && b->num_params == a->num_params,
          "%s: camera %u", what, a->camera_id);
    if (!b) continue;
    for (int k = 0; k < a->num_params; ++k)
      CHECK(same_bits(a->params[k], b->params[k]), "%s: camera %u param %d: %.17g != %.17g", what,
            a->camera_id, k, a->params[k], b->params[k]);
  }
  for (size_t i = 0; i < want->num_images; ++i) {
    const cf_colmap_image *a = &want->images[i];
    const cf_colmap_image *b = by_id ? image_by_id(got, a->image_id) : &got->images[i];
    CHECK(b && b->image_id == a->image_id && b->camera_id == a->camera_id &&
              strcmp(a->name, b->name) == 0 && b->num_points2d == a->num_points2d,
          "%s: image %u", what, a->image_id);
    if (!b || b->num_points2d != a->num_points2d) continue;
    for (int k = 0; k < 4; ++k)
      CHECK(same_bits(a->qvec[k], b->qvec[k]), "%s: image %u q[%d] %.17g != %.17g", what,
            a->image_id, k, a->qvec[k], b->qvec[k]);
    for (int k = 0; k < 3; ++k)
      CHECK(same_bits(a->tvec[k], b->tvec[k]), "%s: image %u t[%d] %.17g != %.17g", what,
            a->image_id, k, a->tvec[k], b->tvec[k]);
    for (size_t j = 0; j < a->num_points2d; ++j) {
      const cf_point2d *p = &a->points2d[j], *q = &b->points2d[j];
      CHECK(same_bits(p->x, q->x) && same_bits(p->y, q->y) && p->point3d_id == q->point3d_id,
            "%s: image %u point %zu", what, a->image_id, j);
    }
  }
  for (size_t i = 0; with_points && i < want->num_points3d; ++i) {
    const cf_point3d *a = &want->points3d[i];
    const cf_point3d *b = by_id ? point_by_id(got, a->point3d_id) : &got->points3d[i];
    CHECK(b && b->point3d_id == a->point3d_id && b->track_length == a->track_length &&
              memcmp(a->rgb, b->rgb, 3) == 0 && same_bits(a->error, b->error),
          "%s: point %llu", what, (unsigned long long)a->point3d_id);
    if (!b || b->track_length != a->track_length) continue;
    for (int k = 0; k < 3; ++k)
      CHECK(same_bits(a->xyz[k], b->xyz[k]), "%s: point %llu xyz[%d]", what,
            (unsigned long long)a->point3d_id, k);
    for (size_t j = 0; j < a->track_length; ++j)
      CHECK(a->track[j].image_id == b->track[j].image_id &&
                a->track[j].point2d_idx == b->track[j].point2d_idx,
            "%s: point %llu track %zu", what, (unsigned long long)a->point3d_id, j);
  }
  return check_global.failures - before;
}

/* ---- files ---- */

enum { PATH_SIZE = 8192 };

static void join(char *out, size_t size, const char *dir, const char *name) {
  int n = snprintf(out, size, "%s/%s", dir, name);
  CHECK(n > 0 && (size_t)n < size, "path too long: %s/%s", dir, name);
}

static const char *const model_files[] = {"cameras.txt", "images.txt", "points3D.txt",
                                          "cameras.bin", "images.bin", "points3D.bin",
                                          "log"};

static void remove_model_dir(const char *dir) {
  char path[PATH_SIZE];
  for (size_t k = 0; k < sizeof model_files / sizeof model_files[0]; ++k) {
    join(path, sizeof path, dir, model_files[k]);
    remove(path);
  }
  rmdir(dir);
}

static long file_size(const char *dir, const char *name) {
  char path[PATH_SIZE];
  struct stat st;
  join(path, sizeof path, dir, name);
  return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

/* The binary files' sizes from the layouts in reconstruction.cc. */
static void check_binary_sizes(const char *dir, const cf_colmap_model *m) {
  long cameras = 8, images = 8, points = 8;
  for (size_t i = 0; i < m->num_cameras; ++i)
    cameras += 4 + 4 + 8 + 8 + 8 * m->cameras[i].num_params;
  for (size_t i = 0; i < m->num_images; ++i)
    images += 4 + 7 * 8 + 4 + (long)strlen(m->images[i].name) + 1 + 8 +
              24 * (long)m->images[i].num_points2d;
  for (size_t i = 0; i < m->num_points3d; ++i)
    points += 8 + 24 + 3 + 8 + 8 + 8 * (long)m->points3d[i].track_length;
  CHECK(file_size(dir, "cameras.bin") == cameras, "cameras.bin: %ld bytes, layout says %ld",
        file_size(dir, "cameras.bin"), cameras);
  CHECK(file_size(dir, "images.bin") == images, "images.bin: %ld bytes, layout says %ld",
        file_size(dir, "images.bin"), images);
  CHECK(file_size(dir, "points3D.bin") == points, "points3D.bin: %ld bytes, layout says %ld",
        file_size(dir, "points3D.bin"), points);
}

/* The parse cores on the files' bytes, without cf_colmap_read. */
static void parse_directly(const char *dir, int binary, const cf_colmap_model *want) {
  static const char *const text_names[3] = {"cameras.txt", "images.txt", "points3D.txt"};
  static const char *const binary_names[3] = {"cameras.bin", "images.bin", "points3D.bin"};
  cf_colmap_model got = {0};
  cf_error err = {0};
  for (int f = 0; f < 3; ++f) {
    char path[PATH_SIZE], *data;
    size_t size;
    join(path, sizeof path, dir, binary ? binary_names[f] : text_names[f]);
    if (cf_read_file(path, 1 << 24, &data, &size, &err) != CF_OK) {
      CHECK(0, "%s", err.message);
      continue;
    }
    cf_status s;
    const uint8_t *bytes = (const uint8_t *)data;
    if (f == 0)
      s = binary ? cf_colmap_parse_cameras_binary(bytes, size, path, &got, &err)
                 : cf_colmap_parse_cameras_text(data, size, path, &got, &err);
    else if (f == 1)
      s = binary ? cf_colmap_parse_images_binary(bytes, size, path, &got, &err)
                 : cf_colmap_parse_images_text(data, size, path, &got, &err);
    else
      s = binary ? cf_colmap_parse_points3d_binary(bytes, size, path, &got, &err)
                 : cf_colmap_parse_points3d_text(data, size, path, &got, &err);
    CHECK(s == CF_OK, "%s", err.message);
    free(data);
  }
  compare_models(binary ? "parse cores, binary" : "parse cores, text", want, &got, 0, 1);
  cf_colmap_model_free(&got);
}

static void read_and_compare(const char *what, const char *dir, const cf_colmap_model *want,
                             int by_id) {
  cf_colmap_model got = {0};
  cf_error err = {0};
  cf_status s = cf_colmap_read(dir, 1, &got, &err);
  CHECK(s == CF_OK, "%s: %s", what, err.message);
  if (s == CF_OK && compare_models(what, want, &got, by_id, 1) == 0)
    printf("%s: %zu cameras, %zu images, %zu points equal bit for bit\n", what, got.num_cameras,
           got.num_images, got.num_points3d);
  cf_colmap_model_free(&got);
}

/* ---- the lines of two text files, as multisets ---- */

static int compare_lines(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Split text into lines (in place), sorted. */
static char **sorted_lines(char *text, size_t *count) {
  size_t n = 0, capacity = 64;
  char **lines = malloc(capacity * sizeof *lines);
  for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
    if (n == capacity) lines = realloc(lines, (capacity *= 2) * sizeof *lines);
    lines[n++] = line;
  }
  qsort(lines, n, sizeof *lines, compare_lines);
  *count = n;
  return lines;
}

static void compare_text_files(const char *ours_dir, const char *colmap_dir, const char *name) {
  char a_path[PATH_SIZE], b_path[PATH_SIZE], *a, *b;
  size_t a_size, b_size, na, nb;
  join(a_path, sizeof a_path, ours_dir, name);
  join(b_path, sizeof b_path, colmap_dir, name);
  if (cf_read_file(a_path, 1 << 24, &a, &a_size, NULL) != CF_OK) {
    CHECK(0, "cannot read %s", a_path);
    return;
  }
  if (cf_read_file(b_path, 1 << 24, &b, &b_size, NULL) != CF_OK) {
    CHECK(0, "cannot read %s", b_path);
    free(a);
    return;
  }
  char **la = sorted_lines(a, &na), **lb = sorted_lines(b, &nb);
  size_t differ = na > nb ? na - nb : nb - na;
  for (size_t k = 0; k < na && k < nb; ++k) {
    if (strcmp(la[k], lb[k]) != 0 && ++differ <= 3)
      CHECK(0, "%s: ours '%s' vs COLMAP's '%s'", name, la[k], lb[k]);
  }
  CHECK(differ == 0, "%s: %zu lines differ (%zu vs %zu lines)", name, differ, na, nb);
  if (differ == 0) printf("%s: the same %zu lines as COLMAP's\n", name, na);
  free(la);
  free(lb);
  free(a);
  free(b);
}

/* ---- COLMAP ---- */

static int colmap_on_path(void) {
  const char *path = getenv("PATH");
  if (!path) return 0;
  char buf[4096];
  for (const char *p = path; *p;) {
    size_t len = strcspn(p, ":");
    snprintf(buf, sizeof buf, "%.*s/colmap", (int)len, p);
    if (len && access(buf, X_OK) == 0) return 1;
    p += len;
    if (*p == ':') ++p;
  }
  return 0;
}

static int run_model_converter(const char *in, const char *out, const char *type) {
  char command[4 * PATH_SIZE];
  snprintf(command, sizeof command,
           "colmap model_converter --input_path '%s' --output_path '%s' --output_type %s "
           "> '%s/log' 2>&1",
           in, out, type, out);
  int status = system(command);
  CHECK(status == 0, "'%s' failed with status %d (see %s/log)", command, status, out);
  return status == 0;
}

int main(void) {
  const char *tmp = getenv("TMPDIR");
  char root[4096];
  snprintf(root, sizeof root, "%s/clayfit_colmap_io_XXXXXX", tmp && *tmp ? tmp : "/tmp");
  if (!mkdtemp(root)) {
    printf("cannot create a temporary folder under %s\n", tmp && *tmp ? tmp : "/tmp");
    return 1;
  }
  static const char *const subdirs[] = {"txt",
                                        "bin",
                                        "colmap_txt_to_bin",
                                        "colmap_txt_to_txt",
                                        "colmap_bin_to_txt",
                                        "colmap_bin_to_bin"};
  enum { TXT, BIN, TXT_TO_BIN, TXT_TO_TXT, BIN_TO_TXT, BIN_TO_BIN, SUBDIRS };
  char dirs[SUBDIRS][4096 + 32];
  for (int d = 0; d < SUBDIRS; ++d) {
    snprintf(dirs[d], sizeof dirs[d], "%s/%s", root, subdirs[d]);
    CHECK(mkdir(dirs[d], 0700) == 0, "mkdir %s", dirs[d]);
  }

  cf_rng rng = cf_rng_seed(38);
  cf_colmap_model model = {0};
  build_model(&model, &rng);
  cf_error err = {0};

  /* ours → ours */
  CHECK(cf_colmap_write_text(dirs[TXT], &model, &err) == CF_OK, "%s", err.message);
  CHECK(cf_colmap_write_binary(dirs[BIN], &model, &err) == CF_OK, "%s", err.message);
  check_binary_sizes(dirs[BIN], &model);
  read_and_compare("our text, read back", dirs[TXT], &model, 0);
  read_and_compare("our binary, read back", dirs[BIN], &model, 0);
  parse_directly(dirs[TXT], 0, &model);
  parse_directly(dirs[BIN], 1, &model);

  /* without points; look-ups */
  cf_colmap_model poses = {0};
  CHECK(cf_colmap_read(dirs[BIN], 0, &poses, &err) == CF_OK, "%s", err.message);
  compare_models("binary without points", &model, &poses, 0, 0);
  const cf_camera *camera = cf_colmap_find_camera(&poses, 4000000000u);
  CHECK(camera && camera->model == CF_CAMERA_THIN_PRISM_FISHEYE, "find camera 4000000000");
  CHECK(cf_colmap_find_camera(&poses, 2) == NULL, "camera 2 is not there");
  const cf_colmap_image *image = cf_colmap_find_image_by_name(&poses, "sub/dir/b.png");
  CHECK(image && image->image_id == 2, "find sub/dir/b.png");
  CHECK(cf_colmap_find_image_by_name(&poses, "b.png") == NULL, "b.png is not there");
  cf_colmap_model_free(&poses);
  CHECK(poses.images == NULL && poses.num_images == 0, "free leaves an empty model");

  /* text and binary chosen by what is in the folder: both, binary wins */
  CHECK(cf_colmap_write_binary(dirs[TXT], &model, &err) == CF_OK, "%s", err.message);
  char path[PATH_SIZE];
  join(path, sizeof path, dirs[TXT], "images.txt");
  FILE *f = fopen(path, "a");
  if (f) {
    fputs("garbage that the binary reader never sees\n", f);
    fclose(f);
  }
  read_and_compare("folder with both formats", dirs[TXT], &model, 0);
  CHECK(cf_colmap_write_text(dirs[TXT], &model, &err) == CF_OK, "%s", err.message);
  for (int k = 3; k < 6; ++k) {
    join(path, sizeof path, dirs[TXT], model_files[k]);
    remove(path);
  }

  long own_failures = check_global.failures;
  int status;
  if (!colmap_on_path()) {
    printf("skipped the COLMAP half: `colmap` (COLMAP 3.8) is not on PATH\n");
    status = own_failures ? check_finish("test_colmap_io") : CHECK_SKIPPED;
  } else {
    /* ours → COLMAP → ours, in both directions and formats */
    if (run_model_converter(dirs[TXT], dirs[TXT_TO_BIN], "BIN"))
      read_and_compare("our text → COLMAP binary", dirs[TXT_TO_BIN], &model, 1);
    if (run_model_converter(dirs[BIN], dirs[BIN_TO_TXT], "TXT"))
      read_and_compare("our binary → COLMAP text", dirs[BIN_TO_TXT], &model, 1);
    if (run_model_converter(dirs[TXT], dirs[TXT_TO_TXT], "TXT")) {
      read_and_compare("our text → COLMAP text", dirs[TXT_TO_TXT], &model, 1);
      for (int k = 0; k < 3; ++k) compare_text_files(dirs[TXT], dirs[TXT_TO_TXT], model_files[k]);
    }
    if (run_model_converter(dirs[BIN], dirs[BIN_TO_BIN], "BIN"))
      read_and_compare("our binary → COLMAP binary", dirs[BIN_TO_BIN], &model, 1);
    status = check_finish("test_colmap_io");
  }

  cf_colmap_model_free(&model);
  if (status != 1) { /* keep the files of a failure for a look */
    for (int d = 0; d < SUBDIRS; ++d) remove_model_dir(dirs[d]);
    rmdir(root);
  } else {
    printf("files kept in %s\n", root);
  }
  return status;
}
