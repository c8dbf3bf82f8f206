/* The image adapter (include/clayfit/image.h): a thin C++ layer over
 * OpenImageIO 2.4 with C linkage. Nothing thrown by OpenImageIO or the
 * standard library crosses the C boundary: every entry point catches all
 * and turns it into a cf_error naming the file.
 *
 * Pixels are read with ImageInput::read_image(0, 0, 0, nchannels,
 * TypeDesc::FLOAT, ...), which scales integer samples to [0, 1] and applies
 * no colour transform ("oiio:ColorSpace" is metadata only; ImageInput never
 * linearises). "oiio:UnassociatedAlpha" = 1 keeps PNG and TIFF readers
 * from premultiplying colour by alpha and writers from dividing by it.
 *
 * OpenImageIO 2.4 reads PFM (bottom row first in the file) top row first,
 * but cannot write it, so PFM is written here (Netpbm's PFM: "PF" or "Pf",
 * width height, a negative scale for little-endian floats, rows bottom to
 * top). */
#include <sys/stat.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "clayfit/image.h"
#include "image_exr_check.h"
extern "C" {
#include "core/file.h"
}

namespace {

const int64_t kMaxValues = int64_t(1) << 31;

/* OpenImageIO's messages may span lines; keep ours on one. */
std::string one_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ' || text.back() == '.'))
    text.pop_back();
  for (char &c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text.empty() ? std::string("no details from OpenImageIO") : text;
}

/* Clear OpenImageIO's pending global error (it complains at exit about
 * messages never retrieved). */
void drain_errors() noexcept {
  try {
    OIIO::geterror();
  } catch (...) {
  }
}

/* The lower-case extension of path without the dot ("" if none). */
std::string extension_of(const char *path) {
  const char *slash = std::strrchr(path, '/');
  const char *dot = std::strrchr(path, '.');
  if (!dot || (slash && dot < slash)) return std::string();
  std::string ext(dot + 1);
  for (char &c : ext)
    if (c >= 'A' && c <= 'Z') c = char(c - 'A' + 'a');
  return ext;
}

void info_clear(cf_image_info *info) {
  if (!info) return;
  std::memset(info->format, 0, sizeof info->format);
  info->bits_per_sample = 0;
  info->is_float = 0;
  info->exposure_time = NAN;
  info->f_number = NAN;
  info->iso = NAN;
}

/* A numeric attribute, or NaN when absent, non-numeric or not positive
 * (EXIF uses 0 for "unknown"). */
double positive_attribute(const OIIO::ImageSpec &spec, const char *name) {
  if (spec.getattributetype(name) == OIIO::TypeUnknown) return NAN;
  double value = spec.get_float_attribute(name, NAN);
  return std::isfinite(value) && value > 0.0 ? value : NAN;
}

bool is_float(const OIIO::TypeDesc &type) {
  return type.basetype == OIIO::TypeDesc::HALF || type.basetype == OIIO::TypeDesc::FLOAT ||
         type.basetype == OIIO::TypeDesc::DOUBLE;
}

void info_fill(cf_image_info *info, const OIIO::ImageInput &input, const OIIO::ImageSpec &spec) {
  if (!info) return;
  std::snprintf(info->format, sizeof info->format, "%s", input.format_name());
  info->is_float = is_float(spec.format);
  for (const OIIO::TypeDesc &channel : spec.channelformats) /* per-channel formats */
    info->is_float |= is_float(channel);
  info->bits_per_sample = int(spec.format.basesize() * 8);
  info->exposure_time = positive_attribute(spec, "ExposureTime");
  info->f_number = positive_attribute(spec, "FNumber");
  info->iso = positive_attribute(spec, "Exif:PhotographicSensitivity");
  if (std::isnan(info->iso)) info->iso = positive_attribute(spec, "Exif:ISOSpeedRatings");
}

/* Integer samples scaled to [0, 1] as OpenImageIO's conversion to FLOAT
 * does (v × (1 / max), bit for bit), in a loop the compiler vectorises:
 * OpenImageIO's own took a seventh of loading DiLiGenT's 96 16-bit PNGs. */
template <typename T>
bool read_scaled(OIIO::ImageInput &input, const OIIO::ImageSpec &spec, OIIO::TypeDesc type,
                 float *pixels) {
  const size_t values = size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels);
  std::unique_ptr<T[]> stored(new T[values]); /* not zeroed: read over */
  if (!input.read_image(0, 0, 0, spec.nchannels, type, stored.get())) return false;
  const float scale = 1.0f / float(std::numeric_limits<T>::max());
  for (size_t i = 0; i < values; ++i) pixels[i] = float(stored[i]) * scale;
  return true;
}

