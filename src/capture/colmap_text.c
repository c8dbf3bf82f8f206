/* COLMAP 3.8's text model files (cameras.txt, images.txt, points3D.txt)
 * parsed from memory, after Reconstruction::Read*Text in
 * src/base/reconstruction.cc:
 *
 *   cameras.txt   CAMERA_ID MODEL WIDTH HEIGHT PARAMS...
 *   images.txt    IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME
 *                 X Y POINT3D_ID X Y POINT3D_ID ...   (the next line, maybe
 *                                                     empty; POINT3D_ID −1 = none)
 *   points3D.txt  POINT3D_ID X Y Z R G B ERROR IMAGE_ID POINT2D_IDX ...
 *
 * Lines are trimmed; empty lines and lines starting with '#' between
 * records are skipped (as COLMAP does; the line after an image's line is
 * always its points, and a file that ends right after an image's line
 * gives that image no points). Fields are separated by blanks. NAME is the rest of
 * the line (COLMAP reads up to the first blank, so names without blanks
 * read the same). Every field is checked as it is read and an error names
 * the file, the line, the record and the field. Numbers are read with
 * strtod, which follows the C locale that a program has unless it calls
 * setlocale. The records are parsed into arrays of their own and appended
 * to the model only when the whole file is good. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "colmap_internal.h"
#include "clayfit/colmap.h"

typedef struct span {
  const char *begin;
  size_t length;
} span;

typedef struct text_reader {
  const char *text;
  size_t size, pos;
  size_t line;        /* the number of the line last read, from 1 */
  const char *name;   /* the file, for messages */
  const char *layout; /* what a record line holds, for messages */
  char record[64];    /* "image 3", or "image record 2" before the id is known */
  cf_error *err;
} text_reader;

static int is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* The next physical line, without its '\n', trimmed. 0 at the end. */
static int next_line(text_reader *t, span *line) {
  if (t->pos >= t->size) return 0;
  const char *start = t->text + t->pos;
  size_t rest = t->size - t->pos;
  const char *newline = memchr(start, '\n', rest);
  size_t length = newline ? (size_t)(newline - start) : rest;
  t->pos += newline ? length + 1 : length;
  t->line += 1;
  while (length && is_blank(*start)) {
    ++start;
    --length;
  }
  while (length && is_blank(start[length - 1])) --length;
  *line = (span){start, length};
  return 1;
}

/* The next line that holds a record: not empty and not a '#' comment. */
static int next_record_line(text_reader *t, span *line) {
  while (next_line(t, line))
    if (line->length && line->begin[0] != '#') return 1;
  return 0;
}

/* Splits a line into blank-separated tokens. */
typedef struct tokens {
  const char *p, *end;
} tokens;

static tokens tokens_of(span line) {
  return (tokens){line.begin, line.begin + line.length};
}

static int next_token(tokens *ts, span *token) {
  while (ts->p < ts->end && is_blank(*ts->p)) ++ts->p;
  if (ts->p == ts->end) return 0;
  const char *begin = ts->p;
  while (ts->p < ts->end && !is_blank(*ts->p)) ++ts->p;
  *token = (span){begin, (size_t)(ts->p - begin)};
  return 1;
}

static size_t count_tokens(tokens ts) {
  size_t n = 0;
  span token;
  while (next_token(&ts, &token)) ++n;
  return n;
}

/* ---- numbers ---- */

/* NULL if the token is a finite number (stored), else what is wrong. */
static const char *finite_number(span token, double *value) {
  char buf[128];
  if (token.length >= sizeof buf) return "is not a number";
  memcpy(buf, token.begin, token.length);
  buf[token.length] = '\0';
  char *end;
  double v = strtod(buf, &end);
  if (token.length == 0 || end != buf + token.length) return "is not a number";
  if (!isfinite(v)) return "is not a finite number";
  *value = v;
  return NULL;
}

static const char not_whole[] = "is not a whole number";

/* NULL if the token is a whole number in [0, max] (stored), else what is
 * wrong (not_whole, or a range written into why). */
static const char *whole_number(span token, uint64_t max, uint64_t *value, char *why, size_t size) {
  uint64_t v = 0;
  int too_large = 0;
  if (token.length == 0) return not_whole;
  for (size_t i = 0; i < token.length; ++i) {
    char c = token.begin[i];
    if (c < '0' || c > '9') return not_whole;
    unsigned digit = (unsigned)(c - '0');
    if (v > (UINT64_MAX - digit) / 10)
      too_large = 1;
    else
      v = v * 10 + digit;
  }
  if (too_large || v > max) {
    snprintf(why, size, "is out of range [0, %llu]", (unsigned long long)max);
    return why;
  }
  *value = v;
  return NULL;
}

