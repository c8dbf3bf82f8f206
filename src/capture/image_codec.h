/* The codecs behind include/clayfit/image.h. image_io.c picks a reader
 * from a file's first bytes (PNG, JPEG, OpenEXR, PFM here; every other
 * format through OpenImageIO, image_oiio.cpp, loaded only then) and a
 * writer from the path's extension. Private to the image component.
 *
 * Every reader has one shape: it reads the header into *header, has it
 * accepted (image_header_accept: channels, size, the size expected)
 * before it decodes a pixel, and, when image is not NULL, decodes the
 * whole image as float, top row first, interleaved, samples as stored
 * (no colour transform, alpha never premultiplied, EXIF Orientation not
 * applied), integer samples scaled by image_scale_u8/_u16. On failure
 * *image is empty (pixels NULL) and err names the file. */
#ifndef CLAYFIT_IMAGE_CODEC_H
#define CLAYFIT_IMAGE_CODEC_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "clayfit/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A reader. `file` is `path` opened for reading at byte 0, a regular
 * file of `size` bytes whose first bytes are this format's (the caller
 * checked them and closes the file); width, height > 0: the size the
 * header must declare (0, 0: any). header->info is cleared by the
 * caller (NaN, "", 0) and filled here where the file says. */
typedef cf_status (*image_reader)(const char *path, FILE *file, long long size, int width,
                                  int height, cf_image_header *header, cf_image *image,
                                  cf_error *err);

cf_status image_png_read(const char *path, FILE *file, long long size, int width, int height,
                         cf_image_header *header, cf_image *image, cf_error *err);
cf_status image_jpeg_read(const char *path, FILE *file, long long size, int width, int height,
                          cf_image_header *header, cf_image *image, cf_error *err);
cf_status image_exr_read(const char *path, FILE *file, long long size, int width, int height,
                         cf_image_header *header, cf_image *image, cf_error *err);
cf_status image_pfm_read(const char *path, FILE *file, long long size, int width, int height,
                         cf_image_header *header, cf_image *image, cf_error *err);

/* Writers: the image is non-empty with 1 to 4 channels and `bits` is one
 * the format takes (image_io.c checked both). Integer formats store
 * image_quantize_u8/_u16 of every value. */
cf_status image_png_write(const char *path, const cf_image *image, int bits,
                          const cf_image_info *info, cf_error *err);
cf_status image_exr_write(const char *path, const cf_image *image, int bits,
                          const cf_image_info *info, cf_error *err);
cf_status image_pfm_write(const char *path, const cf_image *image, cf_error *err);
/* quality 1..100 (libjpeg's), chroma subsampling; 1 or 3 channels */
cf_status image_jpeg_write(const char *path, const cf_image *image, int quality, cf_chroma chroma,
                           const cf_image_info *info, cf_error *err);
/* cf_image_jpeg_roundtrip after its checks (3 channels, quality 1..100) */
cf_status image_jpeg_roundtrip(const cf_image *in, int quality, cf_chroma chroma, cf_image *out,
                               cf_error *err);

/* ---- EXIF (image_exif.c) ---- */

/* The exposure time (tag 0x829A), f-number (0x829D) and ISO (0x8827) of
 * an EXIF block (its TIFF structure, after JPEG's "Exif\0\0"), into info
 * where present, finite and positive. Every offset is checked against
 * `size`: a malformed field is skipped, never read outside the block. */
void image_exif_read(const unsigned char *tiff, size_t size, cf_image_info *info);

/* The EXIF block (TIFF structure) holding info's finite exposure time,
 * f-number and ISO, written into out (capacity bytes); its size, or 0
 * when info has none of them. */
size_t image_exif_write(const cf_image_info *info, unsigned char *out, size_t capacity);

/* ---- OpenImageIO (image_oiio.cpp) ---- */

/* The general reader: any format OpenImageIO opens, by `path`, the same
 * checks and the same output as the readers above. */
cf_status image_oiio_read(const char *path, int width, int height, cf_image_header *header,
                          cf_image *image, cf_error *err);
/* The general writer (the format from the extension; quality and chroma
 * for a JPEG), and a JPEG round trip in memory: the codecs' reference in
 * their tests. */
cf_status image_oiio_write(const char *path, const cf_image *image, int bits,
                           const cf_image_info *info, int quality, cf_chroma chroma,
                           cf_error *err);
cf_status image_oiio_jpeg_roundtrip(const cf_image *in, int quality, cf_chroma chroma,
                                    cf_image *out, cf_error *err);

/* ---- shared by the codecs (image_codec.c) ---- */

/* CF_OK when a header of width x height pixels and `channels` channels
 * can be read: positive sizes, 1 to 4 channels, at most 2^31 values, and
 * the size expected (width_expected, height_expected > 0; 0, 0 for any).
 * Otherwise the error every reader gives, naming the file. */
cf_status image_header_accept(const char *path, int width, int height, int channels,
                              int width_expected, int height_expected, cf_error *err);

/* The error for a file whose data window is not its display window
 * (OpenEXR, TIFF): clayfit reads whole images only. */
cf_status image_window_refuse(const char *path, int width, int height, int x, int y,
                              int full_width, int full_height, int full_x, int full_y,
                              cf_error *err);

/* Integer samples to float, v × (1 / max) in float: bit for bit what
 * OpenImageIO's conversion gives, in loops the compiler vectorises. */
void image_scale_u8(const uint8_t *in, size_t count, float *out);
void image_scale_u16(const uint16_t *in, size_t count, float *out);

/* A value stored as an integer sample: clamped to [0, 1], × max, rounded
 * half up (NaN gives 0), bit for bit what OpenImageIO's conversion from
 * float gives. */
uint8_t image_quantize_u8(float value);
uint16_t image_quantize_u16(float value);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_IMAGE_CODEC_H */
