/* The JPEG codec (image_codec.h) over libjpeg-turbo's libjpeg 6.2 API,
 * bit for bit what OpenImageIO 2.4 reads and writes through the same
 * library (src/jpeg.imageio/jpeginput.cpp and jpegoutput.cpp there):
 *  - decoding with libjpeg's defaults (islow IDCT, fancy upsampling, RGB
 *    or greyscale out); a CMYK or YCCK file as 3 channels, R = C × K,
 *    G = M × K, B = Y × K in float from the stored (Adobe-inverted)
 *    values, as jpeginput.cpp's cmyk_to_rgb;
 *  - encoding with jpeg_set_defaults, jpeg_set_quality(q, TRUE) and the
 *    sampling factors 1x1 / 2x1 / 2x2 for 4:4:4 / 4:2:2 / 4:2:0, values
 *    through image_quantize_u8 (OpenImageIO's conversion, no dither).
 * libjpeg's errors longjmp back here (error_exit); its warnings end the
 * read too, as in OpenImageIO (whose output_message longjmps): a warning
 * is corrupt or truncated data ("premature end of data", "extraneous
 * bytes"), and would otherwise come back as grey pixels. Nothing is
 * printed. Each function that calls setjmp keeps its state in a struct
 * reached by pointer, so no local is modified between setjmp and longjmp. */
#include <setjmp.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jerror.h>
#include <jpeglib.h>

#include "image_codec.h"

/* A progressive file's scans, at most: libjpeg's jpeg_simple_progression
 * writes 10 (6 for greyscale); every scan is a pass over the coefficients,
 * so a hostile file of thousands of valid scans decodes for minutes (see
 * tests/capture/test_image_jpeg.c, which times one). */
#define MOST_SCANS 100

/* EXIF is one APP1 segment: at most 65533 bytes. */
#define EXIF_MOST 65533

/* ---- errors ---- */

typedef struct jpeg_failure {
  struct jpeg_error_mgr pub;
  jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
  int out_of_memory;
} jpeg_failure;

static void failure_exit(j_common_ptr cinfo) {
  jpeg_failure *f = (jpeg_failure *)cinfo->err;
  f->out_of_memory = f->pub.msg_code == JERR_OUT_OF_MEMORY;
  (*f->pub.format_message)(cinfo, f->message);
  longjmp(f->jump, 1);
}

/* level < 0: a warning, which fails the read; trace messages (level >= 0)
 * are dropped. */
static void failure_emit(j_common_ptr cinfo, int level) {
  if (level < 0) failure_exit(cinfo);
}

static void failure_silent(j_common_ptr cinfo) {
  (void)cinfo;
}

static void failure_init(jpeg_failure *f) {
  jpeg_std_error(&f->pub);
  f->pub.error_exit = failure_exit;
  f->pub.emit_message = failure_emit;
  f->pub.output_message = failure_silent;
  f->message[0] = '\0';
  f->out_of_memory = 0;
}

static cf_status failure_status(const jpeg_failure *f, const char *what, const char *doing,
                                cf_error *err) {
  if (f->out_of_memory)
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while %s it (libjpeg: %s)", what, doing,
                        f->message);
  return cf_error_set(err, CF_EIO, "%s: %s failed: libjpeg: %s", what, doing, f->message);
}

/* ---- decoding ---- */

typedef struct jpeg_reading {
  struct jpeg_decompress_struct cinfo;
  jpeg_failure failure;
  struct jpeg_progress_mgr progress;
  int created, cmyk, channels;
  unsigned char *row; /* one decoded row, as libjpeg outputs it */
  char scan_message[96];
} jpeg_reading;

/* Called by libjpeg while it consumes input: stops a file of too many
 * scans (libjpeg has no such limit of its own in this version). */
static void progress_check(j_common_ptr common) {
  j_decompress_ptr cinfo = (j_decompress_ptr)common;
  if (cinfo->input_scan_number <= MOST_SCANS) return;
  jpeg_reading *r = (jpeg_reading *)((char *)cinfo - offsetof(jpeg_reading, cinfo));
  snprintf(r->failure.message, sizeof r->failure.message,
           "more than %d progressive scans (a hostile file?)", MOST_SCANS);
  longjmp(r->failure.jump, 1);
}