/* Every sample as float, integer ones scaled to [0, 1]. */
bool read_pixels(OIIO::ImageInput &input, const OIIO::ImageSpec &spec, float *pixels) {
  if (spec.channelformats.empty() && spec.format == OIIO::TypeDesc::UINT16)
    return read_scaled<uint16_t>(input, spec, OIIO::TypeDesc::UINT16, pixels);
  if (spec.channelformats.empty() && spec.format == OIIO::TypeDesc::UINT8)
    return read_scaled<uint8_t>(input, spec, OIIO::TypeDesc::UINT8, pixels);
  return input.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels);
}

/* A PNG's chunks walked from their lengths without decoding: CF_EPARSE
 * when the file ends inside a chunk or before IEND. libpng's error on a
 * truncated file unwinds (longjmp) through OpenImageIO's read callback and
 * leaks its message string; this refuses such a file before it is opened. */
cf_status check_png_chunks(const char *path, FILE *file, long long file_size, cf_error *err) {
  long long at = 8; /* after the signature */
  for (;;) {
    unsigned char head[8];
    if (std::fseek(file, long(at), SEEK_SET) != 0 || std::fread(head, 1, 8, file) != 8)
      return cf_error_set(err, CF_EIO,
                          "%s: a truncated PNG: the file ends at byte %lld, before its IEND chunk",
                          path, file_size);
    unsigned long long length =
        (unsigned long long)head[0] << 24 | head[1] << 16 | head[2] << 8 | head[3];
    char type[5] = {char(head[4]), char(head[5]), char(head[6]), char(head[7]), 0};
    for (char &c : type)
      if (c && !std::isalpha((unsigned char)c)) c = '?';
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
    if (std::memcmp(head + 4, "IEND", 4) == 0) return CF_OK;
  }
}

/* The file at path: a regular file, and if a PNG, whole (check_png_chunks);
 * if an OpenEXR file, its headers sound (cf_exr_check_headers). */
cf_status check_file(const char *path, cf_error *err) {
  struct stat st;
  if (stat(path, &st) != 0) {
    char hidden[160];
    cf_path_hidden_characters(path, hidden, sizeof hidden);
    if (errno == ENOENT) return cf_error_set(err, CF_ENOTFOUND, "%s: no such file%s", path, hidden);
    return cf_error_set(err, CF_EIO, "%s: %s%s", path, std::strerror(errno), hidden);
  }
  if (!S_ISREG(st.st_mode)) return cf_error_set(err, CF_EIO, "%s: not a regular file", path);
  FILE *file = std::fopen(path, "rb");
  if (!file) return cf_error_set(err, CF_EIO, "%s: %s", path, std::strerror(errno));
  static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  unsigned char magic[8];
  cf_status s = CF_OK;
  static const unsigned char exr[4] = {0x76, 0x2f, 0x31, 0x01};
  size_t got = std::fread(magic, 1, 8, file);
  if (got == 8 && std::memcmp(magic, png, 8) == 0)
    s = check_png_chunks(path, file, (long long)st.st_size, err);
  else if (got == 8 && std::memcmp(magic, exr, 4) == 0)
    s = cf_exr_check_headers(path, file, (long long)st.st_size, err);
  std::fclose(file);
  return s;
}

/* The file opened and its header checked: one 2D, flat image of 1 to 4
 * channels and at most 2^31 values, whole (data window = display window). */
