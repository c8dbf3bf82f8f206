/* clayfit: images. Every image clayfit reads or writes goes through
 * OpenImageIO (behind this C interface); colour decoding turns stored
 * values into linear radiance.
 *
 * Pixels are float, interleaved, row-major with the top row first:
 * pixels[(y * width + x) * channels + c]. Pixel (x, y) has its centre at
 * (x + 0.5, y + 0.5) in COLMAP's continuous pixel coordinates. */
#ifndef CLAYFIT_IMAGE_H
#define CLAYFIT_IMAGE_H

#include <stddef.h>

#include "clayfit/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cf_image {
  int width, height, channels;
  float *pixels; /* width × height × channels, owned (cf_image_free) */
} cf_image;

/* Allocate a zeroed image; CF_ENOMEM or CF_EINVAL (sizes <= 0, channels
 * outside 1..4, or more than 2^31 values). */
cf_status cf_image_alloc(cf_image *image, int width, int height, int channels, cf_error *err);
void cf_image_free(cf_image *image);

/* What a file says about itself. Absent metadata is NaN or "". */
typedef struct cf_image_info {
  char format[32];      /* OpenImageIO's format name: "openexr", "png", "jpeg", ... */
  int bits_per_sample;  /* of the stored sample type: 8, 16 (also half) or 32 (also
                           float and Radiance RGBE) */
  int is_float;         /* 1 for half/float data (EXR, HDR, PFM, float TIFF) */
  double exposure_time; /* seconds (EXIF ExposureTime) */
  double f_number;      /* EXIF FNumber */
  double iso;           /* EXIF PhotographicSensitivity (tag 0x8827, formerly
                           ISOSpeedRatings; OpenImageIO 2.4 reads it as
                           "Exif:PhotographicSensitivity") */
} cf_image_info;

/* Read a whole image as stored, without any colour transform: integer
 * formats scaled to [0, 1] (value / (2^bits − 1)), float formats as they
 * are. PFM comes out top row first like every other format. Alpha is left
 * as stored (never premultiplied into the colour channels), and an EXIF
 * Orientation tag is not applied (pixels come out as stored, as COLMAP
 * reads them). Errors name the file: missing, unreadable, unsupported,
 * zero size, more than 4 channels, more than 2^31 values, a truncated
 * PNG; CF_ENOMEM when memory runs out decoding it; *image is then empty
 * (pixels NULL). info may be NULL. Non-finite values are kept
 * (see cf_image_check_finite). */
cf_status cf_image_read(const char *path, cf_image *image, cf_image_info *info, cf_error *err);

/* cf_image_read, but a file whose header declares another size than
 * width x height (both > 0; 0 and 0 for any) is refused (CF_EINVAL naming
 * both sizes) before any pixel is decoded: a small compressed file may
 * declare an image of gigabytes. */
cf_status cf_image_read_sized(const char *path, int width, int height, cf_image *image,
                              cf_image_info *info, cf_error *err);

/* What an image file's header declares, read without decoding a pixel. */
typedef struct cf_image_header {
  int width, height, channels;
  cf_image_info info;
} cf_image_header;

/* The header of `path`, checked as cf_image_read checks it (every error
 * but those of the pixels themselves). A PNG is also walked chunk by chunk
 * (lengths only): one that ends before its IEND chunk is CF_EIO. */
cf_status cf_image_read_header(const char *path, cf_image_header *header, cf_error *err);

/* The bytes the header's pixels take once decoded, as 32-bit floats: what
 * the decoded-data caps (--max-image-memory) count before decoding. */
unsigned long long cf_image_header_bytes(const cf_image_header *header);

/* s, with " (from its header, before decoding)" added to err's message
 * when s is an error: a refusal from a header says nothing was decoded. */
cf_status cf_image_header_refusal(cf_status s, cf_error *err);

/* CF_EINVAL naming `path`, the first non-finite value's pixel (x, y) and
 * channel, and how many there are, if the image holds NaN or Inf. */