static void reading_begin(jpeg_reading *r) {
  memset(r, 0, sizeof *r);
  failure_init(&r->failure);
  r->cinfo.err = &r->failure.pub;
  jpeg_create_decompress(&r->cinfo);
  r->created = 1;
  r->progress.progress_monitor = progress_check;
  r->cinfo.progress = &r->progress;
  jpeg_save_markers(&r->cinfo, JPEG_APP0 + 1, 0xffff);
}

static void reading_end(jpeg_reading *r) {
  if (r->created) jpeg_destroy_decompress(&r->cinfo);
  r->created = 0;
  free(r->row);
  r->row = NULL;
}

/* The EXIF of every APP1 "Exif\0\0" segment, in file order (a later one
 * replaces an earlier one's values, as in OpenImageIO). */
static void read_exif_markers(const jpeg_reading *r, cf_image_info *info) {
  for (jpeg_saved_marker_ptr m = r->cinfo.marker_list; m; m = m->next)
    if (m->marker == JPEG_APP0 + 1 && m->data_length >= 6 && memcmp(m->data, "Exif\0", 5) == 0)
      image_exif_read(m->data + 6, m->data_length - 6, info);
}

/* The header read and accepted: channels as OpenImageIO counts them
 * (CMYK and YCCK read as RGB), the output colour space set. */
static cf_status read_header(jpeg_reading *r, const char *what, int width, int height,
                             cf_image_header *header, cf_error *err) {
  jpeg_read_header(&r->cinfo, TRUE);
  j_decompress_ptr c = &r->cinfo;
  r->channels = c->num_components;
  if (c->jpeg_color_space == JCS_CMYK || c->jpeg_color_space == JCS_YCCK) {
    c->out_color_space = JCS_CMYK; /* libjpeg turns YCCK into CMYK */
    r->cmyk = 1, r->channels = 3;
  }
  const int w = c->image_width > 0x7fffffffu ? 0 : (int)c->image_width;
  const int h = c->image_height > 0x7fffffffu ? 0 : (int)c->image_height;
  cf_status s = image_header_accept(what, w, h, r->channels, width, height, err);
  if (s != CF_OK) return s;
  header->width = w, header->height = h, header->channels = r->channels;
  snprintf(header->info.format, sizeof header->info.format, "jpeg");
  header->info.bits_per_sample = 8;
  header->info.is_float = 0;
  read_exif_markers(r, &header->info);
  return CF_OK;
}

/* CMYK as stored (inverted, Adobe) to RGB: OpenImageIO's cmyk_to_rgb. */
static void cmyk_row(const unsigned char *cmyk, int width, float *out) {
  const float scale = 1.0f / 255.0f;
  for (int x = 0; x < width; ++x, cmyk += 4, out += 3) {
    const float k = (float)cmyk[3] * scale;
    for (int c = 0; c < 3; ++c) {
      const float product = ((float)cmyk[c] * scale) * k;
      out[c] = (float)image_quantize_u8(product) * scale;
    }
  }
}

/* Every row decoded into image (allocated by the caller: width x height x
 * r->channels), then the rest of the file read to its end (EOI). */
static void decode_rows(jpeg_reading *r, cf_image *image) {
  j_decompress_ptr c = &r->cinfo;
  jpeg_start_decompress(c);
  const int stored = r->cmyk ? 4 : r->channels;
  if ((int)c->output_width != image->width || (int)c->output_height != image->height ||
      c->output_components != stored) {
    snprintf(r->failure.message, sizeof r->failure.message,
             "decodes to %u x %u x %d, not the %d x %d x %d its header says", c->output_width,
             c->output_height, c->output_components, image->width, image->height, stored);
    longjmp(r->failure.jump, 1);
  }
  r->row = malloc((size_t)image->width * (size_t)stored);
  if (!r->row) ERREXIT1(c, JERR_OUT_OF_MEMORY, 0);
  const size_t row_values = (size_t)image->width * (size_t)image->channels;
  while (c->output_scanline < c->output_height) {
    float *out = image->pixels + (size_t)c->output_scanline * row_values;
    JSAMPROW rows[1] = {r->row};
    if (jpeg_read_scanlines(c, rows, 1) != 1) ERREXIT(c, JERR_INPUT_EMPTY);
    if (r->cmyk)
      cmyk_row(r->row, image->width, out);
    else
      image_scale_u8(r->row, row_values, out);
  }
  jpeg_finish_decompress(c);
}