/* ---- messages ---- */

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static cf_status
record_error(text_reader *t, cf_status status, const char *format, ...);

static cf_status record_error(text_reader *t, cf_status status, const char *format, ...) {
  char what[768];
  va_list args;
  va_start(args, format);
  vsnprintf(what, sizeof what, format, args);
  va_end(args);
  return cf_error_set(t->err, status, "%s:%zu: %s: %s", t->name, t->line, t->record, what);
}

/* "field QW: 'abc' is not a number" (long tokens shortened). */
static cf_status bad_token(text_reader *t, const char *field, span token, const char *what) {
  char shown[44];
  size_t n = token.length > 40 ? 40 : token.length;
  for (size_t i = 0; i < n; ++i) /* control bytes (a NUL, say) as '?' */
    shown[i] =
        (unsigned char)token.begin[i] < 0x20 || token.begin[i] == 0x7f ? '?' : token.begin[i];
  memcpy(shown + n, token.length > 40 ? "..." : "", token.length > 40 ? 4 : 1);
  return record_error(t, CF_EPARSE, "field %s: '%s' %s", field, shown, what);
}

static cf_status missing(text_reader *t, const char *field) {
  return record_error(t, CF_EPARSE, "field %s is missing; a line reads %s", field, t->layout);
}

static cf_status out_of_memory(text_reader *t) {
  return cf_error_set(t->err, CF_ENOMEM, "%s:%zu: out of memory", t->name, t->line);
}

/* The next token as a finite number / a whole number in [0, max]. */
static cf_status read_finite(text_reader *t, tokens *ts, const char *field, double *value) {
  span token;
  if (!next_token(ts, &token)) return missing(t, field);
  const char *why = finite_number(token, value);
  return why ? bad_token(t, field, token, why) : CF_OK;
}

static cf_status read_whole(text_reader *t, tokens *ts, const char *field, uint64_t max,
                            uint64_t *value) {
  span token;
  if (!next_token(ts, &token)) return missing(t, field);
  char buf[64];
  const char *why = whole_number(token, max, value, buf, sizeof buf);
  return why ? bad_token(t, field, token, why) : CF_OK;
}

/* An id used twice, in this file or already in the model. */
static cf_status check_duplicates(text_reader *t, const uint64_t *ids, size_t existing,
                                  size_t total, const size_t *lines, const char *kind,
                                  const char *id_field) {
  size_t first, second;
  int found = cf__find_duplicate_id(ids, existing, total, &first, &second);
  if (found < 0) return out_of_memory(t);
  if (!found) return CF_OK;
  t->line = lines[second - existing];
  snprintf(t->record, sizeof t->record, "%s %llu", kind, (unsigned long long)ids[second]);
  if (first < existing)
    return record_error(t, CF_EPARSE, "%s %llu is already in the model", id_field,
                        (unsigned long long)ids[second]);
  return record_error(t, CF_EPARSE, "%s %llu is used twice (first on line %zu)", id_field,
                      (unsigned long long)ids[second], lines[first - existing]);
}

/* ---- cameras.txt ---- */

static cf_status read_camera_line(text_reader *t, span line, size_t index, cf_camera *camera) {
  tokens ts = tokens_of(line);
  snprintf(t->record, sizeof t->record, "camera record %zu", index + 1);
  uint64_t id;
  cf_status s = read_whole(t, &ts, "CAMERA_ID", UINT32_MAX, &id);
  if (s != CF_OK) return s;
  camera->camera_id = (uint32_t)id;
  snprintf(t->record, sizeof t->record, "camera %u", camera->camera_id);

  span token;
  if (!next_token(&ts, &token)) return missing(t, "MODEL");
  char model_name[64];
  snprintf(model_name, sizeof model_name, "%.*s", token.length < 63 ? (int)token.length : 63,
           token.begin);
  if (token.length >= 63 || cf_camera_model_find(model_name, &camera->model, NULL) != CF_OK) {
    char known[512], what[600];
    snprintf(what, sizeof what, "is not a camera model; the known models are %s",
             cf__camera_model_list(0, known, sizeof known));
    return bad_token(t, "MODEL", token, what);
  }
  if ((s = read_whole(t, &ts, "WIDTH", UINT64_MAX, &camera->width)) != CF_OK) return s;
  if ((s = read_whole(t, &ts, "HEIGHT", UINT64_MAX, &camera->height)) != CF_OK) return s;

  camera->num_params = cf_camera_model_param_count(camera->model);
  size_t given = count_tokens(ts);
  if (given != (size_t)camera->num_params)
    return record_error(t, CF_EPARSE,
                        "field PARAMS: model %s takes %d parameters (%s) but the line has %zu",
                        cf_camera_model_name(camera->model), camera->num_params,
                        cf_camera_model_param_names(camera->model), given);
  for (int k = 0; k < camera->num_params; ++k) {
    char name[32];
    cf__camera_param_name(camera->model, k, name, sizeof name);
    if ((s = read_finite(t, &ts, name, &camera->params[k])) != CF_OK) return s;
  }
  return CF_OK;
}

