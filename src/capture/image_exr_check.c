/* OpenEXR headers walked before OpenEXR reads them (image_exr_check.h).
 * OpenEXR 3.1 (Debian 12) trusts the sizes a file declares: an attribute
 * of an unknown type, the strings of a string vector and a preview image
 * are allocated at their declared sizes (0.8 and 1.6 GB from files of a
 * few hundred bytes: tests/fuzz/regressions/fuzz_image), an attribute of a
 * known type is read at its type's size whatever the file declares (so the
 * rest of the header is misread), the offset table is allocated from the
 * data window or chunkCount, and a chunk's buffer from the data window's
 * width (1.8 GB from a file of 632 bytes). This walk refuses all of these;
 * a valid file passes (all of it is in the file) unless a chunk of its
 * pixels needs more than 256 MB. Layout: "OpenEXR File
 * Layout" (openexr.com). */
#include "image_exr_check.h"

#include <ctype.h>
#include <stdint.h>
#include <string.h>

typedef struct exr_walk {
  const char *path;
  FILE *file;
  long long size, at; /* the file's size, the next byte */
  cf_error *err;
} exr_walk;

/* What one header says about its offset table. */
typedef struct exr_part {
  long long window[4];   /* dataWindow: x min, y min, x max, y max */
  long long tile[2];     /* tiles: x size, y size (0: scan lines) */
  long long chunks;      /* chunkCount (multi-part), -1 if absent */
  long long pixel_bytes; /* channels: the bytes of one pixel of all */
  int lines;             /* compression: scan lines per chunk */
  int has_window;
} exr_part;

/* Types whose value has one size, as OpenEXR reads them. */
static int fixed_size(const char *type) {
  static const struct {
    const char *type;
    int size;
  } sizes[] = {{"box2i", 16},    {"box2f", 16},   {"v2i", 8},
               {"v2f", 8},       {"v2d", 16},     {"v3i", 12},
               {"v3f", 12},      {"v3d", 24},     {"int", 4},
               {"float", 4},     {"double", 8},   {"compression", 1},
               {"lineOrder", 1}, {"envmap", 1},   {"deepImageState", 1},
               {"tiledesc", 9},  {"rational", 8}, {"timecode", 8},
               {"keycode", 28},  {"m33f", 36},    {"m33d", 72},
               {"m44f", 64},     {"m44d", 128},   {"chromaticities", 32}};
  for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; ++k)
    if (strcmp(type, sizes[k].type) == 0) return sizes[k].size;
  return -1;
}

/* A NUL-terminated name of at most 255 bytes, '?' for what is not
 * printable; 0 at the end of the file or past 255 bytes. */
static int get_name(exr_walk *w, char out[256]) {
  for (size_t n = 0; n < 256; ++n) {
    int c = fgetc(w->file);
    if (c == EOF) return 0;
    ++w->at;
    out[n] = c == 0 || isprint(c) ? (char)c : '?';
    if (c == 0) return 1;
  }
  return 0;
}