cf_status cf_image_check_finite(const cf_image *image, const char *path, cf_error *err);

/* Write an image; the format follows the extension (.exr, .hdr, .pfm,
 * .png, .tif/.tiff, .jpg/.jpeg). bits: 8 or 16 for PNG and TIFF, 8 for
 * JPEG, 16 (half) or 32 (float) for EXR, 32 for HDR and PFM. Values are
 * written as given (integer formats: clamped to [0, 1] and rounded); encode
 * them first (cf_linear_to_srgb) where the file should hold sRGB. Whole or
 * not at all: written to a temporary file beside `path` (PATH.tmp-PID.EXT),
 * flushed to the disk and renamed into place; on a failure `path` is left
 * as it was. A `path` that exists and is not a regular file (a FIFO, a
 * device) is refused (CF_EINVAL). */
cf_status cf_image_write(const char *path, const cf_image *image, int bits, cf_error *err);

/* cf_image_write, and also the EXIF exposure time, f-number and ISO of
 * `info` where they are finite (format, bits_per_sample and is_float are
 * ignored; info may be NULL). JPEG and TIFF keep them in EXIF, OpenEXR
 * as attributes; other formats may drop them. For synthetic captures and
 * tests. EXIF values are read as the float nearest their rational
 * (OpenImageIO's reading, which clayfit's JPEG reader keeps): 1/125 s
 * comes back as 0.00800000038 s. A JPEG stores an exposure time 1/N s
 * as exactly 1/N (1/64, 1/50, 0.5 s too) and other values to at least 9
 * significant digits, so every value comes back as its float; a TIFF,
 * written through OpenImageIO 2.4, turns a power-of-two fraction (1/64 s,
 * 0.5 s) into infinity and 1/50 s into 0.019999 s. */
cf_status cf_image_write_with_info(const char *path, const cf_image *image, int bits,
                                   const cf_image_info *info, cf_error *err);

/* Chroma subsampling of a JPEG: full, half horizontally, half both ways. */
typedef enum cf_chroma { CF_CHROMA_444, CF_CHROMA_422, CF_CHROMA_420 } cf_chroma;

/* An 8-bit JPEG (.jpg/.jpeg) at libjpeg's quality 1..100 with that chroma
 * subsampling (cameras write 4:2:0 at 85-95), and info's EXIF as
 * cf_image_write_with_info. cf_image_write's JPEGs are quality 100, 4:4:4. */
cf_status cf_image_write_jpeg(const char *path, const cf_image *image, int quality,
                              cf_chroma chroma, const cf_image_info *info, cf_error *err);

/* `in` (3 channels, stored values in [0, 1]) coded as an 8-bit JPEG at
 * libjpeg's quality 1..100 with that chroma subsampling, in memory, and
 * decoded back into *out (allocated here; freed on failure): what the
 * codec makes of an image (the fit's model of a JPEG's coding error). */
cf_status cf_image_jpeg_roundtrip(const cf_image *in, int quality, cf_chroma chroma, cf_image *out,
                                  cf_error *err);

/* How a JPEG file was coded, from its markers: the quality whose
 * libjpeg-scaled standard luminance table (ITU-T T.81 Annex K, Table K.1;
 * libjpeg's jcparam.c scaling) comes nearest the file's first
 * quantisation table (exact: 1 when it is that table), and the chroma
 * subsampling of its frame header's sampling factors. */
typedef struct cf_jpeg_coding {
  int quality;
  int exact;
  cf_chroma chroma;
} cf_jpeg_coding;

/* Read from the file's bytes (its markers up to the first scan); every
 * length and field is checked: CF_EINVAL naming the file and the marker
 * for a file that is not a baseline or progressive JPEG with an 8-bit
 * luminance table and a 3-component frame (or 1 component: 4:4:4). */
cf_status cf_jpeg_coding_read(const char *path, cf_jpeg_coding *coding, cf_error *err);