cf_status open_checked(const char *path, std::unique_ptr<OIIO::ImageInput> &input, cf_error *err) {
  cf_status s = check_file(path, err);
  if (s != CF_OK) return s;
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  input = OIIO::ImageInput::open(path, &config);
  if (!input)
    return cf_error_set(err, CF_EIO, "%s: cannot read this image: %s", path,
                        one_line(OIIO::geterror()).c_str());
  const OIIO::ImageSpec &spec = input->spec();
  if (spec.deep)
    return cf_error_set(err, CF_EUNSUPPORTED, "%s: deep images are not supported", path);
  if (spec.width <= 0 || spec.height <= 0 || spec.depth <= 0 || spec.nchannels <= 0)
    return cf_error_set(err, CF_EPARSE, "%s: zero size (%d x %d pixels, %d channels)", path,
                        spec.width, spec.height, spec.nchannels);
  if (spec.depth != 1)
    return cf_error_set(err, CF_EUNSUPPORTED, "%s: a volume image (depth %d) is not supported",
                        path, spec.depth);
  if (spec.nchannels > 4)
    return cf_error_set(err, CF_EUNSUPPORTED,
                        "%s: %d channels; clayfit reads images of 1 to 4 channels", path,
                        spec.nchannels);
  int64_t values = int64_t(spec.width) * spec.height * spec.nchannels;
  if (values > kMaxValues)
    return cf_error_set(err, CF_ERANGE,
                        "%s: %d x %d pixels x %d channels is %lld values, more than the 2^31 "
                        "clayfit reads",
                        path, spec.width, spec.height, spec.nchannels, (long long)values);
  if (spec.x != spec.full_x || spec.y != spec.full_y || spec.width != spec.full_width ||
      spec.height != spec.full_height)
    return cf_error_set(err, CF_EUNSUPPORTED,
                        "%s: the data window (%d x %d at %d, %d) differs from the display window "
                        "(%d x %d at %d, %d); clayfit reads whole images only",
                        path, spec.width, spec.height, spec.x, spec.y, spec.full_width,
                        spec.full_height, spec.full_x, spec.full_y);
  return CF_OK;
}

cf_status read_header(const char *path, cf_image_header *header, cf_error *err) {
  std::unique_ptr<OIIO::ImageInput> input;
  cf_status s = open_checked(path, input, err);
  if (s != CF_OK) return s;
  const OIIO::ImageSpec &spec = input->spec();
  header->width = spec.width;
  header->height = spec.height;
  header->channels = spec.nchannels;
  info_fill(&header->info, *input, spec);
  input->close();
  input->geterror();
  return CF_OK;
}

/* width, height > 0: the size the header must declare, checked before
 * any pixel is decoded. */
cf_status read_image(const char *path, int width, int height, cf_image *image, cf_image_info *info,
                     cf_error *err) {
  std::unique_ptr<OIIO::ImageInput> input;
  cf_status status = open_checked(path, input, err);
  if (status != CF_OK) return status;
  const OIIO::ImageSpec &spec = input->spec();
  if (width > 0 && height > 0 && (spec.width != width || spec.height != height))
    return cf_error_set(err, CF_EINVAL,
                        "%s: its header says %d x %d pixels, not the %d x %d expected; not decoded",
                        path, spec.width, spec.height, width, height);
  status = cf_image_alloc(image, spec.width, spec.height, spec.nchannels, err);
  if (status != CF_OK) {
    cf_error_prefix(err, "%s", path);
    return status;
  }
  if (!read_pixels(*input, spec, image->pixels)) {
    cf_image_free(image);
    return cf_error_set(err, CF_EIO, "%s: cannot read the pixels: %s", path,
                        one_line(input->geterror()).c_str());
  }
  info_fill(info, *input, spec);
  input->close();
  input->geterror(); /* nothing left pending */
  return CF_OK;
}

/* What went wrong reading path, from an exception: out of memory is not
 * a bad input. */
cf_status read_failed(const char *path, cf_image *image, cf_error *err) {
  if (image) cf_image_free(image);
  drain_errors();
  try {
    throw;
  } catch (const std::bad_alloc &) {
    return cf_error_set(err, CF_ENOMEM, "%s: out of memory while decoding it", path);
  } catch (const std::exception &e) {
    return cf_error_set(err, CF_EIO, "%s: reading failed: %s", path, e.what());
  } catch (...) {
    return cf_error_set(err, CF_EIO, "%s: reading failed (an unknown exception)", path);
  }
}

/* ---- writing ---- */

enum class Kind { exr, hdr, pfm, png, tiff, jpeg, unknown };

Kind kind_of(const std::string &ext) {
  if (ext == "exr") return Kind::exr;
  if (ext == "hdr") return Kind::hdr;
  if (ext == "pfm") return Kind::pfm;
  if (ext == "png") return Kind::png;
  if (ext == "tif" || ext == "tiff") return Kind::tiff;
  if (ext == "jpg" || ext == "jpeg") return Kind::jpeg;
  return Kind::unknown;
}