cf_status cf_colmap_parse_cameras_text(const char *text, size_t size, const char *name,
                                       cf_colmap_model *model, cf_error *err) {
  text_reader t = {.text = text,
                   .size = size,
                   .name = name,
                   .err = err,
                   .layout = "CAMERA_ID MODEL WIDTH HEIGHT PARAMS..."};
  cf_camera *cameras = NULL;
  size_t *lines = NULL, count = 0, capacity = 0, line_capacity = 0;
  cf_status s = CF_OK;
  span line;
  while (s == CF_OK && next_record_line(&t, &line)) {
    if (cf__grow((void **)&cameras, &capacity, count + 1, sizeof *cameras) != CF_OK ||
        cf__grow((void **)&lines, &line_capacity, count + 1, sizeof *lines) != CF_OK) {
      s = out_of_memory(&t);
      break;
    }
    memset(&cameras[count], 0, sizeof cameras[count]);
    lines[count] = t.line;
    s = read_camera_line(&t, line, count, &cameras[count]);
    if (s == CF_OK) ++count;
  }
  uint64_t *ids = NULL;
  if (s == CF_OK) {
    ids = calloc(model->num_cameras + count + 1, sizeof *ids);
    if (!ids) s = out_of_memory(&t);
  }
  if (s == CF_OK) {
    for (size_t i = 0; i < model->num_cameras; ++i) ids[i] = model->cameras[i].camera_id;
    for (size_t i = 0; i < count; ++i) ids[model->num_cameras + i] = cameras[i].camera_id;
    s = check_duplicates(&t, ids, model->num_cameras, model->num_cameras + count, lines, "camera",
                         "CAMERA_ID");
  }
  if (s == CF_OK && cf__append((void **)&model->cameras, &model->num_cameras, cameras, count,
                               sizeof *cameras) != CF_OK)
    s = out_of_memory(&t);
  free(cameras);
  free(lines);
  free(ids);
  return s;
}

/* ---- images.txt ---- */

static cf_status read_image_line(text_reader *t, span line, size_t index, cf_colmap_image *image) {
  tokens ts = tokens_of(line);
  snprintf(t->record, sizeof t->record, "image record %zu", index + 1);
  uint64_t id;
  cf_status s = read_whole(t, &ts, "IMAGE_ID", UINT32_MAX, &id);
  if (s != CF_OK) return s;
  image->image_id = (uint32_t)id;
  snprintf(t->record, sizeof t->record, "image %u", image->image_id);
  static const char *const pose_fields[7] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
  for (int k = 0; k < 4; ++k)
    if ((s = read_finite(t, &ts, pose_fields[k], &image->qvec[k])) != CF_OK) return s;
  for (int k = 0; k < 3; ++k)
    if ((s = read_finite(t, &ts, pose_fields[4 + k], &image->tvec[k])) != CF_OK) return s;
  if ((s = read_whole(t, &ts, "CAMERA_ID", UINT32_MAX, &id)) != CF_OK) return s;
  image->camera_id = (uint32_t)id;

  /* NAME: the rest of the line (already trimmed at its end) */
  while (ts.p < ts.end && is_blank(*ts.p)) ++ts.p;
  size_t length = (size_t)(ts.end - ts.p);
  if (length == 0) return missing(t, "NAME");
  if (length > CF_COLMAP_MAX_NAME)
    return record_error(t, CF_EPARSE, "field NAME: %zu bytes long, more than the %d accepted",
                        length, CF_COLMAP_MAX_NAME);
  if (memchr(ts.p, '\0', length))
    return record_error(t, CF_EPARSE, "field NAME: contains a NUL byte");
  image->name = malloc(length + 1);
  if (!image->name) return out_of_memory(t);
  memcpy(image->name, ts.p, length);
  image->name[length] = '\0';
  return CF_OK;
}

