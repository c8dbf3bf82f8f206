/* Images read and written (include/clayfit/image.h): the file checked,
 * then a codec (image_codec.h) chosen. A reader is chosen by the file's
 * first bytes: PNG, JPEG, OpenEXR and PFM are read here; every other
 * format goes to OpenImageIO (image_oiio.cpp), built as a module of its
 * own (libclayfit_oiio.so) and loaded only when such a file appears,
 * because linking it costs every clayfit process 0.4 s of start (262
 * shared libraries; docs/images.md). A writer is chosen by the
 * extension. */
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clayfit/image.h"
#include "core/file.h"
#include "image_codec.h"
#include "image_exr_check.h"

/* The OpenImageIO module, by its full path: CMake's build puts it in its
 * lib/ folder and names that folder here. Not through the run path: under
 * AddressSanitizer, dlopen is called from libasan, whose run path it
 * searches instead. A build without the folder (the fuzzing's) has no
 * module. */
#ifdef CLAYFIT_MODULE_DIR
#define OIIO_MODULE CLAYFIT_MODULE_DIR "/libclayfit_oiio.so"
#else
#define OIIO_MODULE "libclayfit_oiio.so"
#endif

/* ---- reading ---- */

static const unsigned char PNG_MAGIC[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
static const unsigned char EXR_MAGIC[4] = {0x76, 0x2f, 0x31, 0x01};
static const unsigned char JPEG_MAGIC[3] = {0xff, 0xd8, 0xff};

/* A file's reads go through a buffer of READ_BUFFER bytes (read_any):
 * 64 KiB, not stdio's 4 KiB: loading s96 (192 opens of 692 KB PNGs) made
 * 3511 reads, not 33153. */
enum { READ_BUFFER = 1 << 16 };

/* A stream at byte `from` moved on to byte `to` (>= from): read through a
 * gap within the buffer's size (glibc's fseek costs a system call even
 * inside the buffer: 16905 of them on s96), seek over a longer one. 0 at
 * the file's end. */
static int skip_to(FILE *file, long long from, long long to) {
  if (to - from > READ_BUFFER) return fseek(file, (long)to, SEEK_SET) == 0;
  unsigned char discard[4096];
  for (long long left = to - from; left > 0;) {
    const size_t n = left < (long long)sizeof discard ? (size_t)left : sizeof discard;
    if (fread(discard, 1, n, file) != n) return 0;
    left -= (long long)n;
  }
  return 1;
}

/* A PNG's chunks walked from their lengths without decoding: CF_EIO when
 * the file ends inside a chunk or before IEND, so that a truncated file is
 * refused before libpng decodes part of it. The stream is after the
 * signature. */
static cf_status check_png_chunks(const char *path, FILE *file, long long file_size,
                                  cf_error *err) {
  long long at = 8, position = 8; /* after the signature */
  for (;;) {
    unsigned char head[8];
    const int got = skip_to(file, position, at) && fread(head, 1, 8, file) == 8;
    position = at + 8;
    if (!got)
      return cf_error_set(err, CF_EIO,
                          "%s: a truncated PNG: the file ends at byte %lld, before its IEND chunk",
                          path, file_size);
    const unsigned long long length = (unsigned long long)head[0] << 24 |
                                      (unsigned long long)head[1] << 16 |
                                      (unsigned long long)head[2] << 8 | head[3];
    char type[5] = {(char)head[4], (char)head[5], (char)head[6], (char)head[7], 0};
    for (int i = 0; i < 4; ++i)
      if (!((type[i] >= 'a' && type[i] <= 'z') || (type[i] >= 'A' && type[i] <= 'Z')))
        type[i] = '?';
    if (length > 0x7fffffffULL)
      return cf_error_set(err, CF_EPARSE,
                          "%s: a corrupt PNG: chunk '%s' at byte %lld claims %llu bytes", path,
                          type, at, length);
    if (at + 12 + (long long)length > file_size)
      return cf_error_set(err, CF_EIO,
                          "%s: a truncated PNG: chunk '%s' at byte %lld needs %llu bytes but the "
                          "file ends at byte %lld",
                          path, type, at, length + 12, file_size);
    at += 12 + (long long)length;
    if (memcmp(head + 4, "IEND", 4) == 0) return CF_OK;
  }
}

/* PFM's "PF" or "Pf" and a whitespace byte. */
static int is_pfm(const unsigned char *magic, size_t got) {
  return got >= 3 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f') &&
         (magic[2] == '\n' || magic[2] == '\r' || magic[2] == ' ' || magic[2] == '\t');
}

/* The reader of a file starting with `magic` (NULL: OpenImageIO's), the
 * file's structure checked first where a reader needs it. */
static cf_status reader_of(const char *path, FILE *file, long long size,
                           const unsigned char *magic, size_t got, image_reader *reader,
                           cf_error *err) {
  *reader = NULL;
  if (got >= 8 && memcmp(magic, PNG_MAGIC, 8) == 0) {
    *reader = image_png_read;
    return check_png_chunks(path, file, size, err);
  }
  if (got >= 4 && memcmp(magic, EXR_MAGIC, 4) == 0) {
    *reader = image_exr_read;
    return cf_exr_check_headers(path, file, size, err);
  }
  if (got >= 3 && memcmp(magic, JPEG_MAGIC, 3) == 0) *reader = image_jpeg_read;
  if (is_pfm(magic, got)) *reader = image_pfm_read;
  return CF_OK;
}

/* A function of the OpenImageIO module, or NULL with the reason in err.
 * dlopen counts the module's uses and loads it once; it stays loaded. */
static void *oiio_function(const char *path, const char *name, cf_error *err) {
  void *module = dlopen(OIIO_MODULE, RTLD_NOW | RTLD_LOCAL);
  void *function = module ? dlsym(module, name) : NULL;
  if (!function) {
    const char *why = dlerror();
    cf_error_set(err, CF_EUNSUPPORTED,
                 "%s: clayfit reads PNG, JPEG, OpenEXR and PFM itself and every other format "
                 "through OpenImageIO, which this build cannot load (%s): install "
                 "libopenimageio-dev and build again (scripts/install-deps.sh test, "
                 "scripts/build.sh)",
                 path, why ? why : OIIO_MODULE);
  }
  return function;
}

/* cf_image_read_sized and cf_image_read_header: the file checked, then
 * read by its codec (the header alone when image is NULL). */
static cf_status read_any(const char *path, int width, int height, cf_image_header *header,
                          cf_image *image, cf_error *err) {
  FILE *file;
  long long size;
  cf_status s = cf_open_regular_file(path, &file, &size, err);
  if (s != CF_OK) return s;
  char *buffer = malloc(READ_BUFFER); /* (glibc ignores the size without one) */
  if (buffer) setvbuf(file, buffer, _IOFBF, READ_BUFFER);
  unsigned char magic[8];
  const size_t got = fread(magic, 1, sizeof magic, file);
  image_reader reader;
  s = reader_of(path, file, size, magic, got, &reader, err);
  if (s == CF_OK && reader) {
    rewind(file);
    s = reader(path, file, size, width, height, header, image, err);
  }
  fclose(file);
  free(buffer);
  if (s != CF_OK || reader) return s;
  cf_status (*general)(const char *, int, int, cf_image_header *, cf_image *, cf_error *);
  *(void **)&general = oiio_function(path, "image_oiio_read", err);
  return general ? general(path, width, height, header, image, err) : CF_EUNSUPPORTED;
}

static void info_clear(cf_image_info *info) {
  memset(info->format, 0, sizeof info->format);
  info->bits_per_sample = 0;
  info->is_float = 0;
  info->exposure_time = NAN;
  info->f_number = NAN;
  info->iso = NAN;
}

cf_status cf_image_read_sized(const char *path, int width, int height, cf_image *image,
                              cf_image_info *info, cf_error *err) {
  image->width = image->height = image->channels = 0;
  image->pixels = NULL;
  cf_image_header header = {0};
  info_clear(&header.info);
  if (info) info_clear(info);
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  cf_status s = read_any(path, width, height, &header, image, err);
  if (s != CF_OK) {
    cf_image_free(image);
    return s;
  }
  if (info) *info = header.info;
  return CF_OK;
}

cf_status cf_image_read(const char *path, cf_image *image, cf_image_info *info, cf_error *err) {
  return cf_image_read_sized(path, 0, 0, image, info, err);
}

cf_status cf_image_read_header(const char *path, cf_image_header *header, cf_error *err) {
  header->width = header->height = header->channels = 0;
  info_clear(&header->info);
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  return read_any(path, 0, 0, header, NULL, err);
}

/* ---- writing ---- */

typedef enum { KIND_EXR, KIND_HDR, KIND_PFM, KIND_PNG, KIND_TIFF, KIND_JPEG, KIND_UNKNOWN } kind;

/* The format of path's extension (case-insensitive). */
static kind kind_of(const char *path) {
  const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
  if (!dot || (slash && dot < slash)) return KIND_UNKNOWN;
  char ext[8] = {0};
  for (size_t i = 0; dot[1 + i] && i + 1 < sizeof ext; ++i)
    ext[i] = (char)(dot[1 + i] >= 'A' && dot[1 + i] <= 'Z' ? dot[1 + i] - 'A' + 'a' : dot[1 + i]);
  if (strlen(dot + 1) >= sizeof ext) return KIND_UNKNOWN;
  static const struct {
    const char *ext;
    kind kind;
  } table[] = {{"exr", KIND_EXR},   {"hdr", KIND_HDR},   {"pfm", KIND_PFM},  {"png", KIND_PNG},
               {"tif", KIND_TIFF},  {"tiff", KIND_TIFF}, {"jpg", KIND_JPEG}, {"jpeg", KIND_JPEG}};
  for (size_t i = 0; i < sizeof table / sizeof table[0]; ++i)
    if (strcmp(ext, table[i].ext) == 0) return table[i].kind;
  return KIND_UNKNOWN;
}

/* NULL when the format takes `bits` and `channels`, else what it takes. */
static const char *refused(kind k, int bits, int channels) {
  switch (k) {
    case KIND_PNG:
    case KIND_TIFF:
      return bits == 8 || bits == 16 ? NULL : "8 or 16 bits";
    case KIND_JPEG:
      if (channels != 1 && channels != 3) return "1 or 3 channels";
      return bits == 8 ? NULL : "8 bits";
    case KIND_EXR:
      return bits == 16 || bits == 32 ? NULL : "16 (half) or 32 (float) bits";
    case KIND_HDR:
      if (channels != 3) return "3 channels";
      return bits == 32 ? NULL : "32 bits";
    case KIND_PFM:
      if (channels != 1 && channels != 3) return "1 or 3 channels";
      return bits == 32 ? NULL : "32 bits";
    case KIND_UNKNOWN:
      break;
  }
  return "an extension .exr, .hdr, .pfm, .png, .tif, .tiff, .jpg or .jpeg";
}

/* The temporary file an image is written to, beside `path` and with its
 * extension (OpenImageIO picks the format by it): "a/b.png" becomes
 * "a/b.png.tmp-PID.png". An existing path that is not a regular file (a
 * FIFO, a device) is refused: a FIFO with no reader would block the
 * writer forever, and renaming over /dev/stdout would replace the link. */
static cf_status temporary_beside(const char *path, char *out, size_t size, cf_error *err) {
  struct stat st;
  if (stat(path, &st) == 0 && !S_ISREG(st.st_mode))
    return cf_error_set(err, CF_EINVAL, "%s: exists and is not a regular file; an image is "
                        "written to a file", path);
  const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
  const char *ext = dot && (!slash || dot > slash) ? dot : "";
  int n = snprintf(out, size, "%s.tmp-%ld%s", path, (long)getpid(), ext);
  if (n < 0 || (size_t)n >= size) return cf_error_set(err, CF_EINVAL, "%s: the path is too long", path);
  return CF_OK;
}

/* The written temporary flushed to the disk (the codecs close it but do
 * not sync) and renamed to `path` when the writer's status s is CF_OK,
 * else removed: a killed or failed write leaves the earlier file. */
static cf_status into_place(const char *temporary, const char *path, cf_status s, cf_error *err) {
  size_t n = strlen(temporary);
  if (s != CF_OK && err && strncmp(err->message, temporary, n) == 0) { /* name the caller's file */
    char message[sizeof err->message];
    snprintf(message, sizeof message, "%s%s", path, err->message + n);
    memcpy(err->message, message, sizeof message);
  }
  if (s == CF_OK) {
    int fd = open(temporary, O_RDONLY);
    int failed = fd < 0 || fsync(fd) != 0 ? errno : 0;
    if (fd >= 0 && close(fd) != 0 && !failed) failed = errno;
    if (failed)
      s = cf_error_set(err, CF_EIO, "%s: could not flush %s to the disk: %s", path, temporary,
                       strerror(failed));
  }
  if (s == CF_OK && rename(temporary, path) != 0)
    s = cf_error_set(err, CF_EIO, "%s: could not rename %s into place: %s", path, temporary,
                     strerror(errno));
  if (s != CF_OK) unlink(temporary);
  return s;
}

/* Every writer's entry: the image and the format's bits checked, then the
 * codec of the extension (quality and chroma for a JPEG). */
static cf_status write_any(const char *path, const cf_image *image, int bits,
                           const cf_image_info *info, int quality, cf_chroma chroma,
                           cf_error *err) {
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  if (!image || !image->pixels || image->width <= 0 || image->height <= 0 || image->channels < 1 ||
      image->channels > 4)
    return cf_error_set(err, CF_EINVAL, "%s: nothing to write (an empty image)", path);
  const kind k = kind_of(path);
  const char *why = refused(k, bits, image->channels);
  if (why)
    return cf_error_set(err, CF_EINVAL,
                        "%s: cannot write %d bits x %d channels in this format; it takes %s", path,
                        bits, image->channels, why);
  char temporary[4200];
  cf_status s = temporary_beside(path, temporary, sizeof temporary, err);
  if (s != CF_OK) return s;
  switch (k) {
    case KIND_PNG:
      s = image_png_write(temporary, image, bits, info, err);
      break;
    case KIND_JPEG:
      s = image_jpeg_write(temporary, image, quality, chroma, info, err);
      break;
    case KIND_EXR:
      s = image_exr_write(temporary, image, bits, info, err);
      break;
    case KIND_PFM:
      s = image_pfm_write(temporary, image, err);
      break;
    default: {
      cf_status (*general)(const char *, const cf_image *, int, const cf_image_info *, int,
                           cf_chroma, cf_error *);
      *(void **)&general = oiio_function(path, "image_oiio_write", err);
      s = general ? general(temporary, image, bits, info, quality, chroma, err) : CF_EUNSUPPORTED;
    }
  }
  return into_place(temporary, path, s, err);
}

cf_status cf_image_write(const char *path, const cf_image *image, int bits, cf_error *err) {
  return write_any(path, image, bits, NULL, 100, CF_CHROMA_444, err);
}

cf_status cf_image_write_with_info(const char *path, const cf_image *image, int bits,
                                   const cf_image_info *info, cf_error *err) {
  return write_any(path, image, bits, info, 100, CF_CHROMA_444, err);
}

cf_status cf_image_write_jpeg(const char *path, const cf_image *image, int quality,
                              cf_chroma chroma, const cf_image_info *info, cf_error *err) {
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  if (quality < 1 || quality > 100)
    return cf_error_set(err, CF_EINVAL, "%s: JPEG quality %d is outside [1, 100]", path, quality);
  if (kind_of(path) != KIND_JPEG)
    return cf_error_set(err, CF_EINVAL, "%s: a JPEG needs the extension .jpg or .jpeg", path);
  return write_any(path, image, 8, info, quality, chroma, err);
}

cf_status cf_image_jpeg_roundtrip(const cf_image *in, int quality, cf_chroma chroma, cf_image *out,
                                  cf_error *err) {
  out->width = out->height = out->channels = 0;
  out->pixels = NULL;
  if (!in || !in->pixels || in->width <= 0 || in->height <= 0 || in->channels != 3)
    return cf_error_set(err, CF_EINVAL, "a JPEG round trip needs a 3-channel image");
  if (quality < 1 || quality > 100)
    return cf_error_set(err, CF_EINVAL, "JPEG quality %d is outside [1, 100]", quality);
  return image_jpeg_roundtrip(in, quality, chroma, out, err);
}