static int get_i32(exr_walk *w, long long *value) {
  unsigned char b[4];
  if (fread(b, 1, 4, w->file) != 4) return 0;
  w->at += 4;
  *value =
      (int32_t)((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24);
  return 1;
}

static int seek(exr_walk *w, long long at) {
  w->at = at;
  return at <= w->size && fseek(w->file, (long)at, SEEK_SET) == 0;
}

/* chlist: channels (a name, a pixel type, 12 more bytes) until an empty
 * name, ending exactly at `end`; adds each channel's sample size (UINT
 * and FLOAT 4 bytes, HALF 2) to *pixel_bytes. */
static int chlist_fits(exr_walk *w, long long end, long long *pixel_bytes) {
  char name[256];
  for (long long type;;) {
    if (!get_name(w, name) || w->at > end) return 0;
    if (!name[0]) return w->at == end;
    if (!get_i32(w, &type) || !seek(w, w->at + 12) || w->at > end) return 0;
    *pixel_bytes += type == 1 ? 2 : 4;
  }
}

/* stringvector: strings (a length, then its bytes) ending exactly at end. */
static int strings_fit(exr_walk *w, long long end) {
  while (w->at < end) {
    long long length;
    if (!get_i32(w, &length) || length < 0 || w->at + length > end || !seek(w, w->at + length))
      return 0;
  }
  return w->at == end;
}

/* preview: width, height, then width x height RGBA bytes: `size` in all. */
static int preview_fits(exr_walk *w, long long size) {
  long long width, height;
  if (size < 8 || !get_i32(w, &width) || !get_i32(w, &height)) return 0;
  width &= 0xffffffffLL;
  height &= 0xffffffffLL;
  return width == 0 ? size == 8
                    : height <= (size - 8) / 4 / width && 8 + 4 * width * height == size;
}

/* The values that size the offset table. */
static void note_value(exr_walk *w, const char *name, const char *type, exr_part *part) {
  long long v[4] = {0, 0, 0, 0};
  if (strcmp(name, "dataWindow") == 0 && strcmp(type, "box2i") == 0) {
    for (int k = 0; k < 4; ++k) get_i32(w, &v[k]);
    memcpy(part->window, v, sizeof v);
    part->has_window = 1;
  } else if (strcmp(name, "tiles") == 0 && strcmp(type, "tiledesc") == 0) {
    get_i32(w, &v[0]);
    get_i32(w, &v[1]);
    part->tile[0] = v[0] & 0xffffffffLL;
    part->tile[1] = v[1] & 0xffffffffLL;
  } else if (strcmp(name, "chunkCount") == 0 && strcmp(type, "int") == 0) {
    get_i32(w, &part->chunks);
  } else if (strcmp(name, "compression") == 0 && strcmp(type, "compression") == 0) {
    /* none, RLE, ZIPS, ZIP, PIZ, PXR24, B44, B44A, DWAA, DWAB */
    static const int lines[10] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
    int c = fgetc(w->file);
    part->lines = c >= 0 && c < 10 ? lines[c] : 256;
  }
}

/* One attribute's value, of `size` bytes from w->at: a reason it does not
 * fit, or NULL. */
static const char *check_value(exr_walk *w, const char *name, const char *type, long long size,
                               exr_part *part) {
  long long end = w->at + size;
  if (size < 0 || end > w->size) return "declares more bytes than the file has";
  int fixed = fixed_size(type);
  if (fixed >= 0 && size != fixed) return "declares another size than its type's";
  if (strcmp(type, "chlist") == 0 && !chlist_fits(w, end, &part->pixel_bytes))
    return "has a malformed channel list";
  if (strcmp(type, "stringvector") == 0 && !strings_fit(w, end))
    return "has a string longer than the attribute";
  if (strcmp(type, "preview") == 0 && !preview_fits(w, size))
    return "declares a preview of another size than its bytes";
  if (fixed >= 0) note_value(w, name, type, part);
  return seek(w, end) ? NULL : "ends past the end of the file";
}

/* What OpenEXR allocates when it opens the file fits: one 8-byte offset
 * per chunk in the file (a chunk holds at most 256 scan lines, or one
 * tile), and one chunk's pixels (a tile, or `lines` scan lines of all
 * channels: OpenEXR's compressor buffer) within 256 MB. A reason it does
 * not, or NULL. 256 MB: a chunk of 256 scan lines 65536 pixels wide in
 * RGBA float. */
static const char *check_part(const exr_part *part, long long file_size) {
  const char *too_many = "needs more chunk offsets than the file holds";
  const long long max_chunk = 1LL << 28;
  if (part->chunks > file_size / 8) return too_many;
  if (!part->has_window) return NULL; /* OpenEXR refuses it */
  int counted = part->chunks >= 0;    /* multi-part: the table has chunkCount offsets */
  long long width = part->window[2] - part->window[0] + 1;
  long long height = part->window[3] - part->window[1] + 1;
  if (width < 1 || height < 1) return "its data window is empty";
  if (width > (1LL << 31) / height) return "its data window holds more than 2^31 pixels";
  long long pixel = part->pixel_bytes > 0 ? part->pixel_bytes : 4;
  if (part->tile[0] == 0 && part->tile[1] == 0) {
    if (width > max_chunk / pixel / part->lines)
      return "its scan lines are wider than a chunk of 256 MB allows";
    return counted || (height + 255) / 256 <= file_size / 8 ? NULL : too_many;
  }
  if (part->tile[0] < 1 || part->tile[1] < 1 || part->tile[0] > max_chunk / pixel / part->tile[1])
    return "its tiles are empty or larger than 256 MB";
  long long tiles = ((width + part->tile[0] - 1) / part->tile[0]) *
                    ((height + part->tile[1] - 1) / part->tile[1]);
  return counted || tiles <= file_size / 8 ? NULL : too_many;
}

/* One header's attributes, up to its empty name; *empty when it has none. */
static cf_status walk_header(exr_walk *w, int *empty) {
  exr_part part = {{0, 0, 0, 0}, {0, 0}, -1, 0, 256, 0};
  char name[256], type[256];
  for (*empty = 1;; *empty = 0) {
    long long start = w->at, size;
    if (!get_name(w, name))
      return cf_error_set(w->err, CF_EPARSE,
                          "%s: a corrupt OpenEXR header: no attribute name ends at byte %lld",
                          w->path, start);
    if (!name[0]) break;
    if (!get_name(w, type) || !get_i32(w, &size))
      return cf_error_set(w->err, CF_EPARSE,
                          "%s: a corrupt OpenEXR header: attribute '%s' at byte %lld is cut short",
                          w->path, name, start);
    const char *why = check_value(w, name, type, size, &part);
    if (why)
      return cf_error_set(w->err, CF_EPARSE,
                          "%s: a corrupt OpenEXR header: attribute '%s' (%s) at byte %lld %s "
                          "(%lld bytes; the file ends at byte %lld)",
                          w->path, name, type, start, why, size, w->size);
  }
  const char *why = *empty ? NULL : check_part(&part, w->size);
  if (why)
    return cf_error_set(w->err, CF_EPARSE,
                        "%s: a corrupt OpenEXR header: %s (a file of %lld bytes)", w->path, why,
                        w->size);
  return CF_OK;
}

cf_status cf_exr_check_headers(const char *path, FILE *file, long long file_size, cf_error *err) {
  exr_walk w = {path, file, file_size, 0, err};
  unsigned char version[4];
  if (!seek(&w, 4) || fread(version, 1, 4, file) != 4)
    return cf_error_set(err, CF_EPARSE, "%s: a truncated OpenEXR file (%lld bytes)", path,
                        file_size);
  w.at = 8;
  int multipart = (version[1] & 0x10) != 0, empty;
  for (;;) { /* one header, or (multi-part) headers until an empty one */
    cf_status s = walk_header(&w, &empty);
    if (s != CF_OK || !multipart || empty) return s;
  }
}