/* The line after an image's line: X Y POINT3D_ID triples. */
static cf_status read_points2d_line(text_reader *t, span line, cf_colmap_image *image) {
  tokens ts = tokens_of(line);
  size_t n = count_tokens(ts);
  if (n % 3 != 0)
    return record_error(t, CF_EPARSE,
                        "field POINTS2D: %zu numbers, not a multiple of 3 (X Y POINT3D_ID)", n);
  image->num_points2d = n / 3;
  image->points2d = calloc(n ? n / 3 : 1, sizeof *image->points2d);
  if (!image->points2d) return out_of_memory(t);
  for (size_t j = 0; j < n / 3; ++j) {
    cf_point2d *point = &image->points2d[j];
    char field[48];
    span token = {NULL, 0};
    const char *why;
    next_token(&ts, &token);
    if ((why = finite_number(token, &point->x)) != NULL) {
      snprintf(field, sizeof field, "POINTS2D[%zu].X", j);
      return bad_token(t, field, token, why);
    }
    next_token(&ts, &token);
    if ((why = finite_number(token, &point->y)) != NULL) {
      snprintf(field, sizeof field, "POINTS2D[%zu].Y", j);
      return bad_token(t, field, token, why);
    }
    next_token(&ts, &token);
    uint64_t id;
    char buf[64];
    if (token.length == 2 && memcmp(token.begin, "-1", 2) == 0) {
      point->point3d_id = -1;
    } else if ((why = whole_number(token, INT64_MAX, &id, buf, sizeof buf)) != NULL) {
      snprintf(field, sizeof field, "POINTS2D[%zu].POINT3D_ID", j);
      return bad_token(t, field, token,
                       why == not_whole ? "is neither -1 nor a whole number" : why);
    } else {
      point->point3d_id = (int64_t)id;
    }
  }
  return CF_OK;
}

cf_status cf_colmap_parse_images_text(const char *text, size_t size, const char *name,
                                      cf_colmap_model *model, cf_error *err) {
  text_reader t = {.text = text,
                   .size = size,
                   .name = name,
                   .err = err,
                   .layout = "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME"};
  cf_colmap_image *images = NULL;
  size_t *lines = NULL, count = 0, capacity = 0, line_capacity = 0;
  cf_status s = CF_OK;
  span line;
  while (s == CF_OK && next_record_line(&t, &line)) {
    if (cf__grow((void **)&images, &capacity, count + 1, sizeof *images) != CF_OK ||
        cf__grow((void **)&lines, &line_capacity, count + 1, sizeof *lines) != CF_OK) {
      s = out_of_memory(&t);
      break;
    }
    cf_colmap_image *image = &images[count];
    memset(image, 0, sizeof *image);
    lines[count] = t.line;
    ++count; /* counted now so that a failure frees what it holds */
    s = read_image_line(&t, line, count - 1, image);
    if (s != CF_OK) break;
    span points;
    if (next_line(&t, &points)) {
      s = read_points2d_line(&t, points, image);
    } else {
      image->points2d = calloc(1, sizeof *image->points2d); /* the file ends: no points */
      if (!image->points2d) s = out_of_memory(&t);
    }
  }
  uint64_t *ids = NULL;
  if (s == CF_OK) {
    ids = calloc(model->num_images + count + 1, sizeof *ids);
    if (!ids) s = out_of_memory(&t);
  }
  if (s == CF_OK) {
    for (size_t i = 0; i < model->num_images; ++i) ids[i] = model->images[i].image_id;
    for (size_t i = 0; i < count; ++i) ids[model->num_images + i] = images[i].image_id;
    s = check_duplicates(&t, ids, model->num_images, model->num_images + count, lines, "image",
                         "IMAGE_ID");
  }
  if (s == CF_OK && cf__append((void **)&model->images, &model->num_images, images, count,
                               sizeof *images) != CF_OK)
    s = out_of_memory(&t);
  if (s == CF_OK)
    free(images);
  else
    cf__free_images(images, count);
  free(lines);
  free(ids);
  return s;
}