/* The sample type for `bits` in this format, or UNKNOWN (with a message)
 * when the format does not take that many bits or channels. */
OIIO::TypeDesc sample_type(Kind kind, int bits, int channels, const char **why) {
  switch (kind) {
    case Kind::png:
    case Kind::tiff:
      if (bits == 8) return OIIO::TypeDesc::UINT8;
      if (bits == 16) return OIIO::TypeDesc::UINT16;
      *why = "8 or 16 bits";
      break;
    case Kind::jpeg:
      if (channels != 1 && channels != 3) {
        *why = "1 or 3 channels";
        break;
      }
      if (bits == 8) return OIIO::TypeDesc::UINT8;
      *why = "8 bits";
      break;
    case Kind::exr:
      if (bits == 16) return OIIO::TypeDesc::HALF;
      if (bits == 32) return OIIO::TypeDesc::FLOAT;
      *why = "16 (half) or 32 (float) bits";
      break;
    case Kind::hdr:
      if (channels != 3) {
        *why = "3 channels";
        break;
      }
      if (bits == 32) return OIIO::TypeDesc::FLOAT;
      *why = "32 bits";
      break;
    case Kind::pfm:
      if (channels != 1 && channels != 3) {
        *why = "1 or 3 channels";
        break;
      }
      if (bits == 32) return OIIO::TypeDesc::FLOAT;
      *why = "32 bits";
      break;
    case Kind::unknown:
      *why = "an extension .exr, .hdr, .pfm, .png, .tif, .tiff, .jpg or .jpeg";
      break;
  }
  return OIIO::TypeDesc::UNKNOWN;
}

/* Netpbm PFM: little-endian floats (negative scale), rows bottom to top. */
cf_status write_pfm(const char *path, const cf_image *image, cf_error *err) {
  const uint32_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  const bool little_endian = first == 1;
  FILE *file = std::fopen(path, "wb");
  if (!file) return cf_error_set(err, CF_EIO, "%s: %s", path, std::strerror(errno));
  bool ok = std::fprintf(file, "%s\n%d %d\n%s\n", image->channels == 3 ? "PF" : "Pf", image->width,
                         image->height, little_endian ? "-1.0" : "1.0") > 0;
  const size_t row = size_t(image->width) * size_t(image->channels);
  for (int y = image->height - 1; ok && y >= 0; --y)
    ok = std::fwrite(image->pixels + size_t(y) * row, sizeof(float), row, file) == row;
  ok = (std::fclose(file) == 0) && ok;
  if (!ok) return cf_error_set(err, CF_EIO, "%s: could not write the PFM file", path);
  return CF_OK;
}

/* How a JPEG is written: libjpeg's quality (1..100) and the chroma
 * subsampling ("4:4:4", "4:2:2", "4:2:0"). */
struct JpegSettings {
  int quality;
  const char *subsampling;
};
const JpegSettings kLosslessAsCanBe = {100, "4:4:4"};

/* OpenImageIO's name of a chroma subsampling. */
const char *subsampling_name(cf_chroma chroma) {
  return chroma == CF_CHROMA_420 ? "4:2:0" : chroma == CF_CHROMA_422 ? "4:2:2" : "4:4:4";
}