/* The source is set; reads the header and, with image, the pixels. */
static cf_status read_from(jpeg_reading *r, const char *what, int width, int height,
                           cf_image_header *header, cf_image *image, cf_error *err) {
  cf_status s = read_header(r, what, width, height, header, err);
  if (s != CF_OK || !image) return s;
  s = cf_image_alloc(image, header->width, header->height, header->channels, err);
  if (s != CF_OK) {
    cf_error_prefix(err, "%s", what);
    return s;
  }
  decode_rows(r, image);
  return CF_OK;
}

cf_status image_jpeg_read(const char *path, FILE *file, long long size, int width, int height,
                          cf_image_header *header, cf_image *image, cf_error *err) {
  (void)size;
  jpeg_reading reading, *r = &reading;
  reading_begin(r);
  if (image) *image = (cf_image){0};
  if (setjmp(r->failure.jump)) {
    if (image) cf_image_free(image);
    cf_status s = failure_status(&r->failure, path, "decoding", err);
    reading_end(r);
    return s;
  }
  jpeg_stdio_src(&r->cinfo, file);
  cf_status s = read_from(r, path, width, height, header, image, err);
  reading_end(r);
  return s;
}

/* ---- encoding ---- */

/* A growing buffer in memory as libjpeg's destination: owned here (not
 * by libjpeg's jpeg_mem_dest, which loses its buffer on an error). */
typedef struct memory_destination {
  struct jpeg_destination_mgr pub;
  unsigned char *bytes;
  size_t capacity, size;
} memory_destination;

static void memory_init(j_compress_ptr cinfo) {
  memory_destination *d = (memory_destination *)cinfo->dest;
  d->capacity = 1u << 16;
  d->bytes = malloc(d->capacity);
  if (!d->bytes) ERREXIT1(cinfo, JERR_OUT_OF_MEMORY, 0);
  d->pub.next_output_byte = d->bytes;
  d->pub.free_in_buffer = d->capacity;
}

static boolean memory_grow(j_compress_ptr cinfo) {
  memory_destination *d = (memory_destination *)cinfo->dest;
  unsigned char *bigger = realloc(d->bytes, 2 * d->capacity);
  if (!bigger) ERREXIT1(cinfo, JERR_OUT_OF_MEMORY, 1);
  d->bytes = bigger;
  d->pub.next_output_byte = bigger + d->capacity;
  d->pub.free_in_buffer = d->capacity;
  d->capacity *= 2;
  return TRUE;
}

static void memory_term(j_compress_ptr cinfo) {
  memory_destination *d = (memory_destination *)cinfo->dest;
  d->size = d->capacity - d->pub.free_in_buffer;
}

typedef struct jpeg_writing {
  struct jpeg_compress_struct cinfo;
  jpeg_failure failure;
  memory_destination memory;
  int created;
  unsigned char *row;
} jpeg_writing;

static void writing_begin(jpeg_writing *w) {
  memset(w, 0, sizeof *w);
  failure_init(&w->failure);
  w->cinfo.err = &w->failure.pub;
  jpeg_create_compress(&w->cinfo);
  w->created = 1;
}

static void writing_end(jpeg_writing *w) {
  if (w->created) jpeg_destroy_compress(&w->cinfo);
  w->created = 0;
  free(w->row);
  free(w->memory.bytes);
  w->row = NULL, w->memory.bytes = NULL;
}

static void memory_dest(jpeg_writing *w) {
  w->memory.pub.init_destination = memory_init;
  w->memory.pub.empty_output_buffer = memory_grow;
  w->memory.pub.term_destination = memory_term;
  w->cinfo.dest = &w->memory.pub;
}

/* jpegoutput.cpp's settings: 1 channel greyscale; 2 channels as RGB with
 * blue 0 and 4 as RGB without alpha (JFIF holds 1 or 3); the quality with
 * force_baseline; the chroma's sampling factors (JPEG_444_COMP and its
 * siblings in jpeg_pvt.h). */
static void set_parameters(j_compress_ptr c, const cf_image *image, int quality, cf_chroma chroma) {
  c->image_width = (JDIMENSION)image->width;
  c->image_height = (JDIMENSION)image->height;
  c->input_components = image->channels == 1 ? 1 : 3;
  c->in_color_space = image->channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(c);
  jpeg_set_quality(c, quality < 1 ? 1 : quality > 100 ? 100 : quality, TRUE);
  if (c->input_components == 3) {
    jpeg_set_colorspace(c, JCS_YCbCr);
    c->comp_info[0].h_samp_factor = chroma == CF_CHROMA_444 ? 1 : 2;
    c->comp_info[0].v_samp_factor = chroma == CF_CHROMA_420 ? 2 : 1;
    for (int k = 1; k < 3; ++k) c->comp_info[k].h_samp_factor = c->comp_info[k].v_samp_factor = 1;
  }
}