/* ---- points3D.txt ---- */

static cf_status read_point3d_line(text_reader *t, span line, size_t index, cf_point3d *point) {
  tokens ts = tokens_of(line);
  snprintf(t->record, sizeof t->record, "point record %zu", index + 1);
  cf_status s = read_whole(t, &ts, "POINT3D_ID", INT64_MAX, &point->point3d_id);
  if (s != CF_OK) return s;
  snprintf(t->record, sizeof t->record, "point %llu", (unsigned long long)point->point3d_id);
  static const char *const xyz[3] = {"X", "Y", "Z"}, *const rgb[3] = {"R", "G", "B"};
  for (int k = 0; k < 3; ++k)
    if ((s = read_finite(t, &ts, xyz[k], &point->xyz[k])) != CF_OK) return s;
  for (int k = 0; k < 3; ++k) {
    uint64_t c;
    if ((s = read_whole(t, &ts, rgb[k], 255, &c)) != CF_OK) return s;
    point->rgb[k] = (uint8_t)c;
  }
  if ((s = read_finite(t, &ts, "ERROR", &point->error)) != CF_OK) return s;

  size_t n = count_tokens(ts);
  if (n % 2 != 0)
    return record_error(t, CF_EPARSE,
                        "field TRACK: %zu numbers, not a multiple of 2 (IMAGE_ID POINT2D_IDX)", n);
  point->track_length = n / 2;
  point->track = calloc(n ? n / 2 : 1, sizeof *point->track);
  if (!point->track) return out_of_memory(t);
  for (size_t j = 0; j < n / 2; ++j) {
    char field[48], buf[64];
    span token = {NULL, 0};
    uint64_t v;
    const char *why;
    next_token(&ts, &token);
    if ((why = whole_number(token, UINT32_MAX, &v, buf, sizeof buf)) != NULL) {
      snprintf(field, sizeof field, "TRACK[%zu].IMAGE_ID", j);
      return bad_token(t, field, token, why);
    }
    point->track[j].image_id = (uint32_t)v;
    next_token(&ts, &token);
    if ((why = whole_number(token, UINT32_MAX, &v, buf, sizeof buf)) != NULL) {
      snprintf(field, sizeof field, "TRACK[%zu].POINT2D_IDX", j);
      return bad_token(t, field, token, why);
    }
    point->track[j].point2d_idx = (uint32_t)v;
  }
  return CF_OK;
}

cf_status cf_colmap_parse_points3d_text(const char *text, size_t size, const char *name,
                                        cf_colmap_model *model, cf_error *err) {
  text_reader t = {.text = text,
                   .size = size,
                   .name = name,
                   .err = err,
                   .layout = "POINT3D_ID X Y Z R G B ERROR IMAGE_ID POINT2D_IDX ..."};
  cf_point3d *points = NULL;
  size_t *lines = NULL, count = 0, capacity = 0, line_capacity = 0;
  cf_status s = CF_OK;
  span line;
  while (s == CF_OK && next_record_line(&t, &line)) {
    if (cf__grow((void **)&points, &capacity, count + 1, sizeof *points) != CF_OK ||
        cf__grow((void **)&lines, &line_capacity, count + 1, sizeof *lines) != CF_OK) {
      s = out_of_memory(&t);
      break;
    }
    memset(&points[count], 0, sizeof points[count]);
    lines[count] = t.line;
    ++count;
    s = read_point3d_line(&t, line, count - 1, &points[count - 1]);
  }
  uint64_t *ids = NULL;
  if (s == CF_OK) {
    ids = calloc(model->num_points3d + count + 1, sizeof *ids);
    if (!ids) s = out_of_memory(&t);
  }
  if (s == CF_OK) {
    for (size_t i = 0; i < model->num_points3d; ++i) ids[i] = model->points3d[i].point3d_id;
    for (size_t i = 0; i < count; ++i) ids[model->num_points3d + i] = points[i].point3d_id;
    s = check_duplicates(&t, ids, model->num_points3d, model->num_points3d + count, lines, "point",
                         "POINT3D_ID");
  }
  if (s == CF_OK && cf__append((void **)&model->points3d, &model->num_points3d, points, count,
                               sizeof *points) != CF_OK)
    s = out_of_memory(&t);
  if (s == CF_OK)
    free(points);
  else
    cf__free_points3d(points, count);
  free(lines);
  free(ids);
  return s;
}