cf_status write_image(const char *path, const cf_image *image, int bits, const cf_image_info *info,
                      const JpegSettings &jpeg, cf_error *err) {
  if (!image || !image->pixels || image->width <= 0 || image->height <= 0 || image->channels < 1 ||
      image->channels > 4)
    return cf_error_set(err, CF_EINVAL, "%s: nothing to write (an empty image)", path);
  Kind kind = kind_of(extension_of(path));
  const char *why = "";
  OIIO::TypeDesc type = sample_type(kind, bits, image->channels, &why);
  if (type == OIIO::TypeDesc::UNKNOWN)
    return cf_error_set(err, CF_EINVAL,
                        "%s: cannot write %d bits x %d channels in this format; it takes %s", path,
                        bits, image->channels, why);
  if (kind == Kind::pfm) return write_pfm(path, image, err);

  auto output = OIIO::ImageOutput::create(path);
  if (!output)
    return cf_error_set(err, CF_EUNSUPPORTED, "%s: OpenImageIO has no writer for it: %s", path,
                        one_line(OIIO::geterror()).c_str());
  OIIO::ImageSpec spec(image->width, image->height, image->channels, type);
  spec.attribute("oiio:UnassociatedAlpha", 1);
  if (kind == Kind::exr) spec.attribute("compression", "zip");
  if (kind == Kind::tiff) spec.attribute("compression", "zip");
  if (kind == Kind::jpeg) {
    spec.attribute("Compression", "jpeg:" + std::to_string(jpeg.quality));
    spec.attribute("jpeg:subsampling", jpeg.subsampling);
  }
  if (info) {
    if (std::isfinite(info->exposure_time))
      spec.attribute("ExposureTime", float(info->exposure_time));
    if (std::isfinite(info->f_number)) spec.attribute("FNumber", float(info->f_number));
    if (std::isfinite(info->iso))
      spec.attribute("Exif:PhotographicSensitivity", int(std::lround(info->iso)));
  }
  if (!output->open(path, spec))
    return cf_error_set(err, CF_EIO, "%s: cannot create the file: %s", path,
                        one_line(output->geterror()).c_str());
  bool ok = output->write_image(OIIO::TypeDesc::FLOAT, image->pixels);
  ok = output->close() && ok;
  std::string failed = output->geterror(); /* the PNG writer reports a failed write
                                              (/dev/full, a full disk) only here; the
                                              TIFF writer leaves a harmless note on
                                              its EXIF directory there */
  if (!ok || (kind == Kind::png && !failed.empty()))
    return cf_error_set(err, CF_EIO, "%s: could not write the image: %s", path,
                        one_line(failed).c_str());
  return CF_OK;
}

}  // namespace