/* One row as stored: image_quantize_u8 of the first 1 or 3 channels. */
static void quantize_row(const cf_image *image, int y, int components, unsigned char *row) {
  const float *in = image->pixels + (size_t)y * (size_t)image->width * (size_t)image->channels;
  for (int x = 0; x < image->width; ++x, in += image->channels, row += components)
    for (int c = 0; c < components; ++c)
      row[c] = c < image->channels ? image_quantize_u8(in[c]) : 0;
}

/* The destination is set: the whole image coded, with info's EXIF. */
static void encode(jpeg_writing *w, const cf_image *image, int quality, cf_chroma chroma,
                   const cf_image_info *info) {
  j_compress_ptr c = &w->cinfo;
  set_parameters(c, image, quality, chroma);
  jpeg_start_compress(c, TRUE);
  unsigned char exif[6 + 256];
  size_t exif_size = image_exif_write(info, exif + 6, sizeof exif - 6);
  if (exif_size) {
    memcpy(exif, "Exif\0\0", 6);
    jpeg_write_marker(c, JPEG_APP0 + 1, exif, (unsigned)(6 + exif_size));
  }
  w->row = malloc((size_t)image->width * (size_t)c->input_components);
  if (!w->row) ERREXIT1(c, JERR_OUT_OF_MEMORY, 2);
  while (c->next_scanline < c->image_height) {
    quantize_row(image, (int)c->next_scanline, c->input_components, w->row);
    JSAMPROW rows[1] = {w->row};
    jpeg_write_scanlines(c, rows, 1);
  }
  jpeg_finish_compress(c);
}

/* Coded into w->memory. */
static cf_status encode_to_memory(jpeg_writing *w, const cf_image *image, int quality,
                                  cf_chroma chroma, const cf_image_info *info, const char *what,
                                  cf_error *err) {
  if (setjmp(w->failure.jump)) return failure_status(&w->failure, what, "coding", err);
  memory_dest(w);
  encode(w, image, quality, chroma, info);
  return CF_OK;
}

cf_status image_jpeg_write(const char *path, const cf_image *image, int quality, cf_chroma chroma,
                           const cf_image_info *info, cf_error *err) {
  jpeg_writing writing;
  writing_begin(&writing);
  cf_status s = encode_to_memory(&writing, image, quality, chroma, info, path, err);
  if (s == CF_OK) {
    FILE *file = fopen(path, "wb");
    int ok =
        file && fwrite(writing.memory.bytes, 1, writing.memory.size, file) == writing.memory.size;
    if (file) ok = fclose(file) == 0 && ok;
    if (!ok) {
      s = cf_error_set(err, CF_EIO, "%s: cannot write the JPEG file", path);
      if (file) remove(path);
    }
  }
  writing_end(&writing);
  return s;
}

/* Decoded from memory into out (allocated here). */
static cf_status decode_memory(const unsigned char *bytes, size_t size, cf_image *out,
                               cf_error *err) {
  const char *what = "a JPEG coded in memory";
  jpeg_reading reading, *r = &reading;
  reading_begin(r);
  *out = (cf_image){0};
  if (setjmp(r->failure.jump)) {
    cf_image_free(out);
    cf_status s = failure_status(&r->failure, what, "decoding", err);
    reading_end(r);
    return s;
  }
  jpeg_mem_src(&r->cinfo, bytes, (unsigned long)size);
  cf_image_header header = {0};
  cf_status s = read_from(r, what, 0, 0, &header, out, err);
  reading_end(r);
  return s;
}

cf_status image_jpeg_roundtrip(const cf_image *in, int quality, cf_chroma chroma, cf_image *out,
                               cf_error *err) {
  jpeg_writing writing;
  writing_begin(&writing);
  cf_status s = encode_to_memory(&writing, in, quality, chroma, NULL, "a JPEG round trip", err);
  if (s == CF_OK)
    s = decode_memory(writing.memory.bytes, writing.memory.size, out, err);
  else
    *out = (cf_image){0};
  writing_end(&writing);
  return s;
}
