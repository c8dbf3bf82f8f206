/* Writes the seed corpus of fuzz_colmap_binary (scripts/fuzz.sh): small
 * valid models in both formats, written by clayfit's own writers, into
 * <dir>/<model>/{cameras,images,points3D}.{bin,txt}.
 *   make_seeds DIR */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "clayfit/colmap.h"

static char *copy_string(const char *s) {
  char *c = malloc(strlen(s) + 1);
  if (c) strcpy(c, s);
  return c;
}

/* Cameras of every model; `images` images with `points` keypoints each,
 * every other one on a 3D point with a two-element track. */
static void build(cf_colmap_model *m, int cameras, int images, int points) {
  memset(m, 0, sizeof *m);
  m->num_cameras = (size_t)cameras;
  m->cameras = calloc((size_t)cameras + 1, sizeof *m->cameras);
  for (int i = 0; i < cameras; ++i) {
    cf_camera *c = &m->cameras[i];
    c->camera_id = (uint32_t)(i + 1);
    c->model = (cf_camera_model)(i % CF_CAMERA_MODEL_COUNT);
    c->width = 64;
    c->height = 48;
    c->num_params = cf_camera_model_param_count(c->model);
    int single = c->num_params == 3 || c->model == CF_CAMERA_SIMPLE_RADIAL ||
                 c->model == CF_CAMERA_RADIAL || c->model == CF_CAMERA_SIMPLE_RADIAL_FISHEYE ||
                 c->model == CF_CAMERA_RADIAL_FISHEYE;
    int focal = single ? 1 : 2;
    for (int k = 0; k < c->num_params; ++k)
      c->params[k] = k < focal ? 50.0 : k == focal ? 32.0 : k == focal + 1 ? 24.0 : 0.01 * k;
  }
  m->num_images = (size_t)images;
  m->images = calloc((size_t)images + 1, sizeof *m->images);
  m->num_points3d = (size_t)(images * points / 2);
  m->points3d = calloc(m->num_points3d + 1, sizeof *m->points3d);
  size_t next = 0;
  for (int i = 0; i < images; ++i) {
    cf_colmap_image *im = &m->images[i];
    char name[32];
    snprintf(name, sizeof name, "img_%d.jpg", i);
    im->image_id = (uint32_t)(i + 1);
    im->qvec[0] = 1;
    im->tvec[2] = 1.5;
    im->camera_id = (uint32_t)(i % cameras + 1);
    im->name = copy_string(name);
    im->num_points2d = (size_t)points;
    im->points2d = calloc((size_t)points + 1, sizeof *im->points2d);
    for (int j = 0; j < points; ++j) {
      im->points2d[j] = (cf_point2d){j + 0.5, 2.25, -1};
      if (j % 2 == 1 && next < m->num_points3d) {
        cf_point3d *p = &m->points3d[next];
        p->point3d_id = next + 1;
        p->xyz[0] = 0.125 * (double)next;
        p->rgb[0] = 200;
        p->error = 0.5;
        p->track_length = 2;
        p->track = calloc(2, sizeof *p->track);
        p->track[0] = (cf_track_element){im->image_id, (uint32_t)j};
        p->track[1] = (cf_track_element){im->image_id, (uint32_t)j};
        im->points2d[j].point3d_id = (int64_t)p->point3d_id;
        ++next;
      }
    }
  }
  m->num_points3d = next;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: make_seeds DIR\n");
    return 2;
  }
  static const int shapes[][3] = {{1, 1, 2}, {CF_CAMERA_MODEL_COUNT, 3, 4}, {2, 2, 0}, {0, 0, 0}};
  for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; ++s) {
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/model%zu", argv[1], s);
    if (mkdir(dir, 0777) != 0) {
      perror(dir);
      return 1;
    }
    cf_colmap_model m;
    build(&m, shapes[s][0], shapes[s][1], shapes[s][2]);
    cf_error err = {0};
    if (cf_colmap_write_binary(dir, &m, &err) != CF_OK ||
        cf_colmap_write_text(dir, &m, &err) != CF_OK) {
      fprintf(stderr, "make_seeds: %s\n", err.message);
      return 1;
    }
    cf_colmap_model_free(&m);
  }
  return 0;
}