extern "C" {

cf_status cf_image_alloc(cf_image *image, int width, int height, int channels, cf_error *err) {
  image->width = image->height = image->channels = 0;
  image->pixels = nullptr;
  if (width <= 0 || height <= 0 || channels < 1 || channels > 4)
    return cf_error_set(err, CF_EINVAL,
                        "cannot make an image of %d x %d pixels with %d channels (sizes must be "
                        "positive, channels 1 to 4)",
                        width, height, channels);
  int64_t values = int64_t(width) * height * channels;
  if (values > kMaxValues)
    return cf_error_set(err, CF_EINVAL,
                        "an image of %d x %d pixels x %d channels has %lld values, more than 2^31",
                        width, height, channels, (long long)values);
  float *pixels = static_cast<float *>(std::calloc(size_t(values), sizeof(float)));
  if (!pixels)
    return cf_error_set(err, CF_ENOMEM, "out of memory for an image of %d x %d x %d floats", width,
                        height, channels);
  image->width = width;
  image->height = height;
  image->channels = channels;
  image->pixels = pixels;
  return CF_OK;
}

void cf_image_free(cf_image *image) {
  if (!image) return;
  std::free(image->pixels);
  image->pixels = nullptr;
  image->width = image->height = image->channels = 0;
}

cf_status cf_image_read_sized(const char *path, int width, int height, cf_image *image,
                              cf_image_info *info, cf_error *err) {
  image->width = image->height = image->channels = 0;
  image->pixels = nullptr;
  info_clear(info);
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  try {
    return read_image(path, width, height, image, info, err);
  } catch (...) {
    return read_failed(path, image, err);
  }
}

cf_status cf_image_read(const char *path, cf_image *image, cf_image_info *info, cf_error *err) {
  return cf_image_read_sized(path, 0, 0, image, info, err);
}

cf_status cf_image_read_header(const char *path, cf_image_header *header, cf_error *err) {
  header->width = header->height = header->channels = 0;
  info_clear(&header->info);
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  try {
    return read_header(path, header, err);
  } catch (...) {
    return read_failed(path, nullptr, err);
  }
}

cf_status cf_image_write_with_info(const char *path, const cf_image *image, int bits,
                                   const cf_image_info *info, cf_error *err) {
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  try {
    return write_image(path, image, bits, info, kLosslessAsCanBe, err);
  } catch (const std::exception &e) {
    drain_errors();
    return cf_error_set(err, CF_EIO, "%s: writing failed: %s", path, e.what());
  } catch (...) {
    return cf_error_set(err, CF_EIO, "%s: writing failed (an unknown exception)", path);
  }
}

cf_status cf_image_write_jpeg(const char *path, const cf_image *image, int quality,
                              cf_chroma chroma, const cf_image_info *info, cf_error *err) {
  if (!path || !path[0]) return cf_error_set(err, CF_EINVAL, "an empty image path");
  if (quality < 1 || quality > 100)
    return cf_error_set(err, CF_EINVAL, "%s: JPEG quality %d is outside [1, 100]", path, quality);
  std::string ext = extension_of(path);
  if (kind_of(ext) != Kind::jpeg)
    return cf_error_set(err, CF_EINVAL, "%s: a JPEG needs the extension .jpg or .jpeg", path);
  const char *subsampling = subsampling_name(chroma);
  try {
    return write_image(path, image, 8, info, JpegSettings{quality, subsampling}, err);
  } catch (const std::exception &e) {
    drain_errors();
    return cf_error_set(err, CF_EIO, "%s: writing failed: %s", path, e.what());
  } catch (...) {
    return cf_error_set(err, CF_EIO, "%s: writing failed (an unknown exception)", path);
  }
}

cf_status cf_image_write(const char *path, const cf_image *image, int bits, cf_error *err) {
  return cf_image_write_with_info(path, image, bits, nullptr, err);
}

namespace {

/* cf_image_jpeg_roundtrip's body: code `in` into memory, decode it back. */
cf_status jpeg_roundtrip(const cf_image *in, int quality, const char *subsampling, cf_image *out,
                         cf_error *err) {
  OIIO::Filesystem::IOVecOutput coded;
  auto output = OIIO::ImageOutput::create("jpeg");
  if (!output)
    return cf_error_set(err, CF_EUNSUPPORTED, "OpenImageIO has no JPEG writer: %s",
                        one_line(OIIO::geterror()).c_str());
  OIIO::ImageSpec spec(in->width, in->height, in->channels, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:" + std::to_string(quality));
  spec.attribute("jpeg:subsampling", subsampling);
  bool ok = output->set_ioproxy(&coded) && output->open("coded.jpg", spec);
  ok = ok && output->write_image(OIIO::TypeDesc::FLOAT, in->pixels);
  ok = output->close() && ok;
  if (!ok)
    return cf_error_set(err, CF_EIO, "coding a JPEG in memory failed: %s",
                        one_line(output->geterror()).c_str());
  OIIO::Filesystem::IOMemReader reader(coded.buffer().data(), coded.buffer().size());
  auto input = OIIO::ImageInput::open("coded.jpg", nullptr, &reader);
  if (!input)
    return cf_error_set(err, CF_EIO, "decoding a JPEG from memory failed: %s",
                        one_line(OIIO::geterror()).c_str());
  cf_status s = cf_image_alloc(out, in->width, in->height, in->channels, err);
  if (s == CF_OK && !input->read_image(0, 0, 0, in->channels, OIIO::TypeDesc::FLOAT, out->pixels)) {
    cf_image_free(out);
    s = cf_error_set(err, CF_EIO, "decoding a JPEG from memory failed: %s",
                     one_line(input->geterror()).c_str());
  }
  input->close();
  return s;
}

}  // namespace

cf_status cf_image_jpeg_roundtrip(const cf_image *in, int quality, cf_chroma chroma, cf_image *out,
                                  cf_error *err) {
  *out = cf_image{};
  if (!in || !in->pixels || in->width <= 0 || in->height <= 0 || in->channels != 3)
    return cf_error_set(err, CF_EINVAL, "a JPEG round trip needs a 3-channel image");
  if (quality < 1 || quality > 100)
    return cf_error_set(err, CF_EINVAL, "JPEG quality %d is outside [1, 100]", quality);
  const char *subsampling = subsampling_name(chroma);
  try {
    return jpeg_roundtrip(in, quality, subsampling, out, err);
  } catch (const std::exception &e) {
    drain_errors();
    cf_image_free(out);
    return cf_error_set(err, CF_EIO, "a JPEG round trip failed: %s", e.what());
  } catch (...) {
    cf_image_free(out);
    return cf_error_set(err, CF_EIO, "a JPEG round trip failed (an unknown exception)");
  }
}

}  // extern "C"