/* The same from `size` bytes in memory (`what` names them in errors). */
cf_status cf_jpeg_coding_parse(const unsigned char *bytes, size_t size, const char *what,
                               cf_jpeg_coding *coding, cf_error *err);

/* ---- colour decoding ---- */

typedef enum cf_transfer {
  CF_TRANSFER_LINEAR, /* stored value proportional to radiance */
  CF_TRANSFER_SRGB,   /* IEC 61966-2-1 piecewise curve */
  CF_TRANSFER_GAMMA   /* stored = linear^(1/gamma) */
} cf_transfer;

double cf_srgb_to_linear(double encoded);
double cf_linear_to_srgb(double linear);

/* Camera response curves: linear exposure (1 = the curve's white) to a
 * code in [0, 1], and back (src/capture/colour.c gives their sources).
 * `synth --response` renders through them; tests take the truth from here.
 *   linear    code = linear
 *   srgb      code = cf_linear_to_srgb(linear)       (IEC 61966-2-1)
 *   gamma2.2  code = linear^(1/2.2)
 *   filmic    code = f(11.2 linear) / f(11.2), f Hable's "Uncharted 2"
 *             filmic curve: a toe (slope 4.3 at 0, not sRGB's 12.92) and a
 *             shoulder (slope 0.22 at 1); asymptote 1.29 above the white.
 * All are odd-symmetric for negative values and strictly increasing;
 * decode(encode(x)) = x to rounding (filmic's decode of a code at or above
 * its asymptote is +inf). */
typedef enum cf_response {
  CF_RESPONSE_LINEAR,
  CF_RESPONSE_SRGB,
  CF_RESPONSE_GAMMA22,
  CF_RESPONSE_FILMIC,
  CF_RESPONSE_COUNT
} cf_response;

/* "linear", "srgb", "gamma2.2", "filmic" ("?" out of range). */
const char *cf_response_name(cf_response response);
/* The curve of that name; CF_EINVAL listing the names otherwise. */
cf_status cf_response_find(const char *name, cf_response *response, cf_error *err);
double cf_response_encode(cf_response response, double linear);
double cf_response_decode(cf_response response, double code);

/* How one image's stored values become linear radiance:
 *   clipped  <=> the stored value >= clip_level (in any channel; tested
 *                before decoding, per channel);
 *   linear    = transfer⁻¹(stored);
 *   radiance  = (linear − black_level) / exposure.
 * black_level is in linear units; exposure > 0. Nothing is clamped:
 * radiance may be slightly negative after the black level (noise). */
typedef struct cf_decode {
  cf_transfer transfer;
  double gamma;       /* for CF_TRANSFER_GAMMA, > 0 */
  double black_level; /* linear units */
  double clip_level;  /* stored units, in (0, +inf]; +inf for never */
  double exposure;    /* relative exposure e_k (docs/model.md (38)) */
} cf_decode;

/* Decode the first three channels of one stored pixel; returns the
 * per-channel clip mask (bit c set when channel c is clipped; a clipped
 * channel is decoded at the clip level, which is all it says). A one- or
 * two-channel pixel (grey, grey + alpha) is read as grey: r = g = b from
 * channel 0, and when that is clipped all three bits are set. The transfer
 * is extended to negative stored values by odd symmetry (−f(−x)), so noise
 * below zero stays finite. */
unsigned cf_decode_pixel(const cf_decode *decode, const float *stored, int channels,
                         double radiance[3]);

/* A transfer's stored value to linear (gamma: CF_TRANSFER_GAMMA's), odd
 * symmetric below 0; cf_decode_pixel's, before the black level and the
 * exposure. */
double cf_transfer_to_linear(cf_transfer transfer, double gamma, double stored);

/* The inverse: the stored value that decodes to `radiance` (one channel,
 * clip level aside), and (slope not NULL) d stored / d radiance. */
double cf_encode_value(const cf_decode *decode, double radiance, double *slope);

#ifdef __cplusplus
}
#endif

#endif /* CLAYFIT_IMAGE_H */
